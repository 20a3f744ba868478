"""Diameter target: scale the centerline's radial reach until the tip diameter is the one asked for.

The tip radius is the largest distance of the blade surface from the spin axis. The free
control points' radial coordinates (z_L of P2 and P3; P1 and P4 stay in the hub) are
multiplied by a scale k; the tip radius is a smooth, increasing function of k (the blade's
outermost point moves out with the control points), so k is found by a bracketed root
search (scipy.optimize.brentq) on tip_radius(k) - D / 2, to DIAMETER_TOLERANCE_MM.

The tip radius itself is found on the analytic surface: a grid over (s, t) locates the
outermost point, then grids zoomed around it refine it to ~1e-7 mm.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq

from torus_cad.errors import GeometryError, ParameterError

#: The tip diameter must match its target within this (mm).
DIAMETER_TOLERANCE_MM = 0.01

#: The radial scale k of the free control points is searched in this range.
RADIAL_SCALE_RANGE = (0.2, 5.0)

#: Grid of the tip-radius search and its zoom steps.
TIP_SEARCH_SECTIONS = 81
TIP_SEARCH_POINTS = 121
TIP_SEARCH_ZOOMS = 6

SurfaceAt = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def tip_radius(surface_at: SurfaceAt, t_end: float) -> tuple[float, float, float]:
    """Largest distance from the z axis of the surface ``surface_at(s, t) -> (len(s), len(t), 3)``.

    ``t_end`` is the end of the closed section parameter (2, or 3 with a blunt trailing edge).
    Returns ``(radius mm, s, t)`` of the outermost point.
    """
    s = np.linspace(0.0, 1.0, TIP_SEARCH_SECTIONS)
    t = np.linspace(0.0, t_end, TIP_SEARCH_POINTS)
    ds, dt = s[1] - s[0], t[1] - t[0]
    best = (-1.0, 0.0, 0.0)
    for _ in range(TIP_SEARCH_ZOOMS + 1):
        points = surface_at(s, t)
        radius = np.hypot(points[..., 0], points[..., 1])
        i, j = np.unravel_index(int(np.argmax(radius)), radius.shape)
        if radius[i, j] > best[0]:
            best = (float(radius[i, j]), float(s[i]), float(t[j]))
        # Zoom: two cells either side of the best point, 11 x 11 samples (the maximum is smooth
        # there).
        ds, dt = ds / 5.0, dt / 5.0
        s = np.clip(best[1] + ds * np.arange(-10, 11), 0.0, 1.0)
        t = np.clip(best[2] + dt * np.arange(-10, 11), 0.0, t_end)
        s, t = np.unique(s), np.unique(t)
    return best


def radial_scale_for_diameter(
    tip_radius_of_scale: Callable[[float], float],
    diameter_mm: float,
    scale_range: tuple[float, float] = RADIAL_SCALE_RANGE,
) -> float:
    """The scale k of the free control points' z_L that makes the tip diameter ``diameter_mm``.

    ``tip_radius_of_scale(k)`` builds the surface for scale k and returns its tip radius (mm);
    it may raise GeometryError where the design stops being sound (e.g. no Frenet frame).
    Refuses (ParameterError) a diameter outside what the scale range reaches, naming the
    reachable diameters.
    """
    target = diameter_mm / 2.0
    radius_at = _Memo(tip_radius_of_scale)
    if radius_at(1.0) is None:
        raise ParameterError(
            "diameter: the design cannot be evaluated at "
            "its own control points; fix the centerline first"
        )
    low, high = _last_sound(radius_at, scale_range[0]), _last_sound(radius_at, scale_range[1])
    radius_low, radius_high = radius_at.sound(low), radius_at.sound(high)
    if not min(radius_low, radius_high) <= target <= max(radius_low, radius_high):
        raise ParameterError(
            f"diameter = {diameter_mm:g} mm is out of reach for "
            "this design: scaling the radial coordinates z_L "
            f"of centerline.p2 and p3 by {low:.3g}..{high:.3g} gives "
            f"tip diameters {2 * radius_low:.2f}.."
            f"{2 * radius_high:.2f} mm; change the hub "
            "radius, the control points or the section sizes"
        )
    return float(
        brentq(
            lambda scale: radius_at.sound(scale) - target,
            low,
            high,
            xtol=1e-12,
            rtol=1e-12,
            maxiter=200,
        )
    )


class _Memo:
    """tip_radius_of_scale with GeometryError turned into None, remembered per scale."""

    def __init__(self, function: Callable[[float], float]) -> None:
        self.function = function
        self.values: dict[float, float | None] = {}

    def __call__(self, scale: float) -> float | None:
        if scale not in self.values:
            try:
                self.values[scale] = float(self.function(scale))
            except GeometryError:
                self.values[scale] = None
        return self.values[scale]

    def sound(self, scale: float) -> float:
        """The tip radius at a scale known to evaluate (GeometryError if it does not)."""
        value = self(scale)
        if value is None:
            raise GeometryError(f"the design cannot be evaluated at radial scale {scale:g}")
        return value


def _last_sound(radius_at: _Memo, end: float, steps: int = 8) -> float:
    """The scale nearest ``end`` (between 1 and ``end``, log-bisected) at which the design still
    evaluates."""
    if radius_at(end) is not None:
        return end
    good, bad = 0.0, float(np.log(end))
    for _ in range(steps):
        middle = 0.5 * (good + bad)
        if radius_at(float(np.exp(middle))) is not None:
            good = middle
        else:
            bad = middle
    return float(np.exp(good))
