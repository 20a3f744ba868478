"""Is a mesh resolution fine enough for the blade, and small enough for the machine? Checked before
building.

A flat-faced mesh leaves the surface between its points. Its sag (largest distance from the
analytic surface to the straight edges) is measured around the sections (set by ``points``)
and along the blade (set by ``sections``), as a fraction of the local section thickness
(thickness x Sy(s), mm): the leading edge of a thin section, where equal arc-length points
(spec §5) are sparsest for its radius, needs the most points. Above :data:`MESH_SAG_LIMIT`
the resolution is refused with the smallest count that meets the limit, found by search.
The triangle count is estimated from the grid counts and refused when the command's memory at that
count (a fixed base plus bytes per triangle, measured) would be over
:data:`MESH_MEMORY_LIMIT_BYTES`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import BudgetError, ParameterError
from torus_cad.geometry.blade.blade_surface import blade_frames, place_on_frames
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.transforms import evaluate_quartic
from torus_cad.geometry.section.airfoil import airfoil_points
from torus_cad.geometry.section.arc_length import equal_arc_length_section
from torus_cad.geometry.section.section import max_thickness
from torus_cad.mesh.grids import (
    blade_grid,
    blade_triangle_count,
    cell_size,
    hub_layout,
    section_parameters,
)
from torus_cad.parameters.design import SectionSpacing

#: Surface meshes (torus_cad.mesh): largest sag of the flat faces from the analytic blade, as a
#: fraction of the local section thickness, above which a resolution is refused. The default design
#: needs 15 sections (any allowed points); a 6 % thick section needs 31 points (its leading edge).
MESH_SAG_LIMIT = 0.10


#: Sections at which the sag around the section is measured.
AROUND_CHECK_SECTIONS = 33
#: Points per section at which the sag between sections is measured (a subset of the mesh's points).
ALONG_CHECK_POINTS = 240
#: Resolution of the cheap grid that the hub's cell size is estimated from.
ESTIMATE_GRID = (41, 160)


#: Peak resident memory of ``torus-cad mesh`` (binary STL, --no-compare) grows by this much per
#: triangle of its estimate (:func:`estimate_triangles`), bytes, over a fixed
#: :data:`MESH_BASE_BYTES` (Python, numpy, manifold3d, meshlib); both measured (the docs'
#: measurements page).
MESH_BYTES_PER_TRIANGLE = 290.0
MESH_BASE_BYTES = 0.70e9
#: The B-rep built for the comparison (``--no-compare`` skips it) adds about this much, bytes.
MESH_COMPARE_BYTES = 0.5e9
#: Most memory ``torus-cad mesh`` may plan to use, bytes: a share of the 24 GiB machine that
#: several jobs use at once.
MESH_MEMORY_LIMIT_BYTES = 4.0e9
#: The triangles that fit :data:`MESH_MEMORY_LIMIT_BYTES` with the comparison on.
MESH_TRIANGLE_LIMIT = math.floor(
    (MESH_MEMORY_LIMIT_BYTES - MESH_BASE_BYTES - MESH_COMPARE_BYTES) / MESH_BYTES_PER_TRIANGLE
)


def mesh_memory_bytes(triangles: int, compare: bool = True) -> float:
    """Estimated peak memory of ``torus-cad mesh`` for a mesh estimated at ``triangles``, bytes."""
    return (
        MESH_BASE_BYTES
        + (MESH_COMPARE_BYTES if compare else 0.0)
        + MESH_BYTES_PER_TRIANGLE * triangles
    )


def check_mesh_memory(
    triangles: int, compare: bool = True, limit_bytes: float = MESH_MEMORY_LIMIT_BYTES
) -> None:
    """BudgetError (exit 2) with the estimate and the limit when the mesh would need more than
    ``limit_bytes``."""
    need = mesh_memory_bytes(triangles, compare)
    if need > limit_bytes:
        fits = math.floor((limit_bytes - mesh_memory_bytes(0, compare)) / MESH_BYTES_PER_TRIANGLE)
        raise BudgetError(
            f"the mesh would have about {triangles:,} triangles "
            f"and need about {need / 1e9:.1f} GB of memory, over "
            f"the limit of {limit_bytes / 1e9:.1f} GB (about "
            f"{fits:,} triangles); lower mesh.sections or "
            "mesh.points (--sections, --points)"
        )


@dataclass(frozen=True)
class Sag:
    """Largest sag of the mesh edges as a fraction of the local section thickness, and where it is.

    Attributes:
        relative: sag / (thickness x Sy(s)).
        s: centerline parameter where it is largest.
        chord_position: position along the chord there (0 leading edge, 1 trailing edge).
    """

    relative: float
    s: float
    chord_position: float


def _line_distance(
    point: NDArray[np.float64], start: NDArray[np.float64], end: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Distance of ``point`` from the infinite line through ``start`` and ``end`` (any matching
    shapes ``(..., d)``)."""
    direction = end - start
    length2 = np.einsum("...k,...k->...", direction, direction)
    offset = point - start
    along = np.einsum("...k,...k->...", offset, direction) / np.where(length2 > 0, length2, 1.0)
    return np.linalg.norm(offset - along[..., None] * direction, axis=-1)


