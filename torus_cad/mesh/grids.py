"""Structured grids of the parts, straight from the spec's math (§5, §6.2, §7.1-7.2).

Each blade is its (sections x points) grid, split along diagonals mirrored about the chord and
capped at both ends by a triangulation of the end sections (:func:`mirrored_diagonal_mesh`);
the hub is the cylinder X = R cos(theta), Y = R sin(theta), Z = z of §6.2 sampled on a
structured (theta, z) grid whose cells are as long as the blade cells' longer edge (its
chamfers, if any, are rows of the grid), closed by end caps made of concentric rings (each
ring has as many points as its circumference holds cells, so the caps have no slivers at the
centre). Everything is vectorised: no Python loop runs per triangle.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.blade_surface import (
    BladeSurface,
    blade_frames,
    place_sections,
    sections_along,
    sections_at,
)
from torus_cad.geometry.blade.centerline import Centerline
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.geometry.section.arc_length import equal_arc_length_section
from torus_cad.geometry.section.section import RoundTrailingEdge
from torus_cad.parameters.design import SectionSpacing

#: Points on the centerline used to tabulate its arc length for arc-length spacing.
CENTERLINE_LENGTH_SAMPLES = 4001

#: Fewest points on the innermost ring of a hub cap (a hexagon around the centre).
CAP_INNER_RING_POINTS = 6


@dataclass(frozen=True)
class CellSize:
    """Typical edge lengths of a blade grid (medians), mm.

    Attributes:
        around: along a section, between neighbouring points.
        along: between neighbouring sections.
    """

    around: float
    along: float

    @property
    def matched(self) -> float:
        """Edge of a square cell with a blade cell's area, sqrt(around x along), mm."""
        return float(np.sqrt(self.around * self.along))

    @property
    def hub(self) -> float:
        """The hub grid's cell size, mm: the longer edge of a blade cell. The cylinder is flat along
        its axis and its polygon's sag around it is (cell)^2 / (8 R), so it needs no finer cells;
        square cells of the blade cell's area would put most of a fine mesh's triangles on the hub
        (4.8 of 8.9 million at 400 x 2000)."""
        return max(self.around, self.along)


def section_parameters(
    centerline: Centerline, sections: int, spacing: SectionSpacing
) -> NDArray[np.float64]:
    """``(sections,)`` centerline parameters s in [0, 1], 0 and 1 included, spread as ``spacing``
    says."""
    if spacing == SectionSpacing.PARAMETER:
        return np.linspace(0.0, 1.0, sections)
    fine = np.linspace(0.0, 1.0, CENTERLINE_LENGTH_SAMPLES)
    steps = np.linalg.norm(np.diff(centerline.points(fine), axis=0), axis=1)
    arc_length = np.concatenate([[0.0], np.cumsum(steps)])
    s = np.interp(np.linspace(0.0, arc_length[-1], sections), arc_length, fine)
    s[0], s[-1] = 0.0, 1.0
    return s


def blade_grid(
    geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing
) -> BladeSurface:
    """Blade 0 sampled on ``sections`` x ``points``: sections spread by ``spacing``, points equally
    spaced in arc length around each section with the trailing edge's corners kept as points (spec
    §5).

    A blunt trailing edge (flat or round, ``airfoil.trailing_edge_*``) is sampled as
    ``geometry.blade.surface.blade_surface`` samples it for the solid: every section at the
    parameters of the middle one, so the mesh and the B-rep have the same edge.
    """
    centerline = geometry.centerline(0)
    frames = blade_frames(
        geometry.blade, centerline, section_parameters(centerline, sections, spacing)
    )
    along = sections_along(geometry.blade, frames.s)
    shared = all(section is along[0] for section in along)
    reference = along[0] if shared else sections_along(geometry.blade, [0.5])[0]
    sampling = equal_arc_length_section(reference, points)
    planar = sampling.points if shared else sections_at(along, sampling.t)
    return BladeSurface(
        place_sections(geometry.blade, frames, planar),
        frames.s,
        sampling.t,
        sampling.trailing_edge_index,
        frames,
        sampling.lower_corner_index,
        isinstance(reference, RoundTrailingEdge),
    )


def cell_size(surface: BladeSurface) -> CellSize:
    """Median edge lengths of the blade grid around the sections and along the blade, mm."""
    grid = surface.points
    around = np.linalg.norm(np.roll(grid, -1, axis=1) - grid, axis=-1)
    along = np.linalg.norm(np.diff(grid, axis=0), axis=-1)
    return CellSize(float(np.median(around)), float(np.median(along)))


def rotated_about_axis(vertices: NDArray[np.float64], angle_deg: float) -> NDArray[np.float64]:
    """``(v, 3)`` points rotated by ``angle_deg`` about +z (spec §6.1), mm."""
    angle = np.radians(angle_deg)
    cos, sin = np.cos(angle), np.sin(angle)
    rotation = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])
    return vertices @ rotation.T


