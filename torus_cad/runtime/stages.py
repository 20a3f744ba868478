"""The pipeline's stages, in the order they run, and a timer that records each one's seconds.

One list for everything that names a stage: the build's timer, the JSON report's
``stage_seconds``, the progress display, the sweep table's ``time_<stage>_s`` columns and the
benchmarks. The timer also times the mesh and CFD pipelines, whose stages are their own enums.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum
from typing import Generic, TypeVar


class Stage(StrEnum):
    """A stage of building and writing a propeller; the value is its key in reports."""

    PARAMETERS = "parameters"
    DESIGN_TARGETS = "design_targets"
    SECTION_MATH = "section_math"
    WIRES = "wires"
    LOFT = "loft"
    FUSE = "fuse"
    CHECK = "check"
    FILLET = "fillet"
    STRICT_CHECK = "strict_check"
    MIRROR = "mirror"
    STEP_WRITE = "step_write"
    STL_WRITE = "stl_write"
    SECTIONS_TABLE = "sections_table"
    THREE_MF_WRITE = "3mf_write"
    # the steps a command shows around the pipeline (progress only; no report key)
    KERNEL_IMPORT = "kernel_import"
    WRITE = "write"
    PREVIEW_TESSELLATE = "tessellate"
    PREVIEW_RENDER = "render"

    @property
    def label(self) -> str:
        """Words for a progress display."""
        return _LABELS[self]


_LABELS = {
    Stage.PARAMETERS: "reading parameters",
    Stage.DESIGN_TARGETS: "diameter and pitch targets",
    Stage.SECTION_MATH: "blade sections (geometry)",
    Stage.WIRES: "section curves",
    Stage.LOFT: "lofting the blade",
    Stage.FUSE: "fusing blades with the hub",
    Stage.CHECK: "checking the solid",
    Stage.FILLET: "filleting the blade roots",
    Stage.STRICT_CHECK: "checking for self-intersections",
    Stage.MIRROR: "mirroring (clockwise)",
    Stage.STEP_WRITE: "writing STEP",
    Stage.STL_WRITE: "writing STL",
    Stage.SECTIONS_TABLE: "writing the blade-element table",
    Stage.THREE_MF_WRITE: "writing 3MF",
    Stage.KERNEL_IMPORT: "loading the schema and the CAD kernel (OpenCascade)",
    Stage.WRITE: "writing the files",
    Stage.PREVIEW_TESSELLATE: "tessellating for the preview",
    Stage.PREVIEW_RENDER: "rendering the preview",
}


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
