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
back with a tolerance that does not cover them. So a solid valid in memory can read back invalid,
and the file is checked as read, not the solid. What the kernel does about it: the blade-hub
intersection edges are rebuilt to 4e-8 mm (torus_cad.kernel.edge_curves), a root fillet's edges
moved to end on their vertices, its p-curves squared and its edges split where the largest distance
falls between samples
(torus_cad.kernel.readable_edges). Measured, every test on (``python
scripts/step_readback_check.py``, ``examples/workshop_fillet.toml`` as argument for the root
fillet): every shipped design reads back with 0 faults; ``workshop_fillet`` had 93
``InvalidCurveOnSurface`` faults before the fillet's edges were made readable, ``prop_10x5_2blade``
and ``marine_3blade_loop`` with a 0.5 mm fillet (``--fillet 0.5 --fast``) 4 and 6 before the edges'
3D curves were also moved to end on their vertices.
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from OCP.BOPAlgo import BOPAlgo_ArgumentAnalyzer
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.IFSelect import IFSelect_RetDone
from OCP.STEPControl import STEPControl_Reader
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel.edge_curves import distinct_faces
from torus_cad.kernel.topology import BLADE_SURFACES

if TYPE_CHECKING:
    import cadquery as cq

#: Two faces whose outward normals part by less than this at an edge meet tangentially there (deg).
TANGENT_FACES_DEG = 1.0

#: Every test of BOPAlgo_ArgumentAnalyzer, as FreeCAD's check with BOP turns them on.
ANALYZER_TESTS = (
    "ArgumentTypeMode",
    "SelfInterMode",
    "SmallEdgeMode",
    "RebuildFaceMode",
    "TangentMode",
    "MergeVertexMode",
    "MergeEdgeMode",
    "ContinuityMode",
    "CurveOnSurfaceMode",
)


@dataclass(frozen=True)
class EdgeFault:
    """One fault of the argument analyzer on an edge, with what kind of edge it is.

    Attributes:
        status: the analyzer's status name (``InvalidCurveOnSurface``, ...).
        edge_kind: what the edge is in the propeller (:func:`edge_kind`).
        surfaces: the surface types on its sides, sorted, joined by ", " ("BSplineSurface,
            Cylinder").
        gap_mm: how far the edge's curves part (the analyzer's largest distance), mm; 0 if not
            measured.
        tolerance_mm: the edge's tolerance (as the reader gave it, for a file read back), mm.
    """

    status: str
    edge_kind: str
    surfaces: str
    gap_mm: float
    tolerance_mm: float

    def as_dict(self) -> dict[str, str | float]:
        """For a JSON row."""
        return asdict(self)


@dataclass(frozen=True)
class ArgumentFaults:
    """What BOPAlgo_ArgumentAnalyzer (every test) found on a shape.

    Attributes:
        counts: number of faults by status name (``InvalidCurveOnSurface``, ``GeomAbs_C0``, ...);
            empty when the shape passes.
        first: one line on the first fault (status, faulty sub-shapes, distance in mm if measured).
        seconds: wall-clock seconds of the analysis.
        on_edges: the faults that name an edge, each with its edge's kind (:class:`EdgeFault`).
    """

    counts: dict[str, int] = field(default_factory=dict)
    first: str = ""
    seconds: float = 0.0
    on_edges: tuple[EdgeFault, ...] = ()

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
    """:func:`read_step` as OpenCascade's shape (no cadquery); KernelError for a file that does not
    read or holds no shape."""
    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise KernelError(f"cannot read STEP file {str(path)!r}")
    reader.TransferRoots()
    shape = reader.OneShape()
    if shape.IsNull():  # a file whose DATA section holds no shape
        raise KernelError(f"STEP file {str(path)!r} holds no shape")
    return shape


def argument_faults(shape: TopoDS_Shape, self_interference: bool = True) -> ArgumentFaults:
    """BOPAlgo_ArgumentAnalyzer with every test of :data:`ANALYZER_TESTS` on ``shape``
    (single-threaded); without the self-interference test if ``self_interference`` is False (see
    :func:`check_step_readback`)."""
    start = time.perf_counter()
    findings = [_finding(result) for result in _analyzer(shape, self_interference).GetCheckResult()]
    return _faults(shape, findings, time.perf_counter() - start)


def self_intersection_faults(
    shape: TopoDS_Shape, pairs: Sequence[tuple[TopoDS_Shape, TopoDS_Shape]], seconds: float
) -> ArgumentFaults:
    """The interfering ``pairs`` of ``shape``'s sub-shapes (BOPAlgo_CheckerSI's, found in
    ``seconds``) as the analyzer reports them: one ``SelfIntersect`` fault a pair."""
    return _faults(shape, [_Finding("SelfIntersect", pair, 0.0) for pair in pairs], seconds)


