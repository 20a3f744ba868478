"""Section transforms along the centerline (spec §2): alpha(s), Sx(s), Sy(s) and their application.

Each transform is a quartic in s in [0, 1] with coefficients highest power first,
a s^4 + b s^3 + c s^2 + d s + e. The section is rotated by alpha(s) first, then scaled
by Sx(s) along X and Sy(s) along Y (spec §2.3: rotation, then scaling).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Coefficients of a quartic in s, highest power first: (a, b, c, d, e).
Quartic = tuple[float, float, float, float, float]


def evaluate_quartic(coefficients: Sequence[float], s: ArrayLike) -> NDArray[np.float64]:
    """a s^4 + b s^3 + c s^2 + d s + e for coefficients (a, b, c, d, e); shape of ``s``."""
    if len(coefficients) != 5:
        raise ValueError(f"a quartic needs 5 coefficients, got {len(coefficients)}")
    return np.polyval(np.asarray(coefficients, dtype=float), np.asarray(s, dtype=float))


def quartic_minimum(coefficients: Sequence[float]) -> tuple[float, float]:
    """Minimum of a quartic (highest power first) on s in [0, 1]: ``(value, s)``.

    Checks the end points and every real root of the derivative inside [0, 1], so the
    answer is exact, not a sampled estimate.
    """
    derivative = np.polyder(np.asarray(coefficients, dtype=float))
    # np.roots divides by the leading coefficient: drop leading terms that are negligible
    # (e.g. subnormal) against the largest, or it overflows.
    significant = np.nonzero(np.abs(derivative) > 1e-12 * np.abs(derivative).max(initial=0.0))[0]
    derivative_roots = np.roots(derivative[significant[0] :]) if significant.size else np.array([])
    candidates = [0.0, 1.0] + [
        r.real
        for r in np.atleast_1d(derivative_roots)
        if abs(r.imag) < 1e-12 and 0.0 <= r.real <= 1.0
    ]
    values = np.polyval(coefficients, candidates)
    index = int(np.argmin(values))
    return float(values[index]), float(candidates[index])


@dataclass(frozen=True)
class SectionLaws:
    """How the section changes along the blade (spec §2): three quartics in s and the pivot.

    Attributes:
        angle_of_attack_deg: alpha(s) coefficients, degrees.
        scale_x_mm: Sx(s) coefficients, mm (the chord, along N).
        scale_y_mm: Sy(s) coefficients, mm (along B).
        pivot: chord fraction put on the centerline, the centre of the rotation (0 = leading edge).
    """

    angle_of_attack_deg: Quartic
    scale_x_mm: Quartic
    scale_y_mm: Quartic
    pivot: float = 0.0

    def apply(self, section: NDArray[np.float64], s: ArrayLike) -> NDArray[np.float64]:
        """A chord-unit section ``(p, 2)`` (or one per s, ``(len(s), p, 2)``) rotated and scaled for
        every s: ``(len(s), p, 2)`` mm."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        return transform_sections(
            section,
            evaluate_quartic(self.angle_of_attack_deg, s),
            evaluate_quartic(self.scale_x_mm, s),
            evaluate_quartic(self.scale_y_mm, s),
            self.pivot,
        )


def rotation_matrices(angle_deg: ArrayLike) -> NDArray[np.float64]:
    """R(s) of spec §2.1 for angles in degrees: shape ``(*angle.shape, 2, 2)``."""
    angle = np.radians(np.asarray(angle_deg, dtype=float))
    cos, sin = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([cos, -sin], -1), np.stack([sin, cos], -1)], -2)


def transform_sections(
    section: NDArray[np.float64],
    angle_deg: ArrayLike,
    scale_x: ArrayLike,
    scale_y: ArrayLike,
    pivot: float = 0.0,
) -> NDArray[np.float64]:
    """Rotate, then scale, one section for every s (spec §2.3).

    Args:
        section: ``(p, 2)`` float, the airfoil in chord units (x along the chord), or
            ``(k, p, 2)``, one per s (sections that change along s, e.g. a blunt trailing edge).
        angle_deg: ``(k,)`` alpha(s) in degrees.
        scale_x: ``(k,)`` Sx(s) in mm.
        scale_y: ``(k,)`` Sy(s) in mm.
        pivot: chord fraction moved to the origin before the rotation (0 = leading edge, the spec).

    Returns:
        ``(k, p, 2)`` float, mm: (X_scaled, Y_scaled) of each section in its own plane.
    """
    shifted = np.asarray(section, dtype=float) - np.array([pivot, 0.0])
    pattern = "kij,pj->kpi" if shifted.ndim == 2 else "kij,kpj->kpi"
    rotated = np.einsum(pattern, rotation_matrices(angle_deg), shifted)
    scales = np.stack([np.asarray(scale_x, float), np.asarray(scale_y, float)], axis=-1)
    return rotated * scales[:, None, :]
