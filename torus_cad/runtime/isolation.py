"""Calls that can hang or crash (OpenCascade's), run in a forked child process with a time limit.

A hang or a crash there then costs that one call, never the command: the parent waits in Python
(``select``), so a signal ends it at once (torus_cad.runtime.interrupts), and the child dies with
its parent (Linux ``PR_SET_PDEATHSIG``), so a stopped command leaves no OpenCascade call running
behind it. The child is forked, so it has the shapes in memory already; what it returns is pickled
back (plain data: BRep text, face indices, status names).

Hand-written with ``os.fork``: multiprocessing, and pebble on top of it, refuse to start a child
from a daemonic process, which the sweep's and the optimiser's pool workers are.
"""

from __future__ import annotations

import contextlib
import ctypes
import faulthandler
import importlib
import os
import pickle
import select
import signal
import sys
import time
from collections.abc import Callable
from typing import Any, Generic, TypeVar, cast

from torus_cad.errors import KernelError

T = TypeVar("T")

_PR_SET_PDEATHSIG = 1  # linux/prctl.h
_CHILD_DEFAULT_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

#: Modules to import the next time this process waits for a child (:func:`prefetch_modules`).
_PREFETCH: list[str] = []


def prefetch_modules(*names: str) -> None:
    """Import the modules ``names`` the next time this process waits for a child's result, instead
    of when they are first used: the wait is time this process would otherwise sleep (``torus-cad
    build`` imports the mesh checker while the strict check runs in its child). A module that does
    not import is left for its first use to report."""
    _PREFETCH.extend(names)


def _import_prefetched() -> None:
    while _PREFETCH:
        name = _PREFETCH.pop(0)
        # its first use raises the error that names the missing package
        with contextlib.suppress(ImportError):
            importlib.import_module(name)


class IsolatedTimeout(KernelError):
    """The call did not finish within its time limit; its child was killed."""


class IsolatedCrash(KernelError):
    """The call's child process died (a crash in OpenCascade, or killed from outside)."""


class IsolatedCall(Generic[T]):
    """``function(*args)`` started now in a forked child, its result collected later by
    :meth:`result`, so the parent can work meanwhile (the child has a core of its own). As a context
    manager, the child is killed on leaving if its result was not collected (the parent raised
    meanwhile)."""

    def __init__(self, function: Callable[..., T], *args: Any, what: str) -> None:
        self.what = what
        parent_pid = os.getpid()
        read_end, write_end = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(read_end)
            _run_child(function, args, write_end, parent_pid, what)
        os.close(write_end)
        self._pid: int | None = pid
        self._read_end = read_end

    @property
    def pid(self) -> int | None:
        """The child's process id until its result is collected or it is cancelled."""
        return self._pid

    def result(self, timeout_s: float) -> T:
        """The call's value; IsolatedTimeout after ``timeout_s`` more seconds, IsolatedCrash if the
        child died, and the child's own exception (pickled back) if it raised."""
        pid = self._pid
        if pid is None:
            raise KernelError(f"{self.what}: its result was collected already")
        _import_prefetched()  # the child works meanwhile; its time limit counts from here on
        data = _read_with_limit(self._read_end, pid, timeout_s)
        _, status = os.waitpid(pid, 0)
        self._pid = None
        if data is None:
            raise IsolatedTimeout(f"{self.what} did not finish within {timeout_s:g} s")
        if not data:
            ended = (
                f"signal {os.WTERMSIG(status)}"
                if os.WIFSIGNALED(status)
                else f"exit {os.WEXITSTATUS(status)}"
            )
            raise IsolatedCrash(f"{self.what} crashed (its process ended with {ended})")
        succeeded, value = pickle.loads(data)
        if succeeded:
            return cast(T, value)
        raise value

    def cancel(self) -> None:
        """Kill the child and reap it, unless its result was collected."""
        if self._pid is None:
            return
        os.kill(self._pid, signal.SIGKILL)
        os.waitpid(self._pid, 0)
        os.close(self._read_end)
        self._pid = None

    def __enter__(self) -> IsolatedCall[T]:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.cancel()


def fork_is_safe_for_opencascade() -> bool:
    """Whether a forked child may run OpenCascade's parallel algorithms (a boolean, the mesher):
    only when this process has not loaded OpenCascade, since a forked copy of its running thread
    pool can deadlock (seen in the fuse). The time-limited calls of the kernel run serial ones."""
    return "OCP" not in sys.modules


def run_isolated(function: Callable[..., T], *args: Any, timeout_s: float, what: str) -> T:
    """``function(*args)`` in a forked child; IsolatedTimeout after ``timeout_s`` seconds,
    IsolatedCrash if the child dies, and the child's own exception (pickled back) if it raises."""
    if timeout_s <= 0.0:
        raise IsolatedTimeout(f"{what}: no time left to run it")
    with IsolatedCall(function, *args, what=what) as call:
        return call.result(timeout_s)


def _run_child(
    function: Callable[..., Any], args: tuple[Any, ...], write_end: int, parent_pid: int, what: str
) -> None:
    """The child's side: die with the parent, run, send (succeeded, result or exception), leave at
    once."""
    status = 1
    try:
        # the parent's handlers print the command's one line; not here
        for signum in _CHILD_DEFAULT_SIGNALS:
            signal.signal(signum, signal.SIG_DFL)
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != parent_pid:
            return
        # a crash here is an expected outcome, reported by the parent; no dump
        faulthandler.disable()
        try:
            outcome: tuple[bool, Any] = (True, function(*args))
        except Exception as error:
            outcome = (False, error)
        try:
            data = pickle.dumps(outcome)
        except Exception as error:  # an exception (or a result) that does not pickle
            data = pickle.dumps((False, KernelError(f"{what}: {type(error).__name__}: {error}")))
        with os.fdopen(write_end, "wb") as pipe:
            pipe.write(data)
        status = 0
    finally:
        os._exit(status)


def _read_with_limit(descriptor: int, pid: int, limit_s: float) -> bytes | None:
    """Everything the child writes, or None (the child killed) when it takes longer than
    ``limit_s``."""
    chunks: list[bytes] = []
    deadline = time.monotonic() + limit_s
    with os.fdopen(descriptor, "rb") as pipe:
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([pipe], [], [], remaining)[0]:
                os.kill(pid, signal.SIGKILL)
                return None
            chunk = pipe.read1(1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)
