"""Mounting features of the hub: bore, D-flat, set screw, chamfer; where they go and what they may
not cut.

Kernel-free: the limits come from the blades' sampled surfaces. The hub's parameters check
what depends on the hub alone (wall thickness, flat depth, ...); here the blades are checked:
the bore and the chamfers may not reach any blade material (the blade roots are buried in
the hub, spec §3.2), and the set-screw hole goes where it stays farthest from every blade.
Units: mm and degrees; angles about +z from +x.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError

#: Smallest gap (mm) the hub's mounting features (bore, chamfer, set-screw hole) must keep from
#: any sampled blade point; covers the blade surface between its samples.
MOUNTING_CLEARANCE_MM = 0.05


#: Candidate angles of the set-screw hole in the coarse scan (one per degree; then refined to 0.05
#: degrees).
_SCREW_ANGLE_SAMPLES = 360

#: The set-screw hole's cutting tool reaches this far beyond the hub's surface (mm), so that
#: it cuts the hub's lateral face cleanly; blades must clear it there too.
SET_SCREW_OVERSHOOT_MM = 1.0

#: How far (in fillet radii) the root fillet may spread over the hub beside a blade root: a chamfer
#: must stay that much farther from the blade roots than it would without a fillet.
FILLET_REACH_RADII = 1.0


@dataclass(frozen=True)
class HubMounting:
    """The hub's mounting features (0 = absent), mm, and where the set screw (and the flat) face.

    Attributes:
        bore_diameter_mm: coaxial through-bore.
        bore_flat_depth_mm: depth of the D-flat into the bore, measured from the bore's circle.
        set_screw_diameter_mm: radial hole at z = 0 from the bore to the outside.
        chamfer_mm: 45-degree chamfer on the hub's outer end edges.
        set_screw_angle_deg: direction of the set-screw hole, which the D-flat faces as well.
    """

    bore_diameter_mm: float = 0.0
    bore_flat_depth_mm: float = 0.0
    set_screw_diameter_mm: float = 0.0
    chamfer_mm: float = 0.0
    set_screw_angle_deg: float = 0.0

    @property
    def any(self) -> bool:
        """Whether the hub has any feature (else it is the spec's plain cylinder)."""
        return any(
            value > 0.0
            for value in (self.bore_diameter_mm, self.set_screw_diameter_mm, self.chamfer_mm)
        )

    def removed_volume_mm3(self, hub_radius_mm: float, hub_length_mm: float) -> float:
        """Volume the bore (with its flat) and the chamfers remove from the plain cylinder, mm^3.

        The set-screw hole is left out (its ends are curved); exact for the rest.
        """
        bore_radius, depth, chamfer = (
            self.bore_diameter_mm / 2.0,
            self.bore_flat_depth_mm,
            self.chamfer_mm,
        )
        segment = 0.0
        if depth > 0.0:  # the circular segment the flat leaves as material
            half_angle = math.acos((bore_radius - depth) / bore_radius)
            segment = bore_radius**2 * (half_angle - math.sin(half_angle) * math.cos(half_angle))
        bore = (math.pi * bore_radius**2 - segment) * hub_length_mm
        # Each chamfer removes a ring of triangular section (legs c, c) at radius R - c/3 (Pappus).
        rings = 2.0 * (chamfer**2 / 2.0) * 2.0 * math.pi * (hub_radius_mm - chamfer / 3.0)
        return bore + rings


def place_mounting(
    mounting: HubMounting,
    blade_points: NDArray[np.float64],
    blades: int,
    hub_radius_mm: float,
    hub_length_mm: float,
    root_fillet_radius_mm: float = 0.0,
) -> HubMounting:
    """Check ``mounting`` against the blades and return it with the set screw's angle chosen.

    ``blade_points`` is blade 0's sampled surface ``(sections, points, 3)`` mm (densely enough
    that its points bound the blade: the check uses the points as they are); blade i is
    blade 0 turned by 360 i / ``blades`` degrees about +z.

    Raises GeometryError naming the field and its limit when the bore reaches a blade root,
    a chamfer cuts into a blade (or into the root fillet, which spreads about FILLET_REACH_RADII
    radii over the hub), or no direction leaves the set-screw hole clear of the blades.
    """
    grid = np.asarray(blade_points, dtype=float)
    points = grid.reshape(-1, 3)
    radius = np.hypot(points[:, 0], points[:, 1])
    _check_bore(mounting, float(radius.min()))
    _check_chamfer(mounting, points, radius, hub_radius_mm, hub_length_mm, root_fillet_radius_mm)
    if mounting.set_screw_diameter_mm == 0.0 and mounting.bore_flat_depth_mm == 0.0:
        return mounting
    diameter = max(mounting.set_screw_diameter_mm, 1.0)
    # Choose the direction on every 4th sample each way, then measure its clearance on all of them.
    angle, _ = set_screw_angle_deg(grid[::4, ::4].reshape(-1, 3), blades, hub_radius_mm, diameter)
    _, clearance = set_screw_angle_deg(
        points, blades, hub_radius_mm, diameter, candidates_deg=(angle,)
    )
    needed = mounting.set_screw_diameter_mm / 2.0 + MOUNTING_CLEARANCE_MM
    if mounting.set_screw_diameter_mm > 0.0 and clearance < needed:
        limit = max(2.0 * (clearance - MOUNTING_CLEARANCE_MM), 0.0)
        raise GeometryError(
            f"hub.set_screw_diameter = {mounting.set_screw_diameter_mm:g} mm "
            "does not fit between the blades at "
            f"mid-length: the best direction ({angle:.1f} deg) "
            f"leaves {clearance:.3g} mm from its axis to a blade; "
            f"allowed less than {limit:.3g} mm"
        )
    return replace(mounting, set_screw_angle_deg=angle)


def _check_bore(mounting: HubMounting, blade_min_radius_mm: float) -> None:
    limit = 2.0 * (blade_min_radius_mm - MOUNTING_CLEARANCE_MM)
    if mounting.bore_diameter_mm > 0.0 and mounting.bore_diameter_mm >= limit:
        raise GeometryError(
            f"hub.bore_diameter = {mounting.bore_diameter_mm:g} mm "
            "cuts the blade roots buried in the hub, which "
            f"reach down to radius {blade_min_radius_mm:.3f} mm; "
            f"allowed less than {max(limit, 0.0):.3f} mm"
        )


def chamfer_limit_mm(
    points: NDArray[np.float64],
    radius: NDArray[np.float64],
    hub_radius_mm: float,
    hub_length_mm: float,
) -> float:
    """Largest chamfer (mm) whose cut, (R - r) + (L/2 - |z|) < c, misses every blade point inside
    the hub."""
    inside = radius <= hub_radius_mm
    if not np.any(inside):
        return math.inf
    depth = (hub_radius_mm - radius[inside]) + (hub_length_mm / 2.0 - np.abs(points[inside, 2]))
    return float(depth.min())


def _check_chamfer(
    mounting: HubMounting,
    points: NDArray[np.float64],
    radius: NDArray[np.float64],
    hub_radius_mm: float,
    hub_length_mm: float,
    root_fillet_radius_mm: float,
) -> None:
    if mounting.chamfer_mm == 0.0:
        return
    fillet_reach = FILLET_REACH_RADII * root_fillet_radius_mm
    limit = (
        chamfer_limit_mm(points, radius, hub_radius_mm, hub_length_mm)
        - MOUNTING_CLEARANCE_MM
        - fillet_reach
    )
    if mounting.chamfer_mm >= limit:
        fillet = (
            " with hub.root_fillet_radius = "
            f"{root_fillet_radius_mm:g} mm (the fillet spreads about "
            f"{fillet_reach:g} mm over the hub)"
            if root_fillet_radius_mm > 0.0
            else ""
        )
        raise GeometryError(
            f"hub.chamfer = {mounting.chamfer_mm:g} mm cuts "
            f"into a blade root near the hub's end{fillet}; "
            f"allowed less than {max(limit, 0.0):.3f} mm"
        )


def set_screw_angle_deg(
    blade_points: NDArray[np.float64],
    blades: int,
    hub_radius_mm: float,
    diameter_mm: float,
    candidates_deg: Sequence[float] | None = None,
) -> tuple[float, float]:
    """The direction of a radial hole at z = 0 whose line stays farthest from every blade, and that
    distance.

    The line is the ray from the z axis outward at z = 0: the hole, and the way a screw and
    its key come in from outside, so it must clear the blades beyond the hub too (a toroidal
    blade loops over the hub). The distance is the smallest from that ray to any blade point
    (all ``blades`` blades, from blade 0's points ``(k, 3)`` mm). Returns
    ``(angle_deg, clearance_mm)``; infinite clearance when no blade comes near mid-length.
    ``candidates_deg``: the directions to try (default: a scan of the circle, refined).
    """
    points = np.asarray(blade_points, dtype=float).reshape(-1, 3)
    # farther points cannot decide the direction
    band = diameter_mm + 2.0 * MOUNTING_CLEARANCE_MM + 1.0
    near = points[np.abs(points[:, 2]) < band]
    reach = (
        float(np.hypot(near[:, 0], near[:, 1]).max(initial=hub_radius_mm)) + SET_SCREW_OVERSHOOT_MM
    )
    if len(near) == 0:
        return (180.0 / blades if candidates_deg is None else float(candidates_deg[0])), math.inf
    turns = np.radians(360.0 * np.arange(blades) / blades)
    # every blade's points
    angle = (np.arctan2(near[:, 1], near[:, 0])[None, :] + turns[:, None]).ravel()
    r = np.tile(np.hypot(near[:, 0], near[:, 1]), blades)
    z = np.tile(near[:, 2], blades)

    def clearance(candidates_deg: NDArray[np.float64]) -> NDArray[np.float64]:
        offset = angle[None, :] - np.radians(candidates_deg)[:, None]
        along = np.clip(r * np.cos(offset), 0.0, reach)  # the nearest point of the hole's axis
        return np.sqrt(
            np.maximum(r**2 + along**2 - 2.0 * r * along * np.cos(offset) + z**2, 0.0)
        ).min(axis=1)

    if candidates_deg is not None:
        distances = clearance(np.asarray(candidates_deg, dtype=float))
        index = int(np.argmax(distances))
        return float(candidates_deg[index]), float(distances[index])
    coarse = np.linspace(0.0, 360.0, _SCREW_ANGLE_SAMPLES, endpoint=False)
    best = coarse[int(np.argmax(clearance(coarse)))]
    step = 360.0 / _SCREW_ANGLE_SAMPLES
    fine = (best + np.linspace(-step, step, 41)) % 360.0
    distances = clearance(fine)
    index = int(np.argmax(distances))
    return float(fine[index]), float(distances[index])


def set_screw_arc_deg(mounting: HubMounting, hub_radius_mm: float) -> tuple[float, float] | None:
    """Angular arc (start, end) degrees the set-screw hole takes on the hub's surface (plus a
    margin), or None."""
    if mounting.set_screw_diameter_mm == 0.0:
        return None
    half = (
        math.degrees(math.asin(min(1.0, mounting.set_screw_diameter_mm / 2.0 / hub_radius_mm)))
        + 2.0
    )
    return (mounting.set_screw_angle_deg - half, mounting.set_screw_angle_deg + half)
