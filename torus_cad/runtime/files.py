"""Files written whole, and who owns a file in flight. Plain ``os``: no CAD kernel is loaded here.

* :func:`atomic_path`: a writer writes a hidden temp file beside the path, which is renamed onto
  the path when it is complete; a failure removes it, so no partial file ever has the final name.
* Temp files and staging folders carry ``<host>-<pid>`` in their names (:func:`owner_tag`): one
  left by a process that was killed can be removed by the next writer on that host
  (:func:`left_by_dead_process`), while files of live processes, or of other hosts sharing the
  folder, are never touched, so concurrent writers of one name cannot delete each other's files.
* :func:`file_ends_with` tells a file written whole from one whose writer lost its tail without
  saying so; :func:`write_failure` says why a writer that reports only that it failed (OpenCascade,
  gmsh) could not write (a full disk, the file size limit).
* :func:`removed_on_exit` lists the paths a signal handler must remove before the process ends
  (torus_cad.runtime.interrupts reads :data:`IN_FLIGHT`); :func:`removed_if_left_empty` the output
  folders a command made, removed on a signal or an error if still empty (:data:`MADE_FOLDERS`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
from collections.abc import Iterator
from itertools import count
from pathlib import Path

from torus_cad.runtime.processes import host_tag, process_alive

#: A writer that fails while its file system has less free space than this (bytes) failed for
#: lack of space: OpenCascade's writers report only that they could not write.
DISK_FULL_FREE_BYTES = 1 << 20


#: Files and folders being written now, by a registration number: what a signal handler removes.
IN_FLIGHT: dict[int, Path] = {}
_registrations = count(1)
_OWNER = re.compile(r"(?P<host>[A-Za-z0-9_]+)-(?P<pid>\d+)-")


def owner_tag() -> str:
    """``<host>-<pid>-``: goes right after a temp name's fixed prefix."""
    return f"{host_tag()}-{os.getpid()}-"


def left_by_dead_process(name: str, prefix: str) -> bool:
    """Whether the file ``name`` (``prefix`` + owner tag + ...) belongs to a process of this host
    that is gone."""
    if not name.startswith(prefix):
        return False
    owner = _OWNER.match(name, len(prefix))
    if owner is None:
        return False
    return owner["host"] == host_tag() and not process_alive(int(owner["pid"]))


def glob_escape(name: str) -> str:
    """``name`` with glob wildcards escaped."""
    return re.sub(r"([*?\[])", r"[\1]", name)


@contextlib.contextmanager
def removed_on_exit(path: str | Path) -> Iterator[Path]:
    """Within the block, ``path`` (a file or a folder) is listed in :data:`IN_FLIGHT`."""
    key = next(_registrations)
    IN_FLIGHT[key] = Path(path)
    try:
        yield Path(path)
    finally:
        IN_FLIGHT.pop(key, None)


#: Folders this process made for output (outermost first), by a registration number: a signal
#: handler removes those still empty, so an interrupted command leaves no empty --out folder behind.
MADE_FOLDERS: dict[int, tuple[Path, ...]] = {}


def make_folders(path: str | Path) -> tuple[Path, ...]:
    """Make ``path`` and any missing parents; return the folders made here, outermost first."""
    path = Path(path)
    missing = [folder for folder in (path, *path.parents) if not folder.exists()][::-1]
    path.mkdir(parents=True, exist_ok=True)
    return tuple(missing)


def remove_if_empty(folders: tuple[Path, ...]) -> None:
    """Remove each of ``folders`` (outermost first, as :func:`make_folders` returns them) that is
    empty, innermost first; a folder something was put into stays."""
    for folder in reversed(folders):
        with contextlib.suppress(OSError):
            os.rmdir(folder)


@contextlib.contextmanager
def removed_if_left_empty(folders: tuple[Path, ...]) -> Iterator[None]:
    """Within the block, ``folders`` are listed in :data:`MADE_FOLDERS` (removed by a signal handler
    if empty); leaving the block removes those still empty (an error: nothing was published)."""
    key = next(_registrations)
    MADE_FOLDERS[key] = folders
    try:
        yield
    finally:
        MADE_FOLDERS.pop(key, None)
        remove_if_empty(folders)


def _remove_stale_temps(path: Path) -> None:
    """Remove temp files of ``path`` left by dead processes of this host (killed mid-write)."""
    prefix = f".{path.name}.tmp-"
    for stale in path.parent.glob(f"{glob_escape(prefix)}*"):
        if left_by_dead_process(stale.name, prefix):
            stale.unlink(missing_ok=True)


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temp path beside ``path``; on success rename it onto ``path``, on failure delete
    it."""
    import tempfile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_temps(path)
    handle, temp_name = tempfile.mkstemp(prefix=f".{path.name}.tmp-{owner_tag()}", dir=path.parent)
    os.close(handle)
    temp = Path(temp_name)
    with removed_on_exit(temp):
        try:
            yield temp
            # mkstemp makes 0600; give the file normal permissions
            os.chmod(temp, 0o666 & ~_current_umask())
            os.replace(temp, path)
        finally:
            temp.unlink(missing_ok=True)


def file_ends_with(path: Path, marker: bytes, tail: int = 256) -> bool:
    """Whether ``path``'s last ``tail`` bytes hold ``marker`` (a format's end line: a writer can
    lose its tail without saying so); False if it cannot be read."""
    try:
        with open(path, "rb") as handle:
            handle.seek(max(0, path.stat().st_size - tail))
            return marker in handle.read()
    except OSError:
        return False


def write_failure(
    path: Path, written: Path | None = None, otherwise: Exception | None = None
) -> Exception:
    """Why a writer that reports only that it failed (OpenCascade, gmsh) could not write ``written``
    (the temp file published as ``path``; default ``path`` itself).

    Looked at while the partial file is still there: a full file system (less than
    DISK_FULL_FREE_BYTES free) or the process's file size limit (``ulimit -f``) is an OSError naming
    ``path``; anything else is ``otherwise`` (default: an input/output OSError naming ``path``).
    """
    written = path if written is None else written
    code = errno.EIO
    with contextlib.suppress(OSError):
        if shutil.disk_usage(written.parent).free < DISK_FULL_FREE_BYTES:
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    with contextlib.suppress(OSError, ValueError, ImportError):
        import resource

        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY and written.stat().st_size >= limit:
            return OSError(errno.EFBIG, os.strerror(errno.EFBIG), str(path))
    return otherwise if otherwise is not None else OSError(code, os.strerror(code), str(path))
