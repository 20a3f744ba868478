"""One trial, as a worker runs it: the sweep's design job, then (for ``performance.*``) the simulation.

The trial's folder ``OUT/trials/<number>/`` holds the build's output set (``trial_<number>.step``,
``.json``, ``.stl`` unless the study says ``stl = false``, ``.3mf`` when the design asks): every
file its best set would hold, so that the trial is judged on them; the design file
``trial_<number>.toml`` that rebuilds it, and ``simulate/`` with the performance report; or the
sweep's ``refusal.json`` / ``failure.json`` naming the reason.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from torus_cad.batch.job import DesignTask, record_result, run_design
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.errors import ParameterError, TorusCadError

__all__ = ["PERFORMANCE_DIR", "TRIALS_DIR", "TrialTask", "run_trial", "trial_name"]

PERFORMANCE_DIR = "simulate"
TRIALS_DIR = "trials"  #: the trials' folders under the study's out folder: ``OUT/trials/<number>/``


def trial_name(number: int) -> str:
    """The design name (and file stem) of trial ``number``."""
    return f"trial_{number}"


@dataclass(frozen=True)
class TrialTask(DesignTask):
    """A design task with the simulation settings (``{"rpm", "airspeed", "level"}``; None: geometry only)
    and the simulation's time limit, s."""

    simulate: dict[str, Any] | None = None
    simulate_time_limit_s: float | None = None


def run_trial(task: DesignTask) -> DesignResult:
    """Build and write the design, write its TOML, simulate a :class:`TrialTask` if asked; never raises for a
    bad design."""
    result = run_design(task)
    if result.outcome is not Outcome.VALID or task.folder is None:
        return result
    simulate = task.simulate if isinstance(task, TrialTask) else None
    time_limit_s = task.simulate_time_limit_s if isinstance(task, TrialTask) else None
    start = time.perf_counter()
    folder = Path(task.folder)
    try:
        config = _write_design_file(task, folder)
        if simulate is not None:
            from torus_cad.optimize.performance import run_simulate

            run_simulate(config, task.design_id, simulate, folder / PERFORMANCE_DIR, time_limit_s)
    except ParameterError as error:
        failed = dataclasses.replace(result, outcome=Outcome.REFUSED, reason=str(error), error="ParameterError")
    except (TorusCadError, OSError) as error:
        failed = dataclasses.replace(result, outcome=Outcome.FAILED, reason=" ".join(str(error).split()),
                                     error=type(error).__name__)
    else:
        return dataclasses.replace(result, seconds=result.seconds + time.perf_counter() - start)
    return record_result(task, dataclasses.replace(failed, seconds=result.seconds + time.perf_counter() - start))


def _write_design_file(task: DesignTask, folder: Path) -> Path:
    """``<id>.toml``: the trial's design, as ``torus-cad build`` reads it."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.runtime.files import atomic_path

    path = folder / f"{task.design_id}.toml"
    with atomic_path(path) as temp:
        temp.write_text(PropellerParameters.from_dict(task.parameters).to_toml())
    return path
