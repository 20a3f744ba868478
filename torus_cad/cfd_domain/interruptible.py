"""Run the long CFD work in a thread, so that a signal ends ``torus-cad cfd`` at once.

Python runs signal handlers in the main thread, between bytecodes: during one long gmsh call
(a volume mesh takes minutes) a SIGTERM would wait for the call to return. gmsh's Python API
calls its library through ctypes, which releases the GIL, so with the work in a worker thread
the main thread, waiting on it, runs torus_cad.runtime.interrupts' handler at once: it removes the
staged files and ends the process (``os._exit``, which ends the worker too).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")

#: How often the waiting main thread wakes up (s); a signal wakes it at once anyway.
_POLL_S = 0.5


def run_in_worker(work: Callable[[], T], on_wait: Callable[[], None] | None = None) -> T:
    """``work()``'s result, computed in a worker thread while this thread waits (calling
    ``on_wait``, if given, every :data:`_POLL_S` seconds: a progress heartbeat); its exception
    re-raised here."""
    outcome: dict[str, Any] = {}

    def target() -> None:
        try:
            outcome["value"] = work()
        except BaseException as error:  # handed to the caller's thread, re-raised there
            outcome["error"] = error

    thread = threading.Thread(target=target, name="torus-cad-cfd", daemon=True)
    thread.start()
    while thread.is_alive():
        thread.join(_POLL_S)
        if on_wait is not None and thread.is_alive():
            on_wait()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]
