"""Section transforms along the centerline (spec §2): alpha(s), Sx(s), Sy(s) and their application.

Each transform is a quartic in s in [0, 1] with coefficients highest power first,
a s^4 + b s^3 + c s^2 + d s + e. The section is rotated by alpha(s) first, then scaled
by Sx(s) along X and Sy(s) along Y (spec §2.3: rotation, then scaling).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray


def evaluate_quartic(coefficients: Sequence[float], s: ArrayLike) -> NDArray[np.float64]:
    """a s^4 + b s^3 + c s^2 + d s + e for coefficients (a, b, c, d, e); shape of ``s``."""
    if len(coefficients) != 5:
        raise ValueError(f"a quartic needs 5 coefficients, got {len(coefficients)}")
    return np.polyval(np.asarray(coefficients, dtype=float), np.asarray(s, dtype=float))


def rotation_matrices(angle_deg: ArrayLike) -> NDArray[np.float64]:
    """R(s) of spec §2.1 for angles in degrees: shape ``(*angle.shape, 2, 2)``."""
    angle = np.radians(np.asarray(angle_deg, dtype=float))
    cos, sin = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([cos, -sin], -1), np.stack([sin, cos], -1)], -2)


def transform_sections(section: NDArray[np.float64], angle_deg: ArrayLike, scale_x: ArrayLike,
                       scale_y: ArrayLike, pivot: float = 0.0) -> NDArray[np.float64]:
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
