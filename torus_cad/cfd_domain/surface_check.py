"""Crossing triangles of the domain's surface mesh, found before the volume mesher is asked to fill
it.

gmsh's 3D Delaunay mesher stops with "PLC Error: A segment and a facet intersect" when the
surface mesh crosses itself. A coarse mesh does that where the propeller is thinner than its
triangles' sag, e.g. at a knife trailing edge that is a crease inside one B-rep face. The
surface mesh is read from gmsh and checked by the package's one crossing check
(torus_cad.kernel.mesh_check.crossing_pairs, meshlib's ``findSelfCollidingTriangles``: a
bounding-volume tree; tens of milliseconds for tens of thousands of triangles).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from torus_cad.kernel.mesh_check import crossing_pairs


@dataclass(frozen=True)
class Crossings:
    """Triangles of the surface mesh that intersect another triangle (not a neighbour).

    Attributes:
        centres_mm: ``(k, 3)`` centroids of the crossing triangles.
        edge_mm: ``(k,)`` longest edge of each crossing triangle.
        surfaces: gmsh surface tags holding them.
    """

    centres_mm: np.ndarray
    edge_mm: np.ndarray
    surfaces: tuple[int, ...]

    def __len__(self) -> int:
        return len(self.centres_mm)


def surface_triangles(gmsh: Any, surfaces: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles of gmsh ``surfaces``: ``(n, 3)`` points (mm), ``(t, 3)`` 0-based point indices
    and ``(t,)`` the surface tag of each triangle."""
    node_tags, coordinates, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(node_tags)
    blocks, owners = [], []
    for tag in surfaces:
        _, nodes = gmsh.model.mesh.getElementsByType(2, tag)
        blocks.append(np.asarray(nodes, dtype=np.int64).reshape(-1, 3))
        owners.append(np.full(len(blocks[-1]), tag))
    tags = np.concatenate(blocks)
    used, inverse = np.unique(tags, return_inverse=True)
    points = coordinates.reshape(-1, 3)[order][np.searchsorted(node_tags[order], used)]
    return points, inverse.reshape(-1, 3), np.concatenate(owners)


def find_crossings(gmsh: Any, surfaces: list[int]) -> Crossings:
    """The triangles of ``surfaces`` (their current gmsh mesh) that cross another one of them."""
    points, triangles, owners = surface_triangles(gmsh, surfaces)
    crossing = np.unique(crossing_pairs(points, triangles)).astype(np.int64)
    corners = points[triangles[crossing]]  # (k, 3 corners, 3)
    edges = (
        np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
        if len(crossing)
        else np.zeros(0)
    )
    return Crossings(
        corners.mean(axis=1).reshape(-1, 3),
        edges,
        tuple(sorted({int(tag) for tag in owners[crossing]})),
    )
