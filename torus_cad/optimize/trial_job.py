"""One trial, as a worker runs it: the sweep's design job, then (for ``performance.*``) the
simulation.

The trial's folder ``OUT/trials/<number>/`` holds the build's output set (``trial_<number>.step``,
``.json``, ``.stl`` unless the study says ``stl = false``, ``.3mf`` when the design asks): every
file its best set would hold, so that the trial is judged on them; the design file
``trial_<number>.toml`` that rebuilds it, and ``simulate/`` with the performance report; or the
sweep's ``refusal.json`` / ``failure.json`` naming the reason.

A study of several mesh levels runs a trial in stages, one task each: the first builds the design
and simulates it at the coarsest level into ``simulate/<level>/``; each further stage (a trial the
pruner let climb) simulates the design file already written at the next level, into its own
``simulate/<level>/``, without building it again.
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

__all__ = [
    "PERFORMANCE_DIR",
    "TRIALS_DIR",
    "TrialTask",
    "performance_dir",
    "run_trial",
    "trial_name",
]

PERFORMANCE_DIR = "simulate"
TRIALS_DIR = "trials"  #: the trials' folders under the study's out folder: ``OUT/trials/<number>/``


def trial_name(number: int) -> str:
    """The design name (and file stem) of trial ``number``."""
    return f"trial_{number}"


def performance_dir(level: str, levels: int) -> str:
    """The folder, under a trial's, of its simulation at ``level`` in a study of ``levels`` mesh
    levels: ``simulate`` (one level), ``simulate/<level>`` (several)."""
    return PERFORMANCE_DIR if levels <= 1 else f"{PERFORMANCE_DIR}/{level}"


@dataclass(frozen=True)
class TrialTask(DesignTask):
    """A design task with the simulation settings (``{"rpm", "airspeed", "level", ...}``; None:
    geometry only), the simulation's time limit, s, the folder of its report under the trial's
    (``simulate_dir``), and the trial's stage: 0 builds the design, a later one (a climb to a finer
    level) simulates the design file the first wrote."""

    simulate: dict[str, Any] | None = None
    simulate_time_limit_s: float | None = None
    simulate_dir: str = PERFORMANCE_DIR
    stage: int = 0


def run_trial(task: DesignTask) -> DesignResult:
    """Build and write the design, write its TOML, simulate a :class:`TrialTask` if asked; never
    raises for a bad design. A later stage of a trial (``stage`` > 0) only simulates the design file
    its first stage wrote."""
    climb = isinstance(task, TrialTask) and task.stage > 0
    result = DesignResult(task.design_id, Outcome.VALID) if climb else run_design(task)
    if result.outcome is not Outcome.VALID or task.folder is None:
        return result
    simulate = task.simulate if isinstance(task, TrialTask) else None
    time_limit_s = task.simulate_time_limit_s if isinstance(task, TrialTask) else None
    start = time.perf_counter()
    folder = Path(task.folder)
    try:
        config = folder / f"{task.design_id}.toml" if climb else _write_design_file(task, folder)
        if simulate is not None:
            from torus_cad.optimize.trial_simulation import run_simulate

            report_dir = task.simulate_dir if isinstance(task, TrialTask) else PERFORMANCE_DIR
            run_simulate(config, task.design_id, simulate, folder / report_dir, time_limit_s)
    except ParameterError as error:
        failed = dataclasses.replace(
            result, outcome=Outcome.REFUSED, reason=str(error), error="ParameterError"
        )
    except (TorusCadError, OSError) as error:
        failed = dataclasses.replace(
            result,
            outcome=Outcome.FAILED,
            reason=" ".join(str(error).split()),
            error=type(error).__name__,
        )
    else:
        return dataclasses.replace(result, seconds=result.seconds + time.perf_counter() - start)
    return record_result(
        task, dataclasses.replace(failed, seconds=result.seconds + time.perf_counter() - start)
    )


def _write_design_file(task: DesignTask, folder: Path) -> Path:
    """``<id>.toml``: the trial's design, as ``torus-cad build`` reads it."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.runtime.files import atomic_path

    path = folder / f"{task.design_id}.toml"
    with atomic_path(path) as temp:
        temp.write_text(PropellerParameters.from_dict(task.parameters).to_toml())
    return path
