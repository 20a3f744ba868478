"""How many tetrahedra, and how much memory, ``torus-cad cfd`` will need: from the settings, before
any meshing.

The mesh follows the size field of :func:`torus_cad.cfd_domain.domain.set_sizes`: ``h(x) =
min(far_size, h_s + (growth_rate - 1) d(x))`` with ``d`` the distance from the propeller and ``h_s``
the size on its surface (``surface_size``, smaller where the surface curves when ``curvature_cells``
is on). A tetrahedral mesh of that field has about ``∫ dV / h³`` elements times a constant, and its
surfaces add triangles ``∫ dA / h²`` that each bring a few more. Both integrals are taken
numerically (no kernel, no gmsh): the propeller as a cloud of analytic surface points (blades and
hub, with outward normals, each carrying its own ``h_s``), the domain sampled at random points (a
fixed seed) whose distance to the cloud comes from a k-d tree; without curvature sizing the trailing
edges' own size field adds a band around them (closed form). The two constants, and the memory
per element, are fitted to measured runs (``scripts/cfd_budget.py``): within 0.8x to 1.15x of
the real count on the default design at four settings; the shipped examples at their own ``[cfd]``
(``scripts/cfd_budget.py --examples``) set :data:`REAL_OVER_ESTIMATE`, the range the printed line
states, and :data:`TETS_PER_SECOND`, the time it implies. The propeller is the one the build makes:
its ``diameter`` and ``pitch`` targets met first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.cfd_domain.sizes import (
    CYLINDER_SEGMENTS,
    MIN_SIZE_FRACTION,
    TRAILING_EDGE_SIZE_PER_THICKNESS,
    Domain,
    TrailingEdges,
    domain_for,
    trailing_edges,
)
from torus_cad.design.described_geometry import sampled_blade_surface
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.errors import BudgetError
from torus_cad.parameters import PropellerParameters
from torus_cad.tolerances import CFD_TETRAHEDRA_LIMIT

#: Blade samples (sections, points around) and hub samples per mm for the surface cloud.
CLOUD_GRID = (32, 112)
HUB_SAMPLES_PER_MM = 2.0
#: Random points in the rotating zone and in the stationary region.
ZONE_SAMPLES, OUTER_SAMPLES = 30_000, 10_000
#: Fitted constants: tetrahedra per unit of ∫ dV / h³ and per surface triangle (∫ dA / h² over
#: the triangle's area, sqrt(3)/4 h²); resident memory of the process in MB, fixed part and per
#: tetrahedron.
TETS_PER_VOLUME_UNIT = 3.0
TETS_PER_TRIANGLE = 1.7
MEMORY_BASE_MB = 750.0
MEMORY_PER_TET_KB = 0.62
#: Tetrahedra per CPU second of a whole ``torus-cad cfd`` run (gmsh meshes on one thread, so on an
#: idle machine that is its wall time), the slowest of the shipped examples measured by
#: ``scripts/cfd_budget.py --examples`` (docs/how-to/cfd.md), rounded down: the time it implies errs
#: long.
TETS_PER_SECOND = 1_500.0
#: The real count over the estimate's, lowest and highest over the shipped examples at their own
#: [cfd] (``scripts/cfd_budget.py --examples``): the factor the printed estimate states.
REAL_OVER_ESTIMATE = (0.5, 1.5)
#: A run expected to take longer than this (s) gets the settings that shorten it on its estimate
#: line.
LONG_RUN_S = 600.0
_SEED = 20260101
_EQUILATERAL_AREA = np.sqrt(3.0) / 4.0


@dataclass(frozen=True)
class CfdEstimate:
    """The expected size of the CFD mesh.

    Attributes:
        tetrahedra: element count.
        surface_triangles: triangles on all surfaces (propeller, interface, caps, farfield).
        memory_mb: peak resident memory of the process, MB.
        wall_seconds: the run's wall time on an idle machine at :data:`TETS_PER_SECOND`, s.
    """

    tetrahedra: int
    surface_triangles: int
    memory_mb: float
    wall_seconds: float

    def line(self) -> str:
        """One line for the terminal: the count with the factor it is within, the memory and the
        time."""
        low, high = (round(factor * self.tetrahedra, -3) for factor in REAL_OVER_ESTIMATE)
        return (
            f"estimate: about {self.tetrahedra:,} tetrahedra "
            f"(real counts {REAL_OVER_ESTIMATE[0]:g}x to "
            f"{REAL_OVER_ESTIMATE[1]:g}x of it on the "
            f"shipped examples: {low:,.0f} to {high:,.0f}), "
            f"{self.memory_mb / 1000.0:.1f} GB, about {_duration(self.wall_seconds)} "
            f"(at {TETS_PER_SECOND:,.0f} tetrahedra/s on an idle core)"
            + (
                "; a lower cfd.cells_per_chord or a higher cfd.growth_rate makes it quicker"
                if self.wall_seconds > LONG_RUN_S
                else ""
            )
        )


def _duration(seconds: float) -> str:
    """``40 s``, ``3 min``, ``1.5 h``."""
    if seconds < 90.0:
        return f"{max(seconds, 1.0):.0f} s"
    if seconds < 5400.0:
        return f"{seconds / 60.0:.0f} min"
    return f"{seconds / 3600.0:.1f} h"


def _section_curvature(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Curvature (1/mm) of each point of ``(sections, points, 3)`` closed rows, from its two
    neighbours."""
    before, after = np.roll(points, 1, axis=1), np.roll(points, -1, axis=1)
    a, b, c = (
        np.linalg.norm(u - v, axis=-1)
        for u, v in ((points, before), (after, points), (after, before))
    )
    twice_area = np.linalg.norm(np.cross(points - before, after - points), axis=-1)
    return 2.0 * twice_area / np.maximum(a * b * c, 1e-30)


