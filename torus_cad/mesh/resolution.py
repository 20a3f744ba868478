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
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.frames import section_frames
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.surface import airfoil_of, place_on_frames, section_coordinates
from torus_cad.mesh.grids import blade_grid, blade_triangle_count, cell_size, hub_layout, section_parameters
from torus_cad.mesh.settings import MeshSettings
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


def around_sag(params: PropellerParameters, points: int) -> Sag:
    """Sag of the section polygons of ``points`` equal-arc-length points, over the blade."""
    sampling = equal_arc_length_section(airfoil_of(params), points)
    t = sampling.t
    t_next = np.append(t[1:], 2.0)
    t_mid = 0.5 * (t + t_next)
    s = np.linspace(0.0, 1.0, AROUND_CHECK_SECTIONS)
    airfoil = airfoil_of(params)
    planar = section_coordinates(params, s, airfoil_points(airfoil, t))
    middle = section_coordinates(params, s, airfoil_points(airfoil, t_mid))
    sag = _line_distance(middle, planar, np.roll(planar, -1, axis=1)) / _chords(planar)[:, None]
    row, column = np.unravel_index(int(np.argmax(sag)), sag.shape)
    return Sag(float(sag[row, column]), float(s[row]), _chord_position(float(t_mid[column])))


def along_sag(params: PropellerParameters, sections: int, settings: MeshSettings) -> Sag:
    """Sag of the straight edges between neighbouring sections, over the blade."""
    centerline = Centerline.for_blade(params, 0)
    s = section_parameters(centerline, sections, settings.spacing)
    sampling = equal_arc_length_section(airfoil_of(params), settings.points)
    columns = np.unique(np.linspace(0, len(sampling.t) - 1, min(ALONG_CHECK_POINTS, len(sampling.t))).astype(int))
    section = sampling.points[columns]
    s_all = np.concatenate([s, 0.5 * (s[:-1] + s[1:])])
    order = np.argsort(s_all, kind="stable")
    frames = section_frames(centerline, s_all[order], params.centerline.frame)
    planar = section_coordinates(params, frames.s, section)
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


def check_resolution(params: PropellerParameters, settings: MeshSettings, limit: float | None = None) -> None:
    """Refuse (ParameterError) a resolution whose flat faces leave the blade by more than ``limit`` of the chord."""
    limit = MESH_SAG_LIMIT if limit is None else limit
    problems = []
    around = around_sag(params, settings.points)
    if around.relative > limit:
        problems.append(
            f"--points {settings.points} cuts the sections by {around.relative:.1%} of the chord near chord position "
            f"{around.chord_position:.2f} (s = {around.s:.2f}); use --points >= "
            f"{_needed(settings.points, around.relative, limit, closed=True)}")
    along = along_sag(params, settings.sections, settings)
    if along.relative > limit:
        problems.append(
            f"--sections {settings.sections} cuts the blade's bends by {along.relative:.1%} of the chord near s = "
            f"{along.s:.2f}; use --sections >= {_needed(settings.sections, along.relative, limit, closed=False)}")
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


def estimate_triangles(params: PropellerParameters, settings: MeshSettings) -> TriangleEstimate:
    """Estimate the triangle count from a cheap coarse grid, without building the mesh."""
    sections, points = ESTIMATE_GRID
    coarse = cell_size(blade_grid(params, sections, points, settings.spacing))
    around = coarse.around * points / settings.points
    along = coarse.along * (sections - 1) / (settings.sections - 1)
    cell = float(np.sqrt(around * along))
    hub = hub_layout(params.hub.radius, params.hub.length, cell).triangles
    return TriangleEstimate(params.blades * blade_triangle_count(settings.sections, settings.points), hub, cell)


def check_budget(estimate: TriangleEstimate, limit: int | None = None) -> None:
    """Refuse (ParameterError) meshes estimated above ``limit`` triangles (default MESH_TRIANGLE_LIMIT)."""
    limit = MESH_TRIANGLE_LIMIT if limit is None else limit
    if estimate.total > limit:
        raise ParameterError(
            f"the mesh would have about {estimate.total:,} triangles ({estimate.blades:,} on the blades, "
            f"{estimate.hub:,} on the hub), over the limit of {limit:,}; lower --sections or --points")
