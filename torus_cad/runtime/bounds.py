"""An interval of allowed values: the parameter schema's ranges and the command line's option
ranges.

Standard library only: the command line shows its options' ranges in ``--help`` before the schema
(pydantic) is loaded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Bounds:
    """An interval of allowed values; an open end is excluded."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    def __str__(self) -> str:
        low = "-inf" if self.low is None else f"{self.low:g}"
        high = "inf" if self.high is None else f"{self.high:g}"
        return (
            f"{'(' if self.low_open or self.low is None else '['}{low}, "
            f"{high}{')' if self.high_open or self.high is None else ']'}"
        )

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies inside (NaN never does)."""
        if isinstance(value, float) and not math.isfinite(value):
            return False
        low_ok = self.low is None or (value > self.low if self.low_open else value >= self.low)
        high_ok = self.high is None or (value < self.high if self.high_open else value <= self.high)
        return low_ok and high_ok
