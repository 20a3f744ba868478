"""Mass properties of a hub with blades from the blade faces alone: the fast route of
:func:`torus_cad.kernel.mass_properties.mass_properties`.

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

The package by job: :mod:`.recognition` (is the shape such a hub, and which faces are its blade
faces), :mod:`.quadrature` (one blade face's integrals), :mod:`.extremes` (its box),
:mod:`.bspline` (the surface as arrays); this module adds the hub and the rotated copies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.Geom import Geom_BSplineSurface
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopoDS import TopoDS_Face, TopoDS_Shape

from torus_cad.kernel.blade_integrals.quadrature import (
    GAUSS_POINTS_PER_SPAN,
    bounds_match,
    face_integrals,
)
from torus_cad.kernel.blade_integrals.recognition import base_surface_and_angle, recognise


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


def hub_with_blade_integrals(
    shape: TopoDS_Shape, gauss_points: int = GAUSS_POINTS_PER_SPAN
) -> HubWithBladeIntegrals | None:
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
    hub = recognise(shape)
    if hub is None:
        return None
    radius, bore, length = hub.radius, hub.bore_radius, hub.z_top - hub.z_bottom
    # a tube round a plain bore (bore 0: a cylinder)
    volume = math.pi * (radius**2 - bore**2) * length
    moment = np.array([0.0, 0.0, volume * (hub.z_top + hub.z_bottom) / 2.0])
    inertia = math.pi * (radius**4 - bore**4) * length / 2.0
    products = np.zeros(3)  # the hub's are 0: it is symmetric about its axis
    area = 2.0 * math.pi * (radius**2 - bore**2) + 2.0 * math.pi * (radius + bore) * length
    # along BOX_DIRECTIONS
    box_max = np.array([radius, radius, radius, radius, -hub.z_bottom, hub.z_top])
    groups: dict[tuple[int, bool], list[tuple[TopoDS_Face, float]]] = {}
    surfaces: dict[tuple[int, bool], Geom_BSplineSurface] = {}
    footprints = np.zeros(2)  # one blade's, summed over its faces (signed)
    for face in hub.blade_faces:
        surface, angle = base_surface_and_angle(face)
        if surface is None or angle is None:
            return None
        key = (id(surface), face.Orientation() == TopAbs_REVERSED)
        surfaces[key] = surface
        groups.setdefault(key, []).append((face, angle))
    for key, members in groups.items():
        angles = np.array([angle for _, angle in members])
        part = face_integrals(surfaces[key], key[1], radius, angles, gauss_points)
        if part is None or not all(bounds_match(face, part) for face, _ in members):
            return None
        count, (cos, sin) = len(members), (np.cos(angles).sum(), np.sin(angles).sum())
        # rotating a copy rotates its x, y moment
        moment_x, moment_y, moment_z = part.first_moment_mm4
        volume += count * part.volume_mm3
        moment += np.array(
            [cos * moment_x - sin * moment_y, sin * moment_x + cos * moment_y, count * moment_z]
        )
        inertia += count * part.spin_inertia_mm5
        area += count * part.area_mm2
        footprints += part.footprints_mm2
        box_max = np.maximum(box_max, part.extremes_mm)
        products += _rotated_products(part.second_moments_mm5, angles)
    if len({len(members) for members in groups.values()}) != 1:
        return None  # not every face has a copy on every blade
    area -= len(next(iter(groups.values()))) * float(np.abs(footprints).sum())
    return HubWithBladeIntegrals(
        volume, moment / volume, inertia, area, -box_max[0::2], box_max[1::2], products
    )


def _rotated_products(
    second_moments: NDArray[np.float64], angles: NDArray[np.float64]
) -> NDArray[np.float64]:
    """(∫xz, ∫yz, ∫xy) summed over copies rotated by ``angles`` about z, from one copy's
    (∫xz, ∫yz, ∫xy, ∫(x² - y²)): (xz, yz) turns by the angle, (x² - y², 2 xy) by twice it."""
    xz, yz, xy, difference = second_moments
    cos, sin = np.cos(angles).sum(), np.sin(angles).sum()
    cos2, sin2 = np.cos(2.0 * angles).sum(), np.sin(2.0 * angles).sum()
    return np.array(
        [cos * xz - sin * yz, sin * xz + cos * yz, (sin2 * difference + cos2 * 2.0 * xy) / 2.0]
    )
