"""A root fillet's contact edges rebuilt on the fillet surface's own boundary, for a STEP file that
reads back valid where making the edges readable (torus_cad.kernel.readable_edges) is not enough.

OpenCascade's rolling-ball fillet gives a contact edge a 3D curve of its own (the approximated
contact line) and, on the fillet face, the surface's iso-line (u or v constant) as its face curve.
The two part *along* the fillet surface, by up to a few 1e-5 mm, while the 3D curve lies within
1e-6 mm of the surface: the face curve is askew to the 3D curve. Where the fillet surface's
parametrisation races (a root fillet's run-out), the feet of the perpendiculars that would make the
face curve square do not converge, so the readable-edges step leaves it askew, and the STEP reader,
projecting the vertices onto the face curve, re-parametrizes it: the curves then part by more than
the tolerance it samples (design 3580 of the design-space tally: 21 faults).

So, for such an edge, the construction is turned round: its 3D curve *is* the fillet surface's
iso-curve at the face curve's parameters (the same curve, exactly: no refit), its face curve on the
fillet the iso-line as a straight line, and its face curve on the other face (the hub's cylinder,
the blade) the feet of the perpendiculars from it. The gap then lies across the contact, on the
other face only, where the surfaces touch tangentially (under 1e-6 mm). A fillet surface that an
edge's face curve runs past (a contact edge ending a few 1e-5 mm beyond the surface, at its vertex)
is first extended there (BRepLib::ExtendFace, the original part's parametrisation kept), and a
vertex all of whose edges were rebuilt moves to where their new curves end.
"""

from __future__ import annotations

import numpy as np
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepLib import BRepLib
from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface, Geom_Surface, Geom_TrimmedCurve
from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Curve
from OCP.GeomConvert import GeomConvert
from OCP.gp import gp_Pnt, gp_Pnt2d
from OCP.TColgp import TColgp_Array1OfPnt2d
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape, TopoDS_Vertex
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.kernel.readable_edges import (
    READBACK_MIN_TOLERANCE_MM,
    SquareFit,
    curves_apart,
    edges_and_faces,
    shifted_pcurve,
)
from torus_cad.kernel.topology import copied, explore

__all__ = ["iso_line_copy"]

#: A face curve is an iso-line if its constant coordinate varies by less than this (parameter units)
#: and its other coordinate is an affine function of the edge's parameter to this (relative) ...
ISO_LINE_TOLERANCE = 1e-8
#: ... checked on this many points.
ISO_LINE_SAMPLES = 21
#: How far (mm) a fillet surface is extended past an end that a face curve runs over.
SURFACE_EXTENSION_MM = 1e-3
#: A face curve runs past its surface's end if it passes it by more than this (parameter units).
PAST_THE_END = 1e-12


def iso_line_copy(shape: TopoDS_Shape) -> TopoDS_Shape | None:
    """A copy of the solid ``shape`` whose edges lying on a B-spline face's iso-line are rebuilt on
    that iso-curve (module doc).

    Args:
        shape: the solid; not changed.

    Returns:
        The rebuilt copy, or None if no edge qualifies or the copy is not valid
            (BRepCheck_Analyzer).
    """
    copy = copied(shape)
    _extend_surfaces_past_their_ends(copy)
    rebuilt = [
        edge
        for edge, faces in edges_and_faces(copy)
        if len(faces) == 2 and _rebuilt_on_iso_line(edge, faces)
    ]
    if not rebuilt:
        return None
    _move_vertices_of(copy, rebuilt)
    return copy if BRepCheck_Analyzer(copy).IsValid() else None


def _extend_surfaces_past_their_ends(shape: TopoDS_Shape) -> None:
    """Extend, in place, each B-spline face's surface on every side one of its face curves runs
    past, re-attaching its edges' face curves to the extended surface (a face shared by several
    instances of a blade is extended once)."""
    done: list[TopoDS_Face] = []
    for face in map(TopoDS.Face_s, explore(shape, TopAbs_FACE)):
        if any(other.IsPartner(face) for other in done):
            continue
        location = TopLoc_Location()
        surface = BRep_Tool.Surface_s(face, location)
        if not isinstance(surface, Geom_BSplineSurface):
            continue
        curves = _face_curves(face)
        sides = _sides_run_past(surface, face, curves)
        if not any(sides):
            continue
        extended = TopoDS_Face()
        u1, u2, v1, v2 = surface.Bounds()
        plain = BRepBuilderAPI_MakeFace(surface, u1, u2, v1, v2, READBACK_MIN_TOLERANCE_MM).Face()
        BRepLib.ExtendFace_s(plain, SURFACE_EXTENSION_MM, *sides, extended)
        builder = BRep_Builder()
        builder.UpdateFace(
            face, BRep_Tool.Surface_s(extended), location, BRep_Tool.Tolerance_s(face)
        )
        for edge, curve, seam_curve in curves:
            tolerance = BRep_Tool.Tolerance_s(edge)
            if seam_curve is None:
                builder.UpdateEdge(edge, curve, face, tolerance)
            else:
                builder.UpdateEdge(edge, curve, seam_curve, face, tolerance)
        done.append(face)


