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
  f = x² + y² (the spin-axis inertia): k = (r² - R⁴/r²)/4; and for the balance's products
  f = xz (yz): k = xz (yz) (1 - R³/r³)/3, f = xy, x² - y²: k = xy, x² - y² times (1 - R⁴/r⁴)/4.
* **The trimmed domain from the surface, not from OpenCascade's trimming curves.** Along each
  v line (u fixed; u runs around the section, v along the span) the part outside the hub is
  v in [a(u), b(u)], the two roots of r(u, v) = R, found by sampling and safeguarded Newton.
* **Gauss-Legendre per knot span**: whole spans as a tensor product, the two spans cut by a(u)
  and b(u) on their own. The integrands are smooth on every piece, so 4 points per span give
  ~4e-10 relative on the default propeller against BRepGProp at 1e-9.
* **The hub's lateral area** is 2πRL less the blade footprints, each R |∮ z dθ| along the root
  and the tip curve (a line integral at the same u Gauss points, summed over the blade's faces).
* **Once per blade shape**: the blades are copies of one face rotated about z. Volume, area,
  z moment and spin-axis inertia do not change under that rotation; the x, y moments and
  (∫xz, ∫yz) rotate as vectors, (∫(x² - y²), 2∫xy) by twice the angle, and the box of each copy
  is the face's support in rotated directions.

OpenCascade's adaptive integration subdivides every trimmed face from scratch and costs far
more (``python scripts/bench.py`` prints both). Whenever the shape is not recognised as a hub
with such blade faces (an end face crossed by a blade, a rational or periodic surface, a blade
re-entering the hub, a fillet, a bore...), :func:`hub_with_blade_integrals` returns None and the
caller integrates with BRepGProp.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineSurface
from OCP.GeomAbs import (
    GeomAbs_BSplineSurface,
    GeomAbs_Circle,
    GeomAbs_Cylinder,
    GeomAbs_Plane,
)
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import (
    TopAbs_EDGE,
    TopAbs_REVERSED,
    TopAbs_SOLID,
    TopAbs_WIRE,
)
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape
from scipy.interpolate import BSpline

from torus_cad.kernel.topology import count, explore, faces

_Array = NDArray[np.float64]

#: Integrands at surface points: (points, d/du, d/dv), each (n, 3) -> (n, 6).
_Integrands = Callable[[_Array, _Array, _Array], _Array]

#: Gauss-Legendre points per knot span, in u and in v. On the default propeller 4 x 4 is
#: ~4e-10 relative in volume (as 8 x 8: the rest is the B-rep's own trimming curves), 3 x 3 ~8e-9.
GAUSS_POINTS_PER_SPAN = 4

#: Adaptive integration over u: an interval's Gauss rules of GAUSS_POINTS_PER_SPAN and one point
#: less must agree to this fraction of each quantity times the interval's share of the u range,
#: else the interval is halved, at most U_MAX_HALVINGS times (then BRepGProp takes over).
U_RELATIVE_TOLERANCE, U_MAX_HALVINGS = 1e-6, 12

#: The same along each v line, relative to the line's own integrals.
V_RELATIVE_TOLERANCE, V_MAX_HALVINGS = 1e-6, 12

#: Quantities integrated along each v line: volume, x, y, z moments, spin-axis inertia, area,
#: the root and tip footprints' line densities, then ∫xz, ∫yz, ∫xy, ∫(x² - y²).
_QUANTITIES = 12

#: Integrated over the face (v, then u): the _QUANTITIES but the footprints'.
_INTEGRANDS = _QUANTITIES - 2

#: Box: the copies whose best integration node along a direction comes within this fraction of
#: the face's extent of the best copy's are refined on the surface (the nodes are far closer);
#: about BOX_START_NODES evenly picked integration nodes are the candidate starts.
BOX_REFINE_MARGIN, BOX_START_NODES = 0.02, 8000

#: Steps of the ascent that refines a box extreme on the surface.
ASCENT_ITERATIONS = 100

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
        products_mm5: ``(3,)`` ∫xz, ∫yz, ∫xy dV about the origin, mm^5.
    """

    volume_mm3: float
    centroid_mm: NDArray[np.float64]
    spin_inertia_mm5: float
    area_mm2: float
    box_min_mm: NDArray[np.float64]
    box_max_mm: NDArray[np.float64]
    products_mm5: NDArray[np.float64]


@dataclass(frozen=True)
class _Hub:
    radius: float
    z_bottom: float
    z_top: float
    blade_faces: list[TopoDS_Face]


def hub_with_blade_integrals(shape: TopoDS_Shape,
                             gauss_points: int = GAUSS_POINTS_PER_SPAN) -> HubWithBladeIntegrals | None:
    """Volume, centroid, spin-axis inertia, area, box and products of a hub-with-blades solid, or
    None when ``shape`` is not one (see the module's docstring).

    The last shape's answer is kept: the JSON report asks for the mass properties and the
    balance of the same solid, one after the other.
    """
    last_shape, last_points, last_answer = _LAST[0]
    if last_shape is not None and last_points == gauss_points and last_shape.IsEqual(shape):
        return last_answer
    answer = _integrate(shape, gauss_points)
    _LAST[0] = (shape, gauss_points, answer)
    return answer


#: The last (shape, gauss points, answer) of :func:`hub_with_blade_integrals`.
_LAST: list[tuple[TopoDS_Shape | None, int, HubWithBladeIntegrals | None]] = [(None, 0, None)]


def _integrate(shape: TopoDS_Shape, gauss_points: int) -> HubWithBladeIntegrals | None:
    hub = _recognise(shape)
    if hub is None:
        return None
    radius, length = hub.radius, hub.z_top - hub.z_bottom
    volume = math.pi * radius**2 * length
    moment = np.array([0.0, 0.0, volume * (hub.z_top + hub.z_bottom) / 2.0])
    inertia = math.pi * radius**4 * length / 2.0
    products = np.zeros(3)  # the hub's are 0: it is symmetric about its axis
    area = 2.0 * math.pi * radius**2 + 2.0 * math.pi * radius * length
    box_max = np.array([radius, radius, radius, radius, -hub.z_bottom, hub.z_top])  # along _BOX_DIRECTIONS
    groups: dict[tuple[int, bool], list[tuple[TopoDS_Face, float]]] = {}
    surfaces: dict[tuple[int, bool], Geom_BSplineSurface] = {}
    footprints = np.zeros(2)  # one blade's, summed over its faces (signed)
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
        area += count * part.area_mm2
        footprints += part.footprints_mm2
        box_max = np.maximum(box_max, part.extremes_mm)
        products += _rotated_products(part.second_moments_mm5, angles)
    if len({len(members) for members in groups.values()}) != 1:
        return None  # not every face has a copy on every blade
    area -= len(next(iter(groups.values()))) * float(np.abs(footprints).sum())
    return HubWithBladeIntegrals(volume, moment / volume, inertia, area, -box_max[0::2], box_max[1::2], products)


def _rotated_products(second_moments: NDArray[np.float64], angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """(∫xz, ∫yz, ∫xy) summed over copies rotated by ``angles`` about z, from one copy's
    (∫xz, ∫yz, ∫xy, ∫(x² - y²)): (xz, yz) turns by the angle, (x² - y², 2 xy) by twice it."""
    xz, yz, xy, difference = second_moments
    cos, sin = np.cos(angles).sum(), np.sin(angles).sum()
    cos2, sin2 = np.cos(2.0 * angles).sum(), np.sin(2.0 * angles).sum()
    return np.array([cos * xz - sin * yz, sin * xz + cos * yz, (sin2 * difference + cos2 * 2.0 * xy) / 2.0])


# -- recognising the shape ----------------------------------------------------------------------

def _recognise(shape: TopoDS_Shape) -> _Hub | None:
    """The hub's radius and end planes and the blade faces, or None unless ``shape`` is one solid
    made of z-axis cylinder faces of one radius, two whole end discs and B-spline faces bounded
    only by the cylinder's edges, their own seam and the edges between two of them (a blade side
    in lower and upper faces meets itself at the leading and trailing edges; each face is still
    integrated over its whole u range, trimmed in v by the cylinder)."""
    if count(shape, TopAbs_SOLID) != 1:
        return None
    by_kind: dict[object, list[TopoDS_Face]] = {}
    for face in faces(shape):
        by_kind.setdefault(BRepAdaptor_Surface(face).GetType(), []).append(face)
    cylinders, planes, blades = (by_kind.pop(kind, []) for kind in (GeomAbs_Cylinder, GeomAbs_Plane,
                                                                     GeomAbs_BSplineSurface))
    if by_kind or not cylinders or len(planes) != 2 or not blades:
        return None
    radius = _z_axis_cylinder_radius(cylinders)
    if radius is None:
        return None
    ends = [z for z in (_end_disc_z(face, radius) for face in planes) if z is not None]
    if len(ends) != 2:
        return None
    z_bottom, z_top = sorted(ends)
    if z_top - z_bottom <= RECOGNITION_TOLERANCE_MM:
        return None
    cylinder_edges = TopTools_IndexedMapOfShape()
    for face in cylinders:
        TopExp.MapShapes_s(face, TopAbs_EDGE, cylinder_edges)
    for face in blades:
        if count(face, TopAbs_WIRE) != 1 or not all(
                cylinder_edges.Contains(edge) or BRep_Tool.IsClosed_s(TopoDS.Edge_s(edge), face)
                or _between_blade_faces(edge, blades) for edge in explore(face, TopAbs_EDGE)):
            return None
    return _Hub(radius, z_bottom, z_top, blades)


def _between_blade_faces(edge: TopoDS_Shape, blades: list[TopoDS_Face]) -> bool:
    """Whether ``edge`` bounds two of the blade faces (the side's faces meet there, inside the blade's boundary)."""
    return sum(1 for face in blades if any(edge.IsSame(own) for own in explore(face, TopAbs_EDGE))) == 2


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
    if abs(abs(plane.Axis().Direction().Z()) - 1.0) > 1e-12 or count(face, TopAbs_WIRE) != 1:
        return None
    for edge in explore(face, TopAbs_EDGE):
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
        footprints_mm2: ``(2,)`` R ∫ z dθ along the face's root and tip crossing curves, mm^2,
            signed: summed over the faces of one blade, their absolute values are the areas of the
            holes the blade leaves in the cylinder (one face: the whole closed curve).
        second_moments_mm5: ``(4,)`` ∫xz, ∫yz, ∫xy, ∫(x² - y²) dV over it, mm^5.
        extremes_mm: ``(6,)`` largest -x, x, -y, y, -z, z over the rotated copies of the face, mm
            (an extreme on the cylinder, if that is one, is inside the hub's box anyway).
        v_range: ``(2,)`` smallest a(u) and largest b(u) over the u Gauss points.
        u_range: ``(2,)`` the surface's u range (the face spans all of it).
    """

    volume_mm3: float
    first_moment_mm4: NDArray[np.float64]
    spin_inertia_mm5: float
    second_moments_mm5: NDArray[np.float64]
    area_mm2: float
    footprints_mm2: NDArray[np.float64]
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
    integrated = _integrate_over_u(surface, radius, reversed_face, gauss_points)
    if integrated is None:
        return None
    totals, samples = integrated
    volume, moment_x, moment_y, moment_z, inertia, area, root_footprint, tip_footprint = totals[:8]
    points = np.concatenate([sample.points for sample in samples])
    return FaceIntegrals(
        volume_mm3=float(volume), first_moment_mm4=np.array([moment_x, moment_y, moment_z]),
        spin_inertia_mm5=float(inertia), second_moments_mm5=totals[8:].copy(), area_mm2=float(area),
        footprints_mm2=np.array([root_footprint, tip_footprint]),
        extremes_mm=_extremes(surface, points, np.concatenate([sample.u for sample in samples]),
                              np.concatenate([sample.v for sample in samples]), radius, angles),
        v_range=np.array([min(sample.roots[:, 0].min() for sample in samples),
                          max(sample.roots[:, 1].max() for sample in samples)]),
        u_range=np.array([surface.u_knots[0], surface.u_knots[-1]]))


def _integrate_over_u(surface: _Surface, radius: float, reversed_face: bool, gauss_points: int
                      ) -> tuple[NDArray[np.float64], list[_LineSamples]] | None:
    """∫ over u of :func:`_line_densities`, adaptively: on each interval (at first the knot
    spans) Gauss rules of ``gauss_points`` and one point less; where they differ by more than
    U_RELATIVE_TOLERANCE the interval is halved. The v integral at fixed u is smooth, but where
    a crossing curve runs nearly along v (a blade entering the hub at a grazing angle) the
    domain's edge b(u) is steep, and so is the integral as a function of u."""
    spans = np.unique(surface.u_knots[surface.u_degree:-surface.u_degree])
    low, high = spans[:-1], spans[1:]
    rules = [np.polynomial.legendre.leggauss(points) for points in (gauss_points, gauss_points - 1)]
    totals, scale, kept = np.zeros(_QUANTITIES), None, []
    for _ in range(U_MAX_HALVINGS + 1):
        nodes = [(low[:, None] + (high - low)[:, None] * (x + 1.0) / 2.0).ravel() for x, _ in rules]
        sample = _line_densities(surface, np.concatenate(nodes), radius, reversed_face, gauss_points)
        if sample is None:
            return None
        kept.append(sample)
        fine_count = nodes[0].size
        estimates = [((high - low)[:, None, None] * w[None, :, None] / 2.0
                      * values.reshape(len(low), len(w), _QUANTITIES)).sum(axis=1)
                     for (_, w), values in zip(rules, (sample.densities[:fine_count], sample.densities[fine_count:]))]
        if scale is None:  # the size of each quantity, for relative errors (moments may sum to ~0)
            scale = np.maximum(np.abs(estimates[0]).sum(axis=0), np.finfo(float).tiny)
        error = (np.abs(estimates[0] - estimates[1]) / scale).max(axis=1)
        done = error <= U_RELATIVE_TOLERANCE * (high - low) / (spans[-1] - spans[0])
        totals += estimates[0][done].sum(axis=0)
        middle = (low + high)[~done] / 2.0
        low, high = np.concatenate([low[~done], middle]), np.concatenate([middle, high[~done]])
        if not len(low):
            return totals, kept
    return None


@dataclass(frozen=True)
class _LineSamples:
    """What the v lines at some u give: per line ``densities`` ``(k, 8)`` (the v integrals of
    the _QUANTITIES, per unit u) and ``roots`` ``(k, 2)``; the integration nodes' ``points``
    ``(n, 3)`` and their ``u``, ``v`` ``(n,)`` (kept for the box)."""

    densities: NDArray[np.float64]
    roots: NDArray[np.float64]
    points: NDArray[np.float64]
    u: NDArray[np.float64]
    v: NDArray[np.float64]


def _line_densities(surface: _Surface, u: NDArray[np.float64], radius: float, reversed_face: bool,
                    gauss_points: int) -> _LineSamples | None:
    """Along the v line at each ``u``, the integrals over v in [a(u), b(u)] of the volume, the
    x, y, z moments, the spin inertia and the area densities (see the module), and the two
    footprints' line densities R z dθ/du at a(u) and b(u). None unless every line crosses
    r = ``radius`` exactly twice."""
    lines = _v_lines(surface, u)
    roots = _crossings(lines, surface.v_knots, surface.v_degree, radius)
    if roots is None:
        return None
    sign = -1.0 if reversed_face else 1.0
    integrals = _v_integrals(lines, surface, roots, lambda point, d_u, d_v: _integrands(point, d_u, d_v, radius, sign),
                             gauss_points)
    if integrals is None:
        return None
    line_integrals, points, rows, v_nodes = integrals
    densities = np.zeros((len(u), _QUANTITIES))
    densities[:, :6], densities[:, 8:] = line_integrals[:, :6], line_integrals[:, 6:]
    for column, root in enumerate(roots.T):
        densities[:, 6 + column] = _footprint_density(lines, root, surface, radius)
    return _LineSamples(densities, roots, points, u[rows], v_nodes)


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
                           for low, high in itertools.pairwise(spans)] + [spans[-1:]])
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


