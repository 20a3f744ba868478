"""Checks, before the kernel runs, that valid parameters describe a sound propeller.

Each failed check raises GeometryError with a one-line reason, so the CLI can refuse the
design (exit 2) instead of handing OpenCascade something it would fail on, hang on or,
worse, fuse wrongly. The checks, in the order :func:`check_feasible` runs them:

1. the blade's end sections lie inside the hub (the fuse hides them);
2. the centerline leaves the hub through its side, not through an end face;
3. the blade does not fold over itself where the centerline bends: a section may not reach
   past the centre of curvature (kappa . offset < 1 on the whole surface);
4. the sections are dense enough to represent the blade: between neighbours it may bend,
   twist or taper only so much;
5. the blade leaves the hub at all;
6. the blade does not run into itself (parts far apart along the blade overlap);
7. the blades do not run into each other outside the hub.

Checks 3 and 5-7 sample the analytic surface on their own grid, independent of
``resolution``; check 4 is about ``resolution.sections`` itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError
from torus_cad.geometry.blade.blade_surface import (
    BladeSurface,
    blade_frames,
    check_trailing_edge,
    place_on_frames,
    sections_along,
    sections_at,
)
from torus_cad.geometry.blade.centerline import Centerline
from torus_cad.geometry.blade.frames import Frames
from torus_cad.geometry.blade.propeller_geometry import HubGeometry, PropellerGeometry

#: A section may reach at most this fraction of the way to the centre of curvature (check 3).
FOLD_LIMIT = 1.0

#: Sections along s and points around each section of the grid the analytic checks sample.
CHECK_SECTIONS = 96
CHECK_POINTS = 48

#: Check 4: half-way between neighbouring sections the analytic surface may sag from the straight
#: line joining them by at most this fraction of the local chord. The loft interpolates the
#: sections exactly, but beyond this the blade changes too much between them to be represented
#: (how it was set: the measurements page of the docs).
RESOLUTION_DEVIATION_LIMIT = 0.10

#: Check 5: parts of one blade closer than this many grid steps along s are neighbours, not
#: overlaps.
SELF_NEIGHBOUR_STEPS = 2


def _radius(points: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.hypot(points[..., 0], points[..., 1])


def _outside_hub(hub: HubGeometry, points: NDArray[np.float64]) -> NDArray[np.bool_]:
    return (_radius(points) > hub.radius_mm) | (np.abs(points[..., 2]) > hub.length_mm / 2.0)


# -- 1, 2: ends and centerline ----------------------------------------------------------------


def check_root_fillet_edge(root_fillet_radius_mm: float, trailing_edge_thickness_mm: float) -> None:
    """GeometryError for a root fillet round a knife trailing edge: OpenCascade's rolling ball turns
    round the zero-thickness edge in one degenerate corner face that crosses itself, which the
    build's strict check refuses (measured: the default at 0.2 and 0.5 mm, cooling_fan_7blade,
    multirotor_5in_3blade, prop_10x5_2blade and marine_3blade_loop with their edges made sharp, 0.5
    mm: every one refused), so it is refused before the kernel, by ``check`` as by the build."""
    if root_fillet_radius_mm > 0.0 and trailing_edge_thickness_mm == 0.0:
        raise GeometryError(
            f"hub.root_fillet_radius = {root_fillet_radius_mm:g} mm round a knife trailing edge "
            "(airfoil.trailing_edge_thickness = 0) leaves a corner face that crosses itself; give "
            "the blade a round blunt edge: airfoil.trailing_edge_thickness > 0 with "
            "airfoil.trailing_edge_shape = 'round'"
        )


def check_ends_inside_hub(hub: HubGeometry, surface: BladeSurface) -> None:
    """The first and last sections must lie inside the hub (r < R, |z| < L/2) so the fuse hides
    them."""
    radius, half_length = hub.radius_mm, hub.length_mm / 2.0
    for label, section in (
        ("root (s = 0)", surface.points[0]),
        ("tip end (s = 1)", surface.points[-1]),
    ):
        outside_radius = _radius(section).max()
        outside_axis = np.abs(section[:, 2]).max()
        if outside_radius >= radius or outside_axis >= half_length:
            raise GeometryError(
                f"the blade's {label} section leaves the hub's "
                f"inset (reaches r = {outside_radius:.3f} mm of "
                f"R = {radius:g}, |z| = {outside_axis:.3f} mm of L/2 = {half_length:g}); "
                "make transforms.scale_x / scale_y smaller at that end or the hub larger"
            )


def check_centerline_leaves_through_side(
    hub: HubGeometry, centerline: Centerline, samples: int = 401
) -> None:
    """Inside the hub's radius the centerline must stay between the end faces (|z| < L/2)."""
    points = centerline.points(np.linspace(0.0, 1.0, samples))
    inside = _radius(points) < hub.radius_mm
    crossing = inside & (np.abs(points[:, 2]) >= hub.length_mm / 2.0)
    if np.any(crossing):
        where = np.linspace(0.0, 1.0, samples)[np.argmax(crossing)]
        raise GeometryError(
            "the centerline leaves the hub through an end "
            f"face near s = {where:.3f}; it must leave through "
            "the hub's side (keep y_L of the control points near the ends between 0 and L - 2)"
        )


