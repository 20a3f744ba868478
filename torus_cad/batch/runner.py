"""The batch runner: designs on a local process pool or a Dask cluster, one outcome each, whatever
happens.

One loop (:func:`run_tasks`) drives any executor with the ``concurrent.futures`` shape
(``submit`` / futures / ``shutdown``): :class:`LocalPool` on this machine, or
``dask.distributed.Client.get_executor()`` on a cluster. A design never stops the batch:

* the local pool is pebble's ``ProcessPool``: each design has a wall-clock limit (past it the
  worker is killed and replaced, the design is ``timeout``), and a worker that dies (a
  segfault in OpenCascade, the OOM killer) costs only its own design (``crash``);
* workers die with the process that started them, even when it is killed with SIGKILL: the
  kernel's parent-death signal (Linux ``prctl(PR_SET_PDEATHSIG)``) plus a watchdog thread
  that notices, within a second, that the batch's process is gone (reaped or not);
* SIGINT, SIGTERM and SIGHUP, within :func:`interrupts_raised`, stop the batch within
  :data:`_POLL_SECONDS`: the handler only records the signal, and :class:`Interrupted` (naming
  it) is raised at the next safe point (:func:`raise_if_interrupted`, which the loop calls
  between two waits), never inside an import, a storage commit or the pool's start-up; the
  pool's workers are then stopped, and the caller still writes its table.

Workers start from multiprocessing's fork server, which imports the kernel once (cadquery
takes seconds to import), so workers start at once and never fork a process that holds
threads. A script that runs a batch needs an ``if __name__ == "__main__":`` guard, as the
workers re-import it.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, CancelledError, Future, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Protocol

from torus_cad.batch.job import DesignTask, record_result, run_design
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.errors import TorusCadError
from torus_cad.runtime.processes import process_identity

__all__ = [
    "BatchError",
    "Executor",
    "Interrupted",
    "Job",
    "LocalPool",
    "available_cores",
    "capped_workers",
    "default_workers",
    "interrupts_raised",
    "raise_if_interrupted",
    "run_tasks",
]

Job = Callable[[DesignTask], DesignResult]

_POLL_SECONDS = 0.5  #: how often the loop wakes up when nothing finishes
_WATCHDOG_SECONDS = 1.0  #: how often a worker checks that its parent is alive
_PR_SET_PDEATHSIG = 1  #: prctl option (linux/prctl.h)
# : pool breaks in a row, with no design finishing between them, before giving up
_MAX_POOL_RESTARTS = 3
_WORKER_STOP_S = 5.0  #: how long a stopped worker may take to exit before pebble kills it, s


class BatchError(TorusCadError):
    """The batch machinery failed (the pool's workers cannot start, the Dask scheduler is
    unreachable)."""


class Interrupted(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP arrived during a batch; ``signum`` says which (exit code 128 +
    signum)."""

    def __init__(self, signum: int) -> None:
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name

    @property
    def exit_code(self) -> int:
        """The shell's convention: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP."""
        return 128 + self.signum


