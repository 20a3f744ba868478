"""How many triangles an STL of the propeller will have, estimated before anything is tessellated.

OpenCascade's mesher (BRepMesh_IncrementalMesh with a linear deflection ``d`` mm and an angular
deflection ``a`` rad) refines a face's interior until every triangle is within ``d`` of the surface
and adjacent normals differ by less than ``2 a`` (its AngleInterior), but never below edges of
``0.1 d`` (its MinSize). Where the surface curves by kappa (1/mm, the larger principal curvature)
that asks for edges of about

    l = max(min(sqrt(8 d / kappa), 2 a / kappa), 0.1 d)

and its Delaunay triangles are close to equilateral, so a patch of area A gets about 2 A / l^2
triangles. Summed over the blade surface sampled by the geometry layer (the trailing edge is a
designed crease, not curvature), times the number of blades, plus the hub, times a calibration
factor, this is an upper estimate of the real count: ``scripts/stl_budget.py`` measures it at 1x to
4x the count BRepMesh makes over designs and deflections 0.002-0.5 mm, 0.02-0.5 rad.

Kernel-free (numpy only) so that work that would blow up is refused before it starts.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

#: BRepMesh's interior angle is twice the angular deflection; its smallest edge a tenth of the
#: linear one.
ANGLE_INTERIOR_FACTOR = 2.0
MIN_SIZE_RELATIVE = 0.1

#: Multiplies the curvature model so that it stays above BRepMesh's real counts
#: (scripts/stl_budget.py).
CALIBRATION_FACTOR = 3.0


def _turns(
    points: NDArray[np.float64], closed: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Turning angle (rad) at each point of polylines along axis 1 and the length (mm) each point
    stands for.

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


def edge_length(
    curvature: NDArray[np.float64], linear_deflection: float, angular_deflection: float
) -> NDArray[np.float64]:
    """The mesher's edge length (mm) where the surface curves by ``curvature`` (1/mm),
    elementwise."""
    curvature = np.maximum(curvature, 1e-12)
    ideal = np.minimum(
        np.sqrt(8.0 * linear_deflection / curvature),
        ANGLE_INTERIOR_FACTOR * angular_deflection / curvature,
    )
    return np.maximum(ideal, MIN_SIZE_RELATIVE * linear_deflection)


def blade_triangles(
    points: NDArray[np.float64],
    trailing_edge_index: int | None,
    linear_deflection: float,
    angular_deflection: float,
) -> float:
    """Triangles of one blade's side surface sampled as ``(sections, points, 3)`` mm (rows: closed
    sections; ``trailing_edge_index``: the column of the sharp trailing edge, if sampled).

    The two planar end caps are counted with the hub, whose footprints they are.
    """
    turn_around, length_around = _turns(points, closed=True)
    if trailing_edge_index is not None:  # the crease is a corner of the section, not a curvature
        neighbours = [(trailing_edge_index + step) % points.shape[1] for step in (-1, 1)]
        turn_around = turn_around.copy()
        turn_around[:, trailing_edge_index] = turn_around[:, neighbours].mean(axis=1)
    turn_along, length_along = (
        values.T for values in _turns(np.swapaxes(points, 0, 1), closed=False)
    )
    curvature = np.maximum(
        turn_around / np.maximum(length_around, 1e-300),
        turn_along / np.maximum(length_along, 1e-300),
    )
    edges = edge_length(curvature, linear_deflection, angular_deflection)
    return float(np.sum(2.0 * length_around * length_along / edges**2))


def outline_segments(
    section: NDArray[np.float64], linear_deflection: float, angular_deflection: float
) -> float:
    """Edges along one closed section outline ``(points, 3)`` mm."""
    turn, length = _turns(section[None], closed=True)
    return float(
        np.sum(
            length
            / edge_length(turn / np.maximum(length, 1e-300), linear_deflection, angular_deflection)
        )
    )


def hub_triangles(radius_mm: float, linear_deflection: float, angular_deflection: float) -> float:
    """Triangles of the bare cylindrical hub: its lateral face in strips along the axis and its two
    end discs."""
    around = (
        2.0
        * math.pi
        * radius_mm
        / float(edge_length(np.array(1.0 / radius_mm), linear_deflection, angular_deflection))
    )
    return 4.0 * max(around, 3.0)


def estimate_stl_triangles(
    blade_points: NDArray[np.float64],
    trailing_edge_index: int | None,
    blades: int,
    hub_radius_mm: float,
    linear_deflection: float,
    angular_deflection: float,
    pole_grid: tuple[int, int],
) -> int:
    """Upper estimate of the STL triangle count of the fused propeller.

    Args:
        blade_points: blade 0's side surface, ``(sections, points, 3)`` mm, rows closed sections;
            about 12 x 40 samples or more resolve it (the estimate converges from there).
        trailing_edge_index: the column of the sharp trailing edge (None if not sampled).
        blades: number of blades (every blade is a rotated copy of blade 0).
        hub_radius_mm: the hub's radius.
        linear_deflection: the STL's chordal deviation, mm (> 0).
        angular_deflection: the STL's angular deviation, radians (> 0).
        pole_grid: (sections, poles around a section) of the blade's B-spline surface: the mesher
            starts from a grid of about that many nodes, whatever the deflections.
    """
    blade = blade_triangles(
        blade_points, trailing_edge_index, linear_deflection, angular_deflection
    )
    start_grid = 2.0 * pole_grid[0] * pole_grid[1]
    # Each blade end leaves a hole in the hub bordered by its section outline: a ring of triangles.
    ends = sum(
        outline_segments(blade_points[i], linear_deflection, angular_deflection) for i in (0, -1)
    )
    hub = hub_triangles(hub_radius_mm, linear_deflection, angular_deflection)
    return math.ceil(
        CALIBRATION_FACTOR * (blades * (blade + 3.0 * ends) + hub) + blades * start_grid
    )
