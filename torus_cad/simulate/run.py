"""Running a case's commands through foamlib's asynchronous runner, watching the solver as it goes.

Each command runs with :class:`foamlib.AsyncFoamCase` (or a subclass: ``AsyncSlurmFoamCase``
sends them to a Slurm cluster), so many cases can run at once in one event loop, within
``AsyncFoamCase.max_cpus``. While the solver runs, a watcher reads the residual and force
histories every ``POLL_SECONDS``, reports each new iteration, and stops the solver when it
diverges (a residual above ``SIMULATE_DIVERGENCE_RESIDUAL`` or not finite, a force not finite)
or runs over its time budget.

The solver's processes are found by their working directory (the case), so stopping one case
leaves the others of a sweep running. :func:`solvers_stopped_on_signals` makes SIGINT / SIGTERM /
SIGHUP stop every solver this process started before the command's own handler runs.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import os
import re
import shutil
import signal
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from foamlib import AsyncFoamCase, CalledProcessError

from torus_cad.errors import KernelError, TorusCadError
from torus_cad.runtime.interrupts import EXIT_SIGNALS
from torus_cad.simulate.history import History, read_history

#: Simulations: an initial residual above this, or any non-finite residual or force, is divergence.
SIMULATE_DIVERGENCE_RESIDUAL = 1e3

POLL_SECONDS = 0.5
#: Seconds a stopped solver gets to exit after SIGTERM before SIGKILL.
STOP_GRACE_SECONDS = 3.0
#: Where Debian's openfoam package keeps OpenFOAM's etc/ (its programs need WM_PROJECT_DIR to find
#: it).
DEBIAN_PROJECT_DIR = Path("/usr/share/openfoam")
INSTALL_HINT = (
    "OpenFOAM is not installed (simpleFoam not found on PATH); on Debian or Ubuntu: "
    "sudo apt-get install --no-install-recommends openfoam (OpenFOAM v1912)"
)


class MissingOpenFoamError(TorusCadError):
    """OpenFOAM's programs are not on PATH; the message says how to install them."""


class SolverError(KernelError):
    """An OpenFOAM program failed; the message names it, the iteration and the cause."""


class DivergedError(SolverError):
    """The solver diverged; the message names the iteration and the residual."""


class TimeBudgetError(SolverError):
    """The run went over its time budget and was stopped."""


def check_openfoam() -> None:
    """MissingOpenFoamError unless simpleFoam, snappyHexMesh, gmshToFoam and the other programs are
    on PATH."""
    for program in (
        "simpleFoam",
        "blockMesh",
        "surfaceTransformPoints",
        "surfaceFeatureExtract",
        "snappyHexMesh",
        "gmshToFoam",
        "transformPoints",
        "foamDictionary",
        "checkMesh",
    ):
        if shutil.which(program) is None:
            raise MissingOpenFoamError(INSTALL_HINT.replace("simpleFoam", program, 1))


def openfoam_environment() -> dict[str, str]:
    """Environment variables OpenFOAM's programs need that are not set: WM_PROJECT_DIR for Debian's
    package, and OpenMPI's consent to run as root (containers)."""
    extra = {}
    if (
        "WM_PROJECT_DIR" not in os.environ
        and (DEBIAN_PROJECT_DIR / "etc" / "controlDict").is_file()
    ):
        extra["WM_PROJECT_DIR"] = str(DEBIAN_PROJECT_DIR)
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        extra.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
        extra.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return {key: value for key, value in extra.items() if key not in os.environ}


@contextlib.contextmanager
def openfoam_environ() -> Iterator[None]:
    """For the block: os.environ with :func:`openfoam_environment` (foamlib passes os.environ on),
    and rich's global console quiet (foamlib draws a bar per command on it; the caller reports
    progress)."""
    import rich

    extra = openfoam_environment()
    console = rich.get_console()
    os.environ.update(extra)
    quiet, console.quiet = console.quiet, True
    try:
        yield
    finally:
        console.quiet = quiet
        for key in extra:
            os.environ.pop(key, None)


