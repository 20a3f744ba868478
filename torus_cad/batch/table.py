"""The results table of a batch: one row per design, written as CSV and Parquet (pyarrow).

The rows are rebuilt from the per-design status files (see :mod:`torus_cad.batch.job`), so
the table always says what is on disk, also after an interrupted or resumed run.

Units: lengths mm, areas mm^2, volumes mm^3, mass g, inertia g mm^2 (and mm^5 for the pure
geometric integral), times s, density g/cm^3.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from torus_cad.batch.designs import Design
from torus_cad.batch.job import read_design_status
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.build_stages import Stage

__all__ = [
    "DESIGNS_DIR",
    "STAGES",
    "TABLE_CSV",
    "TABLE_PARQUET",
    "collect_rows",
    "table_columns",
    "write_table",
]

DESIGNS_DIR = "designs"
TABLE_CSV = "results.csv"
TABLE_PARQUET = "results.parquet"

#: Stage columns of the table (``time_<stage>_s``), in pipeline order.
STAGES = tuple(stage.value for stage in Stage)

_PROPERTY_COLUMNS = (
    "volume_mm3",
    "surface_area_mm2",
    "mass_g",
    "density_g_cm3",
    "spin_axis_inertia_g_mm2",
    "spin_axis_inertia_mm5",
    "centroid_x_mm",
    "centroid_y_mm",
    "centroid_z_mm",
    "section_fit_error_mm",
)


def table_columns(varied_keys: Sequence[str]) -> list[str]:
    """The columns: id and status (``prescreened``: refused before any worker built it), the varied
    keys, mass properties, stage times (s), folder."""
    return (
        ["index", "id", "status", "valid", "reason", "prescreened"]
        + list(varied_keys)
        + list(_PROPERTY_COLUMNS)
        + [f"time_{stage}_s" for stage in STAGES]
        + ["time_total_s", "folder"]
    )


def collect_rows(
    designs: Sequence[Design],
    varied_keys: Sequence[str],
    out_dir: str | Path,
    stl: bool = True,
    results: Mapping[str, DesignResult] | None = None,
) -> list[dict[str, Any]]:
    """The table, rebuilt from the per-design files (``results`` fill in designs with no file).

    Vector values of varied keys are JSON strings (``"[25.0, 3.0, 22.0]"``); numbers stay numbers;
    a column that does not apply (e.g. the volume of a refused design) is None.
    """
    out_dir = Path(out_dir)
    columns = table_columns(varied_keys)
    rows = []
    for design in designs:
        row: dict[str, Any] = dict.fromkeys(columns)
        row.update(
            index=design.index,
            id=design.design_id,
            status=Outcome.PENDING.value,
            valid=False,
            prescreened=False,
            reason="",
            folder=f"{DESIGNS_DIR}/{design.design_id}",
        )
        for key, value in design.varied.items():
            row[key] = json.dumps(value) if isinstance(value, list) else value
        status = read_design_status(
            out_dir / DESIGNS_DIR / design.design_id, design.design_id, design.parameters, stl
        )
        if status is not None:
            _fill_recorded(row, *status)
        elif results and design.design_id in results:
            result = results[design.design_id]
            row.update(
                status=result.outcome.value,
                reason=result.reason,
                time_total_s=result.seconds,
                prescreened=result.prescreened,
            )
        rows.append(row)
    return rows


def _fill_recorded(row: dict[str, Any], outcome: Outcome, record: Mapping[str, Any]) -> None:
    """Fill ``row`` from a design's report (valid) or its refusal / failure record."""
    row["status"] = outcome.value
    if outcome is not Outcome.VALID:
        row["reason"] = record.get("reason", "")
        row["prescreened"] = record.get("prescreened") is True
        row["time_total_s"] = record.get("seconds")
        return
    row["valid"] = bool(record.get("valid", False))
    for column in _PROPERTY_COLUMNS:
        if column in record:
            row[column] = record[column]
    row["centroid_x_mm"], row["centroid_y_mm"], row["centroid_z_mm"] = (
        record.get("centroid_mm") or [None] * 3
    )
    stages = record.get("stage_seconds", {})
    for stage in STAGES:
        row[f"time_{stage}_s"] = stages.get(stage)
    row["time_total_s"] = float(sum(stages.values()))


def write_table(
    rows: Sequence[Mapping[str, Any]], out_dir: str | Path, columns: Sequence[str] | None = None
) -> dict[str, Path]:
    """Write ``results.csv`` (and ``results.parquet`` when pyarrow is installed) atomically; paths
    by format."""
    from torus_cad.runtime.files import atomic_path

    out_dir = Path(out_dir)
    columns = list(columns if columns is not None else (rows[0].keys() if rows else []))
    paths = {"csv": out_dir / TABLE_CSV}
    with atomic_path(paths["csv"]) as temp, temp.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({key: "" if row.get(key) is None else row[key] for key in columns})
    try:  # the `sweep` and `test` extras install it
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        return paths
    paths["parquet"] = out_dir / TABLE_PARQUET
    table = (
        pyarrow.Table.from_pylist([{key: row.get(key) for key in columns} for row in rows])
        if rows
        else pyarrow.table({key: [] for key in columns})
    )
    with atomic_path(paths["parquet"]) as temp:
        pyarrow.parquet.write_table(table, temp)
    return paths
