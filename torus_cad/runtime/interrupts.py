"""Signals: SIGINT, SIGTERM and SIGHUP end a command at any moment with one line and exit 128 +
signal.

The command line installs :func:`exit_on_signals` before it imports anything heavy, so a Ctrl-C
while CadQuery is still loading is as clean as one during the build. The handler does not raise
into whatever code was running (an exception inside a half-finished import can leave a
half-initialised extension module behind, which crashed at exit): it removes the files staged for
publishing (torus_cad.runtime.files.removed_on_exit), prints one line and leaves with ``os._exit``.

Before the handlers are in, while Python itself starts (its ``site`` import, the first few
milliseconds), a SIGINT is Python's: it can end the process with "Fatal Python error" and exit 1.
A caller that needs a clean end at every moment starts the command with the signals blocked
(``env --block-signal=INT,TERM,HUP torus-cad ...``): :func:`exit_on_signals` unblocks them once its
handlers are installed, so one that arrived during the start is handled then, with one line.

A signal that arrives while an output set is being published (:func:`deferred`) waits until the
set is complete. Python runs signal handlers between bytecodes, so a signal during one long
OpenCascade call takes effect when that call returns (the budgets checked before the work starts,
such as torus_cad.design.stl_budget, keep such calls short).
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from types import FrameType
from typing import Any

from torus_cad.runtime.files import IN_FLIGHT, MADE_FOLDERS, remove_if_empty

_Handler = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None

#: The signals that end a command, and their exit codes (128 + the signal number, as shells report).
EXIT_SIGNALS: dict[int, int] = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGHUP: 129}

_deferred_depth = 0
_pending: list[int] = []
_program = "torus-cad"


def _remove(path: Path) -> None:
    import shutil  # here: this module loads before anything else on the command line

    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path, ignore_errors=True)
        else:
            path.unlink(missing_ok=True)
    except OSError:
        pass  # best effort: a stale staging folder is also removed by the next build


def _exit_now(signum: int) -> None:
    for path in list(IN_FLIGHT.values()):
        _remove(path)
    for folders in list(MADE_FOLDERS.values()):  # an --out folder this command made and left empty
        remove_if_empty(folders)
    name = signal.Signals(signum).name
    try:
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        sys.stderr.write(
            f"{_program}: interrupted by {name}; staged files removed, "
            f"published output sets are complete\n"
        )
        sys.stderr.flush()
    except (OSError, ValueError):
        pass  # a closed or broken stderr must not stop the exit
    os._exit(EXIT_SIGNALS.get(signum, 128 + signum))


def _handler(signum: int, frame: FrameType | None) -> None:
    if _deferred_depth:
        _pending.append(signum)
        return
    _exit_now(signum)


def exit_on_signals(program: str = "torus-cad") -> Callable[[], None]:
    """Make SIGINT, SIGTERM and SIGHUP end the process cleanly (see the module doc); return a
    function that restores the previous handlers. Does nothing outside the main thread.

    The signals it handles are then unblocked: one that arrived while they were blocked (a caller
    that blocks them over the interpreter's start-up) takes effect now, through the handler."""
    global _program
    _program = program
    previous: dict[int, _Handler] = {}
    try:
        for signum in EXIT_SIGNALS:
            # ignored by the caller (nohup, `cmd &`): keep it so
            if signal.getsignal(signum) is not signal.SIG_IGN:
                previous[signum] = signal.signal(signum, _handler)
    except ValueError:  # not the main thread: signals are not ours to handle
        pass
    with suppress(AttributeError, OSError, ValueError):  # no pthread_sigmask (not POSIX)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, list(previous))

    def restore() -> None:
        for signum, handler in previous.items():
            signal.signal(signum, handler)

    return restore


def hold_signals_until_exit() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP for the rest of the process: call it when the command's
    work is done and its exit code decided.

    Python puts the default handlers back while it shuts down (which takes a moment once CadQuery is
    loaded), so a signal then would end a finished, successful command as "killed by SIGTERM".
    Python leaves an ignored signal ignored. Ignoring, unlike blocking, is process-wide:
    OpenCascade's worker threads would still take a signal that only the main thread blocks."""
    with suppress(ValueError, OSError):  # not the main thread
        for signum in EXIT_SIGNALS:
            signal.signal(signum, signal.SIG_IGN)


@contextmanager
def deferred() -> Iterator[None]:
    """Signals that arrive within the block take effect when it ends (used while publishing a
    set)."""
    global _deferred_depth
    _deferred_depth += 1
    try:
        yield
    finally:
        _deferred_depth -= 1
        if not _deferred_depth and _pending:
            _exit_now(_pending[0])
