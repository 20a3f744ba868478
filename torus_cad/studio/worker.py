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

Only the parent side (:class:`BuildRunner`) runs in the server process; it imports no kernel.
"""

from __future__ import annotations

import asyncio
import multiprocessing
import multiprocessing.connection
import multiprocessing.forkserver
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from torus_cad.studio.scene import PartMesh


@dataclass(frozen=True)
class BuildRequest:
    """One exact build: the design (``PropellerParameters.to_dict()``) and where its files go."""

    build_id: int
    design: dict[str, Any]
    out_dir: Path


@dataclass(frozen=True)
class SolidResult:
    """What the view and the readouts need from an exact build.

    Attributes:
        parts: one mesh per part (the hub first, then blade 0, 1, ...).
        stage_seconds: seconds per pipeline stage, plus ``display_mesh`` (the tessellation above).
        fuse_route: how the blades were joined (a torus_cad.kernel.fuse.FuseRoute value).

    The solid is valid: a build that is not one valid, closed solid fails instead.
    """

    parts: list[PartMesh]
    stage_seconds: dict[str, float]
    fuse_route: str


# -- parent side -----------------------------------------------------------------------------------

class BuildRunner:
    """Runs at most one build process at a time; a new request kills the one running.

    ``on_message(kind, build_id, payload)`` is called on the event loop for every message, and
    with ``("failed", build_id, reason)`` if the process dies without finishing.
    """

    def __init__(self, on_message: Callable[[str, int, Any], None]) -> None:
        self._on_message = on_message
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload(["torus_cad.studio.exact"])
        # Start the forkserver now: it imports the kernel (seconds) while the page loads.
        multiprocessing.forkserver.ensure_running()
        self._process: multiprocessing.process.BaseProcess | None = None
        self._connection: multiprocessing.connection.Connection | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._build_id = -1
        self._finished = True

    def submit(self, request: BuildRequest) -> None:
        """Start ``request``, killing any build still running (it is superseded)."""
        self.cancel()
        request.out_dir.mkdir(parents=True, exist_ok=True)
        receiver, sender = self._context.Pipe(duplex=False)
        process = self._context.Process(target=_child_main, args=(request, sender), daemon=True,
                                        name=f"torus-cad-studio-build-{request.build_id}")
        process.start()
        sender.close()  # the child holds the only writer: its death ends our reads with EOF
        self._process, self._connection = process, receiver
        self._build_id, self._finished = request.build_id, False
        self._loop = asyncio.get_running_loop()
        self._loop.add_reader(receiver.fileno(), self._readable)

    def cancel(self) -> None:
        """Kill the running build, if any; its messages are dropped."""
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
        connection, build_id = self._connection, self._build_id
        if connection is None:
            return
        try:
            while connection.poll():
                kind, message_id, payload = connection.recv()
                self._on_message(kind, message_id, payload)
                if kind in ("files", "refused", "failed"):
                    self._finished = True
        except (EOFError, OSError):
            if not self._finished:
                code = self._process.exitcode if self._process is not None else None
                self._finished = True
                self._on_message("failed", build_id, f"the build process stopped unexpectedly (exit code {code})")
            if self._connection is connection:
                self.cancel()


def _child_main(request: BuildRequest, connection: multiprocessing.connection.Connection) -> None:
    from torus_cad.studio.exact import run_build  # preloaded by the forkserver

    run_build(request, connection)
