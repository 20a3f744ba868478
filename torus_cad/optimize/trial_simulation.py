"""A trial's performance: ``torus-cad simulate`` run on the trial's design file, behind one
function.

The contract: ``python -m torus_cad simulate CONFIG.toml (--rpm RPM | --thrust N --thrust-tolerance
F --thrust-runs K) [--airspeed M_S] [--iterations N] [--processes N] [--observer D:A ...]
[--time-limit S] --level LEVEL --out DIR --quiet`` writes ``DIR/<name>_performance.json`` (thrust_n,
torque_nm, power_w, ct, cp, efficiency, figure_of_merit, converged, ...) and exits 0; 2 for bad
input (the design is refused), 1 for a failure. :func:`run_simulate` is the only place that knows
it, so that it can become a Python call later.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import signal
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from torus_cad.errors import ParameterError, TorusCadError
from torus_cad.parameters.config_file import read_config_text
from torus_cad.simulate.thrust_target import DEFAULT_MAX_RUNS, DEFAULT_TOLERANCE

__all__ = ["SimulateError", "run_simulate", "simulate_unavailable"]

_EXIT_BAD_INPUT = 2
_REPORT_MAX_BYTES = 1 << 20  #: a performance report is a few kB
_PR_SET_PDEATHSIG = 1


#: The study level (``[simulate] level`` or ``levels``) that runs ``simulate --solver vortex``
#: instead of a mesh level.
VORTEX_LEVEL = "vortex"


class SimulateError(TorusCadError):
    """``torus-cad simulate`` failed on a design (exit 1, a crash, a time-out, no report)."""


def _command(
    config: Path, settings: Mapping[str, Any], out_dir: Path, time_limit_s: float | None
) -> list[str]:
    command = [sys.executable, "-m", "torus_cad", "simulate", str(config)]
    if settings.get("thrust"):
        command += [
            "--thrust",
            repr(float(settings["thrust"])),
            "--thrust-tolerance",
            repr(float(settings.get("thrust_tolerance", DEFAULT_TOLERANCE))),
            "--thrust-runs",
            str(int(settings.get("thrust_runs", DEFAULT_MAX_RUNS))),
        ]
    else:
        command += ["--rpm", repr(float(settings["rpm"]))]
    if settings.get("airspeed"):
        command += ["--airspeed", repr(float(settings["airspeed"]))]
    level = str(settings.get("level", "coarse"))
    for key, option in (("iterations", "--iterations"), ("processes", "--processes")):
        # OpenFOAM's; the vortex solver takes neither
        if settings.get(key) and level != VORTEX_LEVEL:
            command += [option, str(int(settings[key]))]
    for observer in settings.get("observers", ()):
        command += ["--observer", str(observer)]
    # the study's limit for the whole run (a thrust search's runs included), not simulate's default
    if time_limit_s:
        command += ["--time-limit", repr(float(time_limit_s))]
    fidelity = ["--solver", "vortex"] if level == VORTEX_LEVEL else ["--level", level]
    return command + fidelity + ["--out", str(out_dir), "--quiet"]


def _die_with_parent() -> None:
    """In the child: SIGKILL when the trial's worker dies (a worker stopped at its time limit)."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)


def run_simulate(
    config: Path,
    name: str,
    settings: Mapping[str, Any],
    out_dir: Path,
    time_limit_s: float | None = None,
) -> dict[str, Any]:
    """The performance report of the design file ``config`` (named ``name``) at ``settings``
    (``rpm`` or a target ``thrust`` N with ``thrust_tolerance`` and ``thrust_runs``; ``airspeed``
    m/s, ``level``, and ``iterations``, ``processes``, ``observers`` when given), simulated into
    ``out_dir`` within ``time_limit_s``.

    Raises ParameterError when simulate refuses the design (exit 2), SimulateError when it fails.
    The vortex level runs in this process (:func:`_run_vortex`): the same solver and report as
    ``simulate --solver vortex``.
    """
    if str(settings.get("level", "")) == VORTEX_LEVEL:
        return _run_vortex(config, settings, out_dir)
    try:
        done = subprocess.run(
            _command(config, settings, out_dir, time_limit_s),
            capture_output=True,
            text=True,
            timeout=time_limit_s,
            preexec_fn=_die_with_parent,
            check=False,
        )
    except subprocess.TimeoutExpired:
        raise SimulateError(f"torus-cad simulate ran past {time_limit_s:g} s") from None
    last = (done.stderr.strip().splitlines() or done.stdout.strip().splitlines() or [""])[-1][:300]
    if done.returncode == _EXIT_BAD_INPUT:
        raise ParameterError(f"torus-cad simulate refused the design: {last}")
    if done.returncode != 0:
        raise SimulateError(f"torus-cad simulate failed (exit {done.returncode}): {last}")
    report_path = out_dir / f"{name}_performance.json"
    try:
        report = json.loads(read_config_text(report_path, "performance report", _REPORT_MAX_BYTES))
    except (ParameterError, ValueError) as error:
        raise SimulateError(
            f"torus-cad simulate exited 0 but its report is unusable: {error}"
        ) from None
    if not isinstance(report, dict):
        raise SimulateError(f"{report_path.name} is not a JSON object")
    return report


def _run_vortex(config: Path, settings: Mapping[str, Any], out_dir: Path) -> dict[str, Any]:
    """``simulate --solver vortex`` on the design file ``config`` as a Python call, without its
    pictures: a trial takes seconds, and a new process would add the imports' seconds to each (the
    trial's worker has its own time limit). The report published into ``out_dir`` is returned."""
    from torus_cad.acoustics.observers import parse_observer
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.settings import OperatingPoint
    from torus_cad.vortex.pipeline import VortexRequest, simulate_vortex, vortex_thrust_search

    observers = tuple(parse_observer(str(text)) for text in settings.get("observers", ()))
    point = OperatingPoint(float(settings.get("rpm", 0.0)), float(settings.get("airspeed", 0.0)))
    try:
        request = VortexRequest(
            PropellerParameters.from_toml(config), point, observers=observers, pictures=False
        )
        if settings.get("thrust"):
            run = vortex_thrust_search(
                request,
                float(settings["thrust"]),
                out_dir,
                tolerance=float(settings.get("thrust_tolerance", DEFAULT_TOLERANCE)),
                max_runs=int(settings.get("thrust_runs", DEFAULT_MAX_RUNS)),
            )
        else:
            run = simulate_vortex(request, out_dir)
    except ParameterError as error:
        raise ParameterError(f"the vortex solver refused the design: {error}") from None
    except TorusCadError as error:
        raise SimulateError(f"the vortex solver failed: {error}") from None
    return run.report


def simulate_unavailable() -> str:
    """'' when ``torus-cad simulate`` can run here; otherwise why not (for a test's skip, a clear
    error)."""
    if not Path("/usr/bin/simpleFoam").is_file():
        return "OpenFOAM's simpleFoam is not installed (/usr/bin/simpleFoam)"
    try:
        done = subprocess.run(
            [sys.executable, "-m", "torus_cad", "simulate", "--help"],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as error:
        return f"python -m torus_cad simulate --help did not run: {error}"
    if done.returncode != 0:
        return (
            "torus-cad simulate is not available (python -m "
            f"torus_cad simulate --help exits {done.returncode})"
        )
    return ""
