"""Is a mesh resolution fine enough for the blade, and small enough for the machine? Checked before building.

A flat-faced mesh leaves the surface between its points. Its sag (largest distance from
the analytic surface to the straight edges, as a fraction of the local chord) is measured
around the sections (from ``points``) and along the blade (from ``sections``); where it
exceeds :data:`MESH_SAG_LIMIT` the resolution is refused with the smallest count that meets
the limit (the sag falls like the square of the spacing). The triangle count is estimated
from the grid counts and refused above :data:`MESH_TRIANGLE_LIMIT`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import ParameterError
from torus_cad.geometry.airfoil import airfoil_points
from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.propeller import PropellerGeometry
from torus_cad.geometry.surface import blade_frames, place_on_frames
from torus_cad.mesh.grids import blade_grid, blade_triangle_count, cell_size, hub_layout, section_parameters
from torus_cad.parameters.design import SectionSpacing
from torus_cad.tolerances import MESH_SAG_LIMIT, MESH_TRIANGLE_LIMIT

#: Sections at which the sag around the section is measured.
AROUND_CHECK_SECTIONS = 33
#: Points per section at which the sag between sections is measured (a subset of the mesh's points).
ALONG_CHECK_POINTS = 240
#: Resolution of the cheap grid that the hub's cell size is estimated from.
ESTIMATE_GRID = (41, 160)


@dataclass(frozen=True)
class Sag:
    """Largest sag of the mesh edges as a fraction of the local chord, and where it is.

    Attributes:
        relative: sag / chord.
        s: centerline parameter where it is largest.
        chord_position: position along the chord there (0 leading edge, 1 trailing edge).
    """

    relative: float
    s: float
    chord_position: float


def _line_distance(point: NDArray[np.float64], start: NDArray[np.float64], end: NDArray[np.float64]
                   ) -> NDArray[np.float64]:
    """Distance of ``point`` from the infinite line through ``start`` and ``end`` (any matching shapes ``(..., d)``)."""
    direction = end - start
    length2 = np.einsum("...k,...k->...", direction, direction)
    offset = point - start
    along = np.einsum("...k,...k->...", offset, direction) / np.where(length2 > 0, length2, 1.0)
    return np.linalg.norm(offset - along[..., None] * direction, axis=-1)


def _chords(planar: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(k,)`` local chord of ``(k, p, 2)`` sections: twice the largest distance from the centerline."""
    return 2.0 * np.linalg.norm(planar, axis=-1).max(axis=1)


def _chord_position(t: float) -> float:
    return float(t if t <= 1.0 else 2.0 - t)


def around_sag(geometry: PropellerGeometry, points: int) -> Sag:
    """Sag of the section polygons of ``points`` equal-arc-length points, over the blade."""
    airfoil, laws = geometry.blade.airfoil, geometry.blade.laws
    t = equal_arc_length_section(airfoil, points).t
    t_mid = 0.5 * (t + np.append(t[1:], 2.0))
    s = np.linspace(0.0, 1.0, AROUND_CHECK_SECTIONS)
    planar = laws.apply(airfoil_points(airfoil, t), s)
    middle = laws.apply(airfoil_points(airfoil, t_mid), s)
    sag = _line_distance(middle, planar, np.roll(planar, -1, axis=1)) / _chords(planar)[:, None]
    row, column = np.unravel_index(int(np.argmax(sag)), sag.shape)
    return Sag(float(sag[row, column]), float(s[row]), _chord_position(float(t_mid[column])))


