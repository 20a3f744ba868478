"""Calibrate and check the CFD budget's estimate (torus_cad/cfd_domain/estimate.py) against real
runs.

    python scripts/cfd_budget.py
        # the default design at a few [cfd] settings (~10-20 min)
    python scripts/cfd_budget.py --quick         # the two coarsest settings only
    python scripts/cfd_budget.py --examples      # every shipped example at its own [cfd] (~30 min)
    python scripts/cfd_budget.py --examples multirotor_5in_3blade cooling_fan_7blade

For each setting: the size integrals (∫ dV / h³ and the surface triangles), the estimate, and a
real ``torus-cad cfd`` run's tetrahedra, wall time and peak resident memory (its own process);
then the least-squares constants (tetrahedra per volume unit and per triangle, memory base and per
tetrahedron) that the estimate module's constants were set from, and the estimate's time.
With ``--examples``: each shipped example (examples/*.toml, examples/optimize/*.toml) at its own
``[cfd]`` settings: the estimate against the real count (the factor the docs state), wall and CPU
time, peak memory and tetrahedra per CPU second (what the printed time estimate is set from: gmsh
meshes on one thread, so on an idle machine the wall time is the CPU time),
one JSON line each after the table (``--json FILE`` appends them to FILE as they come).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: [cfd] settings measured (command-line options), coarsest first.
SETTINGS: list[list[str]] = [
    [
        "--cells-per-chord",
        "4",
        "--curvature-cells",
        "0",
        "--growth-rate",
        "1.6",
        "--domain-radius",
        "2",
        "--upstream",
        "1.5",
        "--downstream",
        "2",
    ],  # the README example
    ["--cells-per-chord", "4", "--growth-rate", "1.6"],
    ["--cells-per-chord", "6", "--growth-rate", "1.4"],
    [],  # the defaults
]


def _options_to_values(options: list[str]) -> dict[str, float]:
    return {
        f"cfd.{options[i][2:].replace('-', '_')}": float(options[i + 1])
        for i in range(0, len(options), 2)
    }


def measure(options: list[str]) -> dict[str, float]:
    """One ``torus-cad cfd`` run in its own process: tetrahedra, wall seconds, peak RSS (MB)."""
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        process = subprocess.Popen(
            [sys.executable, "-m", "torus_cad", "cfd", *options, "--out", folder, "-q"],
            stdin=subprocess.DEVNULL,
        )
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            raise SystemExit(f"torus-cad cfd {' '.join(options)} exited {process.returncode}")
        report = json.loads(next(Path(folder).glob("*_cfd.json")).read_text())
        return {
            "tetrahedra": report["tetrahedra_total"],
            "wall_s": time.perf_counter() - start,
            "cpu_s": usage.ru_utime + usage.ru_stime,
            "peak_mb": usage.ru_maxrss / 1024.0,
            "estimate": report["estimate"]["tetrahedra"],
        }


EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def shipped_designs() -> list[Path]:
    """Every shipped design file (not the sweep's or the study's own files)."""
    files = sorted(EXAMPLES.glob("*.toml")) + sorted((EXAMPLES / "optimize").glob("*.toml"))
    return [
        path
        for path in files
        if "[sweep]" not in path.read_text() and "[study]" not in path.read_text()
    ]


def measure_examples(names: list[str], json_path: str | None) -> None:
    """The estimate against a real run for each shipped example (or those named), at its own
    [cfd]."""
    from torus_cad.cfd_domain.estimate import estimate_cfd_mesh
    from torus_cad.parameters import resolve_parameters

    shipped = {path.stem: path for path in shipped_designs()}
    designs = [shipped[name] for name in names] if names else list(shipped.values())
    rows = []
    for path in designs:
        estimate = estimate_cfd_mesh(resolve_parameters(path))
        real = measure([str(path)])
        row = {
            "example": path.stem,
            "estimate": estimate.tetrahedra,
            "tetrahedra": real["tetrahedra"],
            "factor": estimate.tetrahedra / real["tetrahedra"],
            "wall_s": real["wall_s"],
            "cpu_s": real["cpu_s"],
            "peak_mb": real["peak_mb"],
            "tets_per_cpu_s": real["tetrahedra"] / real["cpu_s"],
            "load": os.getloadavg()[0],
        }
        rows.append(row)
        print(
            f"{row['example']}: estimate {row['estimate']:,}, "
            f"real {row['tetrahedra']:,} (estimate / real "
            f"{row['factor']:.2f}), {row['wall_s']:.0f} s wall, "
            f"{row['cpu_s']:.0f} s CPU, {row['peak_mb']:,.0f} MB, "
            f"{row['tets_per_cpu_s']:,.0f} tetrahedra per "
            f"CPU second (load average {row['load']:.1f})",
            flush=True,
        )
        if json_path:
            with open(json_path, "a", encoding="utf-8") as stream:
                stream.write(json.dumps(row) + "\n")
    if rows:
        factors = [row["factor"] for row in rows]
        rates = [row["tets_per_cpu_s"] for row in rows]
        print(
            f"estimate / real: {min(factors):.2f} to "
            f"{max(factors):.2f}; tetrahedra per CPU second: "
            f"{min(rates):,.0f} to {max(rates):,.0f}"
        )


def main() -> None:
    from torus_cad.cfd_domain.estimate import estimate_cfd_mesh, size_integrals
    from torus_cad.parameters import PropellerParameters

    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help="the two coarsest settings only")
    parser.add_argument(
        "--examples",
        nargs="*",
        metavar="NAME",
        help="measure the shipped examples (all, or those named) at their own [cfd] instead",
    )
    parser.add_argument(
        "--json", metavar="FILE", help="with --examples: append one JSON line per example to FILE"
    )
    args = parser.parse_args()
    if args.examples is not None:
        measure_examples(args.examples, args.json)
        return
    rows = []
    for options in SETTINGS[:2] if args.quick else SETTINGS:
        params = PropellerParameters().with_values(_options_to_values(options))
        start = time.perf_counter()
        estimate = estimate_cfd_mesh(params)
        estimate_s = time.perf_counter() - start
        volume_units, triangles = size_integrals(params)
        real = measure(options)
        rows.append((volume_units, triangles, real))
        print(
            f"{' '.join(options) or '(defaults)'}: integrals "
            f"{volume_units:,.0f} / {triangles:,} triangles; "
            f"estimate {estimate.tetrahedra:,} tets, "
            f"{estimate.memory_mb:,.0f} MB ({estimate_s:.2f} s); real "
            f"{real['tetrahedra']:,} tets "
            f"({estimate.tetrahedra / real['tetrahedra']:.2f}x), {real['peak_mb']:,.0f} MB "
            f"peak, {real['wall_s']:.1f} s",
            flush=True,
        )
    design = np.array([[volume, triangles] for volume, triangles, _ in rows])
    tets = np.array([real["tetrahedra"] for _, _, real in rows])
    per_volume, per_triangle = np.linalg.lstsq(design, tets, rcond=None)[0]
    memory = np.polyfit(tets, [real["peak_mb"] for _, _, real in rows], 1)
    print(
        f"fit: TETS_PER_VOLUME_UNIT = {per_volume:.2f}, TETS_PER_TRIANGLE = {per_triangle:.2f}; "
        f"MEMORY_BASE_MB = {memory[1]:.0f}, MEMORY_PER_TET_KB = {memory[0] * 1000.0:.2f}"
    )


if __name__ == "__main__":
    main()
