"""The package's exceptions: one base, one subclass per kind of failure.

The CLI maps :class:`ParameterError` (with :class:`BudgetError`) and :class:`GeometryError` to
exit code 2 (bad input), :class:`MissingExtraError` to exit code 2 as well (nothing was tried),
every other :class:`TorusCadError` to exit code 1 (the kernel or the file system failed;
:class:`IncompleteOutputError` is ``torus-cad verify`` finding a broken set).

Messages stay short whatever the input: :func:`shown` quotes a value cut to
:data:`~torus_cad.tolerances.MESSAGE_VALUE_MAX_CHARS` characters, and every error's message passes
through :func:`bounded_message` (any word over :data:`~torus_cad.tolerances.MESSAGE_WORD_MAX_CHARS`
characters, the whole over :data:`~torus_cad.tolerances.MESSAGE_MAX_CHARS`, cut in the middle with
``...``), as does every line ``torus-cad`` prints for an error.
"""

from __future__ import annotations

import re
from typing import Any

from torus_cad.tolerances import MESSAGE_MAX_CHARS, MESSAGE_VALUE_MAX_CHARS, MESSAGE_WORD_MAX_CHARS

_CUT = "..."
_LONG_WORD = re.compile(rf"\S{{{MESSAGE_WORD_MAX_CHARS + 1},}}")


def cut(text: str, limit: int = MESSAGE_VALUE_MAX_CHARS) -> str:
    """``text`` whole if it has at most ``limit`` characters, else its start and end around ``...``
    (``limit`` in all).

    Args:
        text: the text to shorten.
        limit: the most characters to return, ``...`` included.

    Returns:
        ``text`` itself, or its first and last characters joined by ``...`` (at least two of
        ``text`` kept even when ``limit`` is smaller than that).
    """
    if len(text) <= limit:
        return text
    keep = max(limit - len(_CUT), 2)
    head = (keep + 1) // 2
    return text[:head] + _CUT + text[len(text) - (keep - head) :]


def shown(value: Any, limit: int = MESSAGE_VALUE_MAX_CHARS) -> str:
    """``repr(value)`` for a message, :func:`cut` to ``limit`` characters ("a huge number" for an
    int Python will not print, > 4300 digits).

    Args:
        value: any value to quote in a message.
        limit: the most characters to return.

    Returns:
        The value's repr, cut to ``limit`` characters, or "a huge number".
    """
    try:
        text = repr(value)
    except ValueError:
        return "a huge number"
    return cut(text, limit)


def bounded_message(message: str) -> str:
    """``message`` on one line, each word of more than MESSAGE_WORD_MAX_CHARS characters and then
    the whole beyond MESSAGE_MAX_CHARS cut in the middle (:func:`cut`); a short message is returned
    unchanged.

    Args:
        message: an error message of any length, possibly over several lines.

    Returns:
        The message on one line, at most MESSAGE_MAX_CHARS characters.
    """
    if "\n" in message or "\r" in message:
        message = " ".join(message.splitlines())
    if len(message) > MESSAGE_WORD_MAX_CHARS:
        message = _LONG_WORD.sub(lambda match: cut(match.group(), MESSAGE_WORD_MAX_CHARS), message)
    return cut(message, MESSAGE_MAX_CHARS)


class TorusCadError(Exception):
    """Base of every error torus_cad raises on purpose; its message is bounded
    (:func:`bounded_message`).

    Args:
        *args: the exception's arguments; a single string is the message, passed through
            :func:`bounded_message`.
    """

    def __init__(self, *args: object) -> None:
        if len(args) == 1 and isinstance(args[0], str):
            args = (bounded_message(args[0]),)
        super().__init__(*args)


class ParameterError(TorusCadError, ValueError):
    """A design parameter or configuration file is invalid; the message names the field."""


class BudgetError(ParameterError):
    """The parameters ask for work over a documented limit (e.g. an STL of too many triangles);
    refused before it starts."""


class GeometryError(TorusCadError):
    """The parameters are valid one by one but describe no sound propeller (e.g. a Frenet frame is
    undefined)."""


class KernelError(TorusCadError):
    """OpenCascade failed to build, check or export the solid."""


class OutputError(TorusCadError):
    """An output file or folder could not be written (no space left, permission denied); the
    message names the file."""


class IncompleteOutputError(OutputError):
    """An output set on disk is incomplete or mixed: a file is missing or belongs to another build.

    Args:
        *problems: every problem found, one sentence each (the message joins them with "; ").

    Attributes:
        problems: every problem found, one sentence each (the message joins them with "; ").
    """

    def __init__(self, *problems: str) -> None:
        super().__init__("; ".join(problems))
        self.problems: tuple[str, ...] = problems


class MissingExtraError(TorusCadError):
    """An optional dependency is not installed; the message names the extra and the line that
    installs it (see :mod:`torus_cad.runtime.extras`)."""
