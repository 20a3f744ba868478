"""The build's stages, in the order they run, with the words a progress display shows for each.

One list for everything that names a stage of building and writing a propeller: the build's timer
(torus_cad.runtime.stage_timer), the JSON report's ``stage_seconds``, the progress display, the
sweep table's ``time_<stage>_s`` columns and the benchmarks. The mesh and CFD pipelines name their
own stages (``MeshStage``, ``CfdStage``).
"""

from __future__ import annotations

from enum import StrEnum


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
