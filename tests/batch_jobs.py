"""Jobs for the batch runner's tests: fault injection lives here, never in the shipped code.

Each is a top-level function of a :class:`~torus_cad.batch.DesignTask` returning a
:class:`~torus_cad.batch.DesignResult`, as the runner's ``job`` argument wants; the worker
processes import this module by name (the tests folder is on ``sys.path``).
"""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

from torus_cad.batch import DesignResult, DesignTask, Outcome, run_design

#: A design dict with this key gets the fault named by its value instead of being built.
FAULT_KEY = "fault"


#: A hanging design dict may name a file here, where the hang writes its worker's pid first.
PID_FILE_KEY = "pid_file"


def faulty(task: DesignTask) -> DesignResult:
    """``fault = "hang"``: never finishes (writing its worker's pid to ``pid_file`` if given);
    ``"crash"``: kills its worker (like a segfault); else built as usual."""
    fault = task.parameters.get(FAULT_KEY)
    if fault == "hang":
        if PID_FILE_KEY in task.parameters:
            Path(task.parameters[PID_FILE_KEY]).write_text(str(os.getpid()))
        time.sleep(3600)
    elif fault == "crash":
        os.kill(os.getpid(), signal.SIGKILL)
    return run_design(task)


def crash_on_four_or_six_blades(task: DesignTask) -> DesignResult:
    """Kills its worker process for 4 and 6 blades, like a segfault in OpenCascade would."""
    if task.parameters["blades"] in (4, 6):
        os._exit(1)
    return DesignResult(task.design_id, Outcome.VALID)


def announce_and_sleep(task: DesignTask) -> DesignResult:
    """Write ``<folder>.started`` holding this worker's pid, then sleep for ten minutes (a long
    design)."""
    assert task.folder is not None
    marker = Path(f"{task.folder}.started")
    marker.parent.mkdir(parents=True, exist_ok=True)
    marker.write_text(str(os.getpid()))
    time.sleep(600)
    return DesignResult(task.design_id, Outcome.VALID)
