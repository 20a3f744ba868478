"""Seconds per stage of the mesh and CFD pipelines, announced to a progress callback as each starts.

Like :class:`torus_cad.stages.StageTimer` (whose stages are the B-rep build's), for any stage enum.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum


class StageClock:
    """Wall-clock seconds per stage (keys: the stages' values), in the order they ran."""

    def __init__(self, on_start: Callable[[str], None] | None = None) -> None:
        self.seconds: dict[str, float] = {}
        self.on_start = on_start

    @contextmanager
    def stage(self, stage: StrEnum) -> Iterator[None]:
        """Time the ``with`` block as ``stage`` (seconds add up if it runs twice)."""
        if self.on_start is not None:
            self.on_start(stage.value)
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[stage.value] = self.seconds.get(stage.value, 0.0) + time.perf_counter() - start
