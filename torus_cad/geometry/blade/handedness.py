"""Which way a blade must turn to push air toward -z: a flat-plate estimate from the sampled blade.

Model (Newtonian flat plate): each section is a plate of chord c = TE - LE spanning a strip
ds of the centerline, with unit normal n = T x c / |T x c| (T the centerline's tangent). When
the blade turns about +z with angular velocity omega, the section moves at v = omega x p (p
its mid-chord); the air meets it at w = -v and loses its velocity component normal to the
plate, so the plate pushes the air by -(w . n) |w . n| n per unit area. The z components,
times chord x ds, summed over the blade, say which way the air goes. The estimate does not
depend on n's sign, and a mirror image through a plane containing the axis turns its sign, so
the mirror image spins the other way for the same push.

For the spec's blades (P1..P4 descending down the axis as their angle grows, y_L increasing
with x_L) the blade is a descending ribbon, and the estimate is: clockwise seen from +z pushes
air toward -z.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np
from numpy.typing import NDArray


class Handedness(StrEnum):
    """A turn about the z axis, seen from +z (looking down the axis toward -z): the one spin type.

    As a design's ``handedness``: which way the propeller turns to push air toward -z; 'cw' is the
    spec's blade (a ribbon descending as its angle grows), 'ccw' its exact mirror image.
    """

    CW = "cw"
    CCW = "ccw"

    @property
    def sign(self) -> int:
        """The turn's sign about +z by the right-hand rule: -1 clockwise, +1 counter-clockwise."""
        return -1 if self is Handedness.CW else 1

    @property
    def opposite(self) -> Handedness:
        """The other way round (a mirror image through a plane containing the axis)."""
        return Handedness.CCW if self is Handedness.CW else Handedness.CW


def air_push_z(
    blade_points: NDArray[np.float64], trailing_edge_index: int, spin: Handedness = Handedness.CCW
) -> float:
    """z push on the air (arbitrary units) when the blade turns ``spin`` about +z.

    ``blade_points`` is a sampled blade ``(sections, points, 3)`` mm with the leading edge in
    column 0 and the trailing edge in column ``trailing_edge_index``. Negative: air toward -z.
    """
    points = np.asarray(blade_points, dtype=float)
    leading, trailing = points[:, 0], points[:, trailing_edge_index]
    middle = 0.5 * (leading + trailing)
    chord_vector = trailing - leading
    tangent = np.gradient(middle, axis=0)
    step = np.linalg.norm(tangent, axis=1)
    normal = np.cross(tangent, chord_vector)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    wind = -spin.sign * np.stack([-middle[:, 1], middle[:, 0], np.zeros(len(middle))], axis=1)
    across = np.einsum("ij,ij->i", wind, normal)
    return float(
        np.sum(
            -across * np.abs(across) * normal[:, 2] * np.linalg.norm(chord_vector, axis=1) * step
        )
    )


def spin_to_push_air_down(
    blade_points: NDArray[np.float64], trailing_edge_index: int
) -> Handedness:
    """The turn, seen from +z, that pushes air toward -z (module docstring)."""
    return (
        Handedness.CCW
        if air_push_z(blade_points, trailing_edge_index, Handedness.CCW) < 0.0
        else Handedness.CW
    )