def _cap(
    ring: NDArray[np.float64],
    frame_normal: NDArray[np.float64],
    frame_binormal: NDArray[np.float64],
    outward: NDArray[np.float64],
) -> NDArray[np.int64]:
    """Triangles ``(p - 2, 3)`` (indices into the ring) filling one planar section ring ``(p, 3)``
    mm, facing ``outward``: manifold3d's polygon triangulation of the ring in its section plane, so
    no triangle leaves the section (a zipper from the upper to the lower surface can, across a blunt
    edge's base or a concave lower surface)."""
    import manifold3d as mf

    planar = np.stack([ring @ frame_normal, ring @ frame_binormal], axis=-1)
    x, y = planar[:, 0], planar[:, 1]
    if float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 0.0:  # clockwise: wind it CCW
        triangles = np.asarray(mf.triangulate([planar[::-1].copy()]), dtype=np.int64)
        triangles = len(ring) - 1 - triangles
    else:
        triangles = np.asarray(mf.triangulate([planar]), dtype=np.int64)
    corners = ring[triangles[0]]
    if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), outward) < 0.0:
        triangles = triangles[:, ::-1]
    return triangles


def split_along_a_d(surface: BladeSurface) -> NDArray[np.bool_]:
    """``(points,)`` True for the columns whose cells :func:`mirrored_diagonal_mesh` splits along
    a-d: the upper surface, up to the trailing edge (or the middle of a blunt edge's base)."""
    count = surface.points.shape[1]
    upper_end = (
        surface.trailing_edge_index if surface.trailing_edge_index is not None else count // 2
    )
    if surface.lower_corner_index is not None:
        upper_end = (upper_end + surface.lower_corner_index + 1) // 2
    return np.arange(count) < upper_end


def _outward(surface: BladeSurface, split: NDArray[np.bool_]) -> bool:
    """Whether a cell's (a, b, d) points away from its section's centre (then the grid's faces are
    outward as made)."""
    grid = surface.points
    k, j = (len(grid) - 1) // 2, max(int(split.sum()) // 3, 0)
    normal = np.cross(grid[k, j + 1] - grid[k, j], grid[k + 1, j + 1] - grid[k, j])
    return bool(np.dot(normal, grid[k, j] - grid[k].mean(axis=0)) >= 0.0)


def side_faces(surface: BladeSurface, first_row: int, last_row: int) -> NDArray[np.int64]:
    """``(2 (last - first) p, 3)`` outward triangles of the cells between sections ``first_row`` and
    ``last_row`` (indices into the grid's ``(sections * p, 3)`` vertices): every cell's first
    triangle, then every cell's second, split as :func:`mirrored_diagonal_mesh` says."""
    count = surface.points.shape[1]
    column = np.arange(count)
    split = split_along_a_d(surface)
    row = np.arange(first_row, last_row)[:, None] * count
    a, b = row + column, row + (column + 1) % count
    c, d = a + count, b + count
    on_upper = np.broadcast_to(split, a.shape)[..., None]
    first = np.where(on_upper, np.stack([a, b, d], -1), np.stack([a, b, c], -1))
    second = np.where(on_upper, np.stack([a, d, c], -1), np.stack([b, d, c], -1))
    sides = np.concatenate([first.reshape(-1, 3), second.reshape(-1, 3)])
    return sides if _outward(surface, split) else sides[:, ::-1]


def cap_faces(surface: BladeSurface, row: int, toward_row: int) -> NDArray[np.int64]:
    """Triangles closing the grid at section ``row``, facing away from section ``toward_row`` (grid
    vertex indices)."""
    grid, frames = surface.points, surface.frames
    inward = grid[toward_row].mean(axis=0) - grid[row].mean(axis=0)
    return _cap(grid[row], frames.normal[row], frames.binormal[row], -inward) + row * grid.shape[1]


def mirrored_diagonal_mesh(surface: BladeSurface) -> TriangleMesh:
    """Blade 0's closed mesh: its grid's cells split along diagonals mirrored about the chord,
    capped.

    Each cell (a, b on one section, c, d on the next) is split along a-d on the upper surface
    and along b-c on the lower one (the trailing edge's base counts half to each), so the two
    triangles beside the trailing edge, and beside the leading edge, share that edge's vertex
    of the same section pair and fold towards each other, never across: with one diagonal
    direction everywhere, the thin wedge of a sharp trailing edge is crossed by the triangles
    of its two sides where the edge runs obliquely to the sections. Each end section is capped
    by a triangulation of its polygon in its plane (:func:`_cap`). Faces outward.
    """
    sections = len(surface.points)
    faces = [
        side_faces(surface, 0, sections - 1),
        cap_faces(surface, 0, 1),
        cap_faces(surface, sections - 1, sections - 2),
    ]
    return TriangleMesh(surface.points.reshape(-1, 3), np.concatenate(faces))