def _face_curves(
    face: TopoDS_Face,
) -> list[tuple[TopoDS_Edge, Geom2d_Curve, Geom2d_Curve | None]]:
    """Each edge of ``face`` with its face curve (and its second one, on a seam)."""
    found = []
    for edge in map(TopoDS.Edge_s, explore(face, TopAbs_EDGE)):
        curve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        if curve is None:
            continue
        seam = None
        if BRep_Tool.IsClosed_s(edge, face):
            seam = BRep_Tool.CurveOnSurface_s(TopoDS.Edge_s(edge.Reversed()), face, 0.0, 0.0)
        found.append((edge, curve, seam))
    return found


def _sides_run_past(
    surface: Geom_BSplineSurface,
    face: TopoDS_Face,
    curves: list[tuple[TopoDS_Edge, Geom2d_Curve, Geom2d_Curve | None]],
) -> list[bool]:
    """Which of the surface's ends (u first, u last, v first, v last) a face curve runs past."""
    u1, u2, v1, v2 = surface.Bounds()
    sides = [False] * 4
    for edge, curve, _ in curves:
        first, last = BRep_Tool.Range_s(edge)
        uv = np.array([_uv(curve.Value(t)) for t in np.linspace(first, last, ISO_LINE_SAMPLES)])
        sides[0] |= bool(uv[:, 0].min() < u1 - PAST_THE_END)
        sides[1] |= bool(uv[:, 0].max() > u2 + PAST_THE_END)
        sides[2] |= bool(uv[:, 1].min() < v1 - PAST_THE_END)
        sides[3] |= bool(uv[:, 1].max() > v2 + PAST_THE_END)
    return sides


def _rebuilt_on_iso_line(edge: TopoDS_Edge, faces: list[TopoDS_Face]) -> bool:
    """Rebuild ``edge`` on the iso-curve of whichever of its two ``faces`` (a B-spline face) has it
    on an iso-line, if its curves part there; True if it was rebuilt."""
    first, last = BRep_Tool.Range_s(edge)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if curve is None:
        return False
    for fillet, other in (faces, faces[::-1]):
        surface = BRep_Tool.Surface_s(fillet)
        pcurve = BRep_Tool.CurveOnSurface_s(edge, fillet, 0.0, 0.0)
        other_pcurve = BRep_Tool.CurveOnSurface_s(edge, other, 0.0, 0.0)
        if not isinstance(surface, Geom_BSplineSurface) or pcurve is None or other_pcurve is None:
            continue
        iso = _iso_line(pcurve, first, last)
        if (
            iso is None
            or curves_apart(curve, pcurve, surface, first, last)[0] <= READBACK_MIN_TOLERANCE_MM
        ):
            continue
        rebuilt, line = _iso_curve(surface, iso, first, last)
        square = _square_on(rebuilt, other_pcurve, BRep_Tool.Surface_s(other), first, last)
        if square is None:
            continue
        gaps = (
            curves_apart(rebuilt, line, surface, first, last)[0],
            curves_apart(rebuilt, square, BRep_Tool.Surface_s(other), first, last)[0],
        )
        tolerance = max(BRep_Tool.Tolerance_s(edge), *gaps)
        builder = BRep_Builder()
        builder.UpdateEdge(edge, rebuilt, tolerance)
        builder.Range(edge, first, last)
        builder.UpdateEdge(edge, line, fillet, tolerance)
        builder.UpdateEdge(edge, square, other, tolerance)
        return True
    return False


def _iso_line(
    pcurve: Geom2d_Curve, first: float, last: float
) -> tuple[int, float, float, float] | None:
    """(the constant coordinate's axis, its value, the other coordinate at ``first`` and at
    ``last``) if ``pcurve`` runs along an iso-line, its other coordinate affine in the parameter;
    else None."""
    parameters = np.linspace(first, last, ISO_LINE_SAMPLES)
    uv = np.array([_uv(pcurve.Value(t)) for t in parameters])
    for axis in (0, 1):
        along = uv[:, 1 - axis]
        affine = along[0] + (along[-1] - along[0]) * (parameters - first) / (last - first)
        scale = max(1.0, abs(along[-1] - along[0]))
        if (
            np.ptp(uv[:, axis]) < ISO_LINE_TOLERANCE
            and np.abs(along - affine).max() < ISO_LINE_TOLERANCE * scale
        ):
            return axis, float(uv[:, axis].mean()), float(along[0]), float(along[-1])
    return None


