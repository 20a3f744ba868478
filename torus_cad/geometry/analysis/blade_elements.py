"""Blade elements: what a designer reads off each section (radius, chord, thickness, beta, pitch).

Conventions (mm and degrees; the spin axis is z; "cw" / "ccw" = clockwise / counter-clockwise
seen from +z, looking down the axis toward -z). The blade as the spec builds it turns
clockwise (``Handedness.CW``), as ``handedness = "cw"`` says; its mirror image
(``"ccw"``) has the same table with the position angles negated.

* The section's **chord line** runs from its leading edge (the section's point at t = 0) to its
  trailing edge (the sharp edge, or the middle of a blunt edge's base).
* **r**, **axial position** and **position angle** are those of the chord's mid point
  (cylindrical coordinates about the z axis; the angle is blade 0's, phase included).
* **beta**, the blade angle: the angle between the chord line and the plane of rotation,
  measured in the plane that holds the chord and the axis direction:
  tan beta = -c_z / h, with c the chord vector (leading -> trailing edge), c_z its axial part
  and h the length of its part in the plane of rotation, counted negative when the trailing
  edge is ahead of the leading edge in the direction of rotation (a section running
  backwards). beta > 0: moving leading edge first, the element pushes air toward -z.
* **Geometric pitch** P = 2 pi r tan beta: how far the element's chord line, followed as a
  helix, advances along +z per turn.
* Where the definition stops meaning much: a loop blade's sections can turn so that their
  chord runs mostly *radially*; then the element does not move along its chord, beta only says
  how the chord leans toward the axis, and the pitch is no helix's pitch. ``radial_fraction``
  = |c_r| / h flags it: above 1/sqrt(2) the chord runs more radially than around the axis.
* **Thickness**: the largest distance between the upper and the lower surface measured
  perpendicular to the chord line in the section's plane (mm), and as a fraction of the chord.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.section.section import section_thickness

#: Above this |c_r| / h the chord runs more radially than around the axis: beta and the pitch say
#: little.
NEARLY_RADIAL_FRACTION = float(np.sqrt(0.5))


@dataclass(frozen=True)
class BladeElements:
    """One row per section; every array is ``(k,)``.

    Attributes:
        s: centerline parameter of each section.
        radius_mm, axial_mm, position_angle_deg: the chord mid point in cylindrical coordinates.
        chord_mm: chord length.
        thickness_mm, thickness_ratio: largest thickness perpendicular to the chord, and over the
            chord.
        beta_deg: blade angle (module docstring), in (-180, 180].
        pitch_mm: geometric pitch 2 pi r tan beta.
        radial_fraction: |c_r| / h, how radially the chord runs (> NEARLY_RADIAL_FRACTION: beta says
            little).
        spin: which way the propeller turns seen from +z (cw, the default, or ccw).
    """

    s: NDArray[np.float64]
    radius_mm: NDArray[np.float64]
    axial_mm: NDArray[np.float64]
    position_angle_deg: NDArray[np.float64]
    chord_mm: NDArray[np.float64]
    thickness_mm: NDArray[np.float64]
    thickness_ratio: NDArray[np.float64]
    beta_deg: NDArray[np.float64]
    pitch_mm: NDArray[np.float64]
    radial_fraction: NDArray[np.float64]
    spin: Handedness = Handedness.CW

    COLUMNS = (
        "s",
        "radius_mm",
        "axial_mm",
        "chord_mm",
        "thickness_mm",
        "thickness_ratio",
        "beta_deg",
        "pitch_mm",
        "position_angle_deg",
        "radial_fraction",
    )

    def rows(self) -> list[dict[str, float]]:
        """The table as a list of ``{column: value}``, columns in :attr:`COLUMNS` order."""
        return [
            {name: float(getattr(self, name)[index]) for name in self.COLUMNS}
            for index in range(len(self.s))
        ]

    def pitch_at_radius(self, radius_mm: float) -> NDArray[np.float64]:
        """Geometric pitch where r(s) crosses ``radius_mm``, linearly interpolated: ``(c,)``, one
        per crossing.

        A loop blade passes each radius twice (out and back), so there are usually two values.
        """
        r, pitch = self.radius_mm, self.pitch_mm
        values = []
        for index in np.flatnonzero(np.diff(np.sign(r - radius_mm)) != 0):
            weight = (radius_mm - r[index]) / (r[index + 1] - r[index])
            values.append(pitch[index] + weight * (pitch[index + 1] - pitch[index]))
        return np.array(values)


def chord_lines(
    points: NDArray[np.float64], trailing_edge_index: int, lower_corner_index: int | None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Leading-edge points and chord vectors (leading -> trailing edge) of sections ``(k, p, 3)``:
    two ``(k, 3)``."""
    leading = points[:, 0]
    trailing = points[:, trailing_edge_index]
    if lower_corner_index is not None:
        trailing = 0.5 * (trailing + points[:, lower_corner_index])
    return leading, trailing - leading


