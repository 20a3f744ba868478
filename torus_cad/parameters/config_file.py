"""Reading a configuration file safely: only a regular file, only up to a size limit, UTF-8 (BOM allowed).

``/dev/zero``, a named pipe, a socket or a folder given as a design file is refused at once
(checked with ``os.stat`` before opening, opened non-blocking), so the command can neither read
gigabytes nor wait forever.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from torus_cad.errors import ParameterError
from torus_cad.tolerances import CONFIG_FILE_MAX_BYTES

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "another kind of file")


def _check_regular(path: Path, status: os.stat_result, what: str, max_bytes: int) -> None:
    if not stat.S_ISREG(status.st_mode):
        raise ParameterError(f"{what} {str(path)!r} is not a regular file ({_kind(status.st_mode)})")
    if status.st_size > max_bytes:
        raise ParameterError(f"{what} {str(path)!r} is {status.st_size:,} bytes, over the limit of "
                             f"{max_bytes:,} bytes for a {what}")


def read_config_text(path: str | Path, what: str = "configuration", max_bytes: int = CONFIG_FILE_MAX_BYTES) -> str:
    """The text of the configuration file ``path``, or ParameterError (exit 2) naming it and the reason.

    Refused: anything but a regular file (folder, device, named pipe, socket), a file over
    ``max_bytes``, text that is not UTF-8, and an empty (or whitespace-only) file. A UTF-8 byte
    order mark, as some Windows editors write, is accepted and dropped. ``what`` names the file's
    role in messages ("configuration", "sweep file").
    """
    path = Path(path)
    try:
        _check_regular(path, os.stat(path), what, max_bytes)
        # O_NONBLOCK: if the path was swapped for a pipe since the stat, open does not wait for a writer.
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as error:
        raise ParameterError(f"cannot read {what} {str(path)!r}: {error.strerror}") from None
    try:
        _check_regular(path, os.fstat(descriptor), what, max_bytes)  # the file actually opened
        with os.fdopen(descriptor, "rb", closefd=False) as handle:
            raw = handle.read(max_bytes + 1)
    except OSError as error:
        raise ParameterError(f"cannot read {what} {str(path)!r}: {error.strerror}") from None
    finally:
        os.close(descriptor)
    if len(raw) > max_bytes:  # it grew after the stat
        raise ParameterError(f"{what} {str(path)!r} is over the limit of {max_bytes:,} bytes for a {what}")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ParameterError(f"{what} {str(path)!r} is not a UTF-8 text file") from None
    if not text.strip():
        raise ParameterError(f"{what} {str(path)!r} is empty")
    return text