def _iso_curve(
    surface: Geom_BSplineSurface, iso: tuple[int, float, float, float], first: float, last: float
) -> tuple[Geom_BSplineCurve, Geom2d_BSplineCurve]:
    """The iso-curve of ``surface`` between the iso-line's ends, its knots mapped onto [first,
    last] (the same curve), and the iso-line as a straight face curve on that parameter range."""
    axis, constant, start, end = iso
    u1, u2, v1, v2 = surface.Bounds()
    low_bound, high_bound = (v1, v2) if axis == 0 else (u1, u2)
    low, high = max(min(start, end), low_bound), min(max(start, end), high_bound)
    basis = surface.UIso(constant) if axis == 0 else surface.VIso(constant)
    curve = GeomConvert.CurveToBSplineCurve_s(Geom_TrimmedCurve(basis, low, high))
    if end < start:
        curve.Reverse()
    knots = TColStd_Array1OfReal(1, curve.NbKnots())
    span = curve.Knot(curve.NbKnots()) - curve.Knot(1)
    for index in range(1, curve.NbKnots() + 1):
        knots.SetValue(index, first + (curve.Knot(index) - curve.Knot(1)) * (last - first) / span)
    curve.SetKnots(knots)
    return curve, _straight_face_curve(axis, constant, start, end, first, last)


def _straight_face_curve(
    axis: int, constant: float, start: float, end: float, first: float, last: float
) -> Geom2d_BSplineCurve:
    """The iso-line from ``start`` to ``end`` at ``constant`` as a degree-1 face curve on [first,
    last]."""
    poles = TColgp_Array1OfPnt2d(1, 2)
    for index, along in ((1, start), (2, end)):
        poles.SetValue(index, gp_Pnt2d(*((constant, along) if axis == 0 else (along, constant))))
    knots, multiplicities = TColStd_Array1OfReal(1, 2), TColStd_Array1OfInteger(1, 2)
    for index, knot in ((1, first), (2, last)):
        knots.SetValue(index, knot)
        multiplicities.SetValue(index, 2)
    return Geom2d_BSplineCurve(poles, knots, multiplicities, 1)


def _square_on(
    curve: Geom_BSplineCurve, pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> Geom2d_BSplineCurve | None:
    """The face curve on ``surface`` of the feet of the perpendiculars from ``curve`` (fitted, its
    ends on the feet of the curve's ends; the old ``pcurve`` shifted onto them where no fit
    holds)."""
    fit = SquareFit(curve, pcurve, surface, first, last)
    ends = fit.feet(np.array([first, last]))
    if ends is None:
        return None
    square = fit.fit() or shifted_pcurve(pcurve, first, last, ends)
    square.SetPole(1, gp_Pnt2d(*ends[0]))
    square.SetPole(square.NbPoles(), gp_Pnt2d(*ends[1]))
    return square


def _move_vertices_of(shape: TopoDS_Shape, rebuilt: list[TopoDS_Edge]) -> None:
    """Move each vertex all of whose edges were rebuilt to the mean of their curves' ends there, its
    tolerance covering them (a vertex shared with an edge as it was stays)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_VERTEX, TopAbs_EDGE, ancestors)
    for index in range(1, ancestors.Extent() + 1):
        vertex = TopoDS.Vertex_s(ancestors.FindKey(index))
        edges = [TopoDS.Edge_s(edge) for edge in ancestors.FindFromIndex(index)]
        if not edges or not all(any(edge.IsSame(done) for done in rebuilt) for edge in edges):
            continue
        ends = np.array([end for edge in edges for end in _ends_at(edge, vertex)])
        middle = ends.mean(axis=0)
        spread = float(np.linalg.norm(ends - middle, axis=1).max())
        BRep_Builder().UpdateVertex(
            vertex, gp_Pnt(*middle), max(READBACK_MIN_TOLERANCE_MM, 2.0 * spread)
        )


def _ends_at(edge: TopoDS_Edge, vertex: TopoDS_Vertex) -> list[tuple[float, float, float]]:
    """The points where ``edge``'s 3D curve ends at ``vertex`` (both, on a closed edge)."""
    first, last = BRep_Tool.Range_s(edge)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    found = []
    for parameter, end in ((first, TopExp.FirstVertex_s(edge)), (last, TopExp.LastVertex_s(edge))):
        if end.IsSame(vertex):
            point = curve.Value(parameter)
            found.append((point.X(), point.Y(), point.Z()))
    return found


def _uv(value: gp_Pnt2d) -> tuple[float, float]:
    return value.X(), value.Y()
