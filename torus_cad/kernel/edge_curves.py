"""Intersection edges whose 3D curve and p-curves lie on both their faces to 4e-8 mm.

The blade-hub boolean approximates each intersection curve (a 3D curve and a p-curve on each of
the two faces) and gives the edge a tolerance that covers how far they part: on the default, up to
2.1e-6 mm near the trailing edge, within a tolerance of 5e-6 mm. In memory that is valid. A STEP
file has no tolerance per edge, though: OpenCascade's reader gives each edge the deviation it
samples at 23 points along it (at least 1e-7 mm), and the bump near the trailing edge falls between
them, so the file read back has edges whose curves leave their surfaces by 20 times their tolerance
(``InvalidCurveOnSurface`` in FreeCAD's check with BOP; see :mod:`torus_cad.kernel.step_readback`).

So every such edge is built again from exact intersection points: each point solved by Newton's
method on both surfaces (in the plane normal to the old curve through its old point), the 3D curve
and both p-curves interpolated through them at the same parameters (so the edge stays same-range
and same-parameter), and points added half way wherever the curves part by more than
:data:`~torus_cad.kernel.edge_curves.EDGE_CURVE_FIT_MM`, then where OpenCascade's measure finds them
parting most, until it finds at most :data:`~torus_cad.kernel.edge_curves.EDGE_CURVE_ACCEPT_MM`. An
edge is replaced only when the new curves part by less than
:data:`~torus_cad.kernel.edge_curves.EDGE_CURVE_REFIT_ABOVE_MM` (by OpenCascade's own measure,
``GeomLib_CheckCurveOnSurface``, the one the argument analyzer uses) and less than before; otherwise
(surfaces that touch rather than cross, as a fillet's) it keeps its curves.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.Adaptor3d import Adaptor3d_CurveOnSurface
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.Geom import Geom_BSplineCurve, Geom_Curve, Geom_Surface, Geom_TrimmedCurve
from OCP.Geom2d import Geom2d_Curve
from OCP.Geom2dAdaptor import Geom2dAdaptor_Curve
from OCP.Geom2dAPI import Geom2dAPI_Interpolate
from OCP.GeomAdaptor import GeomAdaptor_Curve, GeomAdaptor_Surface
from OCP.GeomAPI import GeomAPI_Interpolate
from OCP.GeomLib import GeomLib_CheckCurveOnSurface
from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec
from OCP.TColgp import TColgp_HArray1OfPnt, TColgp_HArray1OfPnt2d
from OCP.TColStd import TColStd_HArray1OfReal
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

#: ... and then until OpenCascade's own measure (GeomLib_CheckCurveOnSurface) finds them parting by
#: at most this (mm), below EDGE_CURVE_REFIT_ABOVE_MM and 2.5 times below the reader's 1e-7 mm.
EDGE_CURVE_ACCEPT_MM = 4e-8

#: The rebuilt curves are refined until, half way between their points, they part by at most this
#: (mm).
EDGE_CURVE_FIT_MM = 2e-8

#: Most points one rebuilt edge may need (the default's worst edge needs a few hundred); beyond, it
#: is kept.
EDGE_CURVE_MAX_POINTS = 4000

#: Newton steps for one intersection point (it converges in 2-4 from the boolean's curves).
EDGE_CURVE_NEWTON_STEPS = 12

#: An exact intersection point farther than this many edge tolerances from the boolean's curve is
#: another branch of the intersection (or surfaces that touch): the edge keeps its curves.
EDGE_CURVE_REACH_TOLERANCES = 10.0

#: An intersection edge whose 3D curve and p-curves part by more than this (mm) is rebuilt: half of
#: what OpenCascade's STEP reader gives an edge at least (Precision::Confusion, 1e-7 mm), since a
#: STEP file carries no tolerance per edge (torus_cad.kernel.step_readback).
EDGE_CURVE_REFIT_ABOVE_MM = 5e-8

#: Times a point is added where OpenCascade's measure finds the rebuilt curves parting most, after
#: the half-way refinement (the interpolating spline can part between the half-way points).
EDGE_CURVE_WORST_POINT_ROUNDS = 20


#: Newton's method stops when both surfaces' points agree and lie in the plane to this (mm).
_NEWTON_RESIDUAL_MM = 1e-12
#: An intersection point: (u1, v1, u2, v2) on the two surfaces, and the point (mm).
_Point = tuple[NDArray[np.float64], NDArray[np.float64]]
#: Points per knot span of the old 3D curve to start from.
_POINTS_PER_SPAN = 4


@dataclass(frozen=True)
class EdgeRefit:
    """What :func:`refit_intersection_edges` did.

    Attributes:
        edges: edges looked at; refitted: edges whose curves were replaced.
        worst_before_mm / worst_after_mm: the largest curve-to-surface deviation of those edges
            before and after (GeomLib_CheckCurveOnSurface), mm.
        seconds: wall-clock seconds.
    """

    edges: int
    refitted: int
    worst_before_mm: float
    worst_after_mm: float
    seconds: float


def curve_on_surface_deviation(edge: TopoDS_Edge, face: TopoDS_Face) -> float:
    """Largest distance (mm) between ``edge``'s 3D curve and its p-curve on ``face`` at equal
    parameters, as the argument analyzer measures it (GeomLib_CheckCurveOnSurface); 0 for an edge
    without curves."""
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    if curve is None or pcurve is None:
        return 0.0
    first, last = BRep_Tool.Range_s(edge)
    return _deviation(curve, pcurve, BRep_Tool.Surface_s(face), first, last)


def refit_intersection_edges(shape: TopoDS_Shape, on_faces: Sequence[TopoDS_Face]) -> EdgeRefit:
    """Rebuild, in place, every edge of ``shape`` bounding one of ``on_faces`` (and one other face)
    whose curves part by more than EDGE_CURVE_REFIT_ABOVE_MM, from exact intersection points (module
    doc).

    In place: the edges are changed in every shape that shares them (copies moved from ``shape``
    included), which is the point: done on the blade once, before it is patterned.
    """
    start = time.perf_counter()
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    seen: list[TopoDS_Edge] = []
    worst_before = worst_after = 0.0
    refitted = 0
    for face in on_faces:
        for index in range(1, ancestors.Extent() + 1):
            edge = TopoDS.Edge_s(ancestors.FindKey(index))
            adjacent = distinct_faces(ancestors.FindFromIndex(index))
            if (
                BRep_Tool.Degenerated_s(edge)
                or any(edge.IsSame(other) for other in seen)
                or len(adjacent) != 2
                or not any(other.IsSame(face) for other in adjacent)
                or any(BRep_Tool.IsClosed_s(edge, other) for other in adjacent)
            ):
                continue
            seen.append(edge)
            before = max(curve_on_surface_deviation(edge, other) for other in adjacent)
            worst_before = max(worst_before, before)
            after = before
            if before > EDGE_CURVE_REFIT_ABOVE_MM:
                fitted = _IntersectionFit(edge, adjacent[0], adjacent[1]).fit()
                if fitted is not None and fitted.deviation < min(before, EDGE_CURVE_REFIT_ABOVE_MM):
                    fitted.apply(edge, adjacent)
                    after = fitted.deviation
                    refitted += 1
            worst_after = max(worst_after, after)
    return EdgeRefit(len(seen), refitted, worst_before, worst_after, time.perf_counter() - start)


def distinct_faces(faces: object) -> list[TopoDS_Face]:
    """The faces of an OCP shape list (an edge's ancestors), each once: a seam edge lists its face
    twice."""
    distinct: list[TopoDS_Face] = []
    for shape in faces:  # type: ignore[attr-defined]
        face = TopoDS.Face_s(shape)
        if not any(face.IsSame(other) for other in distinct):
            distinct.append(face)
    return distinct


def _deviation(
    curve: Geom_Curve, pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> float:
    return _deviation_at(curve, pcurve, surface, first, last)[0]


def _deviation_at(
    curve: Geom_Curve, pcurve: Geom2d_Curve, surface: Geom_Surface, first: float, last: float
) -> tuple[float, float]:
    """The largest distance between ``curve`` and ``surface(pcurve)`` at equal parameters (mm), and
    where."""
    check = GeomLib_CheckCurveOnSurface(GeomAdaptor_Curve(curve, first, last), 1e-9)
    check.Perform(
        Adaptor3d_CurveOnSurface(
            Geom2dAdaptor_Curve(pcurve, first, last), GeomAdaptor_Surface(surface)
        )
    )
    return (check.MaxDistance(), check.MaxParameter()) if check.IsDone() else (float("inf"), first)


@dataclass(frozen=True)
class _Fitted:
    curve: Geom_Curve
    pcurves: tuple[Geom2d_Curve, Geom2d_Curve]
    deviation: float
    worst_parameter: float

    def apply(self, edge: TopoDS_Edge, faces: Sequence[TopoDS_Face]) -> None:
        """Replace the edge's 3D curve and its two p-curves (same range; the tolerance stays, it
        covers them)."""
        builder = BRep_Builder()
        tolerance = BRep_Tool.Tolerance_s(edge)
        builder.UpdateEdge(edge, self.curve, tolerance)
        for face, pcurve in zip(faces, self.pcurves, strict=True):
            builder.UpdateEdge(edge, pcurve, face, tolerance)


class _IntersectionFit:
    """Exact intersection points of an edge's two surfaces, and curves interpolated through them."""

    def __init__(
        self, edge: TopoDS_Edge, first_face: TopoDS_Face, second_face: TopoDS_Face
    ) -> None:
        self.curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
        self.reach = EDGE_CURVE_REACH_TOLERANCES * BRep_Tool.Tolerance_s(edge)
        self.first, self.last = BRep_Tool.Range_s(edge)
        self.surfaces = (BRep_Tool.Surface_s(first_face), BRep_Tool.Surface_s(second_face))
        self.pcurves = (
            BRep_Tool.CurveOnSurface_s(edge, first_face, 0.0, 0.0),
            BRep_Tool.CurveOnSurface_s(edge, second_face, 0.0, 0.0),
        )

    def fit(self) -> _Fitted | None:
        """The interpolated curves, refined until they part by at most EDGE_CURVE_FIT_MM half way
        between points, then until OpenCascade's measure finds them parting by at most
        EDGE_CURVE_ACCEPT_MM (a point added where they part most, up to
        EDGE_CURVE_WORST_POINT_ROUNDS times); None when a point does not
        converge or the points run out."""
        if self.curve is None or any(pcurve is None for pcurve in self.pcurves):
            return None
        parameters = self._start_parameters()
        points = self._solve_all(parameters)
        unchecked = set(range(len(parameters) - 1))
        for _ in range(EDGE_CURVE_WORST_POINT_ROUNDS):
            while unchecked:
                if (
                    any(point is None for point in points)
                    or len(parameters) > EDGE_CURVE_MAX_POINTS
                ):
                    return None
                curves = self._interpolate(parameters, points)  # type: ignore[arg-type]
                parameters, points, unchecked = self._refined(curves, parameters, points, unchecked)
            if any(point is None for point in points):
                return None
            fitted = self._fitted(parameters, points)  # type: ignore[arg-type]
            if fitted.deviation <= EDGE_CURVE_ACCEPT_MM:
                return fitted
            index = int(np.searchsorted(parameters, fitted.worst_parameter))
            if not 0 < index < len(parameters) or fitted.worst_parameter in parameters:
                return fitted
            parameters.insert(index, fitted.worst_parameter)
            points.insert(index, self._solve_all([fitted.worst_parameter])[0])
            unchecked = {index - 1, index}
        return fitted

    def _refined(
        self,
        curves: tuple[Geom_Curve, Geom2d_Curve, Geom2d_Curve],
        parameters: list[float],
        points: list[_Point | None],
        unchecked: set[int],
    ) -> tuple[list[float], list[_Point | None], set[int]]:
        """A point added half way along every unchecked interval where the curves miss it by more
        than EDGE_CURVE_FIT_MM; the new intervals are the unchecked ones of the next round."""
        new_parameters, new_points, new_unchecked = [parameters[0]], [points[0]], set[int]()
        middles = {i: 0.5 * (parameters[i] + parameters[i + 1]) for i in sorted(unchecked)}
        solved = dict(zip(middles, self._solve_all(list(middles.values())), strict=True))
        for i in range(len(parameters) - 1):
            if i in unchecked:
                middle, exact = middles[i], solved[i]
                if exact is None or self._error(curves, middle, exact) > EDGE_CURVE_FIT_MM:
                    new_unchecked.update((len(new_parameters) - 1, len(new_parameters)))
                    new_parameters.append(middle)
                    new_points.append(exact)
            new_parameters.append(parameters[i + 1])
            new_points.append(points[i + 1])
        return new_parameters, new_points, new_unchecked

    def _fitted(self, parameters: list[float], points: list[_Point]) -> _Fitted:
        curve, first_pcurve, second_pcurve = self._interpolate(parameters, points)
        measured = [
            _deviation_at(curve, pcurve, surface, self.first, self.last)
            for pcurve, surface in (
                (first_pcurve, self.surfaces[0]),
                (second_pcurve, self.surfaces[1]),
            )
        ]
        deviation, worst = max(measured)
        return _Fitted(curve, (first_pcurve, second_pcurve), deviation, worst)

    def _start_parameters(self) -> list[float]:
        basis = self.curve.BasisCurve() if isinstance(self.curve, Geom_TrimmedCurve) else self.curve
        knots = [self.first, self.last]
        if isinstance(basis, Geom_BSplineCurve):
            inside = (basis.Knot(i) for i in range(1, basis.NbKnots() + 1))
            knots = sorted(
                {self.first, self.last, *(knot for knot in inside if self.first < knot < self.last)}
            )
        spans = [np.linspace(a, b, _POINTS_PER_SPAN + 1)[:-1] for a, b in itertools.pairwise(knots)]
        return [*(float(t) for t in np.concatenate(spans)), self.last]

    def _solve_all(self, parameters: Sequence[float]) -> list[_Point | None]:
        """For each ``t`` of ``parameters``: (u1, v1, u2, v2) and the 3D point where both surfaces
        meet in the plane normal to the old curve at ``t``, by Newton's method from the old
        p-curves' points; None if it does not converge or converges farther from the old point than
        EDGE_CURVE_REACH_TOLERANCES edge tolerances. The points' Newton steps are taken together
        (one batched linear solve a step)."""
        count = len(parameters)
        origins, normals, uv = np.empty((count, 3)), np.empty((count, 3)), np.empty((count, 4))
        point, tangent = gp_Pnt(), gp_Vec()
        for index, t in enumerate(parameters):
            self.curve.D1(t, point, tangent)
            origins[index] = point.X(), point.Y(), point.Z()
            normals[index] = tangent.X(), tangent.Y(), tangent.Z()
            a, b = self.pcurves[0].Value(t), self.pcurves[1].Value(t)
            uv[index] = a.X(), a.Y(), b.X(), b.Y()
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        found: list[_Point | None] = [None] * count
        active = np.arange(count)
        for _ in range(EDGE_CURVE_NEWTON_STEPS):
            if not len(active):
                break
            first, first_u, first_v, second, second_u, second_v = (
                np.empty((len(active), 3)) for _ in range(6)
            )
            for row, index in enumerate(active.tolist()):
                first[row], first_u[row], first_v[row] = _d1(
                    self.surfaces[0], uv[index, 0], uv[index, 1]
                )
                second[row], second_u[row], second_v[row] = _d1(
                    self.surfaces[1], uv[index, 2], uv[index, 3]
                )
            residual = np.concatenate(
                [
                    first - second,
                    np.einsum("ij,ij->i", first - origins[active], normals[active])[:, None],
                ],
                axis=1,
            )
            converged = np.abs(residual).max(axis=1) < _NEWTON_RESIDUAL_MM
            for row in np.flatnonzero(converged).tolist():
                index = int(active[row])
                # the old curves are within tolerance of it: farther is another branch
                exact = 0.5 * (first[row] + second[row])
                if float(np.linalg.norm(exact - origins[index])) <= self.reach:
                    found[index] = (uv[index].copy(), exact)
            going = ~converged
            active = active[going]
            jacobian = np.zeros((len(active), 4, 4))
            jacobian[:, :3, 0], jacobian[:, :3, 1] = first_u[going], first_v[going]
            jacobian[:, :3, 2], jacobian[:, :3, 3] = -second_u[going], -second_v[going]
            jacobian[:, 3, 0] = np.einsum("ij,ij->i", first_u[going], normals[active])
            jacobian[:, 3, 1] = np.einsum("ij,ij->i", first_v[going], normals[active])
            solvable = (
                np.abs(np.linalg.det(jacobian)) > 0.0 if len(active) else np.zeros(0, dtype=bool)
            )
            if len(active) and solvable.any():
                uv[active[solvable]] -= np.linalg.solve(
                    jacobian[solvable], residual[going][solvable][:, :, None]
                )[:, :, 0]
            active = active[solvable]  # a singular step ends that point: None
        return found

    def _interpolate(
        self, parameters: list[float], points: list[_Point]
    ) -> tuple[Geom_Curve, Geom2d_Curve, Geom2d_Curve]:
        count = len(parameters)
        values = TColStd_HArray1OfReal(1, count)
        in_space = TColgp_HArray1OfPnt(1, count)
        on_surfaces = (TColgp_HArray1OfPnt2d(1, count), TColgp_HArray1OfPnt2d(1, count))
        for index, (t, (uv, xyz)) in enumerate(zip(parameters, points, strict=True), start=1):
            values.SetValue(index, t)
            in_space.SetValue(index, gp_Pnt(*xyz))
            on_surfaces[0].SetValue(index, gp_Pnt2d(uv[0], uv[1]))
            on_surfaces[1].SetValue(index, gp_Pnt2d(uv[2], uv[3]))
        curve = GeomAPI_Interpolate(in_space, values, False, _NEWTON_RESIDUAL_MM)
        curve.Perform()
        pcurves = [
            Geom2dAPI_Interpolate(points_2d, values, False, _NEWTON_RESIDUAL_MM)
            for points_2d in on_surfaces
        ]
        for pcurve in pcurves:
            pcurve.Perform()
        return curve.Curve(), pcurves[0].Curve(), pcurves[1].Curve()

    def _error(
        self, curves: tuple[Geom_Curve, Geom2d_Curve, Geom2d_Curve], t: float, exact: _Point
    ) -> float:
        """How far the interpolated curves at ``t`` are from the exact point and from each other
        (mm)."""
        curve, first_pcurve, second_pcurve = curves
        target = gp_Pnt(*exact[1])
        on_curve = curve.Value(t)
        on_first = self.surfaces[0].Value(first_pcurve.Value(t).X(), first_pcurve.Value(t).Y())
        on_second = self.surfaces[1].Value(second_pcurve.Value(t).X(), second_pcurve.Value(t).Y())
        return max(
            on_curve.Distance(target), on_curve.Distance(on_first), on_curve.Distance(on_second)
        )


def _d1(surface: Geom_Surface, u: float, v: float) -> tuple[tuple[float, float, float], ...]:
    """The point and its two first derivatives of ``surface`` at (u, v)."""
    point, d_u, d_v = gp_Pnt(), gp_Vec(), gp_Vec()
    surface.D1(u, v, point, d_u, d_v)
    return (
        (point.X(), point.Y(), point.Z()),
        (d_u.X(), d_u.Y(), d_u.Z()),
        (d_v.X(), d_v.Y(), d_v.Z()),
    )
