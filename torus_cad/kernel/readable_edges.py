"""The root fillet's edges made to read back from a STEP file as valid as they are in memory.

A fillet face's contact edge lies on the fillet surface (its 3D curve is the surface's boundary, to
1e-13 mm) but only near the blade or hub surface the fillet rolls on: OpenCascade's fillet surface
is an approximation. In memory the edge's tolerance covers the gap; a STEP file carries no tolerance
per edge, and OpenCascade's reader (FreeCAD's too) gives each edge what it samples (mm):

- it finds where each p-curve starts and ends by projecting the 3D curve's end points onto the
  p-curve's curve on the surface (``ShapeFix_EdgeProjAux``). Where the 3D curve leaves that curve
  askew (its point at parameter t is not the foot of the perpendicular from it), the projection
  lands at another parameter, and the reader reparametrizes the p-curve to match: the curves then
  part differently from what was written;
- it samples the distance between the 3D curve and each p-curve at 23 points at equal parameters
  and gives the edge the largest, times 1.00001 (at least 1e-7 mm). Where they part most between
  two samples, the edge reads back with a tolerance that does not cover its curves: an
  ``InvalidCurveOnSurface`` fault in ``BOPAlgo_ArgumentAnalyzer`` (FreeCAD's check with BOP),
  whose measure (``GeomLib_CheckCurveOnSurface``) finds the largest distance;
- it closes a gap between the face curves of two edges meeting at a vertex on a face by bending
  both to meet half way: a fillet contact edge's 3D curve can end up to a few 1e-4 mm from its
  vertex (its tolerance covers it in memory), so its face curve, square to the surface, ends that
  far from its neighbour's, and a neighbour that is exact (the blade's trailing-edge curve,
  tolerance 1e-7 mm) reads back bent, parting from its face most between two samples.

So, before the file is written:

0. every edge's 3D curve (a B-spline) that ends farther than
   :data:`~torus_cad.kernel.readable_edges.READBACK_VERTEX_GAP_MM` from its vertex is moved to end
   on it (a shift varying linearly along the edge added to it): face curves made square to the
   surfaces then end on the feet of the vertex, and meet on every face;
1. every p-curve whose curves part by more than
   :data:`~torus_cad.kernel.readable_edges.READBACK_MIN_TOLERANCE_MM`, and that is askew, is
   replaced by the curve of the feet of the perpendiculars from the 3D curve to the surface, at the
   same parameters (points solved by Gauss-Newton, the p-curve fitted by least squares in a B-spline
   basis holding the old 3D curve and p-curve and the surface's knot lines they cross, refined until
   it misses the feet half way between them by at most
   :data:`~torus_cad.kernel.readable_edges.READBACK_PCURVE_FIT_MM` or
   :data:`~torus_cad.kernel.readable_edges.READBACK_PCURVE_FIT_GAP` of the gap), its ends on the
   feet of the 3D curve's ends: the curves then part square to the surface everywhere, by the real
   gap only, and the reader's projection of the end points lands where the file says. A new p-curve
   that would make its face's wire cross itself (two edges meeting at a sliver) is undone;
2. every edge whose largest distance (looked for on
   :data:`~torus_cad.kernel.readable_edges.READBACK_WORST_SAMPLES` points and refined by Brent's
   method: GeomLib_CheckCurveOnSurface can put it a fraction of a percent off next to an end) lies
   between the reader's samples is split there: each piece then parts most at an end, which the
   reader samples. The pieces get the tolerance their curves need, not the fillet's.

Before step 1 a high-degree B-spline curve or p-curve gets knots (the same curve) so that
OpenCascade's span-cache evaluation reads its gap as exactly as the reader's samples do; and
:func:`readable_copy`, the writer's rewrite, first splits edges at corners inside their range (C0)
and drops edges shorter than 1e-5 mm, each of which BOPAlgo_ArgumentAnalyzer faults in the file read
back.

The faces stay as they are (only edges are split and curves replaced); the solid is checked
(BRepCheck_Analyzer) and its faces keep their parts. Measured on ``workshop_fillet`` (``python
scripts/step_readback_check.py examples/workshop_fillet.toml``): 93 ``InvalidCurveOnSurface`` faults
read back before, 0 after (every test on); with a 0.5 mm fillet on ``prop_10x5_2blade`` and
``marine_3blade_loop`` (``--fillet 0.5 --fast``) 4 and 6 before step 0 and the refined largest
distance, 0 after; the rest, and what it costs: docs/explanation/how-the-solid-is-built.md.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.Adaptor3d import Adaptor3d_CurveOnSurface
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepCheck import BRepCheck_Analyzer, BRepCheck_NoError, BRepCheck_Wire
from OCP.Geom import (
    Geom_BSplineCurve,
    Geom_BSplineSurface,
    Geom_Curve,
    Geom_Surface,
    Geom_TrimmedCurve,
)
from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Curve, Geom2d_TrimmedCurve
from OCP.Geom2dAdaptor import Geom2dAdaptor_Curve
from OCP.Geom2dConvert import Geom2dConvert
from OCP.GeomAbs import GeomAbs_C0, GeomAbs_C1
from OCP.GeomAdaptor import GeomAdaptor_Curve, GeomAdaptor_Surface
from OCP.GeomLib import GeomLib_CheckCurveOnSurface
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec
from OCP.ShapeBuild import ShapeBuild_ReShape
from OCP.ShapeFix import ShapeFix_ShapeTolerance, ShapeFix_Wireframe
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideContinuity
from OCP.TColgp import TColgp_Array1OfPnt2d
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopAbs import (
    TopAbs_EDGE,
    TopAbs_FACE,
    TopAbs_FORWARD,
    TopAbs_REVERSED,
    TopAbs_VERTEX,
    TopAbs_WIRE,
)
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape, TopoDS_Vertex, TopoDS_Wire
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape
from scipy.interpolate import make_lsq_spline
from scipy.optimize import minimize_scalar

from torus_cad.errors import KernelError
from torus_cad.kernel import face_provenance
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.edge_curves import distinct_faces
from torus_cad.kernel.topology import copied, explore

#: The least tolerance OpenCascade's STEP reader gives an edge (Precision::Confusion, mm): an edge
#: whose curves part by no more than this reads back valid whatever they do.
READBACK_MIN_TOLERANCE_MM = 1e-7

READBACK_PCURVE_FIT_GAP = 1e-3

#: After those rounds, the closest fit is taken if it misses the feet by no more than this (mm):
#: still square to well within the reader's least tolerance (a 3D curve moved onto its vertices can
#: leave feet whose refinement stalls near 1e-9 mm).
READBACK_PCURVE_FIT_LOOSE_MM = 1e-8

#: A p-curve rebuilt from the feet of perpendiculars misses them, half way between its points, by at
#: most this (mm) or this fraction of the largest gap between the 3D curve and the surface,
#: whichever is larger: a miss along the curve of e moves the reader's projection of an end point,
#: and the largest distance it reads, by about e^2 / gap, well within its factor of 1.00001.
READBACK_PCURVE_FIT_MM = 1e-9

#: Rounds of knots added where the rebuilt p-curve misses; beyond, the p-curve is kept.
READBACK_PCURVE_FIT_ROUNDS = 10

#: The reader samples an edge's curves at this many points at equal parameters, ends included
#: (ShapeAnalysis_Edge::CheckSameParameter's 23) ...
READBACK_SAMPLES = 23

#: A split edge's pieces are moved this far (mm) from their face at the split, so that their largest
#: distance is there by more than the evaluation's rounding (about 1e-12 mm): a 1.1e-7 mm gap is
#: within the reader's factor of 1.00001 of it.
READBACK_SPLIT_MARGIN_MM = 1e-10

#: ... and gives the edge the largest distance times this (BRepLib_ValidateEdge).
READBACK_TOLERANCE_FACTOR = 1.00001

#: An edge's 3D curve ending farther than this from its vertex (mm; the vertex's tolerance covers it
#: in memory) is moved to end on it: the reader closes the gap its p-curves then leave on a face by
#: bending them, its neighbour's too, whose edge may have no tolerance for it.
READBACK_VERTEX_GAP_MM = 1e-9

#: Points at equal parameters on which the largest distance between an edge's curves is looked for
#: before refining (GeomLib_CheckCurveOnSurface's own can be a fraction of a percent off next to an
#: end).
READBACK_WORST_SAMPLES = 129


__all__ = [
    "ReadableEdges",
    "SquareFit",
    "curves_apart",
    "edges_and_faces",
    "readable_copy",
    "readable_edges",
    "shifted_pcurve",
]

#: A B-spline curve or p-curve of a degree above this is evaluated by OpenCascade's span cache (a
#: Taylor polynomial about the span's start) with a rounding that grows with the degree and the
#: span: a fillet edge's degree-14 single span reads 2.6e-5 of its gap off near its end (more than
#: the reader's factor) ...
_NOISY_DEGREE = 5
#: ... so its spans are cut (knots inserted, the curve unchanged) to at most this share of the
#: edge's range.
_NOISY_SPAN_SHARE = 1.0 / 8.0
#: An edge shorter than this (mm) is no feature of a propeller but a fillet's sliver
#: (:func:`_without_micro_edges`).
_MICRO_EDGE_MM = 1e-5
#: Gauss-Newton steps for one foot point (it converges in 2-3 from the old p-curve's point).
_FOOT_STEPS = 8
#: A foot point has converged when its step moves it by less than this (mm) ...
_FOOT_STEP_MM = 1e-13
#: ... or, after every step, by less than this: the surface's own rounding (measured: steps of 1e-12
#: mm back and forth on a fillet surface's boundary, up to 2.5e-11 mm just past a fillet surface's
#: end).
_FOOT_NOISE_MM = 1e-10
#: Knots of the 3D curve and p-curve closer than this fraction of the edge's range are one knot.
_KNOT_MERGE = 1e-6
#: Points along a p-curve at which its crossings of the surface's knot lines are looked for ...
_CROSSING_SAMPLES = 200
#: ... and halvings of each crossing's interval (2^-40 of 1/200 of the range).
_BISECTIONS = 40
#: Local maxima of an edge's curves' distance refined (the largest ones) ...
_REFINED_PEAKS = 3
#: ... to this fraction of the edge's range.
_BRENT_XATOL = 1e-12
#: Times the splits are applied again without those whose neighbourhood BRepCheck_Analyzer faulted.
_PRUNING_ROUNDS = 3
#: A split edge's piece shorter than this many times the largest tolerance at it is a short piece
#: (:func:`_split`).
_SHORT_PIECE = 4.0


@dataclass(frozen=True)
class ReadableEdges:
    """What :func:`readable_edges` did.

    Attributes:
        solid: the solid, checked; face_parts: its faces' parts.
        pcurves: p-curves replaced by the feet of perpendiculars; split: edges split where their
            curves part most.
        worst_before_mm / worst_after_mm: the largest distance between an edge's 3D curve and a
            p-curve (GeomLib_CheckCurveOnSurface) before and after the p-curves were replaced, mm.
        closed: edges whose 3D curve was moved to end on its vertices.
    """

    solid: cq.Solid
    face_parts: tuple[int, ...]
    pcurves: int
    split: int
    worst_before_mm: float
    worst_after_mm: float
    closed: int = 0


def readable_edges(solid: cq.Solid, face_parts: Sequence[int]) -> ReadableEdges:
    """``solid`` (its faces' parts ``face_parts``) with its edges' curves ending on their vertices,
    its p-curves square to their surfaces and its edges split where the STEP reader would miss how
    far their curves part (module doc).

    The curves are replaced in place (in every shape that shares the edges); the edges' tolerances
    are raised to cover the new curves where needed. Raises KernelError if the result is not one
    valid solid.
    """
    shape = solid.wrapped
    edges = edges_and_faces(shape)
    closed = sum(_close_ends(edge) for edge, _ in edges)
    replaced, worst_before, worst_after = 0, 0.0, 0.0
    # (edge, faces, where, the tolerance needed)
    splits: list[tuple[TopoDS_Edge, list[TopoDS_Face], float, float]] = []
    for edge, faces in edges:
        _shorter_spans(edge, faces)
        hints = []
        for face in faces:
            before, after = _square_pcurve(edge, face)
            worst_before, worst_after = max(worst_before, before), max(worst_after, after[0])
            replaced += after[0] < before
            hints.append(after[1])
        worst = _true_worst(edge, faces, hints)
        _cover(edge, worst[0])
        where = _split_parameter(edge, faces, *worst)
        if where is not None:
            # the pieces part by the margin more at the split
            _cover(edge, worst[0] + READBACK_SPLIT_MARGIN_MM)
            splits.append(
                (
                    edge,
                    faces,
                    where,
                    max(
                        READBACK_MIN_TOLERANCE_MM,
                        worst[0] * READBACK_TOLERANCE_FACTOR + READBACK_SPLIT_MARGIN_MM,
                    ),
                )
            )
    if not splits and not closed:
        return ReadableEdges(solid, tuple(face_parts), replaced, 0, worst_before, worst_after)
    failure: KernelError | None = None
    # a piece's lower tolerance can make its face's wire cross itself
    for lower_short_pieces in (True, False):
        for _ in range(_PRUNING_ROUNDS):
            context = ShapeBuild_ReShape()
            for edge, faces, where, needed in splits:
                context.Replace(
                    edge.Oriented(TopAbs_FORWARD),
                    _split(edge, faces, where, needed if lower_short_pieces else None),
                )
            result = context.Apply(shape)
            try:
                checked = single_valid_solid(
                    cq.Shape.cast(result), "making the edges readable from STEP"
                )
            except KernelError as error:
                failure = error
                kept = _splits_on_valid_parts(context, result, splits)
                if len(kept) == len(splits):
                    break
                splits = kept
                continue
            origins = face_provenance.through_reshape(
                context, face_provenance.labelled_faces(shape, face_parts), checked.wrapped
            )
            return ReadableEdges(
                checked,
                face_provenance.face_parts(checked.wrapped, origins),
                replaced,
                len(splits),
                worst_before,
                worst_after,
                closed,
            )
    assert failure is not None
    raise failure


def _splits_on_valid_parts(
    context: ShapeBuild_ReShape,
    result: TopoDS_Shape,
    splits: list[tuple[TopoDS_Edge, list[TopoDS_Face], float, float]],
) -> list[tuple[TopoDS_Edge, list[TopoDS_Face], float, float]]:
    """The ``splits`` none of whose pieces BRepCheck_Analyzer faults in ``result`` (on the piece,
    its vertices or a face holding it): a split that leaves its neighbourhood invalid is left out,
    and its edge reads back as it would have without one."""
    analyzer = BRepCheck_Analyzer(result)
    faulty = [
        part
        for kind in (TopAbs_VERTEX, TopAbs_EDGE, TopAbs_FACE)
        for part in explore(result, kind)
        if not _fault_free(analyzer, part)
    ]
    kept = []
    for split in splits:
        pieces = explore(context.Value(split[0].Oriented(TopAbs_FORWARD)), TopAbs_EDGE)
        near = [*pieces, *(vertex for piece in pieces for vertex in explore(piece, TopAbs_VERTEX))]
        touched = [
            face
            for face in explore(result, TopAbs_FACE)
            if any(piece.IsSame(edge) for edge in explore(face, TopAbs_EDGE) for piece in pieces)
        ]
        if not any(part.IsSame(other) for part in faulty for other in [*near, *touched]):
            kept.append(split)
    return kept


def _fault_free(analyzer: BRepCheck_Analyzer, part: TopoDS_Shape) -> bool:
    """Whether BRepCheck_Analyzer finds no fault on ``part`` itself nor on it in the context of its
    faces."""
    result = analyzer.Result(part)
    if result is None:
        return True
    if any(status != BRepCheck_NoError for status in result.Status()):
        return False
    result.InitContextIterator()
    while result.MoreShapeInContext():
        if any(status != BRepCheck_NoError for status in result.StatusOnShape()):
            return False
        result.NextShapeInContext()
    return True


def readable_copy(shape: TopoDS_Shape) -> TopoDS_Shape:
    """A copy of the solid ``shape`` whose edges read back from STEP as they are
    (:func:`readable_edges`); the copy as it is where making them readable would not give a valid
    solid. ``shape`` is not changed."""
    solid = cq.Solid(_without_micro_edges(_split_at_corners(copied(shape))))
    try:
        return readable_edges(solid, [0] * len(solid.Faces())).solid.wrapped
    except KernelError:
        return solid.wrapped


def _split_at_corners(shape: TopoDS_Shape) -> TopoDS_Shape:
    """``shape`` with every edge whose 3D curve or p-curve has a corner (a knot of full
    multiplicity: only C0) inside its range split there, its surfaces as they are:
    BOPAlgo_ArgumentAnalyzer (FreeCAD's check with BOP) faults a C0 edge (a blade's intersection
    with the hub's end face inside a root fillet's run-out)."""
    divide = ShapeUpgrade_ShapeDivideContinuity(shape)
    divide.SetBoundaryCriterion(GeomAbs_C1)
    divide.SetPCurveCriterion(GeomAbs_C1)
    divide.SetSurfaceCriterion(GeomAbs_C0)
    return divide.Result() if divide.Perform() else shape


def _without_micro_edges(shape: TopoDS_Shape) -> TopoDS_Shape:
    """``shape`` with every edge shorter than _MICRO_EDGE_MM dropped, its neighbours joined over it:
    a root fillet can leave a 6e-7 mm edge on the hub, which reads back from STEP as a TooSmallEdge
    fault."""
    fix = ShapeFix_Wireframe(shape)
    fix.SetPrecision(_MICRO_EDGE_MM)
    fix.SetLimitAngle(-1.0)  # no angle spared: every such edge goes
    fix.ModeDropSmallEdges = True
    return fix.Shape() if fix.FixSmallEdges() else shape


def edges_and_faces(shape: TopoDS_Shape) -> list[tuple[TopoDS_Edge, list[TopoDS_Face]]]:
    """Each edge of ``shape`` with a 3D curve, not degenerated and no seam, with its distinct
    faces."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    found = []
    for index in range(1, ancestors.Extent() + 1):
        edge = TopoDS.Edge_s(ancestors.FindKey(index))
        faces = distinct_faces(ancestors.FindFromIndex(index))
        if (
            BRep_Tool.Degenerated_s(edge)
            or BRep_Tool.Curve_s(edge, 0.0, 0.0) is None
            or any(BRep_Tool.IsClosed_s(edge, face) for face in faces)
        ):
            continue
        found.append((edge, faces))
    return found


def curves_apart(
    curve: Geom_Curve, pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> tuple[float, float]:
    """The largest distance between ``curve`` and ``surface(pcurve)`` at equal parameters (mm), and
    where, as BOPAlgo_ArgumentAnalyzer measures it (GeomLib_CheckCurveOnSurface)."""
    check = GeomLib_CheckCurveOnSurface(GeomAdaptor_Curve(curve, first, last), 1e-9)
    check.Perform(
        Adaptor3d_CurveOnSurface(
            Geom2dAdaptor_Curve(pcurve, first, last), GeomAdaptor_Surface(surface)
        )
    )
    return (check.MaxDistance(), check.MaxParameter()) if check.IsDone() else (math.inf, first)


def _close_ends(edge: TopoDS_Edge) -> int:
    """Move ``edge``'s 3D curve to end on its vertices (module doc, step 0) where an end is farther
    from its vertex than READBACK_VERTEX_GAP_MM: the curve (a B-spline; others stay) is cut to the
    edge's range and a linear shift from the gap at one end to the gap at the other added to it
    (each pole moved by the shift at its Greville abscissa, which adds the linear function itself to
    a non-rational curve, a smooth blend of it to a rational one; either way the ends land on the
    vertices). Returns 1 if the curve was moved, else 0; the p-curves are made to follow
    afterwards."""
    forward = TopoDS.Edge_s(edge.Oriented(TopAbs_FORWARD))
    first, last = BRep_Tool.Range_s(forward)
    curve = BRep_Tool.Curve_s(forward, 0.0, 0.0)
    start = gp_Vec(curve.Value(first), BRep_Tool.Pnt_s(TopExp.FirstVertex_s(forward)))
    end = gp_Vec(curve.Value(last), BRep_Tool.Pnt_s(TopExp.LastVertex_s(forward)))
    if max(start.Magnitude(), end.Magnitude()) <= READBACK_VERTEX_GAP_MM:
        return 0
    basis = _shiftable_bspline(curve)
    if basis is None:
        return 0
    moved = _shifted_curve(basis, first, last, start, end)
    builder = BRep_Builder()
    builder.UpdateEdge(edge, moved, BRep_Tool.Tolerance_s(edge))
    builder.Range(edge, first, last)
    return 1


def _shorter_spans(edge: TopoDS_Edge, faces: Sequence[TopoDS_Face]) -> None:
    """Cut the spans of ``edge``'s high-degree B-spline 3D curve and p-curves to at most
    _NOISY_SPAN_SHARE of its range (knots inserted: the same curves, each evaluated as OpenCascade's
    span cache evaluates it to within the reader's factor; the module's _NOISY_DEGREE)."""
    first, last = BRep_Tool.Range_s(edge)
    builder = BRep_Builder()
    curve = _shiftable_bspline(BRep_Tool.Curve_s(edge, 0.0, 0.0))
    if curve is not None and curve.Degree() > _NOISY_DEGREE:
        finer = curve.Copy()
        if _insert_knots(finer, first, last):
            builder.UpdateEdge(edge, finer, BRep_Tool.Tolerance_s(edge))
            builder.Range(edge, first, last)
    for face in faces:
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if (
            isinstance(pcurve, Geom2d_BSplineCurve)
            and not pcurve.IsPeriodic()
            and pcurve.Degree() > _NOISY_DEGREE
        ):
            finer2d = pcurve.Copy()
            if _insert_knots(finer2d, first, last):
                builder.UpdateEdge(edge, finer2d, face, BRep_Tool.Tolerance_s(edge))


def _insert_knots(
    bspline: Geom_BSplineCurve | Geom2d_BSplineCurve, first: float, last: float
) -> bool:
    """Insert simple knots into ``bspline`` so that no span inside [first, last] is longer than
    _NOISY_SPAN_SHARE of it; whether any was inserted."""
    count = bspline.NbKnots()
    knots = np.array([bspline.Knot(index) for index in range(1, count + 1)])
    inside = np.unique(np.clip(np.concatenate([knots, [first, last]]), first, last))
    longest = _NOISY_SPAN_SHARE * (last - first)
    new = [
        float(k)
        for low, high in itertools.pairwise(inside)
        for k in np.linspace(low, high, math.ceil((high - low) / longest - 1e-9) + 1)[1:-1]
    ]
    if not new:
        return False
    added, multiplicities = TColStd_Array1OfReal(1, len(new)), TColStd_Array1OfInteger(1, len(new))
    for index, knot in enumerate(new, 1):
        added.SetValue(index, knot)
        multiplicities.SetValue(index, 1)
    bspline.InsertKnots(added, multiplicities, 1e-12 * (last - first), False)
    return True


def _shiftable_bspline(curve: Geom_Curve) -> Geom_BSplineCurve | None:
    """The non-periodic B-spline under ``curve``'s trims, which :func:`_shifted_curve` can move;
    None for any other curve (a line, a circle, a periodic B-spline stay as they are)."""
    while isinstance(curve, Geom_TrimmedCurve):
        curve = curve.BasisCurve()
    return curve if isinstance(curve, Geom_BSplineCurve) and not curve.IsPeriodic() else None


def _shifted_curve(
    basis: Geom_BSplineCurve, first: float, last: float, start: gp_Vec, end: gp_Vec
) -> Geom_BSplineCurve:
    """``basis`` cut to [first, last] with a shift from ``start`` at ``first`` to ``end`` at
    ``last`` added (each pole moved by the shift at its Greville abscissa, so the ends move by
    exactly those)."""
    moved = basis.Copy()
    if first > moved.FirstParameter() or last < moved.LastParameter():
        moved.Segment(first, last)
    for index, share in enumerate(_greville_shares(moved, first, last), 1):
        moved.SetPole(
            index,
            moved.Pole(index).Translated(
                start.Multiplied(1.0 - share).Added(end.Multiplied(share))
            ),
        )
    return moved


def _greville_shares(
    bspline: Geom_BSplineCurve | Geom2d_BSplineCurve, first: float, last: float
) -> list[float]:
    """Where each pole of ``bspline`` acts along [first, last], as a fraction in [0, 1]: its
    Greville abscissa (the mean of the ``degree`` knots after the pole's own), which a linear shift
    of the poles by that fraction turns into the same linear shift of the curve."""
    count, degree = bspline.NbPoles(), bspline.Degree()
    flat = TColStd_Array1OfReal(1, count + degree + 1)
    bspline.KnotSequence(flat)
    grevilles = (
        sum(flat.Value(index + k) for k in range(1, degree + 1)) / degree
        for index in range(1, count + 1)
    )
    return [min(1.0, max(0.0, (greville - first) / (last - first))) for greville in grevilles]


def _square_pcurve(edge: TopoDS_Edge, face: TopoDS_Face) -> tuple[float, tuple[float, float]]:
    """Replace ``edge``'s p-curve on ``face`` by the feet of the perpendiculars from its 3D curve
    (module doc, step 1), its ends on the feet of the 3D curve's ends, if its curves part by more
    than READBACK_MIN_TOLERANCE_MM and the new one parts by less; failing that, by the old p-curve
    shifted linearly to end on those feet. Returns the largest distance before (mm), and after with
    its parameter. The edge's tolerance is raised to cover the new curve."""
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    first, last = BRep_Tool.Range_s(edge)
    if pcurve is None:
        return 0.0, (0.0, first)
    surface = BRep_Tool.Surface_s(face)
    before = curves_apart(curve, pcurve, surface, first, last)
    if before[0] <= READBACK_MIN_TOLERANCE_MM:
        return before[0], before
    fit = SquareFit(curve, pcurve, surface, first, last)
    ends = fit.feet(np.array([first, last]))
    candidates = [
        fit.fit(),
        shifted_pcurve(pcurve, first, last, ends) if ends is not None else None,
    ]
    builder = BRep_Builder()
    for square in candidates:
        if square is None:
            continue
        # the ends exactly on the feet: the p-curves meeting at a vertex meet on every face
        if ends is not None:
            square.SetPole(1, gp_Pnt2d(*ends[0]))
            square.SetPole(square.NbPoles(), gp_Pnt2d(*ends[1]))
        after = curves_apart(curve, square, surface, first, last)
        if after[0] >= before[0]:
            continue
        tolerance = max(BRep_Tool.Tolerance_s(edge), after[0] * READBACK_TOLERANCE_FACTOR)
        builder.UpdateEdge(edge, square, face, tolerance)
        if not _wires_cross(edge, face):
            return before[0], after
        # moved across a neighbour's p-curve where two edges meet at a sliver: undone
        builder.UpdateEdge(edge, pcurve, face, tolerance)
    return before[0], before


def shifted_pcurve(
    pcurve: Geom2d_Curve, first: float, last: float, ends: NDArray[np.float64]
) -> Geom2d_BSplineCurve:
    """``pcurve`` on [first, last] as a B-spline, shifted linearly in (u, v) to run from ``ends[0]``
    to ``ends[1]``."""
    bspline = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(pcurve, first, last))
    start = ends[0] - np.array(_uv(bspline.Value(first)))
    end = ends[1] - np.array(_uv(bspline.Value(last)))
    for index, share in enumerate(_greville_shares(bspline, first, last), 1):
        u, v = np.array(_uv(bspline.Pole(index))) + start * (1.0 - share) + end * share
        bspline.SetPole(index, gp_Pnt2d(float(u), float(v)))
    return bspline


def _wires_cross(edge: TopoDS_Edge, face: TopoDS_Face) -> bool:
    """Whether a wire of ``face`` holding ``edge`` crosses itself on the face (BRepCheck_Wire)."""
    first, second = TopoDS_Edge(), TopoDS_Edge()
    return any(
        BRepCheck_Wire(TopoDS.Wire_s(wire)).SelfIntersect(face, first, second) != BRepCheck_NoError
        for wire in explore(face, TopAbs_WIRE)
        if any(edge.IsSame(other) for other in explore(wire, TopAbs_EDGE))
    )


class SquareFit:
    """The feet of the perpendiculars from a 3D curve to a surface, and a p-curve fitted through
    them."""

    def __init__(
        self,
        curve: Geom_Curve,
        pcurve: Geom2d_Curve,
        surface: Geom_Surface,
        first: float,
        last: float,
    ) -> None:
        self.curve, self.pcurve, self.surface = curve, pcurve, surface
        self.first, self.last = first, last
        self.degree, self.knots, self.multiplicities = _basis(curve, pcurve, surface, first, last)

    def fit(self) -> Geom2d_BSplineCurve | None:
        """The fitted p-curve, refined (a knot added half way along each span where it misses a foot
        half way between points by more than READBACK_PCURVE_FIT_MM, or READBACK_PCURVE_FIT_GAP of
        the gap) for READBACK_PCURVE_FIT_ROUNDS at most. None when the old p-curve is as square as
        that already, or the fit still misses, a foot does not converge or the least squares cannot
        be solved."""
        try:
            return self._fit()
        # a singular system (scipy's, numpy's): the old p-curve stays
        except (ValueError, np.linalg.LinAlgError):
            return None

    def _fit(self) -> Geom2d_BSplineCurve | None:
        knots, multiplicities = self.knots, self.multiplicities
        best: tuple[float, Geom2d_BSplineCurve | None] = (READBACK_PCURVE_FIT_LOOSE_MM, None)
        for round_ in range(READBACK_PCURVE_FIT_ROUNDS):
            flat = _flat(knots, multiplicities, self.degree)
            parameters = _sample_parameters(knots, multiplicities, self.degree)
            middles = 0.5 * (parameters[1:] + parameters[:-1])
            feet, exact = self.feet(parameters), self.feet(middles)
            if feet is None or exact is None:
                return best[1]
            allowed = max(
                READBACK_PCURVE_FIT_MM, READBACK_PCURVE_FIT_GAP * self._gap(middles, exact)
            )
            if (
                round_ == 0
                and self._misses(
                    np.array([_uv(self.pcurve.Value(t)) for t in middles]), exact
                ).max()
                <= allowed
            ):
                return None  # square already
            spline = make_lsq_spline(parameters, feet, flat, k=self.degree)
            misses = self._misses(spline(middles), exact)
            if not np.isfinite(misses).all():
                return best[1]
            if misses.max() <= allowed:
                return _bspline2d(spline.c, flat, self.degree)
            if misses.max() <= best[0]:
                best = (float(misses.max()), _bspline2d(spline.c, flat, self.degree))
            spans = np.unique(np.searchsorted(knots, middles[misses > allowed]))
            added = 0.5 * (knots[spans - 1] + knots[spans])
            order = np.argsort(np.concatenate([knots[1:-1], added]))
            inner = np.concatenate([knots[1:-1], added])[order]
            multiplicities = np.concatenate([multiplicities, np.ones(len(added), dtype=np.int64)])[
                order
            ]
            knots = np.concatenate([[knots[0]], inner, [knots[-1]]])
        # the closest fit, if it misses the feet by no more than READBACK_PCURVE_FIT_LOOSE_MM
        return best[1]

    def feet(self, parameters: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """``(n, 2)``: (u, v) of the foot of the perpendicular from the 3D curve at each parameter
        to the surface, by Gauss-Newton from the old p-curve's point; None if one does not
        converge."""
        targets = np.array([_xyz(self.curve.Value(t)) for t in parameters])
        uv = np.array([_uv(self.pcurve.Value(t)) for t in parameters])
        point, d_u, d_v = gp_Pnt(), gp_Vec(), gp_Vec()
        moved = math.inf
        for _ in range(_FOOT_STEPS):
            residual, jacobian = np.empty((len(uv), 3)), np.empty((len(uv), 3, 2))
            for row, (u, v) in enumerate(uv.tolist()):
                self.surface.D1(u, v, point, d_u, d_v)
                residual[row] = _xyz(point)
                jacobian[row, :, 0], jacobian[row, :, 1] = _xyz(d_u), _xyz(d_v)
            residual -= targets
            normal = np.einsum("nij,nik->njk", jacobian, jacobian)
            step = np.linalg.solve(normal, np.einsum("nij,ni->nj", jacobian, residual)[:, :, None])[
                :, :, 0
            ]
            uv -= step
            moved = float(np.linalg.norm(np.einsum("nij,nj->ni", jacobian, step), axis=1).max())
            if moved < _FOOT_STEP_MM:
                return uv
        return uv if moved < _FOOT_NOISE_MM else None

    def _gap(self, parameters: NDArray[np.float64], feet: NDArray[np.float64]) -> float:
        """The largest distance (mm) from the 3D curve at ``parameters`` to the surface at
        ``feet``."""
        return max(
            self.curve.Value(t).Distance(self.surface.Value(u, v))
            for t, (u, v) in zip(parameters.tolist(), feet.tolist(), strict=True)
        )

    def _misses(
        self, fitted: NDArray[np.float64], exact: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """How far (mm) the surface's points at ``fitted`` (u, v) are from its points at
        ``exact``."""
        return np.array(
            [
                self.surface.Value(*a).Distance(self.surface.Value(*b))
                for a, b in zip(fitted.tolist(), exact.tolist(), strict=True)
            ]
        )


def _basis(
    curve: Geom_Curve, pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> tuple[int, NDArray[np.float64], NDArray[np.int64]]:
    """A B-spline basis on [first, last] that holds the curve of feet: the higher of the curves'
    degrees (at least 3); the knots of both curves and the parameters where the p-curve crosses a
    knot line of the surface (where the feet, which follow the surface's normal, are one degree less
    smooth than the surface), close ones merged, each with the multiplicity that keeps the
    continuity there. Returns the degree, the distinct knots (both ends included) and the inner
    ones' multiplicities."""
    found: list[tuple[float, int]] = []  # (knot, continuity)
    degree = 3
    for geometry in (curve, pcurve):
        while isinstance(geometry, (Geom_TrimmedCurve, Geom2d_TrimmedCurve)):
            geometry = geometry.BasisCurve()
        if isinstance(geometry, (Geom_BSplineCurve, Geom2d_BSplineCurve)):
            degree = max(degree, geometry.Degree())
            found += [
                (geometry.Knot(i), geometry.Degree() - geometry.Multiplicity(i))
                for i in range(1, geometry.NbKnots() + 1)
            ]
    found += _knot_line_crossings(pcurve, surface, first, last)
    merge = _KNOT_MERGE * (last - first)
    knots, continuities = [first], [degree]
    for knot, continuity in sorted(found):
        if knot - first <= merge or last - knot <= merge:
            continue
        if knot - knots[-1] <= merge:
            continuities[-1] = min(continuities[-1], continuity)
        else:
            knots.append(knot)
            continuities.append(continuity)
    multiplicities = [min(degree, max(1, degree - continuity)) for continuity in continuities[1:]]
    return degree, np.array([*knots, last]), np.array(multiplicities, dtype=np.int64)


def _knot_line_crossings(
    pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> list[tuple[float, int]]:
    """(parameter, continuity of the feet there) where ``pcurve`` crosses an inner knot line of
    ``surface`` (a B-spline surface; none for others), found on :data:`_CROSSING_SAMPLES` points and
    refined by bisection."""
    if not isinstance(surface, Geom_BSplineSurface):
        return []
    lines = [
        (0, surface.UKnot(i), surface.UDegree() - surface.UMultiplicity(i) - 1)
        for i in range(2, surface.NbUKnots())
    ]
    lines += [
        (1, surface.VKnot(i), surface.VDegree() - surface.VMultiplicity(i) - 1)
        for i in range(2, surface.NbVKnots())
    ]
    parameters = np.linspace(first, last, _CROSSING_SAMPLES)
    uv = np.array([_uv(pcurve.Value(t)) for t in parameters])
    found = []
    for axis, knot, continuity in lines:
        side = uv[:, axis] > knot
        for index in np.flatnonzero(side[1:] != side[:-1]).tolist():
            low, high = float(parameters[index]), float(parameters[index + 1])
            for _ in range(_BISECTIONS):
                middle = 0.5 * (low + high)
                if (_uv(pcurve.Value(middle))[axis] > knot) == side[index]:
                    low = middle
                else:
                    high = middle
            found.append((0.5 * (low + high), max(0, continuity)))
    return found


def _flat(
    knots: NDArray[np.float64], multiplicities: NDArray[np.int64], degree: int
) -> NDArray[np.float64]:
    """Clamped flat knots of the distinct ``knots`` (ends included) and the inner ones'
    multiplicities."""
    return np.concatenate(
        [
            [knots[0]] * (degree + 1),
            np.repeat(knots[1:-1], multiplicities),
            [knots[-1]] * (degree + 1),
        ]
    )


def _sample_parameters(
    knots: NDArray[np.float64], multiplicities: NDArray[np.int64], degree: int
) -> NDArray[np.float64]:
    """Points for a least-squares fit in the basis of distinct ``knots``: in each span, evenly,
    twice the number of basis functions that start there (its first knot's multiplicity, degree + 1
    in the first), and at least degree + 1 (a span a refinement added holds a whole polynomial
    piece)."""
    starting = np.concatenate([[degree + 1], multiplicities])
    inside = [
        np.linspace(a, b, max(degree + 1, 2 * int(count)) + 1)[:-1]
        for a, b, count in zip(knots[:-1], knots[1:], starting, strict=True)
    ]
    return np.concatenate([*inside, knots[-1:]])


def _bspline2d(
    coefficients: NDArray[np.float64], flat: NDArray[np.float64], degree: int
) -> Geom2d_BSplineCurve:
    values, counts = np.unique(flat, return_counts=True)
    poles = TColgp_Array1OfPnt2d(1, len(coefficients))
    for index, (u, v) in enumerate(coefficients.tolist(), start=1):
        poles.SetValue(index, gp_Pnt2d(u, v))
    knots, multiplicities = (
        TColStd_Array1OfReal(1, len(values)),
        TColStd_Array1OfInteger(1, len(values)),
    )
    for index, (value, count) in enumerate(
        zip(values.tolist(), counts.tolist(), strict=True), start=1
    ):
        knots.SetValue(index, value)
        multiplicities.SetValue(index, count)
    return Geom2d_BSplineCurve(poles, knots, multiplicities, degree)


def _true_worst(
    edge: TopoDS_Edge, faces: Sequence[TopoDS_Face], hints: Sequence[float]
) -> tuple[float, float]:
    """The largest distance between ``edge``'s 3D curve and its p-curves (mm), and where: on
    READBACK_WORST_SAMPLES points at equal parameters and at ``hints`` (where
    GeomLib_CheckCurveOnSurface found the largest, which it can miss by a fraction of a percent next
    to an end), each of the largest local maxima refined by Brent's method between its
    neighbours."""
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    first, last = BRep_Tool.Range_s(edge)
    worst = (0.0, first)
    for face, hint in zip(faces, hints, strict=True):
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pcurve is None:
            continue
        surface = BRep_Tool.Surface_s(face)

        def distance(
            t: float, pcurve: Geom2d_Curve = pcurve, surface: Geom_Surface = surface
        ) -> float:
            return curve.Value(t).Distance(surface.Value(*_uv(pcurve.Value(t))))

        parameters = np.unique(
            np.concatenate(
                [np.linspace(first, last, READBACK_WORST_SAMPLES), [min(max(hint, first), last)]]
            )
        )
        values = np.array([distance(t) for t in parameters.tolist()])
        if values.max() <= READBACK_MIN_TOLERANCE_MM:
            worst = max(worst, (float(values.max()), float(parameters[values.argmax()])))
            continue
        padded = np.concatenate([[-1.0], values, [-1.0]])
        peaks = np.flatnonzero((padded[1:-1] >= padded[:-2]) & (padded[1:-1] >= padded[2:]))
        for index in peaks[np.argsort(values[peaks])[::-1][:_REFINED_PEAKS]].tolist():
            low, high = (
                parameters[max(index - 1, 0)],
                parameters[min(index + 1, len(parameters) - 1)],
            )
            found = minimize_scalar(
                lambda t: -distance(t),
                bounds=(low, high),
                method="bounded",
                options={"xatol": _BRENT_XATOL * (last - first)},
            )
            best = (float(-found.fun), float(found.x)) if found.success else (0.0, first)
            worst = max(worst, best, (float(values[index]), float(parameters[index])))
    return worst


def _cover(edge: TopoDS_Edge, worst_mm: float) -> None:
    """Raise ``edge``'s tolerance to cover ``worst_mm`` (times the reader's factor)."""
    if BRep_Tool.Tolerance_s(edge) < worst_mm * READBACK_TOLERANCE_FACTOR:
        BRep_Builder().UpdateEdge(edge, worst_mm * READBACK_TOLERANCE_FACTOR)


def _split_parameter(
    edge: TopoDS_Edge, faces: Sequence[TopoDS_Face], worst: float, where: float
) -> float | None:
    """``where`` (the parameter at which ``edge``'s curves part most, by ``worst`` mm) if that is
    more than the reader would give the edge and not at an end (module doc, step 2); None
    otherwise."""
    if worst <= READBACK_MIN_TOLERANCE_MM:
        return None
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    first, last = BRep_Tool.Range_s(edge)
    samples = np.linspace(first, last, READBACK_SAMPLES).tolist()
    sampled = 0.0
    for face in faces:
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pcurve is not None:
            surface = BRep_Tool.Surface_s(face)
            sampled = max(
                sampled,
                *(curve.Value(t).Distance(surface.Value(*_uv(pcurve.Value(t)))) for t in samples),
            )
    inside = min(where - first, last - where) > _KNOT_MERGE * (last - first)
    return where if worst > sampled * READBACK_TOLERANCE_FACTOR and inside else None


def _split(
    edge: TopoDS_Edge, faces: Sequence[TopoDS_Face], parameter: float, needed: float | None
) -> TopoDS_Wire:
    """``edge`` (forward) as two edges meeting at ``parameter``, with the same p-curves, as a wire.
    Each piece's 3D curve is moved by READBACK_SPLIT_MARGIN_MM at the split, away from the face it
    parts most from there (a shift fading linearly to nothing at its other end): its largest
    distance is then at the split by more than the rounding of the curves' evaluation (measured:
    1.2e-12 mm between GeomLib_CheckCurveOnSurface's value and the point's, 1e-5 of a 1.1e-7 mm gap,
    as much as the reader's factor). A piece shorter than :data:`_SHORT_PIECE` times the largest
    tolerance at it gets ``needed`` (mm, what its curves need) if given, not the fillet's tolerance,
    which would leave it inside its vertices' spheres (a TooSmallEdge fault); so does the vertex
    between the pieces."""
    builder = BRep_Builder()
    forward = TopoDS.Edge_s(edge.Oriented(TopAbs_FORWARD))
    first, last = BRep_Tool.Range_s(forward)
    curve = BRep_Tool.Curve_s(forward, 0.0, 0.0)
    tolerance = BRep_Tool.Tolerance_s(forward)
    ends = (TopExp.FirstVertex_s(forward), TopExp.LastVertex_s(forward))
    short = any(
        curve.Value(a).Distance(curve.Value(parameter))
        <= _SHORT_PIECE * max(tolerance, BRep_Tool.Tolerance_s(end))
        for a, end in ((first, ends[0]), (last, ends[1]))
    )
    if needed is not None and short:
        tolerance = needed
    point = curve.Value(parameter)
    basis = _shiftable_bspline(curve)
    margin = (
        _split_margin(point, forward, faces, parameter)
        if basis is not None
        else gp_Vec(0.0, 0.0, 0.0)
    )
    middle = TopoDS_Vertex()
    builder.MakeVertex(middle, point.Translated(margin), tolerance)
    wire = TopoDS_Wire()
    builder.MakeWire(wire)
    none = gp_Vec(0.0, 0.0, 0.0)
    pieces = (
        (ends[0], middle, first, parameter, none, margin),
        (middle, ends[1], parameter, last, margin, none),
    )
    for start, end, a, b, at_a, at_b in pieces:
        piece = TopoDS.Edge_s(forward.EmptyCopied())
        ShapeFix_ShapeTolerance().SetTolerance(piece, tolerance, TopAbs_EDGE)
        if margin.Magnitude() > 0.0:
            builder.UpdateEdge(piece, _shifted_curve(basis, a, b, at_a, at_b), tolerance)
        builder.Add(piece, start.Oriented(TopAbs_FORWARD))
        builder.Add(piece, end.Oriented(TopAbs_REVERSED))
        builder.Range(piece, a, b)
        builder.Add(wire, piece)
    return wire


def _split_margin(
    point: gp_Pnt, edge: TopoDS_Edge, faces: Sequence[TopoDS_Face], parameter: float
) -> gp_Vec:
    """READBACK_SPLIT_MARGIN_MM along the gap from the face whose surface ``edge``'s p-curve puts
    farthest from ``point`` at ``parameter`` (nothing if none is apart)."""
    gaps = []
    for face in faces:
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if pcurve is not None:
            gaps.append(
                gp_Vec(BRep_Tool.Surface_s(face).Value(*_uv(pcurve.Value(parameter))), point)
            )
    gap = max(gaps, key=lambda vector: vector.Magnitude(), default=gp_Vec(0.0, 0.0, 0.0))
    if gap.Magnitude() <= READBACK_SPLIT_MARGIN_MM:
        return gp_Vec(0.0, 0.0, 0.0)
    return gap.Normalized().Multiplied(READBACK_SPLIT_MARGIN_MM)


def _xyz(value: gp_Pnt | gp_Vec) -> tuple[float, float, float]:
    return value.X(), value.Y(), value.Z()


def _uv(value: gp_Pnt2d) -> tuple[float, float]:
    return value.X(), value.Y()
