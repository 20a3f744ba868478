"""One design's job, as a worker process runs it: build, write, check the files, classify, record.

:func:`run_design` never raises for a bad design: every exception becomes an
:class:`~torus_cad.batch.outcome.Outcome`. A design with a folder leaves exactly one status
file there: its report ``<id>.json`` (valid), ``refusal.json`` (refused) or ``failure.json``
(anything else), which is how a resumed sweep knows what is done.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import tempfile
import threading
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.errors import GeometryError, KernelError, ParameterError
from torus_cad.parameters import PropellerParameters

__all__ = [
    "FAILURE_FILE",
    "REFUSAL_FILE",
    "DesignTask",
    "prescreen",
    "read_design_status",
    "record_result",
    "run_design",
    "verify_files",
]

REFUSAL_FILE = "refusal.json"
FAILURE_FILE = "failure.json"

# OpenCascade keeps global state (e.g. the STEP writer's schema and product name), so designs
# in one process never run concurrently, even on a Dask worker with several threads.
_KERNEL_LOCK = threading.Lock()


@dataclass(frozen=True)
class DesignTask:
    """What a worker needs to run one design; plain data, so it pickles to any worker.

    Attributes:
        design_id: the design's id (also its ``name`` and its files' stem in a sweep).
        parameters: the full parameter dict (the TOML layout).
        folder: absolute path of the design's folder (on a cluster: on the shared file system),
            where its files and status file go; None: a temporary folder, deleted afterwards.
        write: write STEP / STL / JSON at all (False: build and check the solid only).
        stl: write the STL file.
        density_g_cm3: material density, g/cm^3 (None: the package default).
        verify: read every written file back (:func:`verify_files`); a bad one is ``bad_file``.
    """

    design_id: str
    parameters: dict[str, Any]
    folder: str | None = None
    write: bool = True
    stl: bool = True
    density_g_cm3: float | None = None
    verify: bool = False


def run_design(task: DesignTask) -> DesignResult:
    """Build (and write, and check) one design in this process; never raises for a bad design."""
    from torus_cad.propeller import build_propeller  # once per process, not timed

    start = time.perf_counter()
    scratch = (
        Path(tempfile.mkdtemp(prefix="torus_batch_"))
        if task.write and task.folder is None
        else None
    )
    folder = scratch if scratch is not None else (Path(task.folder) if task.folder else None)
    outcome, reason, detail, error_type = Outcome.VALID, "", "", ""
    try:
        with _KERNEL_LOCK:
            propeller = build_propeller(PropellerParameters.from_dict(task.parameters))
            if task.write and folder is not None:
                outcome, reason = _write(propeller, folder, task)
    except Exception as error:  # a batch records every failure and carries on
        (outcome, reason, detail), error_type = _classify(error), type(error).__name__
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    result = DesignResult(
        task.design_id, outcome, reason, time.perf_counter() - start, detail, error_type
    )
    if task.folder is not None:
        result = record_result(task, result)
    return result


def prescreen(task: DesignTask) -> DesignResult | None:
    """The design's refusal by the checks the build makes before the kernel, run here, in the
    batch's own process, before a worker is given it
    (:func:`torus_cad.design.design_checks.check_design`, tens of ms, no kernel); None when it
    passes, and the worker builds it. The refusal is recorded in the task's folder
    (``refusal.json``, ``"prescreened": true``) as a worker records one. Never raises for a bad
    design: an unexpected exception is left for the worker to meet and classify."""
    from torus_cad.design.design_checks import check_design
    from torus_cad.parameters.design import ExportFormat

    start = time.perf_counter()
    try:
        params = PropellerParameters.from_dict(task.parameters)
        formats = params.export.formats
        mesh = task.write and (
            (task.stl and ExportFormat.STL in formats) or ExportFormat.THREE_MF in formats
        )
        check_design(params, mesh=mesh)  # the mesh's budget as the write checks it (output_set)
    except (ParameterError, GeometryError) as error:
        result = DesignResult(
            task.design_id,
            Outcome.REFUSED,
            str(error),
            time.perf_counter() - start,
            error=type(error).__name__,
            prescreened=True,
        )
        return record_result(task, result) if task.folder is not None else result
    except Exception:  # a bug is the worker's to record, with its traceback
        return None
    return None


def _classify(error: Exception) -> tuple[Outcome, str, str]:
    """The outcome, one-line reason and traceback of what a design raised (call inside
    ``except``)."""
    if isinstance(error, (ParameterError, GeometryError)):  # the package's own refusal
        return Outcome.REFUSED, str(error), ""
    if isinstance(error, KernelError):  # OpenCascade failed on a design the checks let through
        return Outcome.FAILED, _one_line(error), traceback.format_exc()
    return Outcome.ERROR, f"{type(error).__name__}: {_one_line(error)}", traceback.format_exc()


def _write(propeller: Any, folder: Path, task: DesignTask) -> tuple[Outcome, str]:
    """Write the design's files (and read them back when asked); the outcome and its reason."""
    from torus_cad.propeller import DEFAULT_DENSITY_G_CM3

    density = DEFAULT_DENSITY_G_CM3 if task.density_g_cm3 is None else task.density_g_cm3
    paths = propeller.write(folder, density_g_cm3=density, stl=task.stl)
    problem = verify_files(paths) if task.verify else ""
    return (Outcome.BAD_FILE, problem) if problem else (Outcome.VALID, "")


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split())


