"""Which process is which: this host's name, whether a pid runs, and what tells a live process from
a successor that was given its pid. Plain ``os`` and psutil; shared by the files written whole
(torus_cad.runtime.files), the batch's worker watchdog and the optimiser's trial owners."""

from __future__ import annotations

import re


def host_tag() -> str:
    """This host's name reduced to ``[A-Za-z0-9_]`` (so ``-`` can separate the fields)."""
    import socket  # here: the command line imports this module before its signal handlers are in

    return re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:40] or "host"


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host (psutil)."""
    import psutil

    return bool(psutil.pid_exists(pid))


def process_identity(pid: int) -> str | None:
    """What tells a live process from a successor with its pid: its start time (psutil).

    None when the process is gone or a zombie (killed, not yet reaped); '' for a process this
    user may not inspect.
    """
    import psutil

    try:
        process = psutil.Process(pid)
        if process.status() == psutil.STATUS_ZOMBIE:
            return None
        return repr(process.create_time())
    except psutil.NoSuchProcess:  # ZombieProcess included
        return None
    except psutil.AccessDenied:
        return ""
