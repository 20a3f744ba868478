"""How many triangles an STL of the propeller will have, estimated before anything is tessellated.

A mesher that keeps every edge within a chordal deviation ``d`` (mm) and within an angular
deviation ``a`` (radians) of a surface with normal curvature kappa (1/mm) along a direction needs
edges no longer than min(sqrt(8 d / kappa), a / kappa) there. Summed over a sampled surface this
gives edges per direction, ``n = max(theta / a, sqrt(theta * length / (8 d)))`` for a piece of
``length`` mm that turns by ``theta`` radians, and about ``2 n_u n_v`` triangles per patch.

Kernel-free (numpy only) so that work that would blow up is refused before the kernel starts.
The estimate is calibrated against OpenCascade's BRepMesh (``scripts/stl_budget.py``) to be an
upper bound of the real count within a small factor; it is a budget, not a prediction.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

#: The estimate is multiplied by this: BRepMesh refines a lofted B-spline face beyond the
#: ideal edge lengths above (measured by scripts/stl_budget.py, see the README).
BREPMESH_FACTOR = 2.0


def _segments_needed(turn_rad: NDArray[np.float64], length_mm: NDArray[np.float64], linear_deflection: float,
                     angular_deflection: float) -> NDArray[np.float64]:
    """Edges a piece of curve of ``length_mm`` that turns by ``turn_rad`` needs (fractional, elementwise)."""
    return np.maximum(turn_rad / angular_deflection, np.sqrt(turn_rad * length_mm / (8.0 * linear_deflection)))


def _turns(points: NDArray[np.float64], closed: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Turning angle (rad) at each point of polylines along axis 1 and the length (mm) each point stands for.

    ``points`` is ``(rows, k, 3)``; open polylines get zero turn at their two ends.
    """
    if closed:
        before = points - np.roll(points, 1, axis=1)
        after = np.roll(before, -1, axis=1)
    else:
        steps = np.diff(points, axis=1)
        zero = np.zeros_like(steps[:, :1])
        before = np.concatenate([zero, steps], axis=1)
        after = np.concatenate([steps, zero], axis=1)
    len_before = np.linalg.norm(before, axis=-1)
    len_after = np.linalg.norm(after, axis=-1)
    cosine = np.einsum("rkc,rkc->rk", before, after) / np.maximum(len_before * len_after, 1e-300)
    turn = np.where((len_before > 0) & (len_after > 0), np.arccos(np.clip(cosine, -1.0, 1.0)), 0.0)
    return turn, 0.5 * (len_before + len_after)


def blade_triangles(points: NDArray[np.float64], linear_deflection: float, angular_deflection: float) -> float:
    """Triangles of one blade's side surface sampled as ``(sections, points, 3)`` mm (rows closed).

    The sample grid must resolve the surface (turning angles of a few degrees per step); the
    two planar end caps are counted with the hub, whose footprints they are.
    """
    turn_around, length_around = _turns(points, closed=True)
    turn_along, length_along = _turns(np.swapaxes(points, 0, 1), closed=False)
    turn_along, length_along = turn_along.T, length_along.T
    n_around = _segments_needed(turn_around, length_around, linear_deflection, angular_deflection)
    n_along = _segments_needed(turn_along, length_along, linear_deflection, angular_deflection)
    # A direction without curvature still gets edges: as many as one the other direction needs
    # over the whole span (the mesher's triangles stay within a bounded aspect ratio there).
    span_mm = length_along.sum(axis=0, keepdims=True)
    n_along = np.maximum(n_along, length_along / span_mm * n_around.sum(axis=1, keepdims=True).mean())
    return float(2.0 * np.sum(n_around * n_along))


def section_outline_segments(section: NDArray[np.float64], linear_deflection: float,
                             angular_deflection: float) -> float:
    """Edges around one closed section outline ``(points, 3)`` mm."""
    turn, length = _turns(section[None], closed=True)
    return float(_segments_needed(turn, length, linear_deflection, angular_deflection).sum())


def hub_triangles(radius_mm: float, linear_deflection: float, angular_deflection: float) -> float:
    """Triangles of the bare cylindrical hub: its lateral face in strips and its two end discs."""
    around = _segments_needed(np.array(2.0 * math.pi), np.array(2.0 * math.pi * radius_mm),
                              linear_deflection, angular_deflection)
    return 4.0 * float(max(around, 3.0))


def estimate_stl_triangles(blade_points: NDArray[np.float64], blades: int, hub_radius_mm: float,
                           linear_deflection: float, angular_deflection: float) -> int:
    """Upper-ish estimate of the STL triangle count of the fused propeller.

    Args:
        blade_points: blade 0's side surface, ``(sections, points, 3)`` mm, rows closed sections.
        blades: number of blades (every blade is a rotated copy of blade 0).
        hub_radius_mm: the hub's radius.
        linear_deflection: the STL's chordal deviation, mm (> 0).
        angular_deflection: the STL's angular deviation, radians (> 0).
    """
    blade = blade_triangles(blade_points, linear_deflection, angular_deflection)
    # Each blade end leaves a hole in the hub bordered by its section outline: a ring of triangles.
    ends = sum(section_outline_segments(blade_points[i], linear_deflection, angular_deflection) for i in (0, -1))
    hub = hub_triangles(hub_radius_mm, linear_deflection, angular_deflection)
    return math.ceil(BREPMESH_FACTOR * (blades * (blade + 3.0 * ends) + hub))
