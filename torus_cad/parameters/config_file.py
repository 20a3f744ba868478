"""Reading a configuration file's text safely: regular files only, bounded size, UTF-8 (a BOM is fine)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from torus_cad.errors import ParameterError
from torus_cad.tolerances import CONFIG_FILE_MAX_BYTES


def read_config_text(path: str | Path) -> str:
    """The text of the configuration file at ``path``.

    Refuses (ParameterError, one line) anything but a regular file of at most
    CONFIG_FILE_MAX_BYTES, before reading it, so ``/dev/zero`` or a named pipe never blocks or
    fills memory; a UTF-8 byte-order mark (as Windows editors write) is dropped.
    """
    name = str(path)
    try:
        status = os.stat(path)
    except OSError as error:
        raise ParameterError(f"cannot read configuration {name!r}: {error.strerror}") from None
    if not stat.S_ISREG(status.st_mode):
        raise ParameterError(f"configuration {name!r} is not a regular file")
    if status.st_size > CONFIG_FILE_MAX_BYTES:
        raise ParameterError(f"configuration {name!r} is {status.st_size} bytes; the limit is "
                             f"{CONFIG_FILE_MAX_BYTES} bytes")
    try:
        with open(path, "rb") as stream:
            raw = stream.read(CONFIG_FILE_MAX_BYTES + 1)
    except OSError as error:
        raise ParameterError(f"cannot read configuration {name!r}: {error.strerror}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ParameterError(f"configuration {name!r} is not a UTF-8 text file") from None
    if not text.strip():
        raise ParameterError(f"configuration {name!r} is empty")
    return text