# -- the analytic tube the remaining checks sample ----------------------------------------------


@dataclass(frozen=True)
class Tube:
    """The blade surface sampled on a check grid, with its frames and in-plane coordinates.

    Attributes:
        frames: the ``m`` sections' frames (s, origin, unit tangent, normal, binormal).
        planar: ``(m, p, 2)`` section coordinates (X along N, Y along B), mm.
        points: ``(m, p, 3)`` surface points, mm.
        curvature: ``(m, 3)`` curvature vectors of the centerline (kappa times the Frenet normal),
            1/mm.
        arc_length: ``(m,)`` centerline arc length from s = 0, mm.
    """

    frames: Frames
    planar: NDArray[np.float64]
    points: NDArray[np.float64]
    curvature: NDArray[np.float64]
    arc_length: NDArray[np.float64]

    @property
    def section_radius(self) -> NDArray[np.float64]:
        """``(m,)`` largest distance of a section's points from the centerline, mm."""
        return np.linalg.norm(self.planar, axis=-1).max(axis=1)


def tube_grid(sections: int, at_least: int = CHECK_SECTIONS) -> tuple[NDArray[np.float64], int]:
    """A uniform s grid that holds every section's s and every midpoint between sections, and its
    step.

    Returns ``(s, k)``: section i sits at ``s[k i]``, the midpoint after it at ``s[k i + k / 2]``.
    """
    k = 2 * max(1, int(np.ceil(at_least / (2.0 * (sections - 1)))))
    return np.linspace(0.0, 1.0, k * (sections - 1) + 1), k


def sample_tube(
    geometry: PropellerGeometry,
    centerline: Centerline,
    s: NDArray[np.float64],
    t: NDArray[np.float64],
) -> Tube:
    """Blade 0's analytic surface at every (s, t) of the grid, with frames and curvature.

    The frames are the blade's own kind
    (:func:`torus_cad.geometry.blade.blade_surface.blade_frames`).
    """
    derivatives = centerline.derivatives(s, order=2)
    first, second = derivatives[:, 1], derivatives[:, 2]
    speed = np.linalg.norm(first, axis=-1)
    tangent = first / speed[:, None]
    curvature = (second - np.sum(second * tangent, axis=-1, keepdims=True) * tangent) / speed[
        :, None
    ] ** 2
    frames = blade_frames(geometry.blade, centerline, s)
    planar = geometry.blade.laws.apply(sections_at(sections_along(geometry.blade, s), t), s)
    surface = place_on_frames(frames, planar)
    steps = np.linalg.norm(np.diff(frames.origin, axis=0), axis=-1)
    arc_length = np.concatenate([[0.0], np.cumsum(steps)])
    return Tube(frames, planar, surface, curvature, arc_length)