def _blade_cloud(
    params: PropellerParameters,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Points ``(n, 3)``, outward normals ``(n, 3)`` and curvature ``(n,)`` of every blade."""
    clouds = []
    for index in range(params.blades):
        points = sampled_blade_surface(params, index, *CLOUD_GRID).points
        along = np.gradient(points, axis=0)
        around = np.roll(points, -1, axis=1) - np.roll(points, 1, axis=1)
        normals = np.cross(along, around)
        centre = points.mean(axis=1, keepdims=True)
        normals *= np.sign(np.sum(normals * (points - centre), axis=-1, keepdims=True) + 1e-300)
        normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-30)
        clouds.append(
            (points.reshape(-1, 3), normals.reshape(-1, 3), _section_curvature(points).ravel())
        )
    return tuple(np.concatenate(parts) for parts in zip(*clouds))  # type: ignore[return-value]


def _hub_cloud(
    radius: float, length: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Points, outward normals and curvature of the hub's lateral face and end faces."""
    around = max(int(2.0 * np.pi * radius * HUB_SAMPLES_PER_MM), 16)
    along = max(int(length * HUB_SAMPLES_PER_MM), 4)
    angles = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)
    zs = np.linspace(-length / 2.0, length / 2.0, along)
    a, z = np.meshgrid(angles, zs)
    lateral = np.stack([radius * np.cos(a), radius * np.sin(a), z], axis=-1).reshape(-1, 3)
    lateral_normals = np.stack([np.cos(a), np.sin(a), 0.0 * a], axis=-1).reshape(-1, 3)
    rings = np.linspace(0.0, radius, max(int(radius * HUB_SAMPLES_PER_MM), 2), endpoint=False)
    r, a = np.meshgrid(rings, angles)
    caps, cap_normals = [], []
    for side in (-1.0, 1.0):
        caps.append(
            np.stack(
                [r * np.cos(a), r * np.sin(a), np.full_like(r, side * length / 2.0)], axis=-1
            ).reshape(-1, 3)
        )
        cap_normals.append(np.tile([0.0, 0.0, side], (r.size, 1)))
    points = np.concatenate([lateral, *caps])
    normals = np.concatenate([lateral_normals, *cap_normals])
    curvature = np.concatenate([np.full(len(lateral), 1.0 / radius), np.zeros(2 * r.size)])
    return points, normals, curvature


def _cylinder_samples(
    rng: np.random.Generator, count: int, radius: float, z_range: tuple[float, float]
) -> NDArray[np.float64]:
    r = radius * np.sqrt(rng.random(count))
    a = 2.0 * np.pi * rng.random(count)
    return np.stack(
        [r * np.cos(a), r * np.sin(a), z_range[0] + (z_range[1] - z_range[0]) * rng.random(count)],
        axis=1,
    )


