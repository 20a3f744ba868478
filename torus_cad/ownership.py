"""Which process a temp file or staging folder belongs to: their names carry ``<host>-<pid>``.

A file whose process is gone (killed mid-write) can be removed by anyone on the same host; a
file of a live process, or of another host sharing the folder, is never touched.
"""

from __future__ import annotations

import os
import re
import socket

_OWNER = re.compile(r"(?P<host>[A-Za-z0-9_]+)-(?P<pid>\d+)-")


def host_tag() -> str:
    """This host's name reduced to ``[A-Za-z0-9_]`` (so ``-`` can separate the fields)."""
    return re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:40] or "host"


def owner_tag() -> str:
    """``<host>-<pid>-``: put right after a temp name's fixed prefix."""
    return f"{host_tag()}-{os.getpid()}-"


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # alive, another user's
    return True


def left_by_dead_process(name: str, prefix: str) -> bool:
    """Whether the file ``name`` = ``prefix`` + owner tag + ... belongs to a process of this host that is gone."""
    if not name.startswith(prefix):
        return False
    owner = _OWNER.match(name, len(prefix))
    return bool(owner) and owner["host"] == host_tag() and not process_alive(int(owner["pid"]))


def glob_escape(name: str) -> str:
    """``name`` with glob wildcards escaped."""
    return re.sub(r"([*?\[])", r"[\1]", name)
