"""The full boolean-argument analysis of a shape, and of a STEP file as OpenCascade reads it back.

``BOPAlgo_ArgumentAnalyzer`` with every test on is what FreeCAD's "Check geometry" runs when its
BOP check is ticked (``Part.Shape.check(True)``): argument type, self-interference, small edges,
rebuilt faces, tangent faces, vertices and edges to merge, continuity (a curve or surface that is
only C0 is a ``GeomAbs_C0`` fault) and curve on surface (an edge's 3D curve further from its
p-curve on a face than the edge's tolerance is an ``InvalidCurveOnSurface`` fault).

The STEP file carries no tolerance per edge, only one uncertainty for the whole file: OpenCascade's
reader gives each edge the deviation between its 3D curve and its p-curves that it samples (23
points along the edge at equal parameters, times 1.00001, at least 1e-7 mm), whatever
``write.precision.mode`` / ``write.precision.val`` put in the file (measured: 5e-6, 1e-4 and 1e-3 mm
give the same edge tolerances read back). It also finds where each p-curve starts and ends by
projecting the 3D curve's end points onto it, and reparametrizes a p-curve whose curve the 3D curve
leaves askew. An edge whose curves part most between those samples, or whose p-curve is askew, reads
back with a tolerance that does not cover them. So a solid valid in memory can read back invalid, and
the file is checked as read, not the solid. What the kernel does about it: the blade-hub
intersection edges are rebuilt to 4e-8 mm (torus_cad.kernel.edge_curves), a root fillet's edges
moved to end on their vertices, its p-curves squared and its edges split where the largest distance
falls between samples
(torus_cad.kernel.fillet_readback). Measured, every test on (``python scripts/step_readback_check.py``,
``examples/workshop_fillet.toml`` as argument for the root fillet): every shipped design reads back
with 0 faults; ``workshop_fillet`` had 93 ``InvalidCurveOnSurface`` faults before the fillet's edges
were made readable, ``prop_10x5_2blade`` and ``marine_3blade_loop`` with a 0.5 mm fillet (``--fillet
0.5 --fast``) 4 and 6 before the edges' 3D curves were also moved to end on their vertices.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from OCP.BOPAlgo import BOPAlgo_ArgumentAnalyzer
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopoDS import TopoDS, TopoDS_Shape

from torus_cad.errors import KernelError

if TYPE_CHECKING:
    import cadquery as cq

#: Every test of BOPAlgo_ArgumentAnalyzer, as FreeCAD's check with BOP turns them on.
ANALYZER_TESTS = ("ArgumentTypeMode", "SelfInterMode", "SmallEdgeMode", "RebuildFaceMode", "TangentMode",
                  "MergeVertexMode", "MergeEdgeMode", "ContinuityMode", "CurveOnSurfaceMode")


@dataclass(frozen=True)
class ArgumentFaults:
    """What BOPAlgo_ArgumentAnalyzer (every test) found on a shape.

    Attributes:
        counts: number of faults by status name (``InvalidCurveOnSurface``, ``GeomAbs_C0``, ...);
            empty when the shape passes.
        first: one line on the first fault (status, faulty sub-shapes, distance in mm if measured).
        seconds: wall-clock seconds of the analysis.
    """

    counts: dict[str, int] = field(default_factory=dict)
    first: str = ""
    seconds: float = 0.0

    @property
    def total(self) -> int:
        """All faults together."""
        return sum(self.counts.values())


def read_step(path: str | Path) -> cq.Shape:
    """Read a STEP file back as one shape (OpenCascade's STEP reader, default settings); raise
    KernelError if it does not read."""
    import cadquery as cq

    return cq.Shape.cast(read_step_shape(path))


def read_step_shape(path: str | Path) -> TopoDS_Shape:
    """:func:`read_step` as OpenCascade's shape (no cadquery)."""
    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise KernelError(f"cannot read STEP file {str(path)!r}")
    reader.TransferRoots()
    return reader.OneShape()


def argument_faults(shape: TopoDS_Shape, self_interference: bool = True) -> ArgumentFaults:
    """BOPAlgo_ArgumentAnalyzer with every test of :data:`ANALYZER_TESTS` on ``shape`` (single-threaded);
    without the self-interference test if ``self_interference`` is False (see :func:`check_step_readback`)."""
    start = time.perf_counter()
    analyzer = BOPAlgo_ArgumentAnalyzer()
    analyzer.SetShape1(shape)
    for test in ANALYZER_TESTS:
        setattr(analyzer, test, self_interference or test != "SelfInterMode")  # OCP binds the modes as properties
    analyzer.SetRunParallel(False)
    analyzer.Perform()
    results = list(analyzer.GetCheckResult())
    counts = Counter(_status(result) for result in results)
    first = _describe(results[0]) if results else ""
    return ArgumentFaults(dict(sorted(counts.items())), first, time.perf_counter() - start)


def step_readback_faults(path: str | Path, self_interference: bool = True) -> ArgumentFaults:
    """:func:`argument_faults` of the shape OpenCascade's STEP reader (default settings) makes of ``path``."""
    return argument_faults(read_step_shape(path), self_interference)


def check_step_readback(path: str | Path, what: str, self_interference: bool = True) -> ArgumentFaults:
    """The faults of ``path`` read back (none); KernelError naming the first fault otherwise.

    ``self_interference=False`` leaves out the one costly test (on the default's file read back 1.3 s
    of CPU, the other tests together 0.2 s): the build runs it, on the blade pattern, on the solid the
    file is written from (torus_cad.kernel.strict), whose faces the file carries unchanged.
    """
    faults = step_readback_faults(path, self_interference)
    if faults.counts:
        listed = ", ".join(f"{count} {status}" for status, count in faults.counts.items())
        raise KernelError(f"{what}: the STEP file read back fails BOPAlgo_ArgumentAnalyzer (every test, as "
                          f"FreeCAD's check with BOP): {listed}; first: {faults.first}")
    return faults


def _status(result: object) -> str:
    return str(result.GetCheckStatus()).rsplit(".", 1)[-1].removeprefix("BOPAlgo_")  # type: ignore[attr-defined]


def _describe(result: object) -> str:
    """'InvalidCurveOnSurface: edge (tolerance 1e-07 mm) on a BSplineSurface face, 2.1e-06 mm apart'."""
    shapes = [*result.GetFaultyShapes1(), *result.GetFaultyShapes2()]  # type: ignore[attr-defined]
    parts = []
    for shape in shapes:
        if shape.ShapeType() == TopAbs_EDGE:
            parts.append(f"edge (tolerance {BRep_Tool.Tolerance_s(TopoDS.Edge_s(shape)):.2g} mm)")
        elif shape.ShapeType() == TopAbs_FACE:
            kind = str(BRepAdaptor_Surface(TopoDS.Face_s(shape)).GetType()).rsplit(".", 1)[-1]
            parts.append(f"{kind.removeprefix('GeomAbs_')} face")
        else:
            parts.append(str(shape.ShapeType()).rsplit(".", 1)[-1].removeprefix("TopAbs_").lower())
    distance = max(result.GetMaxDistance1(), result.GetMaxDistance2())  # type: ignore[attr-defined]
    apart = f", curves {distance:.2g} mm apart" if distance > 0.0 else ""
    return f"{_status(result)} on {' and '.join(parts) or 'the shape'}{apart}"