# -- the solver's processes -----------------------------------------------------------------------


def _descendants() -> list[Any]:
    import psutil

    try:
        return list(psutil.Process().children(recursive=True))
    except psutil.Error:
        return []


def stop_processes(case: Path | None = None) -> None:
    """SIGTERM the processes this process started (only those working in ``case``, if given), then
    SIGKILL what is left after ``STOP_GRACE_SECONDS``."""
    import psutil

    chosen = []
    for process in _descendants():
        try:
            if case is None or Path(process.cwd()).resolve() == case.resolve():
                chosen.append(process)
        except psutil.Error:
            continue
    for process in chosen:
        with contextlib.suppress(psutil.Error):
            process.terminate()
    _, alive = psutil.wait_procs(chosen, timeout=STOP_GRACE_SECONDS)
    for process in alive:
        with contextlib.suppress(psutil.Error):
            process.kill()


@contextlib.contextmanager
def solvers_stopped_on_signals() -> Iterator[None]:
    """Within the block, SIGINT / SIGTERM / SIGHUP first stop every process this one started, then
    go to the handler that was there before (torus_cad.runtime.interrupts' on the command line).
    Main thread only."""
    previous: dict[int, Any] = {}

    def handler(signum: int, frame: FrameType | None) -> None:
        stop_processes()
        before = previous.get(signum)
        if callable(before):
            before(signum, frame)
        else:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)

    try:
        for signum in EXIT_SIGNALS:
            if signal.getsignal(signum) is not signal.SIG_IGN:
                previous[signum] = signal.signal(signum, handler)
    except ValueError:  # not the main thread
        previous.clear()
    try:
        yield
    finally:
        for signum, before in previous.items():
            signal.signal(signum, before)


# -- watching the solver --------------------------------------------------------------------------


@dataclass(frozen=True)
class Status:
    """One iteration as the watcher saw it: the iteration, of ``total``, the initial residuals and
    the propeller's force (N) and moment (N m) about the origin."""

    iteration: int
    total: int
    residuals: dict[str, float]
    force_n: tuple[float, float, float]
    moment_nm: tuple[float, float, float]


ProgressCallback = Callable[[Status], None]


def _status(history: History, total: int) -> Status | None:
    if not len(history.iterations) or not history.residuals:
        return None
    return Status(
        history.last_iteration,
        total,
        history.last_residuals(),
        tuple(history.force_n[-1].tolist()),
        tuple(history.moment_nm[-1].tolist()),
    )


def divergence(history: History) -> str | None:
    """Why the history shows divergence ("iteration N: p residual 3.2e+05"), or None."""
    for name, values in history.residuals.items():
        bad = [
            index
            for index, value in enumerate(values)
            if not math.isfinite(value) or value > SIMULATE_DIVERGENCE_RESIDUAL
        ]
        if bad:
            return (
                f"iteration {int(history.residual_iterations[bad[0]])}: "
                f"{name} residual {values[bad[0]]:.3g} "
                f"(limit {SIMULATE_DIVERGENCE_RESIDUAL:g})"
            )
    for label, values in (("force", history.force_n), ("moment", history.moment_nm)):
        finite = [bool(row.all()) for row in (abs(values) < 1e30)]
        if not all(finite):
            return (
                f"iteration {int(history.iterations[finite.index(False)])}: "
                f"the propeller's {label} is not finite"
            )
    return None


