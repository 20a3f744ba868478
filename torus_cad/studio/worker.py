"""The studio's exact builds, each in its own process, so the page never waits on OpenCascade.

A build runs :func:`torus_cad.propeller.build_propeller` in a process forked from a
forkserver that has already imported cadquery (a new build starts in ~10 ms, not the ~3 s
of a fresh interpreter). A newer change kills the older build's process: a superseded build
never finishes, a slow one never queues the next, and an OpenCascade crash takes down only
that process. Results come back over a pipe as messages, in this order::

    ("solid", build_id, SolidResult)        the fused solid's tessellation, per part
    ("properties", build_id, dict)          MassProperties.to_dict() at 1 g/cm^3, tip_diameter_mm
    ("files", build_id, {"step": Path, "stl": Path})
    ("refused", build_id, "one-line reason")    ParameterError / GeometryError
    ("failed", build_id, "one-line reason")     KernelError or anything unexpected

Each build is bounded: its process may use at most :data:`BUILD_MEMORY_LIMIT_BYTES` of data
memory (``RLIMIT_DATA``, set in the child before it builds: an allocation beyond it fails in
the child, never in the server) and is killed after :data:`BUILD_TIME_LIMIT_S` seconds
(a "failed" message says so). Whatever a design asks for, the server only waits on a pipe.

The machinery (one process per request, the newest killing the older, a time and memory limit) is
:class:`ProcessRunner`'s; the studio's vortex solves (torus_cad.studio.performance_card) run through
it too. Only the parent side (:class:`ProcessRunner`, :class:`BuildRunner`) runs in the server
process; it imports no kernel.
"""

from __future__ import annotations

import asyncio
import multiprocessing
import multiprocessing.connection
import multiprocessing.forkserver
from collections.abc import Callable
from typing import Any

from torus_cad.studio.messages import BuildRequest

#: Seconds an exact build may run in the studio before its process is killed (the default design
#: takes about 2 s here; the largest resolutions a design may ask for take minutes).
BUILD_TIME_LIMIT_S = 120.0

#: Data memory (heap and anonymous mappings, bytes) a build process may use: RLIMIT_DATA.
BUILD_MEMORY_LIMIT_BYTES = 3 << 30


# -- parent side -----------------------------------------------------------------------------------