def estimate_cfd_mesh(params: PropellerParameters) -> CfdEstimate:
    """The expected tetrahedra, surface triangles and memory of ``torus-cad cfd`` for ``params``."""
    volume_units, triangles = size_integrals(params)
    tetrahedra = int(TETS_PER_VOLUME_UNIT * volume_units + TETS_PER_TRIANGLE * triangles)
    return CfdEstimate(
        tetrahedra,
        triangles,
        MEMORY_BASE_MB + MEMORY_PER_TET_KB * tetrahedra / 1000.0,
        tetrahedra / TETS_PER_SECOND,
    )


def size_integrals(params: PropellerParameters) -> tuple[float, int]:
    """``∫ dV / h³`` over the fluid and the surface triangles (``∫ dA / h²`` over an equilateral
    triangle's area) of ``params``' CFD mesh: what the estimate's constants multiply."""
    # scipy's spatial module only when an estimate is made (cold start)
    from scipy.spatial import cKDTree

    # the built propeller's size (diameter, pitch met)
    params = resolve_design_targets(params).parameters
    settings = params.cfd
    blade_points, blade_normals, blade_curvature = _blade_cloud(params)
    hub = _hub_cloud(params.hub.radius, params.hub.length)
    points, normals = (
        np.concatenate([blade_points, hub[0]]),
        np.concatenate([blade_normals, hub[1]]),
    )
    curvature = np.concatenate([blade_curvature, hub[2]])
    propeller_z = (
        min(float(blade_points[:, 2].min()), -params.hub.length / 2.0),
        max(float(blade_points[:, 2].max()), params.hub.length / 2.0),
    )
    domain = domain_for(params, settings, propeller_z)
    surface_size = np.full(len(points), domain.surface_size)
    if settings.curvature_cells > 0.0:
        bent = 2.0 * np.pi / (settings.curvature_cells * np.maximum(curvature, 1e-12))
        surface_size = np.clip(bent, MIN_SIZE_FRACTION * domain.surface_size, domain.surface_size)
    tree = cKDTree(points)
    rng = np.random.default_rng(_SEED)
    growth = settings.growth_rate - 1.0
    volume_units = 0.0
    for count, volume, samples in (
        (
            ZONE_SAMPLES,
            domain.zone_volume,
            _cylinder_samples(rng, ZONE_SAMPLES, domain.zone_radius, domain.zone_z),
        ),
        (
            OUTER_SAMPLES,
            domain.outer_volume,
            _cylinder_samples(rng, OUTER_SAMPLES, domain.outer_radius, domain.outer_z),
        ),
    ):
        if count == OUTER_SAMPLES:  # the outer cylinder's samples inside the zone are the zone's
            inside = (
                (np.hypot(samples[:, 0], samples[:, 1]) < domain.zone_radius)
                & (samples[:, 2] > domain.zone_z[0])
                & (samples[:, 2] < domain.zone_z[1])
            )
            keep = ~inside
        else:
            keep = np.ones(count, dtype=bool)
        distance, nearest = tree.query(samples, workers=-1)
        outside = np.sum((samples - points[nearest]) * normals[nearest], axis=1) > 0.0
        size = np.minimum(domain.far_size, surface_size[nearest] + growth * distance)
        volume_units += volume / count * float(np.sum(1.0 / size[keep & outside] ** 3))
    triangles = _surface_triangles(
        params, domain, blade_points, surface_size, len(blade_points), CYLINDER_SEGMENTS
    )
    edges = trailing_edges(params)
    smallest = MIN_SIZE_FRACTION * domain.surface_size
    if settings.curvature_cells == 0.0:  # the trailing edges' own size field (domain.set_sizes)
        edge_size = max(TRAILING_EDGE_SIZE_PER_THICKNESS * edges.thickness_mm, smallest)
    # a blunt edge's round (curvature 2 / t), too narrow for the cloud to see
    elif edges.thickness_mm > 0.0:
        edge_size = max(np.pi * edges.thickness_mm / settings.curvature_cells, smallest)
    else:  # a knife edge: the cloud's sections see its corner
        return volume_units, triangles
    edge_volume, edge_triangles = _trailing_edge_band(edges, edge_size, domain.surface_size, growth)
    return volume_units + edge_volume, triangles + edge_triangles