class Watcher:
    """Reads the histories while the solver runs; reports progress; stops the solver on divergence
    or over its time budget (``deadline``, time.monotonic())."""

    def __init__(
        self, case: Path, total: int, deadline: float, progress: ProgressCallback | None
    ) -> None:
        self.case, self.total, self.deadline, self.progress = case, total, deadline, progress
        self.failure: SolverError | None = None
        self._reported = 0

    def check(self, timed: bool = True) -> None:
        history = read_history(self.case)
        status = _status(history, self.total)
        if status is not None and status.iteration > self._reported and self.progress is not None:
            self._reported = status.iteration
            self.progress(status)
        reason = divergence(history)
        if reason is not None:
            self.failure = DivergedError(f"simpleFoam diverged at {reason}")
        elif timed and time.monotonic() > self.deadline:
            self.failure = TimeBudgetError(
                f"simpleFoam ran over its time budget at iteration "
                f"{history.last_iteration} of {self.total}"
            )

    async def watch(self) -> None:
        while self.failure is None:
            await asyncio.sleep(POLL_SECONDS)
            self.check()
        await asyncio.to_thread(stop_processes, self.case)


def _log_cause(case: Path, program: str) -> str:
    """The FATAL ERROR's first lines in log.<program>, or "floating point exception" for a crash in
    sigFpe."""
    try:
        lines = (case / f"log.{program}").read_text(errors="replace").splitlines()
    except OSError:
        return "no log"
    for index, line in enumerate(lines):
        if "FOAM FATAL" in line:
            words = [part.strip() for part in lines[index : index + 4] if part.strip()]
            return " ".join(words).replace("--> ", "")[:300]
    if any("sigFpe::sigHandler" in line or "Floating point exception" in line for line in lines):
        return "floating point exception"
    return f"see {case / f'log.{program}'}"


async def run_command(case: AsyncFoamCase, command: Sequence[str], processes: int = 1) -> None:
    """One OpenFOAM program in ``case`` (log.<program>); in parallel through MPI if it is the solver
    and ``processes`` > 1. SolverError names the program and the cause."""
    parallel = processes > 1 and command[0] == "simpleFoam"
    try:
        await case.run(
            list(command), parallel=parallel, cpus=processes if parallel else 1, log=True
        )
    except CalledProcessError:
        raise SolverError(
            f"{command[0]} failed in {case.path}: {_log_cause(case.path, command[0])}"
        ) from None


async def run_solver(
    case: AsyncFoamCase,
    iterations: int,
    processes: int,
    deadline: float,
    progress: ProgressCallback | None = None,
) -> History:
    """simpleFoam (watched, see :class:`Watcher`); the final history. DivergedError naming the
    iteration and residual, TimeBudgetError, SolverError."""
    path = Path(case.path)
    watcher = Watcher(path, iterations, deadline, progress)
    watch = asyncio.ensure_future(watcher.watch())
    try:
        await run_command(case, ["simpleFoam"], processes)
    except asyncio.CancelledError:  # a cancelled task (a sweep stopping) leaves no solver behind
        await asyncio.shield(asyncio.to_thread(stop_processes, path))
        raise
    except SolverError as error:
        if watcher.failure is None:
            watcher.check(timed=False)
        history = read_history(path, balance=True)
        if watcher.failure is not None:
            raise watcher.failure from None
        if "floating point" in str(error):
            raise DivergedError(
                "simpleFoam diverged at iteration "
                f"{_log_iteration(path) or history.last_iteration}: "
                f"floating point exception; last residuals {_residual_text(history)}"
            ) from None
        raise
    finally:
        watch.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await watch
    if watcher.failure is not None:
        raise watcher.failure
    watcher.check(timed=False)
    if watcher.failure is not None:
        raise watcher.failure
    return read_history(path, balance=True)


def _log_iteration(case: Path) -> int | None:
    """The last ``Time = N`` in log.simpleFoam: the iteration the solver was in."""
    try:
        text = (case / "log.simpleFoam").read_text(errors="replace")
    except OSError:
        return None
    times = re.findall(r"^Time = (\d+)\s*$", text, flags=re.MULTILINE)
    return int(times[-1]) if times else None


def _residual_text(history: History) -> str:
    return (
        ", ".join(f"{name} {value:.3g}" for name, value in history.last_residuals().items())
        or "none"
    )