@dataclass(frozen=True)
class BladePieces:
    """Blade 0's mesh cut where it is well clear of the hub, so that only the pieces that meet the
    hub go through the union (the rest is joined back afterwards, vertex for vertex).

    Attributes:
        near: closed pieces that meet the hub (grid vertex indices): sections 0 to ``cut[0]`` and
            ``cut[1]`` to the last, each closed by the end cap and a cut cap; the whole blade when
            no section is clear of the hub.
        cut_cap_faces: ``(len(face),)`` True for each near piece's faces on a cut cap.
        far: the open band of cells between the cuts, or None.
        cut: the two cut sections, or None.
    """

    near: tuple[NDArray[np.int64], ...]
    cut_cap_faces: tuple[NDArray[np.bool_], ...]
    far: NDArray[np.int64] | None
    cut: tuple[int, int] | None


def blade_pieces(
    surface: BladeSurface, hub_radius_mm: float, hub_length_mm: float, margin_mm: float
) -> BladePieces:
    """Cut blade 0's mesh at the first and last sections lying wholly more than ``margin_mm``
    outside the hub."""
    grid = surface.points
    sections = len(grid)
    radial = np.hypot(grid[..., 0], grid[..., 1]) - hub_radius_mm
    axial = np.abs(grid[..., 2]) - hub_length_mm / 2.0
    clear = np.flatnonzero((np.maximum(radial, axial) > margin_mm).all(axis=1))
    whole = mirrored_diagonal_mesh(surface).faces
    if (
        len(clear) < 2
        or clear[-1] - clear[0] + 1 != len(clear)
        or clear[0] == 0
        or clear[-1] == sections - 1
    ):
        return BladePieces((whole,), (np.zeros(len(whole), dtype=bool),), None, None)
    first, last = int(clear[0]), int(clear[-1])
    start = np.concatenate([side_faces(surface, 0, first), cap_faces(surface, 0, 1)])
    start_cut = cap_faces(surface, first, first - 1)
    end = np.concatenate(
        [side_faces(surface, last, sections - 1), cap_faces(surface, sections - 1, sections - 2)]
    )
    end_cut = cap_faces(surface, last, last + 1)
    near = (np.concatenate([start, start_cut]), np.concatenate([end, end_cut]))
    flags = (np.arange(len(near[0])) >= len(start), np.arange(len(near[1])) >= len(end))
    return BladePieces(near, flags, side_faces(surface, first, last), (first, last))


def blade_meshes(geometry: PropellerGeometry, surface: BladeSurface) -> list[TriangleMesh]:
    """Every blade's closed mesh: blade 0's capped grid rotated to theta_i (spec §6.1), outward
    faces."""
    mesh = mirrored_diagonal_mesh(surface)
    first = geometry.blade_angle_deg(0)
    return [
        TriangleMesh(
            rotated_about_axis(mesh.vertices, geometry.blade_angle_deg(index) - first), mesh.faces
        )
        for index in range(geometry.blades)
    ]


def blade_triangle_count(sections: int, points: int) -> int:
    """Triangles of one capped blade grid: two per cell, ``points - 2`` per cap."""
    return 2 * (sections - 1) * points + 2 * (points - 2)


@dataclass(frozen=True)
class HubLayout:
    """Counts of the hub grid for a cell size.

    Attributes:
        around: points around the axis on the lateral face (and the caps' outer rings).
        profile: ``(k, 2)`` (r, z) mm of the lateral face's rings from the bottom cap's outer ring
            to the top one's: up the chamfer, the cylinder, down the other chamfer.
        ring_points: ``(k,)`` points on each cap ring from the centre out (1 = the centre),
            the last equal to ``around``.
    """

    around: int
    profile: NDArray[np.float64]
    ring_points: NDArray[np.int64]

    @property
    def along(self) -> int:
        """Cell rows on the lateral face (chamfers included)."""
        return len(self.profile) - 1

    @property
    def triangles(self) -> int:
        side = 2 * self.around * self.along
        cap = int(self.ring_points[1:].sum() + self.ring_points[1:-1].sum())
        return side + 2 * cap


def _polyline(corners: NDArray[np.float64], cell: float) -> NDArray[np.float64]:
    """Points ``(k, 2)`` along a polyline ``(c, 2)``, its corners included, each piece cut into
    steps of at most ``cell``."""
    pieces = [corners[:1]]
    for start, end in pairwise(corners):
        steps = max(1, int(np.ceil(np.linalg.norm(end - start) / cell)))
        pieces.append(start + np.linspace(0.0, 1.0, steps + 1)[1:, None] * (end - start))
    return np.concatenate(pieces)