def along_sag(geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing) -> Sag:
    """Sag of the straight edges between neighbouring sections, over the blade."""
    centerline = geometry.centerline(0)
    s = section_parameters(centerline, sections, spacing)
    sampling = equal_arc_length_section(geometry.blade.airfoil, points)
    columns = np.unique(np.linspace(0, len(sampling.t) - 1, min(ALONG_CHECK_POINTS, len(sampling.t))).astype(int))
    section = sampling.points[columns]
    s_all = np.concatenate([s, 0.5 * (s[:-1] + s[1:])])
    order = np.argsort(s_all, kind="stable")
    frames = blade_frames(geometry.blade, centerline, s_all[order])
    planar = geometry.blade.laws.apply(section, frames.s)
    surface = np.empty((len(s_all), len(columns), 3))
    surface[order] = place_on_frames(frames, planar)
    chord = np.empty(len(s_all))
    chord[order] = _chords(planar)
    grid, middle = surface[: len(s)], surface[len(s):]
    sag = _line_distance(middle, grid[:-1], grid[1:]) / chord[len(s):, None]
    row, column = np.unravel_index(int(np.argmax(sag)), sag.shape)
    return Sag(float(sag[row, column]), float(0.5 * (s[row] + s[row + 1])),
               _chord_position(float(sampling.t[columns[column]])))


def _needed(count: int, relative: float, limit: float, closed: bool) -> int:
    """Smallest count whose sag meets ``limit``, given ``relative`` at ``count`` (sag ~ spacing^2)."""
    cells = count if closed else count - 1
    needed_cells = int(np.ceil(cells * np.sqrt(relative / limit) * 1.02))
    return needed_cells if closed else needed_cells + 1


def check_resolution(geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing,
                     limit: float | None = None) -> None:
    """Refuse (ParameterError) a resolution whose flat faces leave the blade by more than ``limit`` of the chord
    (default MESH_SAG_LIMIT); the message gives the smallest ``mesh.sections`` / ``mesh.points`` that would do."""
    limit = MESH_SAG_LIMIT if limit is None else limit
    problems = []
    around = around_sag(geometry, points)
    if around.relative > limit:
        problems.append(
            f"mesh.points = {points} cuts the sections by {around.relative:.1%} of the chord near chord position "
            f"{around.chord_position:.2f} (s = {around.s:.2f}); use mesh.points >= "
            f"{_needed(points, around.relative, limit, closed=True)} (--points)")
    along = along_sag(geometry, sections, points, spacing)
    if along.relative > limit:
        problems.append(
            f"mesh.sections = {sections} cuts the blade's bends by {along.relative:.1%} of the chord near s = "
            f"{along.s:.2f}; use mesh.sections >= {_needed(sections, along.relative, limit, closed=False)} (--sections)")
    if problems:
        raise ParameterError(f"mesh resolution too coarse for this blade (limit {limit:.1%} of the chord): "
                             + "; ".join(problems))


@dataclass(frozen=True)
class TriangleEstimate:
    """Triangles the parts will have before the union (the union only removes some), and the hub's cell size."""

    blades: int
    hub: int
    hub_cell_mm: float

    @property
    def total(self) -> int:
        return self.blades + self.hub


def estimate_triangles(geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing
                       ) -> TriangleEstimate:
    """Estimate the triangle count from a cheap coarse grid, without building the mesh."""
    coarse_sections, coarse_points = ESTIMATE_GRID
    coarse = cell_size(blade_grid(geometry, coarse_sections, coarse_points, spacing))
    around = coarse.around * coarse_points / points
    along = coarse.along * (coarse_sections - 1) / (sections - 1)
    cell = float(np.sqrt(around * along))
    hub = hub_layout(geometry.hub.radius_mm, geometry.hub.length_mm, cell).triangles
    return TriangleEstimate(geometry.blades * blade_triangle_count(sections, points), hub, cell)


def check_budget(estimate: TriangleEstimate, limit: int | None = None) -> None:
    """Refuse (ParameterError) meshes estimated above ``limit`` triangles (default MESH_TRIANGLE_LIMIT)."""
    limit = MESH_TRIANGLE_LIMIT if limit is None else limit
    if estimate.total > limit:
        raise ParameterError(
            f"the mesh would have about {estimate.total:,} triangles ({estimate.blades:,} on the blades, "
            f"{estimate.hub:,} on the hub), over the limit of {limit:,}; lower mesh.sections or mesh.points (--sections, --points)")
