"""Intersecting triangle pairs of the surface mesh, and where they are looked for.

The check is the package's one crossing check (torus_cad.kernel.mesh_check.crossing_pairs, meshlib's
``findSelfCollidingTriangles`` on single-precision coordinates, the precision of a binary STL: the
check is of the mesh as the STL stores it). Triangles that only share an edge or a vertex do not
count.

Checking every triangle costs time in proportion (the docs' measurements page). Meshes up to
:data:`MESH_WHOLE_CROSSING_CHECK_TRIANGLES` are checked whole. Larger ones
are checked where a structured mesh of the blade can cross itself: everywhere on the hub and
at the junctions (where the union and the cleanup made new triangles), and on blade 0 in bands
along the leading and trailing edges, the only places where the blade is thinner than its cells
(elsewhere the resolution check keeps every cell within a small fraction of the local section
thickness of the surface, so its two sides cannot meet). The other blades are blade 0 turned
about the axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.kernel.mesh_check import crossing_pairs as mesh_crossing_pairs

#: Surface meshes (``torus-cad mesh``) up to this many triangles are checked whole for intersecting
#: triangle pairs; larger ones where a structured mesh can cross (the cost per triangle:
#: docs/explanation/measurements.md).
MESH_WHOLE_CROSSING_CHECK_TRIANGLES = 1_500_000

#: Columns on each side of the leading and trailing edges (and the whole base of a blunt edge)
#: that the partial check covers, as a fraction of the points around a section (at least 8).
EDGE_BAND_FRACTION = 0.05


@dataclass(frozen=True)
class CrossingCheck:
    """What the check found and where it looked.

    Attributes:
        pairs: intersecting triangle pairs found.
        checked_triangles: triangles the check covered.
        scope: ``"whole mesh"`` or a description of the parts checked.
    """

    pairs: int
    checked_triangles: int
    scope: str


def crossing_pairs(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], region: NDArray[np.bool_] | None = None
) -> int:
    """How many intersecting pairs among the ``(f, 3)`` faces over ``(v, 3)`` vertices (mm), or
    among the faces where ``region`` ``(f,)`` is True
    (torus_cad.kernel.mesh_check.crossing_pairs)."""
    return len(mesh_crossing_pairs(vertices, faces, region))


def edge_band_faces(
    sections: int, count: int, trailing_edge: int, lower_corner: int | None
) -> NDArray[np.bool_]:
    """``(f,)`` True for the side faces of a structured blade mesh (``grids.mirrored_diagonal_mesh``
    layout: both triangles of every cell, then the caps, which are included) near the edges."""
    band = max(8, int(np.ceil(EDGE_BAND_FRACTION * count)))
    column = np.arange(count)
    last = trailing_edge if lower_corner is None else lower_corner

    def near(edge_start: int, edge_end: int) -> NDArray[np.bool_]:
        return (column >= edge_start - band) & (column < edge_end + band)

    columns = near(trailing_edge, last) | (column < band) | (column >= count - band)
    cells = np.tile(columns, sections - 1)
    caps = np.ones(2 * (count - 2), dtype=bool)
    return np.concatenate([cells, cells, caps])


def blade_crossings(
    blade: TriangleMesh,
    sections: int,
    count: int,
    trailing_edge: int,
    lower_corner: int | None,
    whole: bool,
) -> CrossingCheck:
    """Intersecting pairs of blade 0's closed mesh, whole or in its edge bands."""
    if whole:
        return CrossingCheck(
            crossing_pairs(blade.vertices, blade.faces), len(blade.faces), "whole mesh"
        )
    region = edge_band_faces(sections, count, trailing_edge, lower_corner)
    if len(region) != len(blade.faces):
        region = np.ones(len(blade.faces), dtype=bool)
    return CrossingCheck(
        crossing_pairs(blade.vertices, blade.faces, region),
        int(region.sum()),
        "blade 0's leading- and trailing-edge bands",
    )


__all__ = ["CrossingCheck", "blade_crossings", "crossing_pairs", "edge_band_faces"]