def hub_layout(radius: float, length: float, cell: float, chamfer: float = 0.0) -> HubLayout:
    """Grid counts of a hub of ``radius`` x ``length`` (mm), its end edges chamfered by ``chamfer``
    mm at 45 degrees, with cells of about ``cell`` mm."""
    # Cells no larger than the hub's length and a fraction of its circumference, so they stay
    # square.
    cell = min(cell, length, 2.0 * np.pi * radius / (3 * CAP_INNER_RING_POINTS))
    around = int(np.ceil(2.0 * np.pi * radius / cell))
    half, cap_radius = length / 2.0, radius - chamfer
    corners = np.array(
        [
            (cap_radius, -half),
            (radius, -half + chamfer),
            (radius, half - chamfer),
            (cap_radius, half),
        ]
    )
    if chamfer == 0.0:
        corners = corners[1:3]
    rings = max(1, int(np.ceil(cap_radius / cell)))
    ring_radius = cap_radius * np.arange(1, rings + 1) / rings
    counts = np.maximum(CAP_INNER_RING_POINTS, np.ceil(2.0 * np.pi * ring_radius / cell)).astype(
        np.int64
    )
    counts[-1] = around
    counts = np.minimum(counts, around)
    return HubLayout(around, _polyline(corners, cell), np.concatenate([[1], counts]))


def _ring(radius: float, count: int, z: float) -> NDArray[np.float64]:
    theta = 2.0 * np.pi * np.arange(count) / count
    return np.stack([radius * np.cos(theta), radius * np.sin(theta), np.full(count, z)], axis=-1)


def zip_rings(inner: NDArray[np.int64], outer: NDArray[np.int64]) -> NDArray[np.int64]:
    """Triangles between two closed rings of vertex indices that both start at angle 0, counter-
    clockwise seen from +z: ``(len(inner) + len(outer), 3)``; ``inner`` may be one centre point.

    Walking around the axis, each step advances the ring whose next point comes first in
    angle (a merge of the two sorted angle lists, done with one stable sort).
    """
    n_in, n_out = len(inner), len(outer)
    if n_in == 1:
        j = np.arange(n_out)
        return np.stack([np.full(n_out, inner[0]), outer[j], outer[(j + 1) % n_out]], axis=-1)
    next_angle = np.concatenate([np.arange(1, n_in + 1) / n_in, np.arange(1, n_out + 1) / n_out])
    from_inner = np.concatenate([np.ones(n_in, bool), np.zeros(n_out, bool)])
    order = np.argsort(next_angle, kind="stable")
    step_inner = from_inner[order]
    i = np.cumsum(step_inner) - step_inner  # inner points passed before each step
    j = np.cumsum(~step_inner) - ~step_inner  # outer points passed before each step
    a, b = inner[i % n_in], outer[j % n_out]
    third = np.where(step_inner, inner[(i + 1) % n_in], outer[(j + 1) % n_out])
    return np.stack([a, b, third], axis=-1)


def hub_mesh(radius: float, length: float, cell: float, chamfer: float = 0.0) -> TriangleMesh:
    """Closed mesh of the hub cylinder (spec §6.2), its end edges chamfered by ``chamfer`` mm at
    45 degrees, outward faces, cells of about ``cell`` mm."""
    layout = hub_layout(radius, length, cell, chamfer)
    cap_radius = radius - chamfer
    ring_radius = cap_radius * np.arange(len(layout.ring_points)) / (len(layout.ring_points) - 1)
    half = length / 2.0
    pieces: list[NDArray[np.float64]] = []
    offset = 0

    def add(points: NDArray[np.float64]) -> NDArray[np.int64]:
        nonlocal offset
        pieces.append(points)
        offset += len(points)
        return np.arange(offset - len(points), offset)

    bottom = [add(_ring(r, int(n), -half)) for r, n in zip(ring_radius, layout.ring_points)]
    side = [bottom[-1]] + [add(_ring(r, layout.around, z)) for r, z in layout.profile[1:-1]]
    top = [add(_ring(r, int(n), half)) for r, n in zip(ring_radius, layout.ring_points)]
    side.append(top[-1])
    faces = []
    for inner, outer in pairwise(bottom):
        faces.append(zip_rings(inner, outer)[:, ::-1])  # seen from -z: clockwise from +z
    for inner, outer in pairwise(top):
        faces.append(zip_rings(inner, outer))
    rows = np.stack(side)  # (along + 1, around)
    a, b = rows[:-1], np.roll(rows[:-1], -1, axis=1)
    c, d = rows[1:], np.roll(rows[1:], -1, axis=1)
    faces.append(np.stack([a, b, d], axis=-1).reshape(-1, 3))
    faces.append(np.stack([a, d, c], axis=-1).reshape(-1, 3))
    return TriangleMesh(np.concatenate(pieces), np.concatenate(faces))
