"""Numeric command-line options: each has a range (shown in its ``--help``) and is checked as it is
parsed.

A value outside its range, or not a number, is refused by the parser with one line naming the
option, the value (cut short, torus_cad.errors.shown) and the range, exit code 2, before the command
starts: nothing is read, built or written, no output folder is made. The ranges' limits live in
torus_cad.tolerances (and the design schema, for options that set a design parameter).
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable

from torus_cad.errors import cut, shown
from torus_cad.runtime.bounds import Bounds

_WHOLE_NUMBER = re.compile(r"\s*[+-]?[0-9][0-9_]*\s*")

__all__ = ["Bounds", "in_range", "integer", "number", "range_help"]


def range_help(bounds: Bounds, unit: str = "") -> str:
    """The range as ``--help`` shows it: ``[1, 20000]``, ``(0, 86400] s``."""
    return f"{bounds}{' ' + unit if unit else ''}"


def _refused(
    option: str, value: object, bounds: Bounds, unit: str, note: str
) -> argparse.ArgumentTypeError:
    """``--time-limit = 0 s is out of range; ...``; an option that sets a design parameter is named
    by its key, as the design file's checks name it: ``cfd.growth_rate = 1 is out of range;
    ...``."""
    shown_value = f"{value}{' ' + unit if unit and option.startswith('-') else ''}"
    return argparse.ArgumentTypeError(
        f"{option} = {shown_value} is out of range; allowed {range_help(bounds, unit)}"
        f"{' (' + note + ')' if note else ''}"
    )


def in_range(option: str, value: float, bounds: Bounds, unit: str = "", note: str = "") -> None:
    """argparse.ArgumentTypeError (one line: option, value, range) unless ``value`` lies in
    ``bounds``."""
    if not bounds.contains(value):
        raise _refused(
            option,
            f"{value:g}" if isinstance(value, float) else cut(str(value)),
            bounds,
            unit,
            note,
        )


def integer(option: str, bounds: Bounds, unit: str = "", note: str = "") -> Callable[[str], int]:
    """The ``type`` of an option taking a whole number in ``bounds`` (``note`` explains the range).
    ``option`` names it in messages: ``--threads``, or the design key it sets
    (``mesh.sections``)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            if _WHOLE_NUMBER.fullmatch(text):  # more than 4300 digits: out of range, not malformed
                raise _refused(option, cut(text.strip()), bounds, unit, note) from None
            raise argparse.ArgumentTypeError(
                f"{option} must be a whole number in {range_help(bounds, unit)}, got {shown(text)}"
            ) from None
        in_range(option, value, bounds, unit, note)
        return value

    parse.__name__ = "whole number"  # argparse's fallback message names the type
    parse.bounds = bounds  # type: ignore[attr-defined]  # for tests and docs: the range of this option
    return parse


def number(option: str, bounds: Bounds, unit: str = "", note: str = "") -> Callable[[str], float]:
    """The ``type`` of an option taking a finite number in ``bounds`` (``note`` explains the
    range)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{option} must be a number in {range_help(bounds, unit)}, got {shown(text)}"
            ) from None
        if not math.isfinite(value):
            raise _refused(option, cut(text.strip()), bounds, unit, note)
        in_range(option, value, bounds, unit, note)
        return value

    parse.__name__ = "number"
    parse.bounds = bounds  # type: ignore[attr-defined]
    return parse