def verify_files(paths: Mapping[str, Path]) -> str:
    """'' when every written file is complete and reads back; otherwise what is wrong.

    STEP: reads back as one valid closed solid; STL: binary, its length matches its triangle
    count and every coordinate is finite; JSON: describes a valid solid of positive volume;
    no temporary file left beside them.
    """
    from torus_cad.kernel.checks import is_valid_closed_solid
    from torus_cad.kernel.step_readback import read_step

    for kind, path in paths.items():
        if not path.is_file() or path.stat().st_size == 0:
            return f"{kind} file {path.name} is missing or empty"
    leftovers = [p.name for p in next(iter(paths.values())).parent.glob(".*.tmp-*")]
    if leftovers:
        return f"temporary files left behind: {leftovers}"
    if not is_valid_closed_solid(read_step(paths["step"])):
        return "the STEP file does not read back as one valid closed solid"
    if "stl" in paths:
        problem = _stl_problem(paths["stl"].read_bytes())
        if problem:
            return problem
    report = json.loads(paths["json"].read_text())
    if not report.get("valid") or not report.get("volume_mm3", 0) > 0:
        return "the JSON report does not describe a valid solid"
    return ""


def _stl_problem(data: bytes) -> str:
    count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0]) if len(data) >= 84 else -1
    if count <= 0 or len(data) != 84 + 50 * count:
        return f"the STL file is truncated or empty ({len(data)} bytes for {count} triangles)"
    vertices = np.frombuffer(
        data,
        dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
        count=count,
        offset=84,
    )["v"]
    return "" if np.all(np.isfinite(vertices)) else "the STL file holds non-finite coordinates"


# -- status files ------------------------------------------------------------------------------


def record_result(task: DesignTask, result: DesignResult) -> DesignResult:
    """Leave exactly one status file in the task's folder; a folder that cannot be written is noted
    in the reason.

    Called in the worker after a design ran, and in the parent for outcomes only it sees
    (a time-out, a crashed worker).
    """
    from torus_cad.runtime.files import atomic_path

    assert task.folder is not None
    folder = Path(task.folder)
    stale = [folder / FAILURE_FILE, folder / REFUSAL_FILE]
    try:
        if result.outcome is not Outcome.VALID:
            status_file = REFUSAL_FILE if result.outcome is Outcome.REFUSED else FAILURE_FILE
            stale = [folder / name for name in (REFUSAL_FILE, FAILURE_FILE) if name != status_file]
            stale += [folder / f"{task.design_id}.{suffix}" for suffix in ("json", "step", "stl")]
            record = {
                "id": task.design_id,
                "status": result.outcome.value,
                "error": result.error,
                "reason": result.reason,
                "seconds": result.seconds,
                "prescreened": result.prescreened,
                "parameters": task.parameters,
            }
            with atomic_path(folder / status_file) as temp:
                temp.write_text(json.dumps(record, indent=2, allow_nan=False) + "\n")
        for path in stale:
            path.unlink(missing_ok=True)
    except (OSError, ValueError) as error:  # the outcome still reaches the parent and its table
        note = f"could not record the outcome in {folder}: {error}"
        return dataclasses.replace(
            result, reason=f"{result.reason}; {note}" if result.reason else note
        )
    return result


def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def read_design_status(
    folder: Path, design_id: str, parameters: Mapping[str, Any], stl: bool
) -> tuple[Outcome, dict[str, Any]] | None:
    """The outcome recorded in a design's folder and its record (the report for a valid design), or
    None.

    Valid: the report ``<id>.json`` (for exactly these parameters) with its STEP file, and its
    STL when ``stl``. Otherwise ``refusal.json`` or ``failure.json`` for these parameters.
    Status names of older sweeps (``ok``) are read as today's.
    """
    report = _read_json(folder / f"{design_id}.json")
    if report is not None and report.get("parameters") == parameters:
        files = [folder / f"{design_id}.step"] + ([folder / f"{design_id}.stl"] if stl else [])
        if all(path.is_file() for path in files):
            return Outcome.VALID, report
    for name in (REFUSAL_FILE, FAILURE_FILE):
        record = _read_json(folder / name)
        if record is not None and record.get("parameters") == parameters:
            status = record.get("status")
            return (Outcome(status) if status in tuple(Outcome) else Outcome.ERROR), record
    return None
