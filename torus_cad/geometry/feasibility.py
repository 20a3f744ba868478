"""Checks, before the kernel runs, that valid parameters describe a sound propeller.

Each failed check raises GeometryError with the reason, so the CLI can refuse the design
(exit 2) instead of handing OpenCascade something it would fail on or, worse, fuse wrongly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.surface import BladeSurface


def _radius(points: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.hypot(points[..., 0], points[..., 1])


def check_ends_inside_hub(params: PropellerParameters, surface: BladeSurface) -> None:
    """The first and last sections must lie inside the hub (r < R, |z| < L/2) so the fuse hides them."""
    radius, half_length = params.hub.radius, params.hub.length / 2.0
    for label, section in (("root (s = 0)", surface.points[0]), ("tip end (s = 1)", surface.points[-1])):
        outside_radius = _radius(section).max()
        outside_axis = np.abs(section[:, 2]).max()
        if outside_radius >= radius or outside_axis >= half_length:
            raise GeometryError(
                f"the blade's {label} section leaves the hub's inset (reaches r = {outside_radius:.3f} mm of "
                f"R = {radius:g}, |z| = {outside_axis:.3f} mm of L/2 = {half_length:g}); "
                "make transforms.scale_x / scale_y smaller at that end or the hub larger")


def check_centerline_leaves_through_side(params: PropellerParameters, centerline: Centerline,
                                         samples: int = 401) -> None:
    """Inside the hub's radius the centerline must stay between the end faces (|z| < L/2)."""
    points = centerline.points(np.linspace(0.0, 1.0, samples))
    inside = _radius(points) < params.hub.radius
    crossing = inside & (np.abs(points[:, 2]) >= params.hub.length / 2.0)
    if np.any(crossing):
        where = np.linspace(0.0, 1.0, samples)[np.argmax(crossing)]
        raise GeometryError(
            f"the centerline leaves the hub through an end face near s = {where:.3f}; it must leave through "
            "the hub's side (keep y_L of the control points near the ends between 0 and L - 2)")


def check_blades_clear(params: PropellerParameters, surface: BladeSurface) -> None:
    """Blades must not intersect each other outside the hub.

    Blade i is blade 0 rotated by 360 i / n. The part of blade 0 outside the hub occupies
    an angular interval around the axis at every radius; neighbours collide when that
    interval, measured over the points outside the hub, spans 360 / n degrees or more.
    """
    if params.blades == 1:
        return
    points = surface.points.reshape(-1, 3)
    outside = _radius(points) > params.hub.radius
    if not np.any(outside):
        return
    middle = surface.frames.origin[len(surface.frames.origin) // 2]
    reference = np.arctan2(middle[1], middle[0])
    relative = np.angle(np.exp(1j * (np.arctan2(points[outside, 1], points[outside, 0]) - reference)))
    span_deg = float(np.degrees(relative.max() - relative.min()))
    pitch_deg = 360.0 / params.blades
    if span_deg >= pitch_deg:
        raise GeometryError(
            f"the blades would intersect each other: one blade spans {span_deg:.1f} degrees around the axis "
            f"outside the hub, more than the {pitch_deg:.1f} degrees between blades; reduce centerline x_L "
            "or the number of blades")


def check_feasible(params: PropellerParameters, surface: BladeSurface, centerline: Centerline) -> None:
    """Run every pre-kernel check on blade 0 (the others are its rotations)."""
    check_ends_inside_hub(params, surface)
    check_centerline_leaves_through_side(params, centerline)
    check_blades_clear(params, surface)