def _trailing_edge_band(
    edges: TrailingEdges, edge_size: float, surface_size: float, growth: float
) -> tuple[float, int]:
    """``∫ dV / h³`` and the triangles added around the trailing ``edges`` by sizes ``h =
    edge_size + growth r`` at a distance ``r`` from edges of total length ``L``, up to the surface
    size, on the two faces that meet there (triangles) and in the half space beside them
    (volume)."""
    length = sum(
        float(np.linalg.norm(np.diff(curve, axis=0), axis=1).sum()) for curve in edges.curves_mm
    )
    if edge_size >= surface_size:
        return 0.0, 0
    triangles = 2.0 * length / growth * (1.0 / edge_size - 1.0 / surface_size) / _EQUILATERAL_AREA
    volume = np.pi * length / growth**2 * (1.0 / edge_size - 1.0 / surface_size)
    return float(volume), int(triangles)


def _surface_triangles(
    params: PropellerParameters,
    domain: Domain,
    blade_points: NDArray[np.float64],
    surface_size: NDArray[np.float64],
    blade_count: int,
    segments: int,
) -> int:
    """Triangles on the propeller (its area over its local sizes) and on the cylinders (their caps'
    sizes)."""
    grid = blade_points.reshape(params.blades, *CLOUD_GRID, 3)
    along = np.linalg.norm(np.gradient(grid, axis=1), axis=-1)
    around = np.linalg.norm(np.roll(grid, -1, axis=2) - grid, axis=-1)
    areas = (along * around).ravel()
    blade = float(np.sum(areas / surface_size[:blade_count] ** 2))
    hub_area = (
        2.0 * np.pi * params.hub.radius * params.hub.length + 2.0 * np.pi * params.hub.radius**2
    )
    hub = hub_area / float(np.median(surface_size[blade_count:])) ** 2
    cylinders = 0.0
    for radius, z_range in (
        (domain.zone_radius, domain.zone_z),
        (domain.outer_radius, domain.outer_z),
    ):
        size = min(2.0 * np.pi * radius / segments, domain.far_size)
        cylinders += (
            2.0 * np.pi * radius * (z_range[1] - z_range[0]) + 2.0 * np.pi * radius**2
        ) / size**2
    return int((blade + hub + cylinders) / _EQUILATERAL_AREA)


def over_limit_error(
    mesh: str, count: int, unit: str, needs: str, limit: int, advice: str
) -> BudgetError:
    """The BudgetError (exit 2) of a mesh estimated over its limit: ``mesh`` would have about
    ``count`` ``unit`` (cells, tetrahedra) and need ``needs`` (memory, time, the settings that set
    it), over ``limit`` ``unit``; ``advice`` says what lowers it. ``cfd`` and ``simulate --step``
    refuse with it."""
    return BudgetError(
        f"{mesh} would have about {count:,} {unit} and need about {needs}, over the limit of "
        f"{limit:,} {unit}; {advice}"
    )


def check_cfd_budget(params: PropellerParameters, limit: int = CFD_TETRAHEDRA_LIMIT) -> CfdEstimate:
    """The CFD mesh's estimate, or BudgetError (exit 2) naming it, the sizes that set it and the
    limit when its tetrahedra are over ``limit``."""
    estimate = estimate_cfd_mesh(params)
    if estimate.tetrahedra > limit:
        cfd = params.cfd
        raise over_limit_error(
            "the CFD mesh",
            estimate.tetrahedra,
            "tetrahedra",
            f"{estimate.memory_mb / 1000.0:.1f} GB of "
            f"memory and {_duration(estimate.wall_seconds)} "
            f"(cfd.cells_per_chord = {cfd.cells_per_chord:g}, "
            f"cfd.curvature_cells = {cfd.curvature_cells:g}, "
            f"cfd.growth_rate = {cfd.growth_rate:g}, cfd.far_size = "
            f"{cfd.far_size:g} D, cfd.domain_radius = {cfd.domain_radius:g} D)",
            limit,
            "lower cfd.cells_per_chord or raise cfd.far_size or cfd.growth_rate",
        )
    return estimate