class Executor(Protocol):
    """What :func:`run_tasks` needs of an executor (concurrent.futures' and Dask's have it)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future[Any]: ...

    def shutdown(self, wait: bool = True) -> None: ...


def available_cores() -> int:
    """The CPU cores this process may run on (torus_cad.runtime.cpus.available_cpus)."""
    from torus_cad.runtime.cpus import available_cpus

    return available_cpus()


def default_workers() -> int:
    """One worker per available core."""
    return available_cores()


def capped_workers(
    requested: int | None,
    tasks: int,
    oversubscribe: bool = False,
    warn: Callable[[str], None] | None = None,
) -> int:
    """Worker processes to start for ``tasks`` designs: ``requested`` (default: one per core), never
    more than the tasks, and never more than the available cores unless ``oversubscribe``.

    ``warn`` gets one line when the request is capped at the cores (a process per design of a large
    sweep would only thrash the machine).
    """
    cores = available_cores()
    count = max(1, min(requested or cores, tasks))
    if count > cores and not oversubscribe:
        if warn is not None:
            warn(
                f"--workers {requested} capped at the "
                f"{cores} core{'s' if cores > 1 else ''} available "
                f"(--oversubscribe to start {count})"
            )
        count = cores
    return count


# -- worker processes
# -------------------------------------------------------------------------------


def _worker_started(batch_pid: int) -> None:
    """Initialiser of every local worker: die with the batch's process; SIGTERM ends the worker at
    once.

    A worker's parent is the fork server, which lives as long as any worker does (each holds
    its lifeline), so two guards: the kernel's parent-death signal for when the fork server
    dies, and a watchdog thread for when the batch's process dies, even by SIGKILL and even
    if nobody reaps it. pebble's workers already ignore SIGINT (Ctrl-C goes to the whole
    terminal's process group; the parent decides). Its graceful SIGTERM handler would wait for
    OpenCascade to return before running, so the default action is restored: a stopped worker
    stops now (an export killed mid-write leaves only a temporary file, never a partial file).
    """
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    with contextlib.suppress(OSError, AttributeError):  # not Linux: the watchdog below still works
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
    threading.Thread(
        target=_watch_parents,
        args=(os.getppid(), batch_pid, process_identity(batch_pid)),
        name="torus-cad parent watchdog",
        daemon=True,
    ).start()


def _watch_parents(worker_parent: int, batch_pid: int, batch_identity: str | None) -> None:
    """SIGKILL this worker once its parent changed or the batch's process is no longer the one it
    was."""
    while True:
        time.sleep(_WATCHDOG_SECONDS)
        if os.getppid() != worker_parent or process_identity(batch_pid) != batch_identity:
            os.kill(os.getpid(), signal.SIGKILL)


class LocalPool:
    """A local process pool with a per-design time limit, behind the shape of a concurrent.futures
    executor.

    Args:
        workers: worker processes.
        time_limit_s: wall-clock limit per design, s (None: none); counted from when a worker starts
            it.
    """

    def __init__(self, workers: int, time_limit_s: float | None = None) -> None:
        import pebble

        self.workers = workers
        self.time_limit_s = time_limit_s
        self._pool: Any = pebble.ProcessPool(
            max_workers=workers,
            initializer=_worker_started,
            initargs=(os.getpid(),),
            context=_worker_context(),
        )

    def submit(self, fn: Callable[..., Any], /, *args: Any) -> Future[Any]:
        """Run ``fn(*args)`` in a worker; its future raises TimeoutError past the limit,
        ProcessExpired on a crash."""
        try:
            return self._pool.schedule(fn, args=args, timeout=self.time_limit_s)
        # pebble: "Unexpected error within the Pool" once it is broken
        except RuntimeError as error:
            raise BrokenProcessPool(str(error)) from error

    def shutdown(self, wait: bool = True) -> None:
        """``wait``: let the queued designs finish; otherwise stop the workers now (their designs
        are lost)."""
        if wait:
            self._pool.close()
        else:
            self._pool.stop()
            self._stop_workers()
        self._pool.join()

    def _stop_workers(self) -> None:
        """Stop the workers before pebble's ``join`` does: it removes the pool's semaphores first,
        and a worker still starting (reading its start-up data from the fork server) then fails to
        open them with a FileNotFoundError traceback. Uses pebble 5's internals (constraints.txt
        pins it); where they differ, pebble's own order is kept."""
        # private: pebble has no public way to stop its workers before join; read as of
        # Pebble==5.2.3 (constraints.txt)
        manager = getattr(getattr(self._pool, "_pool_manager", None), "worker_manager", None)
        workers = getattr(manager, "workers", None)
        loop = getattr(self._pool, "_pool_manager_loop", None)
        if not isinstance(workers, dict) or not isinstance(loop, (threading.Thread, type(None))):
            return
        if loop is not None:
            loop.join()  # a stopped pool's manager loop ends, and starts no worker after that
        processes = list(workers.values())
        for process in processes:
            with contextlib.suppress(Exception):
                process.terminate()
        for process in processes:
            with contextlib.suppress(Exception):
                process.join(_WORKER_STOP_S)


