"""NACA 4-digit airfoil (spec §1): camber line, thickness, surfaces and the closed f(t).

All lengths are fractions of the chord; ``t`` is the chord position in [0, 1] for the
camber line and thickness, and the closed-curve parameter in [0, 2] for :func:`airfoil_points`
(upper surface leading edge -> trailing edge on [0, 1], lower surface trailing edge -> leading
edge on [1, 2], spec §1.3).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Coefficients of the NACA thickness polynomial (spec §1.1): sqrt(t), t, t^2, t^3, t^4.
THICKNESS_COEFFICIENTS = (0.2969, -0.1260, -0.3516, 0.2843, -0.1036)


@dataclass(frozen=True)
class NacaAirfoil:
    """A NACA 4-digit section.

    Attributes:
        max_camber: m, fraction of chord, >= 0.
        camber_position: p, fraction of chord in (0, 1) (ignored when m = 0).
        thickness: maximum thickness, fraction of chord.
        camber_normal: apply thickness normal to the camber line (True) or along y (theta_c = 0).
    """

    max_camber: float = 0.02
    camber_position: float = 0.4
    thickness: float = 0.5
    camber_normal: bool = True

    def camber(self, t: ArrayLike) -> NDArray[np.float64]:
        """Mean camber line y_c(t), shape of ``t``."""
        t = np.asarray(t, dtype=float)
        m, p = self.max_camber, self.camber_position
        if m == 0.0:
            return np.zeros_like(t)
        front = m / p**2 * (2 * p * t - t**2)
        back = m / (1 - p) ** 2 * ((1 - 2 * p) + 2 * p * t - t**2)
        return np.where(t <= p, front, back)

    def camber_slope(self, t: ArrayLike) -> NDArray[np.float64]:
        """dy_c/dt, shape of ``t``."""
        t = np.asarray(t, dtype=float)
        m, p = self.max_camber, self.camber_position
        if m == 0.0:
            return np.zeros_like(t)
        front = 2 * m / p**2 * (p - t)
        back = 2 * m / (1 - p) ** 2 * (p - t)
        return np.where(t <= p, front, back)

    def camber_curvature(self, t: ArrayLike) -> NDArray[np.float64]:
        """d^2 y_c/dt^2 (piecewise constant), shape of ``t``."""
        t = np.asarray(t, dtype=float)
        m, p = self.max_camber, self.camber_position
        if m == 0.0:
            return np.zeros_like(t)
        return np.where(t <= p, -2 * m / p**2, -2 * m / (1 - p) ** 2)

    def half_thickness(self, t: ArrayLike) -> NDArray[np.float64]:
        """y_t(t) = 5 * thickness * [0.2969 sqrt(t) - 0.1260 t - ...], shape of ``t``; zero at t = 0 and 1."""
        t = np.asarray(t, dtype=float)
        a0, a1, a2, a3, a4 = THICKNESS_COEFFICIENTS
        return 5 * self.thickness * (a0 * np.sqrt(t) + t * (a1 + t * (a2 + t * (a3 + t * a4))))

    def fold_ratio(self, samples: int = 2001) -> tuple[float, float]:
        """Largest y_t(t) * kappa_c(t) on the chord and where: ``(ratio, t)``.

        With the thickness normal to the camber line, the lower surface is an offset of the
        camber line; where the offset y_t exceeds the camber line's radius of curvature
        1 / kappa_c (ratio >= 1) that surface folds over itself (a swallowtail).
        """
        if not self.camber_normal or self.max_camber == 0.0:
            return 0.0, 0.0
        t = np.linspace(0.0, 1.0, samples)
        kappa = np.abs(self.camber_curvature(t)) / (1 + self.camber_slope(t) ** 2) ** 1.5
        ratio = self.half_thickness(t) * kappa
        worst = int(np.argmax(ratio))
        return float(ratio[worst]), float(t[worst])

    def surfaces(self, chord_position: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Upper and lower surface points at chord positions ``t``, each ``(len(t), 2)`` (spec §1.2)."""
        t = np.asarray(chord_position, dtype=float)
        y_c = self.camber(t)
        y_t = self.half_thickness(t)
        theta = np.arctan(self.camber_slope(t)) if self.camber_normal else np.zeros_like(t)
        offset = np.stack([-y_t * np.sin(theta), y_t * np.cos(theta)], axis=-1)
        camber_point = np.stack([t, y_c], axis=-1)
        return camber_point + offset, camber_point - offset

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """Surface points at chord t = u^2 for u in [0, 1], shape ``(len(u), 2)``.

        The substitution t = u^2 removes the sqrt(t) singularity of the thickness at the
        leading edge, so a curve in u has a bounded derivative everywhere.
        """
        u = np.asarray(root_chord, dtype=float)
        upper_points, lower_points = self.surfaces(u * u)
        return upper_points if upper else lower_points

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """|d f / du| for the surface point at t = u^2, shape of ``u`` (finite at u = 0)."""
        u = np.asarray(root_chord, dtype=float)
        t = u * u
        a0, a1, a2, a3, a4 = THICKNESS_COEFFICIENTS
        # d y_t / du = 2u * d y_t / dt; the sqrt term gives 0.2969 * 5 * thickness exactly.
        dyt_du = 5 * self.thickness * (a0 + 2 * u * (a1 + t * (2 * a2 + t * (3 * a3 + t * 4 * a4))))
        slope = self.camber_slope(t)
        dyc_du = 2 * u * slope
        y_t = self.half_thickness(t)
        sign = 1.0 if upper else -1.0
        if self.camber_normal:
            theta = np.arctan(slope)
            dtheta_du = 2 * u * self.camber_curvature(t) / (1 + slope**2)
            dx = 2 * u - sign * (dyt_du * np.sin(theta) + y_t * np.cos(theta) * dtheta_du)
            dy = dyc_du + sign * (dyt_du * np.cos(theta) - y_t * np.sin(theta) * dtheta_du)
        else:
            dx = 2 * u
            dy = dyc_du + sign * dyt_du
        return np.hypot(dx, dy)


def airfoil_points(airfoil: NacaAirfoil, t: ArrayLike) -> NDArray[np.float64]:
    """The closed section f(t) of spec §1.3 for t in [0, 2], shape ``(len(t), 2)``.

    t in [0, 1]: upper surface at chord t (leading edge -> trailing edge);
    t in (1, 2]: lower surface at chord 2 - t (trailing edge -> leading edge).
    """
    t = np.asarray(t, dtype=float)
    on_upper = t <= 1.0
    chord = np.where(on_upper, t, 2.0 - t)
    upper, lower = airfoil.surfaces(chord)
    return np.where(on_upper[..., None], upper, lower)
