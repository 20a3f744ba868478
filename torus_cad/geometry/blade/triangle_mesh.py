"""Structured, watertight triangle mesh of one blade, straight from the sampled surface (spec
§7.1-7.2).

For users who mesh without the B-rep: the (sections x points) grid is split into triangles
along quad diagonals, the two end sections are capped by zipping the upper surface to the
lower one from leading edge to trailing edge, and all faces are oriented outward.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.geometry.section.section import chord_positions

#: Triangles measured at a time over a large mesh: the temporaries stay in the processor's cache,
#: which makes a mesh of millions of triangles several times faster than whole-array passes.
MEASURE_BLOCK_TRIANGLES = 1 << 16


@dataclass(frozen=True)
class TriangleMesh:
    """Triangles over shared vertices.

    Attributes:
        vertices: ``(v, 3)`` float, mm.
        faces: ``(f, 3)`` int, vertex indices, counter-clockwise seen from outside.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]

    @property
    def volume(self) -> float:
        """Signed enclosed volume (mm^3), positive when the faces point outward."""
        total = 0.0
        for start in range(0, len(self.faces), MEASURE_BLOCK_TRIANGLES):
            a, b, c = np.moveaxis(
                self.vertices[self.faces[start : start + MEASURE_BLOCK_TRIANGLES]], 1, 0
            )
            total += float(np.einsum("ij,ij->", a, np.cross(b, c)))
        return total / 6.0

    @property
    def area(self) -> float:
        """Total triangle area (mm^2)."""
        a, b, c = (self.vertices[self.faces[:, k]] for k in range(3))
        return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())

    def edge_use_counts(self) -> NDArray[np.int64]:
        """How many triangles use each undirected edge, ``(e,)`` int; all 2 for a closed mesh."""
        edges = np.sort(self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        _, counts = np.unique(edges, axis=0, return_counts=True)
        return counts

    def is_watertight(self) -> bool:
        """Every edge shared by exactly two triangles, and each directed edge used once (consistent
        orientation)."""
        directed = self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        unique_directed = np.unique(directed, axis=0)
        return bool(np.all(self.edge_use_counts() == 2) and len(unique_directed) == len(directed))


def _zipper_cap(chord: NDArray[np.float64], trailing_edge_index: int) -> NDArray[np.int64]:
    """Triangulate a section ring ``(p,)`` between its upper and lower chains, ordered by chord
    position."""
    count = len(chord)
    upper = list(range(0, trailing_edge_index + 1))
    lower = [0] + list(range(count - 1, trailing_edge_index - 1, -1))
    triangles: list[tuple[int, int, int]] = []
    i = j = 0
    while i < len(upper) - 1 or j < len(lower) - 1:
        advance_upper = j == len(lower) - 1 or (
            i < len(upper) - 1 and chord[upper[i + 1]] <= chord[lower[j + 1]]
        )
        if advance_upper:
            triangles.append((upper[i], upper[i + 1], lower[j]))
            i += 1
        else:
            triangles.append((upper[i], lower[j + 1], lower[j]))
            j += 1
    # Both chains start at the leading edge and end at the trailing edge; the first and last
    # steps therefore produce triangles with a repeated vertex, which are dropped.
    return np.array([tri for tri in triangles if len(set(tri)) == 3], dtype=np.int64)


def blade_mesh(surface: BladeSurface) -> TriangleMesh:
    """Closed triangle mesh of one blade from its sampled surface, outward normals.

    The ``(sections, points)`` grid is split into two triangles per quad and both end sections
    are capped; the faces are flipped if needed so that the enclosed volume is positive.

    Args:
        surface: the blade's sampled surface, ``points`` ``(sections, points, 3)`` float array,
            mm.

    Returns:
        The mesh: ``vertices`` ``(sections * points, 3)`` float array, mm (the surface's points,
        row by row), and ``faces`` ``(f, 3)`` int array of vertex indices, counter-clockwise
        seen from outside.
    """
    sections, count, _ = surface.points.shape
    vertices = surface.points.reshape(-1, 3)
    section_index, point_index = np.meshgrid(
        np.arange(sections - 1), np.arange(count), indexing="ij"
    )
    a = section_index * count + point_index
    b = section_index * count + (point_index + 1) % count
    c, d = a + count, b + count
    sides = np.concatenate(
        [np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
    )
    chord = chord_positions(surface.t, surface.lower_corner_index is not None)
    trailing_edge_index = surface.trailing_edge_index
    if trailing_edge_index is None:
        trailing_edge_index = int(np.argmax(chord))
    cap = _zipper_cap(chord, trailing_edge_index)
    faces = np.concatenate([sides, cap[:, ::-1], cap + (sections - 1) * count])
    mesh = TriangleMesh(vertices, faces)
    return mesh if mesh.volume > 0 else TriangleMesh(vertices, faces[:, ::-1].copy())


def side_use_counts(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """For each side of each triangle of ``faces`` ``(n, 3)``, how many triangles use its undirected
    edge, ``(3 n,)`` int in the order (0-1, 1-2, 2-0) per triangle; all 2 for a closed mesh (a
    hole's rim: 1)."""
    sides = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keys = sides[:, 0] * (int(faces.max()) + 1) + sides[:, 1]  # one integer per side: a 1-D sort
    _, inverse, uses = np.unique(keys, return_inverse=True, return_counts=True)
    return np.asarray(uses[inverse], dtype=np.int64)
