"""Blade centerline (spec §3): control points in the hub's frame L, then a cubic clamped NURBS.

Frame L (spec §3.1, units as in the configuration): x_L is the angle around the hub axis in
degrees, y_L runs along the axis pointing down (mm, toward -z), z_L runs radially outward (mm).
Its origin P1 sits at cylindrical (r, theta, z) = (R - R/8, theta_blade, L/2 - 1).
"""

from __future__ import annotations

import numpy as np
from geomdl import BSpline
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline as ScipyBSpline

#: Clamped cubic knot vector with a single span (spec §3.4).
KNOT_VECTOR = (0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0)


def hub_inset_radius_mm(hub_radius_mm: float) -> float:
    """R_inset = R - R/8 (spec §3.2), mm: the radius at which the blade's ends (frame L's origin)
    sit in a hub of radius ``hub_radius_mm``. The one place the rule is written."""
    return hub_radius_mm - hub_radius_mm / 8.0


def free_point_z_range_mm(hub_radius_mm: float) -> tuple[float, float]:
    """(low, high), mm: the range of a free control point's z_L (p2, p3), low excluded: from the
    hub's axis (z_L = -R_inset, frame L's origin sitting at R_inset) out to a hundred hub radii."""
    return -hub_inset_radius_mm(hub_radius_mm), 100.0 * hub_radius_mm


def local_to_cylindrical(
    local: ArrayLike, hub_radius: float, hub_length: float, blade_angle_deg: float
) -> NDArray[np.float64]:
    """Frame L -> global cylindrical (r mm, theta deg, z mm), ``(k, 3)`` (spec §3.3: M . P_L +
    P1_C)."""
    local = np.atleast_2d(np.asarray(local, dtype=float))
    change_of_basis = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    origin = np.array([hub_inset_radius_mm(hub_radius), blade_angle_deg, hub_length / 2.0 - 1.0])
    return local @ change_of_basis.T + origin


def cylindrical_to_cartesian(cylindrical: ArrayLike) -> NDArray[np.float64]:
    """(r, theta deg, z) -> (x, y, z), ``(k, 3)`` mm."""
    r, theta_deg, z = np.moveaxis(np.atleast_2d(np.asarray(cylindrical, dtype=float)), -1, 0)
    theta = np.radians(theta_deg)
    return np.stack([r * np.cos(theta), r * np.sin(theta), z], axis=-1)


class Centerline:
    """The cubic clamped B-spline C(s), s in [0, 1] (all weights 1, so the NURBS is polynomial).

    The curve is defined with geomdl (``self.curve``: degree, knots, control points); it is
    evaluated, with its derivatives, for whole arrays of s at once by scipy's B-spline of the
    same knots and poles (geomdl evaluates one point at a time in Python). Results are numpy
    arrays in mm.
    """

    def __init__(self, cartesian_control_points: ArrayLike) -> None:
        points = np.asarray(cartesian_control_points, dtype=float)
        if points.shape != (4, 3):
            raise ValueError(f"a cubic centerline needs (4, 3) control points, got {points.shape}")
        self.control_points = points
        curve = BSpline.Curve()
        curve.degree = 3
        curve.ctrlpts = points.tolist()
        curve.knotvector = list(KNOT_VECTOR)
        self.curve = curve
        spline = ScipyBSpline(np.asarray(curve.knotvector), np.asarray(curve.ctrlpts), curve.degree)
        self._derivatives = [spline] + [spline.derivative(k) for k in range(1, curve.degree + 1)]

    @classmethod
    def in_hub_frame(
        cls,
        local_control_points: ArrayLike,
        hub_radius_mm: float,
        hub_length_mm: float,
        blade_angle_deg: float,
    ) -> "Centerline":
        """The centerline whose control points ``(4, 3)`` are given in frame L of a blade at
        ``blade_angle_deg``."""
        cylindrical = local_to_cylindrical(
            local_control_points, hub_radius_mm, hub_length_mm, blade_angle_deg
        )
        return cls(cylindrical_to_cartesian(cylindrical))

    def derivatives(self, s: ArrayLike, order: int = 3) -> NDArray[np.float64]:
        """C and its derivatives d^k C / ds^k, k = 0..order: ``(len(s), order + 1, 3)`` mm."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        values = [
            self._derivatives[k](s) if k < len(self._derivatives) else np.zeros((len(s), 3))
            for k in range(order + 1)
        ]
        return np.stack(values, axis=1)

    def points(self, s: ArrayLike) -> NDArray[np.float64]:
        """C(s), ``(len(s), 3)`` mm."""
        return np.asarray(self._derivatives[0](np.atleast_1d(np.asarray(s, dtype=float))))

    def length(self, samples: int = 2001) -> float:
        """Arc length of the centerline (mm), from a dense polyline."""
        points = self.points(np.linspace(0.0, 1.0, samples))
        return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