def blade_angles(
    middle: NDArray[np.float64], chord: NDArray[np.float64], spin: Handedness = Handedness.CW
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """beta (degrees) and the radial fraction |c_r| / h of chords ``(k, 3)`` whose mid points are
    ``middle``."""
    radial = middle[:, :2] / np.linalg.norm(middle[:, :2], axis=1, keepdims=True)
    tangential = np.stack([-radial[:, 1], radial[:, 0]], axis=1)  # ccw direction
    c_r = np.sum(chord[:, :2] * radial, axis=1)
    c_theta = np.sum(chord[:, :2] * tangential, axis=1)
    horizontal = np.hypot(c_r, c_theta)
    # The trailing edge trails the leading edge when the chord points against the rotation.
    signed = np.where(spin.sign * c_theta <= 0.0, horizontal, -horizontal)
    beta = np.degrees(np.arctan2(-chord[:, 2], signed))
    return beta, np.abs(c_r) / np.maximum(horizontal, 1e-300)


def blade_elements(
    s: NDArray[np.float64],
    points: NDArray[np.float64],
    origin: NDArray[np.float64],
    normal: NDArray[np.float64],
    binormal: NDArray[np.float64],
    trailing_edge_index: int,
    lower_corner_index: int | None = None,
    spin: Handedness = Handedness.CW,
) -> BladeElements:
    """The blade-element table of sampled sections.

    Args:
        s: ``(k,)`` centerline parameters.
        points: ``(k, p, 3)`` mm, closed sections starting at the leading edge, upper surface first.
        origin, normal, binormal: ``(k, 3)`` each section's frame (its plane is spanned by N and B).
        trailing_edge_index, lower_corner_index: columns of the trailing edge (and a blunt edge's
            lower corner).
        spin: which way the propeller turns seen from +z (cw, the default, or ccw).
    """
    leading, chord = chord_lines(points, trailing_edge_index, lower_corner_index)
    middle = leading + 0.5 * chord
    radius = np.hypot(middle[:, 0], middle[:, 1])
    beta, radial_fraction = blade_angles(middle, chord, spin)
    relative = points - origin[:, None, :]
    planar = np.stack(
        [np.einsum("kpj,kj->kp", relative, normal), np.einsum("kpj,kj->kp", relative, binormal)], -1
    )
    chord_mm = np.linalg.norm(chord, axis=1)
    thickness = section_thickness(planar, trailing_edge_index, lower_corner_index)
    with np.errstate(over="ignore", invalid="ignore"):
        pitch = 2.0 * np.pi * radius * np.tan(np.radians(beta))
    return BladeElements(
        s=np.asarray(s, float),
        radius_mm=radius,
        axial_mm=middle[:, 2],
        position_angle_deg=np.degrees(np.arctan2(middle[:, 1], middle[:, 0])),
        chord_mm=chord_mm,
        thickness_mm=thickness,
        thickness_ratio=thickness / chord_mm,
        beta_deg=beta,
        pitch_mm=pitch,
        radial_fraction=radial_fraction,
        spin=spin,
    )
