"""Remove the needle triangles the union leaves where the blades cut the hub's grid.

Where a blade meets the hub, the union puts new vertices on the intersection curve; when one
lands next to a grid vertex (or next to another intersection vertex) the triangles between
them are needles: one edge far shorter than the others. Each such short edge is collapsed:
the grid vertex moves onto the intersection vertex (so the junction stays where the union
put it), or, between two intersection vertices, one merges into the other. A collapse is
done only when it keeps the surface a closed 2-manifold (the link condition: the edge's two
ends share exactly the two neighbours of its two triangles), flips no triangle and leaves the
moved triangles better shaped than the needle. Only the few triangles at the junction are
visited, so the loop runs over hundreds to thousands of edges, not over the mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.mesh.quality import corner_measures, triangle_measures
from torus_cad.mesh.union import LabeledMesh

#: Surface meshes: at the blade-hub junctions, a triangle edge shorter than this fraction of its
#: triangle's longest edge is a needle the cleanup collapses (torus_cad.mesh.cleanup).
MESH_NEEDLE_EDGE_RATIO = 0.1


@dataclass
class _Adjacency:
    """Faces around each vertex, built for the whole mesh at once (CSR), edited locally as edges
    collapse."""

    faces: NDArray[np.int64]
    starts: NDArray[np.int64]
    order: NDArray[np.int64]
    edited: dict[int, set[int]]

    @classmethod
    def of(cls, faces: NDArray[np.int64], vertex_count: int) -> _Adjacency:
        flat = faces.ravel()
        order = np.argsort(flat, kind="stable") // 3
        starts = np.concatenate([[0], np.cumsum(np.bincount(flat, minlength=vertex_count))])
        return cls(faces, starts, order, {})

    def around(self, vertex: int) -> set[int]:
        if vertex not in self.edited:
            self.edited[vertex] = set(
                self.order[self.starts[vertex] : self.starts[vertex + 1]].tolist()
            )
        return self.edited[vertex]

    def neighbours(self, vertex: int) -> set[int]:
        around = self.around(vertex)
        return set(self.faces[list(around)].ravel().tolist()) - {vertex} if around else set()


def junction_vertices(mesh: LabeledMesh) -> NDArray[np.bool_]:
    """``(v,)`` True for vertices used by faces of two different parts (the union's intersection
    curves)."""
    low = np.full(len(mesh.vertices), np.iinfo(np.int16).max, dtype=np.int16)
    high = np.full(len(mesh.vertices), -1, dtype=np.int16)
    labels = np.repeat(mesh.part, 3)
    np.minimum.at(low, mesh.faces.ravel(), labels)
    np.maximum.at(high, mesh.faces.ravel(), labels)
    return np.asarray(low != high) & np.asarray(high >= 0)


@dataclass(frozen=True)
class Cleanup:
    """What the junction cleanup did.

    Attributes:
        collapsed: edges collapsed.
        aspect_ratio_max_before: worst aspect ratio of the triangles at the junctions before.
        over_100_before: triangles at the junctions with an aspect ratio over 100, before.
    """

    collapsed: int
    aspect_ratio_max_before: float
    over_100_before: int


def collapse_junction_needles(mesh: LabeledMesh) -> tuple[LabeledMesh, Cleanup]:
    """The mesh with the junction's needle edges collapsed, and what was done."""
    cleaned, cleanup, _ = collapse_keeping(mesh)
    return cleaned, cleanup


def collapse_keeping(mesh: LabeledMesh) -> tuple[LabeledMesh, Cleanup, NDArray[np.bool_]]:
    """:func:`collapse_junction_needles`, and ``(f,)`` True for the input faces still in the result
    (in order)."""
    vertices, faces = mesh.vertices, mesh.faces.copy()
    junction = junction_vertices(mesh)
    near = faces[junction[faces].any(axis=1)]
    lengths, ratios = triangle_measures(vertices, near)
    before = (float(ratios.max()) if len(ratios) else 1.0, int(np.sum(ratios > 100.0)))
    shortest = lengths.argmin(axis=1)
    rows = np.flatnonzero(lengths.min(axis=1) < MESH_NEEDLE_EDGE_RATIO * lengths.max(axis=1))
    if len(rows) == 0:
        return mesh, Cleanup(0, *before), np.ones(len(faces), dtype=bool)
    ends = np.stack([near[rows, shortest[rows]], near[rows, (shortest[rows] + 1) % 3]], axis=1)
    candidates = np.unique(np.sort(ends, axis=1), axis=0)
    candidates = candidates[
        np.argsort(np.linalg.norm(vertices[candidates[:, 0]] - vertices[candidates[:, 1]], axis=1))
    ]
    adjacency = _Adjacency.of(faces, len(vertices))
    removed_faces = np.zeros(len(faces), dtype=bool)
    gone: set[int] = set()
    collapsed = 0
    for first, second in candidates.tolist():
        if first in gone or second in gone or not (junction[first] or junction[second]):
            continue
        # Move a grid vertex onto the junction; between two junction vertices, either.
        mover, keeper = (first, second) if not junction[first] else (second, first)
        shared = adjacency.around(mover) & adjacency.around(keeper)
        if len(shared) != 2 or len(adjacency.neighbours(mover) & adjacency.neighbours(keeper)) != 2:
            continue  # not an edge any more, or collapsing it would pinch the surface
        moved = sorted(adjacency.around(mover) - shared)
        if not moved:
            continue
        old = faces[moved]
        after = np.where(old == mover, keeper, old)
        count = len(moved)  # the moved triangles before and after, and the needles, in one pass
        _, normals, ratios = corner_measures(
            vertices[np.concatenate([old, after, faces[sorted(shared)]])]
        )
        turned = (normals[count : 2 * count] * normals[:count]).sum(1)
        if turned.min() <= 0.0 or ratios[count : 2 * count].max() >= ratios[2 * count :].max():
            continue  # a triangle would flip, or the moved ones would be no better than the needle
        faces[moved] = after
        removed_faces[list(shared)] = True
        for opposite in set(faces[list(shared)].ravel().tolist()) - {mover, keeper}:
            adjacency.around(opposite).difference_update(shared)
        adjacency.around(keeper).difference_update(shared)
        adjacency.around(keeper).update(moved)
        gone.add(mover)
        collapsed += 1
    keep = ~removed_faces
    used = np.zeros(len(vertices), dtype=bool)
    used[faces[keep].ravel()] = True
    index = np.cumsum(used) - 1
    cleaned = LabeledMesh(vertices[used], index[faces[keep]], mesh.part[keep], mesh.part_names)
    return cleaned, Cleanup(collapsed, *before), keep
