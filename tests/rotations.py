"""Rotations the tests turn blades and rotors by."""

from __future__ import annotations

import numpy as np


def rotation_about_z(angle_deg: float) -> np.ndarray:
    """The ``(3, 3)`` rotation by ``angle_deg`` degrees about +z (the spin axis)."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
