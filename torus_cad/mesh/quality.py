"""Mesh quality measures, all vectorised: topology, edge evenness, aspect ratio, distance to the
surface.

Definitions used in the report:

- open edge: used by one triangle; non-manifold edge: used by three or more; an edge used by
  two triangles in the same direction is a flipped neighbour (inconsistent orientation).
- aspect ratio of a triangle: longest edge x perimeter / (4 sqrt(3) x area); 1 for an
  equilateral triangle, growing without bound for slivers.
- edge ratio: longest over shortest edge among a set of triangles (the spec's "even cell
  sizes", §5, measured).
- away from the junctions: triangles all of whose corners lie at least a margin outside the
  hub's surface (where the blades meet the hub, any triangulation has to fit a curve).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.triangle_mesh import MEASURE_BLOCK_TRIANGLES


@dataclass(frozen=True)
class Topology:
    """Edge counts of a triangle mesh (``closed`` = all zero)."""

    edges: int
    open_edges: int
    non_manifold_edges: int
    inconsistent_edges: int

    @property
    def closed(self) -> bool:
        """A closed, consistently oriented 2-manifold surface."""
        return (
            self.open_edges == 0 and self.non_manifold_edges == 0 and self.inconsistent_edges == 0
        )

    def to_dict(self) -> dict[str, int | bool]:
        return {**asdict(self), "closed_2_manifold": self.closed}


def edge_topology(faces: NDArray[np.int64]) -> Topology:
    """Count open, non-manifold and inconsistently oriented edges of ``(f, 3)`` faces."""
    faces = np.asarray(faces, dtype=np.int64)
    start = faces.reshape(-1)
    end = faces[:, [1, 2, 0]].reshape(-1)
    # One sort of (edge key, direction bit): the users of an edge are a run of equal keys, and
    # walking each triangle counter-clockwise, the two users of a good edge traverse it in opposite
    # directions.
    keys = (np.minimum(start, end) * (int(faces.max()) + 1) + np.maximum(start, end)) * 2 + (
        start < end
    )
    keys.sort()
    edge = keys >> 1
    first = np.flatnonzero(np.concatenate([[True], edge[1:] != edge[:-1]]))
    counts = np.diff(np.append(first, len(edge)))
    forward = np.add.reduceat(keys & 1, first)
    return Topology(
        edges=len(counts),
        open_edges=int(np.sum(counts == 1)),
        non_manifold_edges=int(np.sum(counts > 2)),
        inconsistent_edges=int(np.sum((counts == 2) & (forward != 1))),
    )


def corner_measures(
    corners: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Of triangles given by their corners ``(k, 3, 3)``: ``(k, 3)`` lengths of the edges 01, 12, 20
    (mm), ``(k, 3)`` normals (01 x 02, twice the area long) and ``(k,)`` aspect ratios (longest edge
    x perimeter / (4 sqrt(3) area): 1 for equilateral, inf for degenerate).

    Written out by components: faster than numpy's general ``cross`` for the whole mesh and for
    the handful of triangles around one edge that the junction cleanup measures."""
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    u, w, v = b - a, c - b, c - a
    normal = np.stack(
        [
            u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        ],
        axis=1,
    )
    lengths = np.sqrt(
        np.stack(
            [np.einsum("kj,kj->k", u, u), np.einsum("kj,kj->k", w, w), np.einsum("kj,kj->k", v, v)],
            axis=1,
        )
    )
    area = 0.5 * np.sqrt(np.einsum("kj,kj->k", normal, normal))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = lengths.max(axis=1) * lengths.sum(axis=1) / (4.0 * np.sqrt(3.0) * area)
    return lengths, normal, np.where(area > 0.0, ratio, np.inf)