@dataclass(frozen=True)
class _Finding:
    """One fault: its status name, the faulty sub-shapes, how far apart (mm; 0 if not measured)."""

    status: str
    shapes: tuple[TopoDS_Shape, ...]
    distance_mm: float


def _finding(result: object) -> _Finding:
    """An analyzer result (BOPAlgo_CheckResult) as a :class:`_Finding`."""
    return _Finding(
        str(result.GetCheckStatus()).rsplit(".", 1)[-1].removeprefix("BOPAlgo_"),  # type: ignore[attr-defined]
        (*result.GetFaultyShapes1(), *result.GetFaultyShapes2()),  # type: ignore[attr-defined]
        max(result.GetMaxDistance1(), result.GetMaxDistance2()),  # type: ignore[attr-defined]
    )


def _faults(shape: TopoDS_Shape, findings: list[_Finding], seconds: float) -> ArgumentFaults:
    """``findings`` on ``shape`` counted by status, the first described, those on edges
    classified."""
    return ArgumentFaults(
        dict(sorted(Counter(finding.status for finding in findings).items())),
        _describe(findings[0]) if findings else "",
        seconds,
        tuple(_on_edges(shape, findings)),
    )


def _analyzer(shape: TopoDS_Shape, self_interference: bool) -> BOPAlgo_ArgumentAnalyzer:
    """The analyzer run on ``shape`` with every test (but self-interference unless
    ``self_interference``)."""
    analyzer = BOPAlgo_ArgumentAnalyzer()
    analyzer.SetShape1(shape)
    for test in ANALYZER_TESTS:
        # OCP binds the modes as properties
        setattr(analyzer, test, self_interference or test != "SelfInterMode")
    analyzer.SetRunParallel(False)
    analyzer.Perform()
    return analyzer


def step_readback_faults(path: str | Path, self_interference: bool = True) -> ArgumentFaults:
    """:func:`argument_faults` of the shape OpenCascade's STEP reader (default settings) makes of
    ``path``."""
    return argument_faults(read_step_shape(path), self_interference)


def check_step_readback(
    path: str | Path, what: str, self_interference: bool = True
) -> ArgumentFaults:
    """The faults of ``path`` read back (none); KernelError naming the first fault otherwise.

    ``self_interference=False`` leaves out the one costly test (on the default's file read back 1.3
    s of CPU, the other tests together 0.2 s): the build runs it, on the blade pattern, on the solid
    the file is written from (torus_cad.kernel.strict), whose faces the file carries unchanged.
    """
    faults = argument_faults(read_step_shape(path), self_interference)
    if faults.counts:
        raise readback_refusal(faults, what)
    return faults


def readback_refusal(faults: ArgumentFaults, what: str) -> KernelError:
    """The refusal of a STEP file that reads back with ``faults``: the faults by status, the first,
    and the worst edge (the largest gap against its tolerance; else the first edge named)."""
    listed = ", ".join(f"{count} {status}" for status, count in faults.counts.items())
    gapped = [fault for fault in faults.on_edges if fault.gap_mm > 0.0]
    worst = max(
        gapped, key=lambda fault: fault.gap_mm / max(fault.tolerance_mm, 1e-300), default=None
    )
    if worst is not None:
        where = (
            f"; worst on a {worst.edge_kind} edge ({worst.surfaces}): curves {worst.gap_mm:.2g} "
            f"mm apart, tolerance read back {worst.tolerance_mm:.2g} mm"
        )
    elif faults.on_edges:
        named = faults.on_edges[0]
        where = (
            f"; on a {named.edge_kind} edge ({named.surfaces}), tolerance read back "
            f"{named.tolerance_mm:.2g} mm"
        )
    else:
        where = ""
    return KernelError(
        f"{what}: the STEP file read back fails BOPAlgo_ArgumentAnalyzer (every test, as "
        f"FreeCAD's check with BOP): {listed}; first: {faults.first}{where}"
    )


def classified_faults(shape: TopoDS_Shape) -> list[EdgeFault]:
    """The argument analyzer's faults on ``shape``'s edges (every test but self-interference), each
    with its edge's kind (:func:`edge_kind`)."""
    return list(argument_faults(shape, self_interference=False).on_edges)


