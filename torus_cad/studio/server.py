"""Serving the studio: the trame server on a host and port, its start line, and stopping on a signal
with the signal's exit code (the builds and the studio's folder removed on the way out)."""

from __future__ import annotations

import asyncio
import contextlib
import errno
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from torus_cad.errors import OutputError, ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.runtime.interrupts import EXIT_SIGNALS, exit_on_signals
from torus_cad.studio.app import Studio

#: Hosts that only this machine can reach.
LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")


@contextlib.contextmanager
def _trame_ignores_command_line() -> Iterator[None]:
    """trame parses sys.argv (and $TRAME_ARGS) itself on start; the studio passes everything
    explicitly."""
    saved = os.environ.get("TRAME_ARGS")
    os.environ["TRAME_ARGS"] = ""
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop("TRAME_ARGS", None)
        else:
            os.environ["TRAME_ARGS"] = saved


def start_message(host: str, port: int) -> str:
    """What the studio prints on start: where it is and who can reach it."""
    url_host = f"[{host}]" if ":" in host else host
    if host in LOCAL_HOSTS:
        reach = "only this machine can connect (use --host to serve other machines)"
    else:
        reach = (
            f"listening on {host}: other machines that can reach it can use it, without a password"
        )
    return f"torus-cad studio: open http://{url_host}:{port}/ ; {reach}; Ctrl-C stops it"


def check_host(host: str) -> str:
    """``host`` if it names an address to listen on; ParameterError for an empty one (it would bind
    every interface while the start line showed none)."""
    if not host.strip():
        raise ParameterError(
            "--host must name an address to listen on, e.g. 127.0.0.1 (this machine only) or "
            "0.0.0.0 (every network); got an empty one"
        )
    return host.strip()


def serve(
    design: PropellerParameters,
    port: int = 8080,
    host: str = "127.0.0.1",
    files_folder: Path | None = None,
) -> int:
    """Serve the studio for ``design`` until a signal stops it (blocking); the exit code, 128 + the
    signal.

    ``files_folder``: a folder whose files uploaded designs may name (besides the files uploaded
    with them). OutputError if the port is in use, ParameterError for an empty ``host``. SIGINT,
    SIGTERM and SIGHUP stop the server's loop (its handlers, not the server's own, which would end
    with exit 0); the builds and the studio's folder are removed on the way out.
    """
    from trame.app import get_server

    from torus_cad.studio.layout import build_layout

    host = check_host(host)
    server = get_server("torus_cad_studio", client_type="vue3")
    stopped: list[int] = []

    def stop(signum: int) -> None:
        if stopped:  # a second signal while stopping: at once
            os._exit(EXIT_SIGNALS[stopped[0]])
        stopped.append(signum)
        asyncio.get_running_loop().create_task(server.stop())

    def ready(**_: Any) -> None:
        loop = asyncio.get_running_loop()
        for signum in EXIT_SIGNALS:
            loop.add_signal_handler(signum, stop, signum)
        print(start_message(host, server.port), flush=True)

    with tempfile.TemporaryDirectory(prefix="torus-cad-studio-") as workdir:
        studio = Studio(server, design, Path(workdir), files_folder)
        build_layout(studio)
        server.controller.on_server_ready.add(ready)
        try:
            with _trame_ignores_command_line():
                # thread=True: the server installs no signal handlers of its own (see ready()).
                server.start(
                    port=port,
                    host=host,
                    open_browser=False,
                    show_connection_info=False,
                    disable_logging=True,
                    timeout=0,
                    thread=True,
                )
        except OSError as error:
            if error.errno == errno.EADDRINUSE:
                raise OutputError(
                    f"port {port} on {host} is already in use (another studio or server?); "
                    "choose another with --port, or --port 0 for any free one"
                ) from None
            raise
        finally:
            # the loop's handlers are gone: a signal while cleaning up ends with one line
            exit_on_signals()
            studio.shut_down()
    return EXIT_SIGNALS[stopped[0]] if stopped else 0