def triangle_measures(
    vertices: NDArray[np.float64], faces: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(f, 3)`` edge lengths (mm) and ``(f,)`` aspect ratios of ``(f, 3)`` faces
    (:func:`corner_measures`).

    Measured in blocks of MEASURE_BLOCK_TRIANGLES triangles."""
    lengths, ratios = np.empty((len(faces), 3)), np.empty(len(faces))
    for start in range(0, len(faces), MEASURE_BLOCK_TRIANGLES):
        block = slice(start, start + MEASURE_BLOCK_TRIANGLES)
        lengths[block], _, ratios[block] = corner_measures(vertices[faces[block]])
    return lengths, ratios


def aspect_ratios(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """``(f,)`` longest edge x perimeter / (4 sqrt(3) area): 1 for equilateral, inf for
    degenerate."""
    return triangle_measures(vertices, faces)[1]


def outside_hub(
    points: NDArray[np.float64], radius: float, length: float, margin: float
) -> NDArray[np.bool_]:
    """``(k,)`` True where a point lies more than ``margin`` mm outside the hub."""
    radial = np.hypot(points[:, 0], points[:, 1]) - radius
    axial = np.abs(points[:, 2]) - length / 2.0
    return np.maximum(radial, axial) > margin


@dataclass(frozen=True)
class Evenness:
    """Edge ratio and worst aspect ratio of a set of triangles."""

    triangles: int
    edge_min_mm: float
    edge_max_mm: float
    aspect_ratio_max: float

    @property
    def edge_ratio(self) -> float:
        return self.edge_max_mm / self.edge_min_mm if self.edge_min_mm > 0 else float("inf")

    def to_dict(self) -> dict[str, float | int]:
        return {**asdict(self), "edge_ratio": self.edge_ratio}


def evenness(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    measures: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> Evenness:
    """Shortest and longest edge and worst aspect ratio of ``(f, 3)`` faces (``measures``: their
    :func:`triangle_measures`, if already computed)."""
    if len(faces) == 0:
        return Evenness(0, float("nan"), float("nan"), float("nan"))
    lengths, ratios = triangle_measures(vertices, faces) if measures is None else measures
    return Evenness(len(faces), float(lengths.min()), float(lengths.max()), float(ratios.max()))


def faces_away_from_hub(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    radius: float,
    length: float,
    margin: float,
) -> NDArray[np.bool_]:
    """``(f,)`` True for triangles whose three corners all lie more than ``margin`` outside the
    hub."""
    outside = outside_hub(vertices, radius, length, margin)
    return np.asarray(outside[faces].all(axis=1))


def cell_deviation(
    grid: NDArray[np.float64],
    centres: NDArray[np.float64],
    split_a_d: NDArray[np.bool_] | None = None,
) -> NDArray[np.float64]:
    """Distance (mm) of the analytic surface at each cell's centre from the cell's two triangles'
    planes.

    ``grid`` is a ``(m, p, 3)`` blade grid (closed around axis 1) whose cell (a, b on one section,
    c, d on the next) is cut into a-b-d and a-d-c where ``split_a_d`` ``(p,)`` is True (default:
    everywhere) and into a-b-c and b-d-c elsewhere, as ``grids.mirrored_diagonal_mesh`` does;
    ``centres`` ``(m - 1, p, 3)`` holds the analytic surface at the parameter midpoints of the
    cells. Returns ``(m - 1, p)``: the smaller distance to the two planes.
    """
    a, b = grid[:-1], np.roll(grid[:-1], -1, axis=1)
    c, d = grid[1:], np.roll(grid[1:], -1, axis=1)

    def plane_distance(
        p: NDArray[np.float64], q: NDArray[np.float64], r: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        normal = np.cross(q - p, r - p)
        norm = np.linalg.norm(normal, axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            distance = np.abs(np.einsum("...k,...k->...", centres - p, normal)) / norm
        return np.where(norm > 0, distance, np.linalg.norm(centres - p, axis=-1))

    along_a_d = np.minimum(plane_distance(a, b, d), plane_distance(a, d, c))
    if split_a_d is None:
        return along_a_d
    along_b_c = np.minimum(plane_distance(a, b, c), plane_distance(b, d, c))
    return np.where(split_a_d[None, :], along_a_d, along_b_c)


def find_rows(query: NDArray[np.float64], reference: NDArray[np.float64]) -> NDArray[np.int64]:
    """``(q,)`` index of a row of ``reference`` ``(r, 3)`` equal bit for bit to each row of
    ``query`` ``(q, 3)``, or -1.

    Rows are hashed to one int64 each (sorted once, looked up with searchsorted), and every hit is
    confirmed by comparing the coordinates, so a hash collision cannot give a false match.
    """

    def keys(rows: NDArray[np.float64]) -> NDArray[np.int64]:
        bits = np.ascontiguousarray(rows, dtype=np.float64).view(np.int64)
        with np.errstate(over="ignore"):
            return np.asarray(
                bits[:, 0] * np.int64(0x9E3779B97F4A7C15 - (1 << 64))
                ^ bits[:, 1] * np.int64(0xC2B2AE3D27D4EB4F - (1 << 64))
                ^ bits[:, 2]
            )

    reference_keys = keys(reference)
    order = np.argsort(reference_keys, kind="stable")
    sorted_keys = reference_keys[order]
    query_keys = keys(query)
    position = np.minimum(np.searchsorted(sorted_keys, query_keys), len(sorted_keys) - 1)
    candidate = order[position]
    found = (sorted_keys[position] == query_keys) & np.all(reference[candidate] == query, axis=1)
    return np.where(found, candidate, -1)


def rows_in(query: NDArray[np.float64], reference: NDArray[np.float64]) -> NDArray[np.bool_]:
    """``(q,)`` True where a row of ``query`` ``(q, 3)`` equals a row of ``reference`` ``(r, 3)``
    bit for bit."""
    return np.asarray(find_rows(query, reference) >= 0)