def _on_edges(shape: TopoDS_Shape, findings: list[_Finding]) -> list[EdgeFault]:
    """The ``findings`` that name an edge of ``shape``, each with its edge's kind."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    fillet_faces = _fillet_faces(ancestors) if findings else []
    found = []
    for finding in findings:
        edge = next(
            (TopoDS.Edge_s(part) for part in finding.shapes if part.ShapeType() == TopAbs_EDGE),
            None,
        )
        if edge is None or not ancestors.Contains(edge):
            continue
        faces = distinct_faces(ancestors.FindFromKey(edge))
        surfaces = ", ".join(sorted(_surface_name(face) for face in faces))
        found.append(
            EdgeFault(
                finding.status,
                edge_kind(edge, faces, fillet_faces),
                surfaces,
                finding.distance_mm,
                BRep_Tool.Tolerance_s(edge),
            )
        )
    return found


def edge_kind(edge: TopoDS_Edge, faces: list[TopoDS_Face], fillet_faces: list[TopoDS_Face]) -> str:
    """What ``edge`` (between ``faces``) is in a propeller: 'blade-hub intersection', 'root fillet
    on the hub', 'root fillet on the blade', 'root fillet seam', 'trailing edge' (a crease between
    blade faces), 'blade face seam' (blade faces meeting tangentially), 'hub feature' (bore, D-flat,
    set screw, chamfer, end faces) or 'face seam' (an edge of one face only). ``fillet_faces``: the
    root fillet's faces.

    Blade and fillet faces are B-spline surfaces, the hub's analytic (plane, cylinder, cone)."""
    if len(faces) != 2:
        return "face seam"
    on_blade = [BRepAdaptor_Surface(face).GetType() in BLADE_SURFACES for face in faces]
    in_fillet = [any(face.IsSame(other) for other in fillet_faces) for face in faces]
    if not any(on_blade):
        return "hub feature"
    if not all(on_blade):
        return "root fillet on the hub" if any(in_fillet) else "blade-hub intersection"
    if all(in_fillet):
        return "root fillet seam"
    if any(in_fillet):
        return "root fillet on the blade"
    return "blade face seam" if _tangent(edge, faces) else "trailing edge"


def _fillet_faces(ancestors: TopTools_IndexedDataMapOfShapeListOfShape) -> list[TopoDS_Face]:
    """The B-spline faces that meet a hub face tangentially: the root fillet's (a blade crosses the
    hub at an angle)."""
    found: list[TopoDS_Face] = []
    for index in range(1, ancestors.Extent() + 1):
        faces = distinct_faces(ancestors.FindFromIndex(index))
        kinds = [BRepAdaptor_Surface(face).GetType() in BLADE_SURFACES for face in faces]
        if (
            len(faces) == 2
            and kinds[0] != kinds[1]
            and _tangent(TopoDS.Edge_s(ancestors.FindKey(index)), faces)
        ):
            found.append(faces[0] if kinds[0] else faces[1])
    return found


def _tangent(edge: TopoDS_Edge, faces: list[TopoDS_Face]) -> bool:
    """Whether the two faces' outward normals agree to within TANGENT_FACES_DEG at the edge's
    middle."""
    first, last = BRep_Tool.Range_s(edge)
    normals = []
    for face in faces:
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pcurve is None:
            return False
        uv = pcurve.Value(0.5 * (first + last))
        props = BRepLProp_SLProps(BRepAdaptor_Surface(face), uv.X(), uv.Y(), 1, 1e-9)
        if not props.IsNormalDefined():
            return False
        normal = props.Normal()
        normals.append(normal.Reversed() if face.Orientation() == TopAbs_REVERSED else normal)
    return normals[0].Angle(normals[1]) < math.radians(TANGENT_FACES_DEG)


def _surface_name(face: TopoDS_Face) -> str:
    return str(BRepAdaptor_Surface(face).GetType()).rsplit(".", 1)[-1].removeprefix("GeomAbs_")


def _describe(finding: _Finding) -> str:
    """'InvalidCurveOnSurface: edge (tolerance 1e-07 mm) on a BSplineSurface face, 2.1e-06 mm
    apart'."""
    parts = []
    for shape in finding.shapes:
        if shape.ShapeType() == TopAbs_EDGE:
            parts.append(f"edge (tolerance {BRep_Tool.Tolerance_s(TopoDS.Edge_s(shape)):.2g} mm)")
        elif shape.ShapeType() == TopAbs_FACE:
            kind = str(BRepAdaptor_Surface(TopoDS.Face_s(shape)).GetType()).rsplit(".", 1)[-1]
            parts.append(f"{kind.removeprefix('GeomAbs_')} face")
        else:
            parts.append(str(shape.ShapeType()).rsplit(".", 1)[-1].removeprefix("TopAbs_").lower())
    apart = f", curves {finding.distance_mm:.2g} mm apart" if finding.distance_mm > 0.0 else ""
    return f"{finding.status} on {' and '.join(parts) or 'the shape'}{apart}"
