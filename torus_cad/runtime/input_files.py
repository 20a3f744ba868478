"""Files a design names, read as untrusted input: configuration files, sweep files, airfoil
coordinate files.

One reader for all of them (:func:`read_untrusted_bytes`):

* the path is opened non-blocking (``O_NONBLOCK | O_NOCTTY``), so a named pipe with no writer or a
  terminal cannot make the open wait, and then checked with ``fstat`` on the descriptor actually
  opened: only a regular file is read (a folder, a device such as ``/dev/zero``, a named pipe or a
  socket is refused), so a path swapped between a check and the open changes nothing;
* the size is checked after opening, and the read itself stops at the limit plus one byte, so a
  file that grows while it is read (or whose reported size is wrong) is refused, not read whole;
* messages name the file, its role and the reason, never its content.

:class:`TimeBudget` bounds the parsing and the checks that a file's content feeds: a file that
would keep them busy past the limit is refused (:class:`~torus_cad.errors.BudgetError`, exit 2).

Only the standard library and torus_cad's error and tolerance modules are imported: the geometry
layer reads coordinate files through this module.
"""

from __future__ import annotations

import os
import stat
import time
from pathlib import Path

from torus_cad.errors import BudgetError, ParameterError

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISFIFO, "a named pipe"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)

#: Bytes asked of the kernel per read call.
_CHUNK_BYTES = 1 << 16


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "another kind of file")


def _check_regular(path: Path, status: os.stat_result, what: str, max_bytes: int) -> None:
    if not stat.S_ISREG(status.st_mode):
        raise ParameterError(
            f"{what} {str(path)!r} is not a regular file ({_kind(status.st_mode)})"
        )
    if status.st_size > max_bytes:
        raise ParameterError(
            f"{what} {str(path)!r} is {status.st_size:,} bytes, over the limit of "
            f"{max_bytes:,} bytes"
        )


def read_untrusted_bytes(path: str | Path, what: str, max_bytes: int) -> bytes:
    """The bytes of the regular file ``path`` (at most ``max_bytes``), or ParameterError naming it
    and the reason.

    ``what`` names the file's role in messages ("configuration", "airfoil file"). Refused: a path
    that cannot be opened, anything but a regular file, and a file over ``max_bytes`` (by its size
    after opening or by what a capped read returns).
    """
    path = Path(path)
    try:
        descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0))
    except OSError as error:
        raise ParameterError(f"cannot read {what} {str(path)!r}: {error.strerror}") from None
    try:
        _check_regular(path, os.fstat(descriptor), what, max_bytes)  # the file actually opened
        chunks: list[bytes] = []
        size = 0
        while size <= max_bytes:
            chunk = os.read(descriptor, min(_CHUNK_BYTES, max_bytes + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as error:
        raise ParameterError(f"cannot read {what} {str(path)!r}: {error.strerror}") from None
    finally:
        os.close(descriptor)
    if size > max_bytes:  # it grew after the fstat
        raise ParameterError(f"{what} {str(path)!r} is over the limit of {max_bytes:,} bytes")
    return b"".join(chunks)


def decode_text(raw: bytes, source: str, what: str, empty_ok: bool = False) -> str:
    """``raw`` as UTF-8 text (a leading byte order mark dropped), or ParameterError naming
    ``source``.

    Refused: bytes that are not UTF-8, a NUL byte (binary data), and (unless ``empty_ok``) empty
    or whitespace-only text.
    """
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = raw[: error.start].count(b"\n") + 1
        raise ParameterError(f"{what} {source!r} line {line}: not a UTF-8 text file") from None
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise ParameterError(f"{what} {source!r} line {line}: not a text file (binary data)")
    if not empty_ok and not text.strip():
        raise ParameterError(f"{what} {source!r} is empty")
    return text


def read_untrusted_text(path: str | Path, what: str, max_bytes: int) -> str:
    """:func:`read_untrusted_bytes` decoded by :func:`decode_text`."""
    return decode_text(read_untrusted_bytes(path, what, max_bytes), str(path), what)


class TimeBudget:
    """A deadline for the work one input file causes; :meth:`check` refuses the file once it has
    passed.

    ``limit_s`` seconds from construction. The message names the file, the step under way and the
    limit (the estimate is the time spent so far, which already exceeds it).
    """

    def __init__(self, source: str, what: str, limit_s: float) -> None:
        self.source, self.what, self.limit_s = source, what, limit_s
        self._start = time.monotonic()

    def check(self, step: str) -> None:
        """BudgetError if the budget is spent; ``step`` says what was being done."""
        spent = time.monotonic() - self._start
        if spent > self.limit_s:
            raise BudgetError(
                f"{self.what} {self.source!r}: {step} took {spent:.1f} s, over the limit of "
                f"{self.limit_s:g} s"
            )


def is_number_text(text: str) -> bool:
    """Whether ``text`` reads as a float (a header word or a time folder's name does not)."""
    try:
        float(text)
    except ValueError:
        return False
    return True
