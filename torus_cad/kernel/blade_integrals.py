"""Mass properties of a hub with blades from the blade faces alone: the fast route of
:func:`torus_cad.kernel.checks.mass_properties`.

A propeller joined by the shared-intersection fuse is a cylinder (radius R, axis z, ends at
z_bottom and z_top) plus blade faces, each a non-rational B-spline surface trimmed by its
intersection curves with the cylinder: the part of the blade's side surface outside r = R.
Every integral splits into the hub's, known in closed form, and one per blade face:

* **Divergence theorem with fields that vanish on the cylinder.** ∫ f dV over a blade's part
  outside the hub equals ∮ G·n dA for any field G with div G = f. Radial fields
  G = (x, y, 0) k with k = 0 at r = R have G·n = 0 on the hub's lateral face, so the holes
  the blades leave in it contribute nothing and only the blade faces are integrated:
  f = 1: k = 1/2 - R²/(2r²); f = x (y): k = x (y) (1 - R³/r³)/3; f = z: k = z (1/2 - R²/(2r²));
  f = x² + y² (the spin-axis inertia): k = (r² - R⁴/r²)/4.
* **The trimmed domain from the surface, not from OpenCascade's trimming curves.** Along each
  v line (u fixed; u runs around the section, v along the span) the part outside the hub is
  v in [a(u), b(u)], the two roots of r(u, v) = R, found by sampling and safeguarded Newton.
* **Gauss-Legendre per knot span**: whole spans as a tensor product, the two spans cut by a(u)
  and b(u) on their own. The integrands are smooth on every piece, so 4 points per span give
  ~4e-10 relative on the default propeller against BRepGProp at 1e-9.
* **The hub's lateral area** is 2πRL less the blade footprints, each R |∮ z dθ| along the root
  and the tip curve (a line integral at the same u Gauss points).
* **Once per blade shape**: the blades are copies of one face rotated about z. Volume, area,
  z moment and spin-axis inertia do not change under that rotation; the x, y moments rotate,
  and the box of each copy is the face's support in rotated directions.

OpenCascade's adaptive integration subdivides every trimmed face from scratch and costs far
more (``python scripts/bench.py`` prints both). Whenever the shape is not recognised as a hub
with such blade faces (an end face crossed by a blade, a rational or periodic surface, a blade
re-entering the hub, a fillet, a bore...), :func:`hub_with_blade_integrals` returns None and the
caller integrates with BRepGProp.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineSurface
from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_Circle, GeomAbs_Cylinder, GeomAbs_Plane
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_SOLID, TopAbs_WIRE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape
from scipy.interpolate import BSpline

#: Gauss-Legendre points per knot span, in u and in v. On the default propeller 4 x 4 is
#: ~4e-10 relative in volume (as 8 x 8: the rest is the B-rep's own trimming curves), 3 x 3 ~8e-9.
GAUSS_POINTS_PER_SPAN = 4

#: Samples per v knot span when looking for the crossings of r = R along a v line.
ROOT_SAMPLES_PER_SPAN = 4

#: Geometric checks of the recognition (axis, radius, end discs, rotations) hold to this, mm.
RECOGNITION_TOLERANCE_MM = 1e-7

#: A blade face's u bounds (from its trimming curves) must be the surface's whole u range to this
#: fraction; its v bounds the computed [min a, max b] to the looser second fraction (the roots
#: are known at the u Gauss points only).
U_BOUNDS_RELATIVE, V_BOUNDS_RELATIVE = 1e-6, 1e-2

#: The six box directions, in the order of :attr:`FaceIntegrals.extremes_mm`: -x, x, -y, y, -z, z.
_BOX_DIRECTIONS = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], dtype=float)


@dataclass(frozen=True)
class HubWithBladeIntegrals:
    """Integrals of a whole hub-with-blades solid.

    Attributes:
        volume_mm3: volume, mm^3.
        centroid_mm: ``(3,)`` centre of volume, mm.
        spin_inertia_mm5: ∫ (x² + y²) dV about the z axis, mm^5.
        area_mm2: boundary area, mm^2.
        box_min_mm, box_max_mm: ``(3,)`` corners of the tight bounding box, mm.
    """

    volume_mm3: float
    centroid_mm: NDArray[np.float64]
    spin_inertia_mm5: float
    area_mm2: float
    box_min_mm: NDArray[np.float64]
    box_max_mm: NDArray[np.float64]


@dataclass(frozen=True)
class _Hub:
    radius: float
    z_bottom: float
    z_top: float
    blade_faces: list[TopoDS_Face]


def hub_with_blade_integrals(shape: TopoDS_Shape,
                             gauss_points: int = GAUSS_POINTS_PER_SPAN) -> HubWithBladeIntegrals | None:
    """Volume, centroid, spin-axis inertia, area and box of a hub-with-blades solid, or None
    when ``shape`` is not one (see the module's docstring)."""
    hub = _recognise(shape)
    if hub is None:
        return None
    radius, length = hub.radius, hub.z_top - hub.z_bottom
    volume = math.pi * radius**2 * length
    moment = np.array([0.0, 0.0, volume * (hub.z_top + hub.z_bottom) / 2.0])
    inertia = math.pi * radius**4 * length / 2.0
    area = 2.0 * math.pi * radius**2 + 2.0 * math.pi * radius * length
    box_max = np.array([radius, radius, radius, radius, -hub.z_bottom, hub.z_top])  # along _BOX_DIRECTIONS
    groups: dict[tuple[int, bool], list[tuple[TopoDS_Face, float]]] = {}
    surfaces: dict[tuple[int, bool], Geom_BSplineSurface] = {}
    for face in hub.blade_faces:
        surface, angle = _base_surface_and_angle(face)
        if surface is None or angle is None:
            return None
        key = (id(surface), face.Orientation() == TopAbs_REVERSED)
        surfaces[key] = surface
        groups.setdefault(key, []).append((face, angle))
    for key, members in groups.items():
        angles = np.array([angle for _, angle in members])
        part = _face_integrals(surfaces[key], key[1], radius, angles, gauss_points)
        if part is None or not all(_bounds_match(face, part) for face, _ in members):
            return None
        count, (cos, sin) = len(members), (np.cos(angles).sum(), np.sin(angles).sum())
        moment_x, moment_y, moment_z = part.first_moment_mm4  # rotating a copy rotates its x, y moment
        volume += count * part.volume_mm3
        moment += np.array([cos * moment_x - sin * moment_y, sin * moment_x + cos * moment_y, count * moment_z])
        inertia += count * part.spin_inertia_mm5
        area += count * (part.area_mm2 - part.footprint_area_mm2)
        box_max = np.maximum(box_max, part.extremes_mm.max(axis=0))
    return HubWithBladeIntegrals(volume, moment / volume, inertia, area, -box_max[0::2], box_max[1::2])


# -- recognising the shape ----------------------------------------------------------------------

def _recognise(shape: TopoDS_Shape) -> _Hub | None:
    """The hub's radius and end planes and the blade faces, or None unless ``shape`` is one solid
    made of z-axis cylinder faces of one radius, two whole end discs and B-spline faces bounded
    only by the cylinder's edges (and their own seam)."""
    if _count(shape, TopAbs_SOLID) != 1:
        return None
    by_kind: dict[object, list[TopoDS_Face]] = {}
    for face in _faces(shape):
        by_kind.setdefault(BRepAdaptor_Surface(face).GetType(), []).append(face)
    cylinders, planes, blades = (by_kind.pop(kind, []) for kind in (GeomAbs_Cylinder, GeomAbs_Plane,
                                                                     GeomAbs_BSplineSurface))
    if by_kind or not cylinders or len(planes) != 2 or not blades:
        return None
    radius = _z_axis_cylinder_radius(cylinders)
    if radius is None:
        return None
    ends = [_end_disc_z(face, radius) for face in planes]
    if None in ends:
        return None
    z_bottom, z_top = sorted(ends)
    if z_top - z_bottom <= RECOGNITION_TOLERANCE_MM:
        return None
    cylinder_edges = TopTools_IndexedMapOfShape()
    for face in cylinders:
        TopExp.MapShapes_s(face, TopAbs_EDGE, cylinder_edges)
    for face in blades:
        if _count(face, TopAbs_WIRE) != 1 or not all(
                cylinder_edges.Contains(edge) or BRep_Tool.IsClosed_s(TopoDS.Edge_s(edge), face)
                for edge in _explore(face, TopAbs_EDGE)):
            return None
    return _Hub(radius, z_bottom, z_top, blades)


def _z_axis_cylinder_radius(faces: list[TopoDS_Face]) -> float | None:
    radii = []
    for face in faces:
        cylinder = BRepAdaptor_Surface(face).Cylinder()
        direction, origin = cylinder.Axis().Direction(), cylinder.Axis().Location()
        if abs(abs(direction.Z()) - 1.0) > 1e-12 or math.hypot(origin.X(), origin.Y()) > RECOGNITION_TOLERANCE_MM:
            return None
        radii.append(cylinder.Radius())
    return radii[0] if max(radii) - min(radii) <= RECOGNITION_TOLERANCE_MM else None


def _end_disc_z(face: TopoDS_Face, radius: float) -> float | None:
    """z of a plane face that is a whole disc of ``radius`` about the z axis, else None."""
    plane = BRepAdaptor_Surface(face).Plane()
    if abs(abs(plane.Axis().Direction().Z()) - 1.0) > 1e-12 or _count(face, TopAbs_WIRE) != 1:
        return None
    for edge in _explore(face, TopAbs_EDGE):
        curve = BRepAdaptor_Curve(TopoDS.Edge_s(edge))
        if curve.GetType() != GeomAbs_Circle:
            return None
        circle = curve.Circle()
        centre = circle.Location()
        if (abs(circle.Radius() - radius) > RECOGNITION_TOLERANCE_MM
                or math.hypot(centre.X(), centre.Y()) > RECOGNITION_TOLERANCE_MM):
            return None
    return float(plane.Location().Z())


def _base_surface_and_angle(face: TopoDS_Face) -> tuple[Geom_BSplineSurface | None, float | None]:
    """The face's surface without its location, and the location's angle about z (radians);
    None for a surface that is not a plain B-spline or a location that is not such a rotation."""
    location = TopLoc_Location()
    surface = BRep_Tool.Surface_s(face, location)
    if not isinstance(surface, Geom_BSplineSurface) or surface.IsURational() or surface.IsVRational() \
            or surface.IsUPeriodic() or surface.IsVPeriodic():
        return None, None
    matrix = np.array([[location.Transformation().Value(row, column) for column in range(1, 5)]
                       for row in range(1, 4)])
    angle = math.atan2(matrix[1, 0], matrix[0, 0])
    rotation = np.array([[math.cos(angle), -math.sin(angle), 0.0, 0.0],
                         [math.sin(angle), math.cos(angle), 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return surface, (angle if np.abs(matrix - rotation).max() <= 1e-12 else None)


# -- one blade face ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class FaceIntegrals:
    """Integrals over the part outside r = R of one blade, from its face alone.

    Attributes:
        volume_mm3: volume outside the cylinder, mm^3.
        first_moment_mm4: ``(3,)`` ∫x, ∫y, ∫z dV over it, mm^4.
        spin_inertia_mm5: ∫ (x² + y²) dV over it, mm^5.
        area_mm2: the face's area, mm^2.
        footprint_area_mm2: area of the holes the blade leaves in the cylinder, mm^2.
        extremes_mm: ``(copies, 6)`` largest -x, x, -y, y, -z, z on each rotated copy of the face,
            mm (its extreme on the cylinder, if that is one, is inside the hub's box anyway).
        v_range: ``(2,)`` smallest a(u) and largest b(u) over the u Gauss points.
        u_range: ``(2,)`` the surface's u range (the face spans all of it).
    """

    volume_mm3: float
    first_moment_mm4: NDArray[np.float64]
    spin_inertia_mm5: float
    area_mm2: float
    footprint_area_mm2: float
    extremes_mm: NDArray[np.float64]
    v_range: NDArray[np.float64]
    u_range: NDArray[np.float64]


@dataclass(frozen=True)
class _Surface:
    """A non-rational B-spline surface as arrays: poles ``(nu, nv, 3)``, full knot vectors."""

    poles: NDArray[np.float64]
    u_knots: NDArray[np.float64]
    v_knots: NDArray[np.float64]
    u_degree: int
    v_degree: int
    geom: Geom_BSplineSurface


@dataclass(frozen=True)
class _Lines:
    """The surface's v lines at the u Gauss nodes: B-spline curves in v with poles ``(U, nv, 3)``,
    the poles of their u derivative (same shape) and of their v derivative ``(U, nv - 1, 3)``."""

    poles: NDArray[np.float64]
    u_derivative_poles: NDArray[np.float64]
    v_derivative_poles: NDArray[np.float64]


def _face_integrals(geom: Geom_BSplineSurface, reversed_face: bool, radius: float, angles: NDArray[np.float64],
                    gauss_points: int) -> FaceIntegrals | None:
    """Integrals of the face on ``geom`` trimmed to r > ``radius``, for copies rotated by
    ``angles`` (radians) about z; None unless every v line crosses r = radius exactly twice."""
    surface = _surface_arrays(geom)
    u_nodes, u_weights = _gauss_on_spans(surface.u_knots, surface.u_degree, gauss_points)
    lines = _v_lines(surface, u_nodes)
    roots = _crossings(lines, surface.v_knots, surface.v_degree, radius)
    if roots is None:
        return None
    rows, v_nodes, points, d_u, d_v, v_weights = _domain_samples(lines, surface, roots, gauss_points)
    normal = np.cross(d_u, d_v) * (-1.0 if reversed_face else 1.0)
    weight = u_weights[rows] * v_weights
    x, y, z = points.T
    r2 = x * x + y * y
    radial = weight * (x * normal[:, 0] + y * normal[:, 1])  # (x, y, 0) . n dA
    volume_k = 0.5 - radius**2 / (2.0 * r2)
    moment_k = (1.0 - radius**3 / (r2 * np.sqrt(r2))) / 3.0
    return FaceIntegrals(
        volume_mm3=float(radial @ volume_k),
        first_moment_mm4=np.array([radial @ (x * moment_k), radial @ (y * moment_k), radial @ (z * volume_k)]),
        spin_inertia_mm5=float(radial @ ((r2 - radius**4 / r2) / 4.0)),
        area_mm2=float(weight @ np.linalg.norm(normal, axis=1)),
        footprint_area_mm2=sum(_footprint_area(lines, root, u_weights, surface, radius) for root in roots.T),
        extremes_mm=_extremes(surface, points, u_nodes[rows], v_nodes, radius, angles),
        v_range=np.array([roots[:, 0].min(), roots[:, 1].max()]),
        u_range=np.array([surface.u_knots[0], surface.u_knots[-1]]))


def _bounds_match(face: TopoDS_Face, part: FaceIntegrals) -> bool:
    """The face's own parameter bounds (from its trimming curves) are the computed domain: the
    whole u range and v in [min a, max b]. Rules out a face that is some other piece."""
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face)
    u_span = part.u_range[1] - part.u_range[0]
    v_span = part.v_range[1] - part.v_range[0]
    return (abs(u_min - part.u_range[0]) <= U_BOUNDS_RELATIVE * u_span
            and abs(u_max - part.u_range[1]) <= U_BOUNDS_RELATIVE * u_span
            and abs(v_min - part.v_range[0]) <= V_BOUNDS_RELATIVE * v_span
            and abs(v_max - part.v_range[1]) <= V_BOUNDS_RELATIVE * v_span)


def _surface_arrays(geom: Geom_BSplineSurface) -> _Surface:
    nu, nv = geom.NbUPoles(), geom.NbVPoles()
    poles = np.array([[geom.Pole(i, j).Coord() for j in range(1, nv + 1)] for i in range(1, nu + 1)])
    return _Surface(poles, np.array(list(geom.UKnotSequence())), np.array(list(geom.VKnotSequence())),
                    geom.UDegree(), geom.VDegree(), geom)


def _v_lines(surface: _Surface, u_nodes: NDArray[np.float64]) -> _Lines:
    d_poles, d_knots, d_degree = _derivative_poles(surface.poles, surface.u_knots, surface.u_degree)
    poles = np.einsum("ai,ijc->ajc", _basis(u_nodes, surface.u_knots, surface.u_degree), surface.poles)
    v_poles, _, _ = _derivative_poles(poles, surface.v_knots, surface.v_degree, axis=1)
    return _Lines(poles, np.einsum("ai,ijc->ajc", _basis(u_nodes, d_knots, d_degree), d_poles), v_poles)


def _crossings(lines: _Lines, knots: NDArray[np.float64], degree: int, radius: float) -> NDArray[np.float64] | None:
    """``(U, 2)``: the two v where each v line crosses r = ``radius``; None unless every line
    starts and ends inside (r < radius) and crosses exactly twice."""
    spans = np.unique(knots[degree:-degree])
    grid = np.concatenate([np.linspace(low, high, ROOT_SAMPLES_PER_SPAN, endpoint=False)
                           for low, high in zip(spans[:-1], spans[1:])] + [spans[-1:]])
    samples = np.matmul(_basis(grid, knots, degree), lines.poles[..., :2])  # (U, samples, 2)
    excess = (samples**2).sum(axis=-1) - radius**2  # r^2 - R^2
    change = np.signbit(excess[:, :-1]) != np.signbit(excess[:, 1:])
    if not (np.all(change.sum(axis=1) == 2) and np.all(excess[:, 0] < 0.0) and np.all(excess[:, -1] < 0.0)):
        return None
    rows, columns = np.nonzero(change)  # row-major: each line's lower crossing first
    low, high = grid[columns], grid[columns + 1]
    f_low, f_high = excess[rows, columns], excess[rows, columns + 1]
    v = low + (high - low) * f_low / (f_low - f_high)
    for _ in range(60):  # Newton, kept inside the bracket (bisection where it would leave it)
        point, _, tangent = _evaluate(lines, rows, v, knots, degree, u_derivative=False)
        f = (point[:, :2] ** 2).sum(axis=1) - radius**2
        slope = 2.0 * (point[:, :2] * tangent[:, :2]).sum(axis=1)
        same_side = np.signbit(f) == np.signbit(f_low)
        low, high = np.where(same_side, v, low), np.where(same_side, high, v)
        proposal = v - f / np.where(slope != 0.0, slope, np.inf)
        proposal = np.where((proposal >= low) & (proposal <= high), proposal, (low + high) / 2.0)
        converged = np.abs(proposal - v).max() <= 1e-13 * (knots[-1] - knots[0])
        v = proposal
        if converged:
            return v.reshape(-1, 2)
    return None


def _domain_samples(lines: _Lines, surface: _Surface, roots: NDArray[np.float64], gauss_points: int):
    """Gauss nodes of the trimmed domain: per v knot span clipped to [a(u), b(u)] on every u line.

    Returns the u line index, v, point, d/du, d/dv and v weight of every node. Whole spans
    are evaluated as a tensor product (one matrix product per quantity); the spans cut by
    a(u) or b(u) one node at a time.
    """
    knots, degree = surface.v_knots, surface.v_degree
    spans = np.unique(knots[degree:-degree])
    x, w = np.polynomial.legendre.leggauss(gauss_points)
    low = np.clip(spans[:-1][None, :], roots[:, :1], roots[:, 1:])  # (U, spans)
    high = np.clip(spans[1:][None, :], roots[:, :1], roots[:, 1:])
    whole = (low == spans[:-1]) & (high == spans[1:])
    cut = (high > low) & ~whole
    # Whole spans: the same v nodes on every line.
    full_v = (spans[:-1, None] + np.diff(spans)[:, None] * (x + 1.0) / 2.0).ravel()
    full_w = (np.diff(spans)[:, None] * w / 2.0).ravel()
    basis, d_basis = _basis(full_v, knots, degree), _basis(full_v, knots[1:-1], degree - 1)
    lines_whole, spans_whole = np.nonzero(whole)
    take = (spans_whole[:, None] * gauss_points + np.arange(gauss_points)).ravel()
    rows_whole = np.repeat(lines_whole, gauss_points)
    point = np.matmul(basis, lines.poles)[rows_whole, take]
    d_u = np.matmul(basis, lines.u_derivative_poles)[rows_whole, take]
    d_v = np.matmul(d_basis, lines.v_derivative_poles)[rows_whole, take]
    # Cut spans: their own nodes.
    lines_cut, spans_cut = np.nonzero(cut)
    start, length = low[lines_cut, spans_cut], (high - low)[lines_cut, spans_cut]
    cut_v = (start[:, None] + length[:, None] * (x + 1.0) / 2.0).ravel()
    rows_cut = np.repeat(lines_cut, gauss_points)
    cut_point, cut_d_u, cut_d_v = _evaluate(lines, rows_cut, cut_v, knots, degree)
    return (np.concatenate([rows_whole, rows_cut]), np.concatenate([full_v[take], cut_v]),
            np.concatenate([point, cut_point]), np.concatenate([d_u, cut_d_u]), np.concatenate([d_v, cut_d_v]),
            np.concatenate([full_w[take], (length[:, None] * w / 2.0).ravel()]))


def _evaluate(lines: _Lines, rows: NDArray[np.int64], v: NDArray[np.float64], knots: NDArray[np.float64],
              degree: int, u_derivative: bool = True):
    """Point, d/du (None unless ``u_derivative``) and d/dv of line ``rows[i]`` at ``v[i]``, each ``(m, 3)``."""
    columns, values = _local_basis(v, knots, degree)
    d_columns, d_values = _local_basis(v, knots[1:-1], degree - 1)
    point = np.einsum("ml,mlc->mc", values, lines.poles[rows[:, None], columns])
    d_v = np.einsum("ml,mlc->mc", d_values, lines.v_derivative_poles[rows[:, None], d_columns])
    d_u = np.einsum("ml,mlc->mc", values, lines.u_derivative_poles[rows[:, None], columns]) if u_derivative else None
    return point, d_u, d_v


def _footprint_area(lines: _Lines, root: NDArray[np.float64], u_weights: NDArray[np.float64],
                    surface: _Surface, radius: float) -> float:
    """Area of the hole a crossing curve v = root(u) cuts in the cylinder: R |∮ z dθ|.

    Along the curve v'(u) = -∂u(r²)/∂v(r²), and dθ = (x dy - y dx) / r²; the curve is closed
    (u runs once around the section, both ends at the trailing edge)."""
    point, d_u, d_v = _evaluate(lines, np.arange(len(root)), root, surface.v_knots, surface.v_degree)
    x, y, z = point.T
    slope = -(x * d_u[:, 0] + y * d_u[:, 1]) / (x * d_v[:, 0] + y * d_v[:, 1])
    tangent = d_u + d_v * slope[:, None]
    d_theta = (x * tangent[:, 1] - y * tangent[:, 0]) / (x * x + y * y)
    return radius * abs(float(u_weights @ (z * d_theta)))


def _extremes(surface: _Surface, points: NDArray[np.float64], u: NDArray[np.float64], v: NDArray[np.float64],
              radius: float, angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(copies, 6)``: the largest -x, x, -y, y, -z, z of each copy of the face rotated by
    ``angles``, i.e. the face's support in the directions rotated back: the best integration
    node, refined by Newton on the surface. A refinement that ends inside r < R is dropped:
    the face's extreme then lies on its boundary on the cylinder, inside the hub's box."""
    cos, sin = np.cos(angles), np.sin(angles)
    extremes = np.empty((len(angles), 6))
    u_range = (float(surface.u_knots[0]), float(surface.u_knots[-1]))
    for copy in range(len(angles)):
        back = np.array([[cos[copy], sin[copy], 0.0], [-sin[copy], cos[copy], 0.0], [0.0, 0.0, 1.0]])
        directions = _BOX_DIRECTIONS @ back.T  # rotated by -angle
        values = points @ directions.T
        best = values.argmax(axis=0)
        for index, direction in enumerate(directions):
            start = best[index]
            refined = _newton_maximum(surface.geom, direction, float(u[start]), float(v[start]), u_range, radius)
            extremes[copy, index] = max(values[start, index], -np.inf if refined is None else refined)
    return extremes


def _newton_maximum(geom: Geom_BSplineSurface, direction: NDArray[np.float64], u: float, v: float,
                    u_range: tuple[float, float], radius: float) -> float | None:
    """Local maximum of direction . S(u, v) near (u, v) by Newton (u kept in its range), if it
    converges to a point outside the cylinder; else None."""
    point, d_u, d_v, d_uu, d_vv, d_uv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
    axis = gp_Vec(*(float(value) for value in direction))
    for _ in range(30):
        geom.D2(u, v, point, d_u, d_v, d_uu, d_vv, d_uv)
        gradient = np.array([d_u.Dot(axis), d_v.Dot(axis)])
        hessian = np.array([[d_uu.Dot(axis), d_uv.Dot(axis)], [d_uv.Dot(axis), d_vv.Dot(axis)]])
        on_edge = (u <= u_range[0] and gradient[0] < 0.0) or (u >= u_range[1] and gradient[0] > 0.0)
        if on_edge:  # the maximum lies on the trailing edge (u at an end): Newton in v alone
            if hessian[1, 1] >= 0.0:
                return None
            step = np.array([0.0, -gradient[1] / hessian[1, 1]])
        elif np.linalg.det(hessian) <= 0.0 or hessian[0, 0] >= 0.0:
            return None  # not locally concave: no clean maximum to converge to
        else:
            step = -np.linalg.solve(hessian, gradient)
        u, v = float(np.clip(u + step[0], *u_range)), v + float(step[1])
        if np.abs(step).max() < 1e-13:
            geom.D0(u, v, point)
            return None if point.X() ** 2 + point.Y() ** 2 < radius**2 else float(gp_Vec(point.XYZ()).Dot(axis))
    return None


# -- B-spline helpers -------------------------------------------------------------------------------

def _design_matrix(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int):
    return BSpline.design_matrix(np.clip(x, knots[degree], knots[-degree - 1]), knots, degree)


def _basis(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int) -> NDArray[np.float64]:
    """Dense ``(len(x), n)`` B-spline basis (scipy's design matrix), x clipped into the knot range."""
    return _design_matrix(x, knots, degree).toarray()


def _local_basis(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int
                 ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The ``degree + 1`` basis functions that can be nonzero at each x: their indices and values,
    both ``(len(x), degree + 1)`` (scipy's design matrix stores exactly these per row)."""
    matrix = _design_matrix(x, knots, degree)
    return matrix.indices.reshape(len(x), degree + 1), matrix.data.reshape(len(x), degree + 1)


def _derivative_poles(poles: NDArray[np.float64], knots: NDArray[np.float64], degree: int, axis: int = 0
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Poles, knots and degree of the derivative along ``axis`` of a B-spline with these poles."""
    moved = np.moveaxis(poles, axis, 0)
    count = moved.shape[0]
    scale = degree / (knots[degree + 1:count + degree] - knots[1:count])
    derivative = (moved[1:] - moved[:-1]) * scale.reshape(-1, *([1] * (moved.ndim - 1)))
    return np.moveaxis(derivative, 0, axis), knots[1:-1], degree - 1


def _gauss_on_spans(knots: NDArray[np.float64], degree: int, points: int
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gauss-Legendre nodes and weights, ``points`` per nonzero knot span."""
    spans = np.unique(knots[degree:-degree])
    x, w = np.polynomial.legendre.leggauss(points)
    low, length = spans[:-1], np.diff(spans)
    return (low[:, None] + length[:, None] * (x + 1.0) / 2.0).ravel(), (length[:, None] * w / 2.0).ravel()


def _explore(shape: TopoDS_Shape, kind) -> list[TopoDS_Shape]:
    found, explorer = [], TopExp_Explorer(shape, kind)
    while explorer.More():
        found.append(explorer.Current())
        explorer.Next()
    return found


def _faces(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    return [TopoDS.Face_s(face) for face in _explore(shape, TopAbs_FACE)]


def _count(shape: TopoDS_Shape, kind) -> int:
    return len(_explore(shape, kind))