def coarsen(tube: Tube, sections: int = CHECK_SECTIONS, points: int = CHECK_POINTS) -> Tube:
    """Every j-th section (the last kept) and every i-th point, for the overlap tests."""
    m, p, _ = tube.points.shape
    rows = np.unique(np.concatenate([np.arange(0, m, max(1, m // sections)), [m - 1]]))
    columns = np.arange(0, p, max(1, int(np.ceil(p / points))))
    return Tube(
        tube.frames.take(rows),
        tube.planar[rows][:, columns],
        tube.points[rows][:, columns],
        tube.curvature[rows],
        tube.arc_length[rows],
    )


# -- 3: folding where the centerline bends -----------------------------------------------------


def fold_ratio(tube: Tube) -> tuple[float, float]:
    """Largest kappa . offset over the surface (>= 1: the section reaches the centre of curvature)
    and its s.

    The sweep C(s) + X N + Y B moves a point at offset o along T at the rate |C'| (1 - k . o),
    where k is the curvature vector: where k . o reaches 1 neighbouring sections cross and
    the surface folds over itself.
    """
    offsets = tube.points - tube.frames.origin[:, None, :]
    ratio = np.einsum("mpk,mk->mp", offsets, tube.curvature).max(axis=1)
    worst = int(np.argmax(ratio))
    return float(ratio[worst]), float(tube.frames.s[worst])


def check_no_fold(tube: Tube, limit: float | None = None) -> None:
    """Refuse sections that reach past the centerline's centre of curvature (default limit
    FOLD_LIMIT)."""
    limit = FOLD_LIMIT if limit is None else limit
    ratio, where = fold_ratio(tube)
    if ratio >= limit:
        index = int(np.argmin(np.abs(tube.frames.s - where)))
        bend_radius = 1.0 / max(float(np.linalg.norm(tube.curvature[index])), 1e-300)
        raise GeometryError(
            f"the blade folds over itself near s = {where:.3f}: "
            f"its section reaches {ratio:.2f} x the "
            f"centerline's bend radius ({bend_radius:.3g} mm) "
            f"on the inside of the bend (limit {limit:g}); "
            "make transforms.scale_x / scale_y smaller there or bend the centerline less"
        )


# -- 4: sections dense enough for the loft ------------------------------------------------------


def resolution_deviation(surface: BladeSurface, fine: Tube, step: int) -> tuple[float, float]:
    """Largest sag between neighbouring sections, as a fraction of the local chord; and its s.

    The sag is the distance from the analytic surface half-way between two sections to the
    midpoint of the straight segment joining their corresponding points (``fine`` holds the
    half-way sections at rows ``step / 2 + step i``, see :func:`tube_grid`). It measures how
    much the blade bends, twists or tapers between sections: OpenCascade's loft through
    sparse sections of a strongly changing blade misses the design badly, can come out
    inside out, and the fuse then fails or hangs (found by ``scripts/fuzz.py``).
    """
    middle = fine.frames.s[step // 2 :: step]
    exact = fine.points[step // 2 :: step]
    straight = 0.5 * (surface.points[:-1] + surface.points[1:])
    sag = np.linalg.norm(straight - exact, axis=-1).max(axis=1)
    chord = 2.0 * np.linalg.norm(fine.planar[step // 2 :: step], axis=-1).max(axis=1)
    relative = sag / np.maximum(chord, 1e-12)
    worst = int(np.argmax(relative))
    return float(relative[worst]), float(middle[worst])


def check_sections_resolved(
    surface: BladeSurface, fine: Tube, step: int, limit: float | None = None
) -> None:
    """Refuse a blade whose sections are too sparse for how fast it bends, twists or tapers.

    The default limit is RESOLUTION_DEVIATION_LIMIT (read at call time).
    """
    limit = RESOLUTION_DEVIATION_LIMIT if limit is None else limit
    relative, where = resolution_deviation(surface, fine, step)
    if relative > limit:
        sections = len(surface.s)
        # The sag falls like the square of the spacing: estimate the sections that meet the limit.
        needed = int(np.ceil((sections - 1) * np.sqrt(relative / limit) * 1.05)) + 1
        raise GeometryError(
            f"resolution.sections = {sections} is too few for "
            f"this blade: between sections near s = {where:.3f} "
            f"it bends, twists or tapers by {relative:.1%} of the chord (limit {limit:.1%}); use "
            f"resolution.sections >= {min(needed, 400)} or make the blade change more gently"
        )


# -- 5, 6, 7: leaving the hub, overlaps
# --------------------------------------------------------------------------------


def _points_inside(
    tube: Tube, query: NDArray[np.float64], allowed: NDArray[np.bool_] | None = None
) -> tuple[NDArray[np.bool_], NDArray[np.int64]]:
    """Which ``(q, 3)`` points lie inside the tube, and in which slab (section k to k + 1) each
    does.

    A point is inside slab k when it lies on the forward side of section k's plane and the
    backward side of section k + 1's, and inside the section interpolated to its position.
    ``allowed`` ``(q, m - 1)`` masks the slabs tested per point (e.g. to skip a point's neighbours).
    """
    # (q, m)
    heights = query @ tube.frames.tangent.T - np.sum(
        tube.frames.origin * tube.frames.tangent, axis=-1
    )
    in_slab = (heights[:, :-1] >= 0.0) & (heights[:, 1:] < 0.0)
    if allowed is not None:
        in_slab &= allowed
    point_index, slab = np.nonzero(in_slab)
    inside = np.zeros(len(query), dtype=bool)
    where = np.full(len(query), -1, dtype=np.int64)
    # A point inside slab k lies within the larger section radius (plus the slab's length) of C_k.
    radius = tube.section_radius
    reach = np.maximum(radius[:-1], radius[1:]) + np.linalg.norm(
        np.diff(tube.frames.origin, axis=0), axis=-1
    )
    near = np.linalg.norm(query[point_index] - tube.frames.origin[slab], axis=-1) <= reach[slab]
    point_index, slab = point_index[near], slab[near]
    if point_index.size == 0:
        return inside, where
    h0, h1 = heights[point_index, slab], heights[point_index, slab + 1]
    weight = (h0 / (h0 - h1))[:, None]
    polygon = (1.0 - weight[:, :, None]) * tube.planar[slab] + weight[:, :, None] * tube.planar[
        slab + 1
    ]
    relative0 = query[point_index] - tube.frames.origin[slab]
    relative1 = query[point_index] - tube.frames.origin[slab + 1]
    x = (1.0 - weight[:, 0]) * np.sum(relative0 * tube.frames.normal[slab], -1) + weight[
        :, 0
    ] * np.sum(relative1 * tube.frames.normal[slab + 1], -1)
    y = (1.0 - weight[:, 0]) * np.sum(relative0 * tube.frames.binormal[slab], -1) + weight[
        :, 0
    ] * np.sum(relative1 * tube.frames.binormal[slab + 1], -1)
    hit = _in_polygons(polygon, x, y)
    inside[point_index[hit]] = True
    where[point_index[hit]] = slab[hit]
    return inside, where


def _in_polygons(
    polygons: NDArray[np.float64], x: NDArray[np.float64], y: NDArray[np.float64]
) -> NDArray[np.bool_]:
    """Even-odd test of points (x[i], y[i]) against closed polygons ``(i, p, 2)``."""
    start = polygons
    end = np.roll(polygons, -1, axis=1)
    x0, y0, x1, y1 = start[..., 0], start[..., 1], end[..., 0], end[..., 1]
    px, py = x[:, None], y[:, None]
    straddles = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing_x = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    crossings = straddles & (px < crossing_x)
    return (np.count_nonzero(crossings, axis=1) % 2) == 1


def check_no_self_intersection(hub: HubGeometry, tube: Tube) -> None:
    """Refuse a blade whose surface enters its own volume away from the neighbouring sections."""
    m, p, _ = tube.points.shape
    query = tube.points.reshape(-1, 3)
    section_of_point = np.repeat(np.arange(m), p)
    slabs = np.arange(m - 1)
    # Slab k spans sections k..k+1; a point of section i is a neighbour of slabs i-w-1 .. i+w.
    allowed = np.abs(slabs[None, :] + 0.5 - section_of_point[:, None]) > SELF_NEIGHBOUR_STEPS + 0.5
    inside, slab = _points_inside(tube, query, allowed)
    if np.any(inside):
        first = int(np.argmax(inside))
        s_point = tube.frames.s[section_of_point[first]]
        s_slab = 0.5 * (tube.frames.s[slab[first]] + tube.frames.s[slab[first] + 1])
        place = "outside" if _outside_hub(hub, query[first]) else "inside"
        low, high = sorted((s_point, s_slab))
        raise GeometryError(
            "the blade intersects itself: its part near s = "
            f"{low:.3f} runs into its part near s = {high:.3f} "
            f"({place} the hub); move the centerline's "
            "control points apart or make the sections smaller"
        )


def check_leaves_hub(hub: HubGeometry, tube: Tube) -> None:
    """Refuse a blade that never leaves the hub: the fuse would swallow it (a propeller without
    blades)."""
    if not np.any(_outside_hub(hub, tube.points)):
        raise GeometryError(
            "the blade never leaves the hub (all of it lies "
            "within r < R and |z| < L/2); raise the centerline's "
            "control points (z_L of p2 / p3) or make the hub smaller"
        )


def check_blades_clear(geometry: PropellerGeometry, tube: Tube) -> None:
    """Refuse blades that run into each other outside the hub (inside, the hub absorbs them).

    Blade i is blade 0 rotated by 360 i / n about the axis: blade 0's surface points are
    rotated to every other blade and tested against blade 0's volume, which covers every
    pair of blades in both directions.
    """
    if geometry.blades == 1:
        return
    m, p, _ = tube.points.shape
    points = tube.points.reshape(-1, 3)
    outside = _outside_hub(geometry.hub, points)
    if not np.any(outside):
        return
    candidates = points[outside]
    section_of_point = np.repeat(np.arange(m), p)[outside]
    for blade in range(1, geometry.blades):
        angle = 2.0 * np.pi * blade / geometry.blades
        cos, sin = np.cos(angle), np.sin(angle)
        rotated = candidates @ np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])
        inside, slab = _points_inside(tube, rotated)
        if np.any(inside):
            first = int(np.argmax(inside))
            s_other = tube.frames.s[section_of_point[first]]
            s_here = 0.5 * (tube.frames.s[slab[first]] + tube.frames.s[slab[first] + 1])
            gap = min(blade, geometry.blades - blade)
            raise GeometryError(
                "the blades would intersect each other outside "
                f"the hub: blade 1's part near s = {s_here:.3f} "
                f"meets blade {1 + blade}'s part near s = "
                f"{s_other:.3f} ({gap} blade pitch{'es' if gap > 1 else ''}"
                f" = {360.0 * gap / geometry.blades:.1f} degrees "
                "apart); reduce the centerline's angular span x_L, "
                "the section sizes or the number of blades"
            )


# -- all checks
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Margins:
    """How close a blade that passed every check comes to the limits of checks 3 and 4.

    Attributes:
        fold_ratio: the largest kappa . offset over the surface (:func:`fold_ratio`; refused at
            FOLD_LIMIT).
        resolution_deviation: the largest sag between neighbouring sections as a fraction of the
            local chord (:func:`resolution_deviation`; refused above RESOLUTION_DEVIATION_LIMIT).
    """

    fold_ratio: float
    resolution_deviation: float


def check_feasible(geometry: PropellerGeometry, surface: BladeSurface) -> Margins:
    """Run every pre-kernel check on blade 0 (the others are its rotations); GeometryError naming
    the first that fails, else the margins to the fold and resolution limits."""
    centerline = geometry.centerline(0)
    check_ends_inside_hub(geometry.hub, surface)
    check_centerline_leaves_through_side(geometry.hub, centerline)
    check_trailing_edge(geometry.blade, centerline, geometry.hub.radius_mm, geometry.hub.length_mm)
    s, step = tube_grid(len(surface.s))
    fine = sample_tube(geometry, centerline, s, surface.t)
    check_no_fold(fine)
    check_sections_resolved(surface, fine, step)
    check_leaves_hub(geometry.hub, fine)
    tube = coarsen(fine)
    check_no_self_intersection(geometry.hub, tube)
    check_blades_clear(geometry, tube)
    return Margins(fold_ratio(fine)[0], resolution_deviation(surface, fine, step)[0])
