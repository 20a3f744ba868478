"""OpenCascade calls that can hang or crash, run in a forked child process with a time limit (pebble).

A hang or a crash there then costs that one call, never the command: the parent waits in Python,
so a signal ends it at once (torus_cad.interrupts), and the child dies with its parent (Linux
``PR_SET_PDEATHSIG``), so a stopped command leaves no OpenCascade call running behind it. The child
is forked, so it has the shapes in memory already; what it returns is pickled back (plain data:
BRep text, face indices, status names).
"""

from __future__ import annotations

import ctypes
import faulthandler
import multiprocessing
import os
import signal
from collections.abc import Callable
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any, TypeVar

from pebble import ProcessExpired, concurrent

from torus_cad.errors import KernelError

T = TypeVar("T")

_FORK = multiprocessing.get_context("fork")
_PR_SET_PDEATHSIG = 1  # linux/prctl.h


class IsolatedTimeout(KernelError):
    """The call did not finish within its time limit; its child was killed."""


class IsolatedCrash(KernelError):
    """The call's child process died (a crash in OpenCascade, or killed from outside)."""


def _die_with(parent_pid: int) -> None:
    """In the child: have the kernel send SIGKILL when the parent exits (or exit now if it already has)."""
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent_pid:
        os._exit(1)


def run_isolated(function: Callable[..., T], *args: Any, timeout_s: float, what: str) -> T:
    """``function(*args)`` in a forked child; IsolatedTimeout after ``timeout_s`` seconds, IsolatedCrash
    if the child dies, and the child's own exception (pickled back) if it raises."""
    if timeout_s <= 0.0:
        raise IsolatedTimeout(f"{what}: no time left to run it")
    parent_pid = os.getpid()

    def child(*child_args: Any) -> T:
        _die_with(parent_pid)
        faulthandler.disable()  # a crash here is an expected outcome, reported by the parent; no dump
        return function(*child_args)

    future = concurrent.process(timeout=timeout_s, mp_context=_FORK, daemon=True)(child)(*args)
    try:
        return future.result()
    except FutureTimeout:
        raise IsolatedTimeout(f"{what} did not finish within {timeout_s:g} s") from None
    except ProcessExpired as error:
        raise IsolatedCrash(f"{what} crashed (its process ended with {error.exitcode})") from None
