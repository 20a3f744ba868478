"""Structured grids of the parts, straight from the spec's math (§5, §6.2, §7.1-7.2).

Each blade is its (sections x points) grid, capped at both ends (``geometry.mesh.blade_mesh``);
the hub is the cylinder X = R cos(theta), Y = R sin(theta), Z = z of §6.2 sampled on a
structured (theta, z) grid whose cells are as large as the blades' cells, closed by end
caps made of concentric rings (each ring has as many points as its circumference holds
cells, so the caps have no slivers at the centre). Everything is vectorised: no Python loop
runs per triangle.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.mesh import TriangleMesh, blade_mesh
from torus_cad.geometry.propeller import PropellerGeometry
from torus_cad.geometry.surface import BladeSurface, blade_frames, place_sections
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
        """Edge of a square cell with a blade cell's area, sqrt(around x along): the hub's cell size, mm."""
        return float(np.sqrt(self.around * self.along))


def section_parameters(centerline: Centerline, sections: int, spacing: SectionSpacing) -> NDArray[np.float64]:
    """``(sections,)`` centerline parameters s in [0, 1], 0 and 1 included, spread as ``spacing`` says."""
    if spacing == SectionSpacing.PARAMETER:
        return np.linspace(0.0, 1.0, sections)
    fine = np.linspace(0.0, 1.0, CENTERLINE_LENGTH_SAMPLES)
    steps = np.linalg.norm(np.diff(centerline.points(fine), axis=0), axis=1)
    arc_length = np.concatenate([[0.0], np.cumsum(steps)])
    s = np.interp(np.linspace(0.0, arc_length[-1], sections), arc_length, fine)
    s[0], s[-1] = 0.0, 1.0
    return s


def blade_grid(geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing) -> BladeSurface:
    """Blade 0 sampled on ``sections`` x ``points``: sections spread by ``spacing``, points equally
    spaced in arc length around each section with the sharp trailing edge kept as a point (spec §5)."""
    centerline = geometry.centerline(0)
    s = section_parameters(centerline, sections, spacing)
    sampling = equal_arc_length_section(geometry.blade.airfoil, points)
    frames = blade_frames(geometry.blade, centerline, s)
    return BladeSurface(place_sections(geometry.blade, frames, sampling.points), s, sampling.t,
                        sampling.trailing_edge_index, frames)


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


def blade_meshes(geometry: PropellerGeometry, surface: BladeSurface) -> list[TriangleMesh]:
    """Every blade's closed mesh: blade 0's capped grid rotated to theta_i (spec §6.1), outward faces."""
    mesh = blade_mesh(surface)
    first = geometry.blade_angle_deg(0)
    return [TriangleMesh(rotated_about_axis(mesh.vertices, geometry.blade_angle_deg(index) - first), mesh.faces)
            for index in range(geometry.blades)]


def blade_triangle_count(sections: int, points: int) -> int:
    """Triangles of one capped blade grid: two per cell, ``points - 2`` per cap."""
    return 2 * (sections - 1) * points + 2 * (points - 2)


@dataclass(frozen=True)
class HubLayout:
    """Counts of the hub grid for a cell size.

    Attributes:
        around: points around the axis on the lateral face (and the caps' outer rings).
        along: cell rows along the axis on the lateral face.
        ring_points: ``(k,)`` points on each cap ring from the centre out (1 = the centre),
            the last equal to ``around``.
    """

    around: int
    along: int
    ring_points: NDArray[np.int64]

    @property
    def triangles(self) -> int:
        side = 2 * self.around * self.along
        cap = int(self.ring_points[1:].sum() + self.ring_points[1:-1].sum())
        return side + 2 * cap


def hub_layout(radius: float, length: float, cell: float) -> HubLayout:
    """Grid counts of a hub of ``radius`` x ``length`` (mm) with cells of about ``cell`` mm."""
    # Cells no larger than the hub's length and a fraction of its circumference, so they stay square.
    cell = min(cell, length, 2.0 * np.pi * radius / (3 * CAP_INNER_RING_POINTS))
    around = int(np.ceil(2.0 * np.pi * radius / cell))
    along = int(np.ceil(length / cell))
    rings = max(1, int(np.ceil(radius / cell)))
    ring_radius = radius * np.arange(1, rings + 1) / rings
    counts = np.maximum(CAP_INNER_RING_POINTS, np.ceil(2.0 * np.pi * ring_radius / cell)).astype(np.int64)
    counts[-1] = around
    counts = np.minimum(counts, around)
    return HubLayout(around, along, np.concatenate([[1], counts]))


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
    i = np.cumsum(step_inner) - step_inner       # inner points passed before each step
    j = np.cumsum(~step_inner) - ~step_inner     # outer points passed before each step
    a, b = inner[i % n_in], outer[j % n_out]
    third = np.where(step_inner, inner[(i + 1) % n_in], outer[(j + 1) % n_out])
    return np.stack([a, b, third], axis=-1)


def hub_mesh(radius: float, length: float, cell: float) -> TriangleMesh:
    """Closed mesh of the hub cylinder (spec §6.2), outward faces, cells of about ``cell`` mm."""
    layout = hub_layout(radius, length, cell)
    ring_radius = radius * np.arange(len(layout.ring_points)) / (len(layout.ring_points) - 1)
    half = length / 2.0
    pieces: list[NDArray[np.float64]] = []
    offset = 0

    def add(points: NDArray[np.float64]) -> NDArray[np.int64]:
        nonlocal offset
        pieces.append(points)
        offset += len(points)
        return np.arange(offset - len(points), offset)

    bottom = [add(_ring(r, int(n), -half)) for r, n in zip(ring_radius, layout.ring_points)]
    side_z = np.linspace(-half, half, layout.along + 1)
    side = [bottom[-1]] + [add(_ring(radius, layout.around, z)) for z in side_z[1:-1]]
    top = [add(_ring(r, int(n), half)) for r, n in zip(ring_radius, layout.ring_points)]
    side.append(top[-1])
    faces = []
    for inner, outer in pairwise(bottom):
        faces.append(zip_rings(inner, outer)[:, ::-1])  # seen from -z: clockwise from +z
    for inner, outer in pairwise(top):
        faces.append(zip_rings(inner, outer))
    rows = np.stack(side)                                # (along + 1, around)
    a, b = rows[:-1], np.roll(rows[:-1], -1, axis=1)
    c, d = rows[1:], np.roll(rows[1:], -1, axis=1)
    faces.append(np.stack([a, b, d], axis=-1).reshape(-1, 3))
    faces.append(np.stack([a, d, c], axis=-1).reshape(-1, 3))
    return TriangleMesh(np.concatenate(pieces), np.concatenate(faces))