def _integrands(points: NDArray[np.float64], d_u: NDArray[np.float64], d_v: NDArray[np.float64], radius: float,
                sign: float) -> NDArray[np.float64]:
    """``(n, _INTEGRANDS)``: the volume, x, y, z moment, spin inertia, area, xz, yz, xy and
    x² - y² integrands per du dv at surface points with these derivatives (``sign`` -1 for a
    reversed face)."""
    normal = np.cross(d_u, d_v) * sign
    x, y, z = points.T
    r2 = x * x + y * y
    radial = x * normal[:, 0] + y * normal[:, 1]  # (x, y, 0) . n
    volume_k = 0.5 - radius**2 / (2.0 * r2)
    moment_k = (1.0 - radius**3 / (r2 * np.sqrt(r2))) / 3.0
    second_k = (1.0 - radius**4 / (r2 * r2)) / 4.0
    return np.column_stack([radial * volume_k, radial * x * moment_k, radial * y * moment_k,
                            radial * z * volume_k, radial * r2 * second_k, np.linalg.norm(normal, axis=1),
                            radial * x * z * moment_k, radial * y * z * moment_k, radial * x * y * second_k,
                            radial * (x * x - y * y) * second_k])


def _v_integrals(lines: _Lines, surface: _Surface, roots: NDArray[np.float64], integrands: _Integrands,
                 gauss_points: int) -> tuple[_Array, _Array, NDArray[np.int64], _Array] | None:
    """The integrals over v in [a(u), b(u)] of ``integrands`` on every line, adaptively.

    The pieces are the v knot spans clipped to [a, b] (a smooth integrand on each); each gets
    Gauss rules of ``gauss_points`` and one point less and is halved where they differ by
    more than V_RELATIVE_TOLERANCE of the line's total times the piece's share of [a, b]. The
    first round evaluates the whole spans as a tensor product (one matrix product per
    quantity, the same v nodes on every line), everything else node by node.

    Returns the ``(U, _INTEGRANDS)`` integrals and the nodes' points ``(n, 3)``, line index and v, or
    None if some piece needs more than V_MAX_HALVINGS halvings.
    """
    knots, degree = surface.v_knots, surface.v_degree
    spans = np.unique(knots[degree:-degree])
    rules = [np.polynomial.legendre.leggauss(points) for points in (gauss_points, gauss_points - 1)]
    low = np.clip(spans[:-1][None, :], roots[:, :1], roots[:, 1:])  # (U, spans)
    high = np.clip(spans[1:][None, :], roots[:, :1], roots[:, 1:])
    whole = (low == spans[:-1]) & (high == spans[1:])
    lines_whole, spans_whole = np.nonzero(whole)
    lines_cut, spans_cut = np.nonzero((high > low) & ~whole)
    row = np.concatenate([lines_whole, lines_cut])
    start = np.concatenate([spans[spans_whole], low[lines_cut, spans_cut]])
    length = np.concatenate([np.diff(spans)[spans_whole], (high - low)[lines_cut, spans_cut]])
    domain = roots[:, 1] - roots[:, 0]
    totals, scale = np.zeros((len(roots), _INTEGRANDS)), None
    kept: list[tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]] = []
    for round_ in range(V_MAX_HALVINGS + 1):
        estimates = []
        for x, w in rules:
            v = (start[:, None] + length[:, None] * (x + 1.0) / 2.0).ravel()
            rows = np.repeat(row, len(x))
            if round_ == 0:  # whole spans: a tensor product, the rest node by node
                split = len(lines_whole) * len(x)
                point, d_u, d_v = _tensor_evaluate(lines, spans, x, knots, degree, lines_whole, spans_whole)
                cut = _evaluate(lines, rows[split:], v[split:], knots, degree)
                point, d_u, d_v = (np.concatenate(pair) for pair in zip((point, d_u, d_v), cut))
            else:
                point, d_u, d_v = _evaluate(lines, rows, v, knots, degree)
            values = integrands(point, d_u, d_v).reshape(len(row), len(x), _INTEGRANDS)
            estimates.append((length[:, None, None] * w[None, :, None] / 2.0 * values).sum(axis=1))
            if len(x) == gauss_points:
                kept.append((point, rows, v))
        if scale is None:  # each line's size of each quantity, for relative errors
            scale = np.zeros_like(totals)
            np.add.at(scale, row, np.abs(estimates[0]))
            scale = np.maximum(scale, np.finfo(float).tiny)
        error = (np.abs(estimates[0] - estimates[1]) / scale[row]).max(axis=1)
        done = error <= V_RELATIVE_TOLERANCE * length / domain[row]
        np.add.at(totals, row[done], estimates[0][done])
        row, start, length = (np.concatenate([values[~done]] * 2) for values in (row, start, length / 2.0))
        start[len(start) // 2:] += length[len(start) // 2:]
        if not len(row):
            points, rows, v = (np.concatenate(parts) for parts in zip(*kept))
            return totals, points, rows, v
    return None


def _tensor_evaluate(lines: _Lines, spans: NDArray[np.float64], x: NDArray[np.float64], knots: NDArray[np.float64],
                     degree: int, line_index: NDArray[np.int64], span_index: NDArray[np.int64]
                     ) -> tuple[_Array, _Array, _Array]:
    """Point, d/du, d/dv at the Gauss nodes ``x`` (on [-1, 1]) of the v knot spans ``span_index``
    of lines ``line_index``: each ``(len(line_index) * len(x), 3)``, node-major per piece."""
    nodes = (spans[:-1, None] + np.diff(spans)[:, None] * (x + 1.0) / 2.0).ravel()
    basis, d_basis = _basis(nodes, knots, degree), _basis(nodes, knots[1:-1], degree - 1)
    take = (span_index[:, None] * len(x) + np.arange(len(x))).ravel()
    rows = np.repeat(line_index, len(x))
    return (np.matmul(basis, lines.poles)[rows, take], np.matmul(basis, lines.u_derivative_poles)[rows, take],
            np.matmul(d_basis, lines.v_derivative_poles)[rows, take])


def _evaluate(lines: _Lines, rows: NDArray[np.int64], v: NDArray[np.float64], knots: NDArray[np.float64],
              degree: int, u_derivative: bool = True) -> tuple[_Array, _Array, _Array]:
    """Point, d/du (zeros unless ``u_derivative``) and d/dv of line ``rows[i]`` at ``v[i]``, each ``(m, 3)``."""
    columns, values = _local_basis(v, knots, degree)
    d_columns, d_values = _local_basis(v, knots[1:-1], degree - 1)
    point = np.einsum("ml,mlc->mc", values, lines.poles[rows[:, None], columns])
    d_v = np.einsum("ml,mlc->mc", d_values, lines.v_derivative_poles[rows[:, None], d_columns])
    d_u = (np.einsum("ml,mlc->mc", values, lines.u_derivative_poles[rows[:, None], columns]) if u_derivative
           else np.zeros_like(point))
    return point, d_u, d_v


def _footprint_density(lines: _Lines, root: NDArray[np.float64], surface: _Surface,
                       radius: float) -> NDArray[np.float64]:
    """R z dθ/du along a crossing curve v = root(u): integrated over u, ± the area of the hole
    the curve cuts in the cylinder (R ∮ z dθ; the curve is closed, u runs once around the
    section and both ends are at the trailing edge). Along the curve v'(u) = -∂u(r²)/∂v(r²),
    and dθ = (x dy - y dx) / r²."""
    point, d_u, d_v = _evaluate(lines, np.arange(len(root)), root, surface.v_knots, surface.v_degree)
    x, y, z = point.T
    slope = -(x * d_u[:, 0] + y * d_u[:, 1]) / (x * d_v[:, 0] + y * d_v[:, 1])
    tangent = d_u + d_v * slope[:, None]
    return radius * z * (x * tangent[:, 1] - y * tangent[:, 0]) / (x * x + y * y)


def _extremes(surface: _Surface, points: NDArray[np.float64], u: NDArray[np.float64], v: NDArray[np.float64],
              radius: float, angles: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(6,)``: the largest -x, x, -y, y, -z, z over the copies of the face rotated by ``angles``.

    A copy's extreme along a direction is the face's support along that direction rotated
    back: the best integration node, refined on the surface (:func:`_refined_maximum`) for the
    copies whose best node comes within BOX_REFINE_MARGIN of the best copy's. A refinement that
    ends inside r < R is dropped: the face's extreme then lies on its boundary on the
    cylinder, inside the hub's box."""
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    x, y, z = _BOX_DIRECTIONS.T
    directions = np.stack([cos * x + sin * y, -sin * x + cos * y, np.broadcast_to(z, (len(angles), 6))],
                          axis=-1)  # (copies, 6, 3): each box direction rotated by -angle
    step = max(1, len(points) // BOX_START_NODES)  # the nodes are far denser than the refinement needs
    points, u, v = points[::step], u[::step], v[::step]
    values = points @ directions.reshape(-1, 3).T  # (nodes, copies * 6)
    best = values.argmax(axis=0).reshape(len(angles), 6)
    best_values = values[best.ravel(), np.arange(values.shape[1])].reshape(len(angles), 6)
    margin = BOX_REFINE_MARGIN * float((points.max(axis=0) - points.min(axis=0)).max())
    bounds = ((float(surface.u_knots[0]), float(surface.u_knots[-1])),
              (float(surface.v_knots[0]), float(surface.v_knots[-1])))
    extremes = best_values.max(axis=0)
    for copy, side in zip(*np.nonzero(best_values >= extremes - margin), strict=True):
        start = best[copy, side]
        refined = _refined_maximum(surface.geom, directions[copy, side], float(u[start]), float(v[start]), bounds,
                                   radius)
        if refined is not None:
            extremes[side] = max(extremes[side], refined)
    return extremes


def _refined_maximum(geom: Geom_BSplineSurface, direction: NDArray[np.float64], u: float, v: float,
                     bounds: tuple[tuple[float, float], tuple[float, float]], radius: float) -> float | None:
    """The local maximum of direction . S(u, v) from (u, v) in the surface's parameter box, if
    it lies outside the cylinder; else None.

    Projected ascent: a parameter at its bound with the gradient pushing out is held there;
    the free ones take a Newton step (second derivatives from OpenCascade) where the function
    is concave in them, else a gradient step of a growing length; every step is halved until
    the function does not decrease."""
    point, d_u, d_v, d_uu, d_vv, d_uv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
    axis = gp_Vec(*(float(value) for value in direction))
    low, high = np.array(bounds).T
    uv, reach = np.array([u, v]), 1e-2 * float((high - low).min())

    def support(at: NDArray[np.float64]) -> float:
        geom.D0(float(at[0]), float(at[1]), point)
        return float(gp_Vec(point.XYZ()).Dot(axis))

    for _ in range(ASCENT_ITERATIONS):
        geom.D2(float(uv[0]), float(uv[1]), point, d_u, d_v, d_uu, d_vv, d_uv)
        value = float(gp_Vec(point.XYZ()).Dot(axis))
        gradient = np.array([d_u.Dot(axis), d_v.Dot(axis)])
        hessian = np.array([[d_uu.Dot(axis), d_uv.Dot(axis)], [d_uv.Dot(axis), d_vv.Dot(axis)]])
        free = ~(((uv <= low) & (gradient < 0.0)) | ((uv >= high) & (gradient > 0.0)))
        if not free.any():
            break  # a corner of the parameter box
        step = np.zeros(2)
        block = hessian[np.ix_(free, free)]
        if np.all(np.linalg.eigvalsh(block) < 0.0):
            step[free] = -np.linalg.solve(block, gradient[free])
        else:
            step[free] = gradient[free] * reach / np.linalg.norm(gradient[free])
            reach *= 2.0
        for _ in range(60):
            candidate = np.clip(uv + step, low, high)
            if support(candidate) >= value:
                break
            step /= 2.0
        else:
            break
        moved = np.abs(candidate - uv).max()
        uv = candidate
        if moved <= 1e-14:
            break
    return _support_outside(geom, axis, uv, radius)


def _support_outside(geom: Geom_BSplineSurface, axis: gp_Vec, uv: NDArray[np.float64], radius: float) -> float | None:
    point = gp_Pnt()
    geom.D0(float(uv[0]), float(uv[1]), point)
    return None if point.X() ** 2 + point.Y() ** 2 < radius**2 else float(gp_Vec(point.XYZ()).Dot(axis))


# -- B-spline helpers -------------------------------------------------------------------------------

def _design_matrix(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int) -> Any:  # scipy sparse array
    return BSpline.design_matrix(np.clip(x, knots[degree], knots[-degree - 1]), knots, degree)


def _basis(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int) -> NDArray[np.float64]:
    """Dense ``(len(x), n)`` B-spline basis (scipy's design matrix), x clipped into the knot range."""
    return _design_matrix(x, knots, degree).toarray()


def _local_basis(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int
                 ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The ``degree + 1`` basis functions that can be nonzero at each x (clipped into the knot
    range): their indices and values, both ``(len(x), degree + 1)``.

    Cox-de Boor (The NURBS Book, A2.2), vectorised over x. It is what scipy's design matrix
    stores per row, without its per-call checks, which cost more than the evaluation here
    (this runs ~50 times per blade face, on a few hundred to a few ten thousand points).
    """
    x = np.clip(np.asarray(x, dtype=float), knots[degree], knots[-degree - 1])
    span = np.clip(np.searchsorted(knots, x, side="right") - 1, degree, len(knots) - degree - 2)
    values = np.zeros((len(x), degree + 1))
    values[:, 0] = 1.0
    left = np.empty((len(x), degree + 1))
    right = np.empty((len(x), degree + 1))
    for j in range(1, degree + 1):
        left[:, j] = x - knots[span + 1 - j]
        right[:, j] = knots[span + j] - x
        saved = np.zeros(len(x))
        for r in range(j):
            temp = values[:, r] / (right[:, r + 1] + left[:, j - r])
            values[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        values[:, j] = saved
    return span[:, None] - degree + np.arange(degree + 1), values


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