class ProcessRunner:
    """Runs at most one request at a time, each in its own process; a new request kills the one
    running.

    ``on_message(kind, request_id, payload)`` is called on the event loop for every message the
    child sends, and with ``("failed", request_id, reason)`` if the process dies without finishing
    (a message of one of ``final_kinds``) or outlives ``time_limit_s`` seconds
    (``time_out_reason(time_limit_s)`` says so). ``target(request, connection, memory_limit_bytes)``
    runs in the child: a module-level function that imports what it needs (the server side imports
    no kernel and no solver).
    """

    def __init__(
        self,
        on_message: Callable[[str, int, Any], None],
        target: Callable[..., None],
        final_kinds: tuple[str, ...],
        time_out_reason: Callable[[float], str],
        name: str,
        time_limit_s: float,
        memory_limit_bytes: int,
    ) -> None:
        self._on_message, self._target, self._final_kinds = on_message, target, final_kinds
        self._time_out_reason, self._name = time_out_reason, name
        self.time_limit_s, self.memory_limit_bytes = time_limit_s, memory_limit_bytes
        self._timer: asyncio.TimerHandle | None = None
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(["torus_cad.studio.exact"])
        # Start the forkserver now: it imports the kernel (seconds) while the page loads.
        multiprocessing.forkserver.ensure_running()
        self._process: multiprocessing.process.BaseProcess | None = None
        self._connection: multiprocessing.connection.Connection | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._request_id = -1
        self._finished = True

    def start(self, request_id: int, request: Any) -> None:
        """Run ``request`` in a new process, killing any still running (it is superseded)."""
        self.cancel()
        receiver, sender = self._context.Pipe(duplex=False)
        process = self._context.Process(
            target=self._target,
            args=(request, sender, self.memory_limit_bytes),
            daemon=True,
            name=f"torus-cad-studio-{self._name.replace(' ', '-')}-{request_id}",
        )
        process.start()
        sender.close()  # the child holds the only writer: its death ends our reads with EOF
        self._process, self._connection = process, receiver
        self._request_id, self._finished = request_id, False
        self._loop = asyncio.get_running_loop()
        self._loop.add_reader(receiver.fileno(), self._readable)
        self._timer = self._loop.call_later(self.time_limit_s, self._time_out, request_id)

    @property
    def running(self) -> bool:
        """A request's process is running and has not finished."""
        return not self._finished

    def _time_out(self, request_id: int) -> None:
        if request_id != self._request_id or self._finished:
            return
        self.cancel()
        self._on_message("failed", request_id, self._time_out_reason(self.time_limit_s))

    def cancel(self) -> None:
        """Kill the running process, if any; its messages are dropped."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._connection is not None:
            if self._loop is not None and not self._loop.is_closed():
                self._loop.remove_reader(self._connection.fileno())
            self._connection.close()
            self._connection = None
        if self._process is not None:
            if self._process.is_alive():
                self._process.kill()
            self._process.join(timeout=0)
            self._process = None
        self._finished = True

    def _readable(self) -> None:
        connection, request_id = self._connection, self._request_id
        if connection is None:
            return
        try:
            while connection.poll():
                kind, message_id, payload = connection.recv()
                if kind in self._final_kinds:
                    self._finished = True
                self._on_message(kind, message_id, payload)
                if self._connection is not connection:
                    return  # the handler cancelled this request or started another
        except (EOFError, OSError):
            if self._connection is not connection:
                return
            if not self._finished:
                code = self._process.exitcode if self._process is not None else None
                self._finished = True
                self._on_message(
                    "failed",
                    request_id,
                    f"the {self._name} process stopped unexpectedly (exit code {code})",
                )
            if self._connection is connection:
                self.cancel()


class BuildRunner(ProcessRunner):
    """The exact builds (module doc): ``submit`` a :class:`BuildRequest`; its messages in the module
    doc's order."""

    def __init__(
        self,
        on_message: Callable[[str, int, Any], None],
        time_limit_s: float = BUILD_TIME_LIMIT_S,
        memory_limit_bytes: int = BUILD_MEMORY_LIMIT_BYTES,
    ) -> None:
        super().__init__(
            on_message,
            _child_main,
            ("files", "refused", "failed"),
            _build_time_out,
            "build",
            time_limit_s,
            memory_limit_bytes,
        )

    def submit(self, request: BuildRequest) -> None:
        """Start ``request``, killing any build still running (it is superseded)."""
        self.cancel()
        request.out_dir.mkdir(parents=True, exist_ok=True)
        self.start(request.build_id, request)


def time_out_reason(what: str, advice: str) -> Callable[[float], str]:
    """The page's line for ``what`` ("the exact build") stopped at its time limit (s), with
    ``advice``."""
    return lambda limit_s: (
        f"{what} took longer than {limit_s:g} s, the limit in the studio, and was stopped; {advice}"
    )


_build_time_out = time_out_reason(
    "the exact build",
    "lower resolution.sections / resolution.points or build it with torus-cad build",
)


def _child_main(
    request: BuildRequest,
    connection: multiprocessing.connection.Connection,
    memory_limit_bytes: int,
) -> None:
    from torus_cad.studio.exact import run_build  # preloaded by the forkserver

    run_bounded(run_build, request, connection, memory_limit_bytes)


def run_bounded(
    run: Callable[[Any, multiprocessing.connection.Connection, int], None],
    request: Any,
    connection: multiprocessing.connection.Connection,
    memory_limit_bytes: int,
) -> None:
    """``run(request, connection, memory_limit_bytes)`` in this child process, its data memory
    bounded to ``memory_limit_bytes`` (bytes) first."""
    import resource

    resource.setrlimit(resource.RLIMIT_DATA, (memory_limit_bytes, memory_limit_bytes))
    run(request, connection, memory_limit_bytes)
