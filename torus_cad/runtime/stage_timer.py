"""A timer that records each stage's wall-clock seconds, for any pipeline's enum of stages (the
build's torus_cad.build_stages.Stage, the mesh's and the CFD domain's own)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum
from typing import Generic, TypeVar

StageT = TypeVar("StageT", bound=StrEnum)


class StageTimer(Generic[StageT]):
    """Wall-clock seconds per stage, in the order the stages ran (keys: the stages' values).

    Generic over the stage enum: the build's :class:`Stage`, or another pipeline's own StrEnum
    (``torus-cad mesh``'s ``MeshStage``, ``torus-cad cfd``'s ``CfdStage``).
    """

    def __init__(self, on_start: Callable[[StageT], None] | None = None) -> None:
        self.seconds: dict[str, float] = {}
        # called with each stage (a str: its value) as it starts (progress display)
        self.on_start = on_start

    @contextmanager
    def stage(self, stage: StageT) -> Iterator[None]:
        """Time the ``with`` block as ``stage`` (seconds add up if the stage runs twice)."""
        if self.on_start is not None:
            self.on_start(stage)
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[stage.value] = (
                self.seconds.get(stage.value, 0.0) + time.perf_counter() - start
            )