def _worker_context() -> Any:
    """The fork server (kernel imported once, no fork of a threaded process); spawn where there is
    none."""
    if "forkserver" not in multiprocessing.get_all_start_methods():  # pragma: no cover - Windows
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["torus_cad.batch.job", "torus_cad.propeller"])
    return context


# -- signals
# ----------------------------------------------------------------------------------------


class _Latch:
    """The first signal of an :func:`interrupts_raised` block, until :func:`raise_if_interrupted`
    raises it."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self.raised = False


_latches: list[_Latch] = []  #: the open interrupts_raised blocks of the main thread, innermost last


@contextmanager
def interrupts_raised(
    signals: Iterable[int] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP),
) -> Iterator[None]:
    """Within the block, the first SIGINT, SIGTERM or SIGHUP is recorded, and
    :func:`raise_if_interrupted` raises it as :class:`Interrupted` at the caller's next safe point;
    later signals are ignored.

    The handler itself never raises: an exception injected between two arbitrary bytecodes can
    land inside an import (leaving a half-initialised extension module: "initialization
    failed"), inside a storage commit, inside ``Process.start`` of the pool's start-up (a
    worker then reads its start-up data after this process removed its semaphores: a
    forkserver traceback) or inside a finaliser ("Exception ignored"). Blocking calls go on
    after the handler (PEP 475), so the signal takes effect when the running step returns;
    :func:`run_tasks` waits at most :data:`_POLL_SECONDS` at a time. Later signals are ignored
    so that the cleanup the first one starts (stopping the pool, writing the table) is not cut
    short. A signal the caller ignores (``nohup``, a background job's SIGINT) stays ignored.
    Outside the main thread, signals cannot be caught and this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    latch = _Latch()

    def handler(signum: int, frame: Any) -> None:
        if latch.signum is None:
            latch.signum = signum

    previous = {
        signum: signal.signal(signum, handler)
        for signum in signals
        if signal.getsignal(signum) is not signal.SIG_IGN
    }
    _latches.append(latch)
    try:
        yield
    finally:
        _latches.remove(latch)
        for signum, old in previous.items():
            signal.signal(signum, old)
    # it arrived after the block's last safe point
    if latch.signum is not None and not latch.raised:
        latch.raised = True
        raise Interrupted(latch.signum)


def raise_if_interrupted() -> None:
    """Raise :class:`Interrupted` if a signal arrived within the innermost :func:`interrupts_raised`
    block and has not been raised yet (once: the cleanup it starts runs without further
    interrupts)."""
    if not _latches or threading.current_thread() is not threading.main_thread():
        return
    latch = _latches[-1]
    if latch.signum is not None and not latch.raised:
        latch.raised = True
        raise Interrupted(latch.signum)


# -- the loop
# ---------------------------------------------------------------------------------------


def _result_of(future: Future[Any], task: DesignTask, check_visible: bool) -> DesignResult:
    """The design's result, or the outcome the executor's exception stands for (recorded in its
    folder)."""
    error = future.exception()
    if error is not None:
        result = _failure(error, task.design_id)
    else:
        result = future.result()
        if not (
            check_visible
            and result.outcome is Outcome.VALID
            and task.folder is not None
            and not (Path(task.folder) / f"{task.design_id}.json").is_file()
        ):
            return result
        result = DesignResult(
            task.design_id,
            Outcome.ERROR,
            f"the worker wrote {task.folder} but it is not visible "
            "here; the output folder must be on a file "
            "system shared by the workers and this machine",
        )
    return record_result(task, result) if task.folder is not None else result


def _failure(error: BaseException, design_id: str) -> DesignResult:
    """The outcome of a design whose future failed: pebble's time-out or dead worker, Dask's killed
    worker."""
    if isinstance(error, TimeoutError):
        limit = error.args[1] if len(error.args) > 1 else "?"
        return DesignResult(
            design_id,
            Outcome.TIMEOUT,
            f"no result within the time limit ({limit} s); the worker was stopped",
        )
    if type(error).__name__ in ("ProcessExpired", "KilledWorker"):
        code = getattr(error, "exitcode", None)
        return DesignResult(
            design_id,
            Outcome.CRASH,
            "the worker process died while running this design"
            + (f" (exit code {code})" if code is not None else "")
            + " (a crash inside OpenCascade?)",
        )
    # e.g. not sent to a worker
    return DesignResult(design_id, Outcome.ERROR, f"{type(error).__name__}: {error}")


def run_tasks(
    tasks: Iterable[DesignTask],
    on_result: Callable[[DesignTask, DesignResult], None],
    make_executor: Callable[[], Executor],
    window: int | None,
    job: Job | None = None,
    check_visible: bool = False,
) -> None:
    """Run ``tasks`` on executors from ``make_executor``, calling ``on_result`` as each one
    finishes.

    Args:
        tasks: the designs to run; taken from the iterable only when a slot is free, so a
            generator may decide each next task from the results so far (an optimiser does).
        on_result: called in this thread with each task and its result, in finishing order; tasks
            found finished at the same poll in the order they were submitted (an optimiser's pruner
            then judges a trial after the ones asked before it, however busy the machine).
        make_executor: makes the executor (again, when a local pool breaks).
        window: most tasks in flight (None: submit all at once, for Dask's scheduler).
        job: the function a worker runs per task (default :func:`run_design`); any top-level
            function of a :class:`DesignTask` returning a :class:`DesignResult`.
        check_visible: a valid design's report must be visible here (a cluster writing to a disk
            this machine cannot see is an error).

    A time-out, a crash and an exception the job did not catch each become that design's
    outcome. On any exception from here (Interrupted included) the executor is stopped
    without waiting and the exception propagates; the tasks that did not finish get no result.
    Within :func:`interrupts_raised`, a signal is raised as :class:`Interrupted` at the top of
    the loop (the designs already finished have had their ``on_result``) or after a submit.
    """
    job = run_design if job is None else job
    source = iter(tasks)
    queue: deque[DesignTask] = deque()  # taken from the source, not yet running (or to run again)
    in_flight: dict[Future[Any], DesignTask] = {}
    executor = make_executor()
    restarts = 0
    try:
        while in_flight or _refilled(queue, source):
            raise_if_interrupted()
            refused = False  # the executor refused a task: its pool is broken
            while (window is None or len(in_flight) < window) and _refilled(queue, source):
                try:
                    future = executor.submit(job, queue[0])
                except BrokenProcessPool:
                    refused = True
                    break
                in_flight[future] = queue.popleft()
                raise_if_interrupted()
            done, _ = wait(list(in_flight), timeout=_POLL_SECONDS, return_when=FIRST_COMPLETED)
            # A signal to the whole process group (what `timeout` and job schedulers send) ends the
            # workers too: their futures fail with it, and the interruption is this run's, not a
            # crash of those designs.
            raise_if_interrupted()
            broken = [in_flight.pop(future) for future in list(done) if _broke(future)]
            # found done together: as submitted
            for future in [future for future in in_flight if future in done]:
                task = in_flight.pop(future)
                on_result(task, _result_of(future, task, check_visible))
                restarts = 0
            if broken or refused:  # the pool broke (e.g. its workers cannot start): a new one
                restarts += 1
                if restarts > _MAX_POOL_RESTARTS:
                    raise BatchError(
                        "the worker processes cannot start or keep dying before finishing a design "
                        '(a script that runs a batch needs an `if __name__ == "__main__":` guard, '
                        "as the workers re-import it)"
                    )
                queue.extendleft(reversed(broken + list(in_flight.values())))
                in_flight.clear()
                executor.shutdown(wait=False)
                executor = make_executor()
    except BaseException:
        for future in in_flight:
            future.cancel()
        executor.shutdown(wait=False)
        raise
    executor.shutdown(wait=True)
    raise_if_interrupted()


def _refilled(queue: deque[DesignTask], source: Iterator[DesignTask]) -> bool:
    """Whether a task is waiting in ``queue``, taking the next one from ``source`` if it is
    empty."""
    if not queue:
        task = next(source, None)
        if task is not None:
            queue.append(task)
    return bool(queue)


def _broke(future: Future[Any]) -> bool:
    """The future failed because its whole pool broke (not because of its own design)."""
    try:
        return isinstance(future.exception(timeout=0), BrokenProcessPool)
    except CancelledError:
        return True