def local_thickness(geometry: PropellerGeometry, s: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(k,)`` section thickness at ``s``: the airfoil's maximum thickness times Sy(s), mm."""
    return max_thickness(geometry.blade.airfoil) * evaluate_quartic(
        geometry.blade.laws.scale_y_mm, s
    )


def _worst(relative: NDArray[np.float64], s: NDArray[np.float64], t: NDArray[np.float64]) -> Sag:
    row, column = np.unravel_index(int(np.argmax(relative)), relative.shape)
    chord = float(t[column] if t[column] <= 1.0 else 2.0 - t[column])
    return Sag(float(relative[row, column]), float(s[row]), chord)


def around_sag(geometry: PropellerGeometry, points: int) -> Sag:
    """Sag of the section polygons of ``points`` equal-arc-length points, over the blade."""
    airfoil, laws = geometry.blade.airfoil, geometry.blade.laws
    t = equal_arc_length_section(airfoil, points).t
    t_mid = 0.5 * (t + np.append(t[1:], 2.0))
    s = np.linspace(0.0, 1.0, AROUND_CHECK_SECTIONS)
    planar = laws.apply(airfoil_points(airfoil, t), s)
    middle = laws.apply(airfoil_points(airfoil, t_mid), s)
    sag = _line_distance(middle, planar, np.roll(planar, -1, axis=1))
    return _worst(sag / local_thickness(geometry, s)[:, None], s, t_mid)


def along_sag(
    geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing
) -> Sag:
    """Sag of the straight edges between neighbouring sections, over the blade."""
    centerline = geometry.centerline(0)
    s = section_parameters(centerline, sections, spacing)
    sampling = equal_arc_length_section(geometry.blade.airfoil, points)
    columns = np.unique(
        np.linspace(0, len(sampling.t) - 1, min(ALONG_CHECK_POINTS, len(sampling.t))).astype(int)
    )
    s_all = np.concatenate([s, 0.5 * (s[:-1] + s[1:])])
    order = np.argsort(s_all, kind="stable")
    frames = blade_frames(geometry.blade, centerline, s_all[order])
    surface = np.empty((len(s_all), len(columns), 3))
    surface[order] = place_on_frames(
        frames, geometry.blade.laws.apply(sampling.points[columns], frames.s)
    )
    grid, middle = surface[: len(s)], surface[len(s) :]
    s_mid = s_all[len(s) :]
    sag = _line_distance(middle, grid[:-1], grid[1:])
    return _worst(sag / local_thickness(geometry, s_mid)[:, None], s_mid, sampling.t[columns])


def smallest_count(passes: Callable[[int], bool], start: int, high: int) -> int | None:
    """Smallest count in (start, high] for which ``passes`` holds (sag falls as counts grow):
    doubling, then bisection; None if even ``high`` fails."""
    low, count = start, start
    while True:
        count = min(2 * count, high)
        if passes(count):
            break
        if count == high:
            return None
        low = count
    while count - low > 1:
        middle = (low + count) // 2
        low, count = (low, middle) if passes(middle) else (middle, count)
    return count


def check_resolution(
    geometry: PropellerGeometry,
    sections: int,
    points: int,
    spacing: SectionSpacing,
    limit: float | None = None,
) -> None:
    """Refuse (ParameterError) a resolution whose flat faces leave the blade by more than ``limit``
    of the local section thickness (default MESH_SAG_LIMIT); the message gives the smallest
    ``mesh.points`` / ``mesh.sections`` that would do."""
    from torus_cad.parameters.design import Mesh

    limit = MESH_SAG_LIMIT if limit is None else limit
    most_points = Mesh.model_fields["points"].metadata[-1].le
    most_sections = Mesh.model_fields["sections"].metadata[-1].le
    problems = []
    around = around_sag(geometry, points)
    if around.relative > limit:
        needed = smallest_count(
            lambda count: around_sag(geometry, count).relative <= limit, points, most_points
        )
        problems.append(
            f"mesh.points = {points} cuts the sections by "
            f"{around.relative:.1%} of their thickness near chord "
            f"position {around.chord_position:.2f} (s = {around.s:.2f}); "
            + (
                f"use mesh.points >= {needed} (--points)"
                if needed
                else "no allowed mesh.points resolves them"
            )
        )
    along = along_sag(geometry, sections, points, spacing)
    if along.relative > limit:
        needed = smallest_count(
            lambda count: along_sag(geometry, count, points, spacing).relative <= limit,
            sections,
            most_sections,
        )
        problems.append(
            f"mesh.sections = {sections} cuts the blade's bends "
            f"by {along.relative:.1%} of the section thickness "
            f"near s = {along.s:.2f}; "
            + (
                f"use mesh.sections >= {needed} (--sections)"
                if needed
                else "no allowed mesh.sections resolves them"
            )
        )
    if problems:
        raise ParameterError(
            f"mesh resolution too coarse for this blade (limit {limit:.0%} of the section "
            "thickness): " + "; ".join(problems)
        )


@dataclass(frozen=True)
class TriangleEstimate:
    """Triangles the parts will have before the union (the union only removes some), and the hub's
    cell size."""

    blades: int
    hub: int
    hub_cell_mm: float

    @property
    def total(self) -> int:
        return self.blades + self.hub


def estimate_triangles(
    geometry: PropellerGeometry, sections: int, points: int, spacing: SectionSpacing
) -> TriangleEstimate:
    """Estimate the triangle count from a cheap coarse grid, without building the mesh."""
    coarse_sections, coarse_points = ESTIMATE_GRID
    coarse = cell_size(blade_grid(geometry, coarse_sections, coarse_points, spacing))
    around = coarse.around * coarse_points / points
    along = coarse.along * (coarse_sections - 1) / (sections - 1)
    cell = max(around, along)  # CellSize.hub
    hub = hub_layout(geometry.hub.radius_mm, geometry.hub.length_mm, cell).triangles
    return TriangleEstimate(geometry.blades * blade_triangle_count(sections, points), hub, cell)


def check_budget(estimate: TriangleEstimate, compare: bool = True) -> None:
    """Refuse (BudgetError, exit 2) meshes whose estimated memory is over
    :data:`MESH_MEMORY_LIMIT_BYTES`."""
    check_mesh_memory(estimate.total, compare)
