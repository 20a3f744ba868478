"""Parameters in, closed surface mesh and quality report out: the ``torus-cad mesh`` pipeline.

Stages: checks (memory budget, resolution, design, root fillet, hub features against the
blades) -> grids (blade 0's structured grid at exactly the requested resolution, checked for
crossing triangles; the hub's §6.2 grid at the blades' cell size with its chamfers, bore, flat
and set-screw hole) -> union (the hub and the blade roots through manifold3d, the junctions'
needle edges collapsed, the rest of each blade joined back: torus_cad.mesh.assembly) ->
crossings (meshlib) -> quality report -> files (one output set).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.design.prepared_design import placed_mounting
from torus_cad.errors import ParameterError
from torus_cad.geometry.analysis import feasibility
from torus_cad.geometry.blade.blade_surface import (
    BladeSurface,
    blade_frames,
    place_sections,
    sections_along,
    sections_at,
)
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.geometry.hub.mounting import HubMounting
from torus_cad.mesh import quality
from torus_cad.mesh.assembly import assemble
from torus_cad.mesh.cleanup import Cleanup
from torus_cad.mesh.crossings import (
    MESH_WHOLE_CROSSING_CHECK_TRIANGLES,
    CrossingCheck,
    blade_crossings,
    crossing_pairs,
)
from torus_cad.mesh.grids import (
    blade_grid,
    cell_size,
    hub_mesh,
    mirrored_diagonal_mesh,
    rotated_about_axis,
    split_along_a_d,
)
from torus_cad.mesh.hub_features import (
    check_meshable,
    cut_features,
    feature_surface_distance,
)
from torus_cad.mesh.mesh_formats import MeshFormat, selected_formats
from torus_cad.mesh.resolution import check_budget, check_resolution, estimate_triangles
from torus_cad.mesh.union import LabeledMesh, MeshBooleanError
from torus_cad.mesh.writers import write_mesh_files
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Handedness, SectionSpacing
from torus_cad.runtime.isolation import IsolatedCall, fork_is_safe_for_opencascade
from torus_cad.runtime.stage_timer import StageTimer

#: Longest wait (s) for the B-rep that ``torus-cad mesh`` compares its mesh with (built in a child
#: beside the mesh): a build, its strict check (STRICT_CHECK_TIME_LIMIT_S) included, and one
#: tessellation.
MESH_COMPARISON_TIME_LIMIT_S = 900.0

#: Surface meshes: triangles with every corner at least this fraction of the hub radius outside
#: the hub count as "away from the junctions" in the quality report.
MESH_JUNCTION_MARGIN_RELATIVE = 0.05


class MeshStage(StrEnum):
    """Stages of ``torus-cad mesh``; the value is the key in the report's ``stage_seconds``."""

    CHECKS = "checks"
    GRIDS = "grids"
    UNION = "union"
    CROSSINGS = "crossings"
    QUALITY = "quality"
    WRITE = "write"


@dataclass
class SurfaceMesh:
    """The united surface mesh of a propeller and how it was made.

    Attributes:
        parameters: the design (``parameters.mesh`` holds the resolution and formats).
        mesh: one closed 2-manifold, faces labelled hub / blade_i.
        blade_grid: blade 0's structured grid (``(sections, points, 3)`` mm) and its parameters.
        hub_cell_mm: edge length of the hub grid's cells.
        estimated_triangles: the estimate the budget was checked against.
        cleanup: what the junction cleanup after the union did (``mesh.cleanup``).
        mounting: the hub's features as meshed (set screw placed).
        crossings: intersecting triangle pairs of the united mesh (meshlib) and what was checked.
        topology: the united mesh's edge counts (closed, checked before anything is written).
        united_vertices: the first vertices, those of the union's result; the others are blade grid
            vertices.
        stage_seconds: seconds per stage (keys: MeshStage values).
    """

    parameters: PropellerParameters
    mesh: LabeledMesh
    blade_grid: BladeSurface
    hub_cell_mm: float
    estimated_triangles: int
    cleanup: Cleanup
    mounting: HubMounting
    crossings: CrossingCheck
    topology: quality.Topology
    united_vertices: int
    stage_seconds: dict[str, float] = field(default_factory=dict)

    @property
    def geometry(self) -> PropellerGeometry:
        return propeller_geometry(self.parameters)


def check_design(params: PropellerParameters) -> None:
    """The pre-kernel design checks of ``geometry.feasibility`` about the shape (not the loft's
    resolution)."""
    geometry = propeller_geometry(params)
    surface = sampled_blade_surface(params)
    centerline = geometry.centerline(0)
    feasibility.check_ends_inside_hub(geometry.hub, surface)
    feasibility.check_centerline_leaves_through_side(geometry.hub, centerline)
    s, _ = feasibility.tube_grid(len(surface.s))
    fine = feasibility.sample_tube(geometry, centerline, s, surface.t)
    feasibility.check_no_fold(fine)
    feasibility.check_leaves_hub(geometry.hub, fine)
    tube = feasibility.coarsen(fine)
    feasibility.check_no_self_intersection(geometry.hub, tube)
    feasibility.check_blades_clear(geometry, tube)


#: On meshes too large to check whole, the junction check covers the triangles within this many
#: blade cells of the hub (or the junction margin, if larger): beyond them the union and the
#: cleanup left the blade grid's own triangles, which blade 0's check covers.
JUNCTION_CHECK_CELLS = 3.0

#: Scale factors of both counts tried, in order, for a resolution whose blade mesh crosses itself.
_CROSSING_FREE_SCALES = (1.25, 1.5, 2.0, 3.0, 4.0)


def _blade_check(
    geometry: PropellerGeometry, grid: BladeSurface, mesh: TriangleMesh
) -> CrossingCheck:
    sections, count, _ = grid.points.shape
    whole = geometry.blades * len(mesh.faces) <= MESH_WHOLE_CROSSING_CHECK_TRIANGLES
    trailing_edge = grid.trailing_edge_index if grid.trailing_edge_index is not None else count // 2
    return blade_crossings(mesh, sections, count, trailing_edge, grid.lower_corner_index, whole)


def check_blade_crossings(
    geometry: PropellerGeometry, grid: BladeSurface, mesh: TriangleMesh, spacing: SectionSpacing
) -> CrossingCheck:
    """Blade 0's crossing check; ParameterError (exit 2) when its mesh crosses itself, naming the
    smallest of the counts scaled by :data:`_CROSSING_FREE_SCALES` whose mesh does not."""
    from torus_cad.parameters.design import Mesh

    check = _blade_check(geometry, grid, mesh)
    found = check.pairs
    if found == 0:
        return check
    sections, points, _ = grid.points.shape
    most = (
        Mesh.model_fields["sections"].metadata[-1].le,
        Mesh.model_fields["points"].metadata[-1].le,
    )
    advice = "no allowed resolution up to 4 times finer avoids it"
    for scale in _CROSSING_FREE_SCALES:
        finer = (
            min(int(np.ceil(sections * scale)), most[0]),
            min(int(np.ceil(points * scale)), most[1]),
        )
        finer_grid = blade_grid(geometry, *finer, spacing)
        if _blade_check(geometry, finer_grid, mirrored_diagonal_mesh(finer_grid)).pairs == 0:
            advice = (
                f"use --sections {finer[0]} --points "
                f"{finer[1]} (mesh.sections, mesh.points) or finer"
            )
            break
    raise ParameterError(
        f"mesh.sections = {sections}, mesh.points = {points} is too coarse for this blade: its "
        f"mesh crosses itself at {found} triangle pairs; {advice}"
    )


def _hub(geometry: PropellerGeometry, mounting: HubMounting, cell: float) -> TriangleMesh:
    hub = hub_mesh(geometry.hub.radius_mm, geometry.hub.length_mm, cell, mounting.chamfer_mm)
    return cut_features(hub, mounting, geometry.hub.radius_mm, geometry.hub.length_mm, cell)


def united_crossings(
    mesh: LabeledMesh,
    united_faces: int,
    blade: CrossingCheck,
    geometry: PropellerGeometry,
    margin_mm: float,
) -> CrossingCheck:
    """Intersecting pairs of the assembled mesh: all of it when blade 0 was checked whole, else the
    hub and every triangle that went through the union within ``margin_mm`` of the hub (the
    junctions, where the union and the cleanup made new triangles), blade 0's edge bands having been
    checked already."""
    if blade.scope == "whole mesh":
        return CrossingCheck(
            crossing_pairs(mesh.vertices, mesh.faces), len(mesh.faces), "whole mesh"
        )
    faces = mesh.faces[:united_faces]
    hub = geometry.hub
    near = (mesh.part[:united_faces] == 0) | ~quality.faces_away_from_hub(
        mesh.vertices, faces, hub.radius_mm, hub.length_mm, margin_mm
    )
    used = np.unique(faces[near])
    pairs = crossing_pairs(mesh.vertices[used], np.searchsorted(used, faces[near]))
    return CrossingCheck(
        blade.pairs + pairs,
        blade.checked_triangles + int(near.sum()),
        f"the hub and every triangle within {margin_mm:.3g} mm "
        f"of it (the junctions), {blade.scope}",
    )


def build_surface_mesh(
    params: PropellerParameters,
    progress: Callable[[str], None] | None = None,
    compare: bool = False,
) -> SurfaceMesh:
    """Check, grid and unite at ``params.mesh``'s resolution: the propeller's closed, labelled
    surface mesh with the hub's features, checked for intersecting triangles.

    ``compare``: the B-rep will be built too (the memory budget counts it).

    Raises ParameterError (memory budget, resolution, a crossing mesh, the root fillet),
    GeometryError (design, hub features), MeshBooleanError (union).
    """
    from torus_cad.design.design_targets import resolve_design_targets

    timer = StageTimer[MeshStage](progress)
    with timer.stage(MeshStage.CHECKS):
        # airfoil.naca, diameter, pitch, as the B-rep's
        params = resolve_design_targets(params).parameters
        check_meshable(params)
        geometry, table = propeller_geometry(params), params.mesh
        estimate = estimate_triangles(geometry, table.sections, table.points, table.spacing)
        check_budget(estimate, compare)
        check_resolution(geometry, table.sections, table.points, table.spacing)
        check_design(params)
        mounting = placed_mounting(params)
    with timer.stage(MeshStage.GRIDS):
        grid = blade_grid(geometry, table.sections, table.points, table.spacing)
        blade = mirrored_diagonal_mesh(grid)
        blade_check = check_blade_crossings(geometry, grid, blade, table.spacing)
        del blade
        cells = cell_size(grid)
        hub = _hub(geometry, mounting, cells.hub)
    with timer.stage(MeshStage.UNION):
        assembled = assemble(geometry, grid, hub, cells.hub)
    mesh = assembled.mesh
    topology = quality.edge_topology(mesh.faces)
    if not topology.closed:
        raise MeshBooleanError(
            f"mesh union, step 'join': the mesh is not closed ({topology.open_edges} open, "
            f"{topology.non_manifold_edges} non-manifold, {topology.inconsistent_edges} "
            "inconsistently oriented edges)"
        )
    with timer.stage(MeshStage.CROSSINGS):
        margin = max(
            _junction_margin(geometry.hub.radius_mm),
            JUNCTION_CHECK_CELLS * max(cells.around, cells.along),
        )
        crossings = united_crossings(mesh, assembled.united_faces, blade_check, geometry, margin)
        if crossings.pairs:
            raise ParameterError(
                f"mesh.sections = {table.sections}, mesh.points = "
                f"{table.points}: the united mesh crosses itself at "
                f"{crossings.pairs} triangle pairs where the blades "
                "meet the hub; use finer --sections and --points"
            )
    return SurfaceMesh(
        params,
        mesh,
        grid,
        cells.hub,
        estimate.total,
        assembled.cleanup,
        mounting,
        crossings,
        topology,
        assembled.united_vertices,
        timer.seconds,
    )


# -- quality report
# ---------------------------------------------------------------------------------


def _junction_margin(hub_radius_mm: float) -> float:
    """How far outside the hub (mm) a triangle counts as away from the junctions."""
    return MESH_JUNCTION_MARGIN_RELATIVE * hub_radius_mm


def vertex_distances(result: SurfaceMesh) -> NDArray[np.float64]:
    """``(v,)`` distance (mm) of each mesh vertex from the analytic surface, or an upper bound of
    it.

    Hub vertices and the junction vertices the union created lie on hub triangles: their distance
    from the nearest of the hub's surfaces (with its features, each surface taken unbounded:
    ``hub_features.feature_surface_distance``) stands for their distance from the propeller's
    surface. Every other vertex is a blade grid vertex, evaluated on the analytic surface
    (distance 0); a vertex that is neither gets its distance from the nearest grid vertex, an
    upper bound.
    """
    mesh, hub = result.mesh, result.geometry.hub
    on_hub = np.zeros(len(mesh.vertices), dtype=bool)
    on_hub[mesh.faces_of(0).ravel()] = True
    distance = np.zeros(len(mesh.vertices))
    distance[on_hub] = feature_surface_distance(
        mesh.vertices[on_hub], result.mounting, hub.radius_mm, hub.length_mm
    )
    # the rest are the blades' joined bands: grid vertices
    others = np.flatnonzero(~on_hub[: result.united_vertices])
    geometry, grid_vertices = result.geometry, result.blade_grid.points.reshape(-1, 3)
    blade_vertices = np.concatenate(
        [
            rotated_about_axis(
                grid_vertices, geometry.blade_angle_deg(index) - geometry.blade_angle_deg(0)
            )
            for index in range(geometry.blades)
        ]
    )
    exact = quality.rows_in(mesh.vertices[others], blade_vertices)
    strays = others[~exact]
    if len(strays):
        from scipy.spatial import cKDTree

        distance[strays], _ = cKDTree(blade_vertices).query(mesh.vertices[strays])
    return distance


def blade_cell_sag(result: SurfaceMesh) -> tuple[float, float]:
    """Largest distance (mm, and as a fraction of the local chord) of the analytic blade at its
    cells' parameter midpoints from the cells' triangles, over the cells outside the hub."""
    geometry, grid = result.geometry, result.blade_grid
    s_mid = 0.5 * (grid.s[:-1] + grid.s[1:])
    # closed parameters of blunt sections run to 3
    period = 3.0 if grid.lower_corner_index is not None else 2.0
    t_mid = 0.5 * (grid.t + np.append(grid.t[1:], period))
    frames = blade_frames(geometry.blade, geometry.centerline(0), s_mid)
    centres = place_sections(
        geometry.blade, frames, sections_at(sections_along(geometry.blade, frames.s), t_mid)
    )
    sag = quality.cell_deviation(grid.points, centres, split_along_a_d(grid))
    outside = quality.outside_hub(
        centres.reshape(-1, 3),
        geometry.hub.radius_mm,
        geometry.hub.length_mm,
        _junction_margin(geometry.hub.radius_mm),
    ).reshape(sag.shape)
    chord = 2.0 * np.linalg.norm(centres - frames.origin[:, None, :], axis=-1).max(axis=1)
    if not outside.any():
        return 0.0, 0.0
    relative = np.where(outside, sag / chord[:, None], 0.0)
    return float(np.where(outside, sag, 0.0).max()), float(relative.max())


def opencascade_comparison(params: PropellerParameters, margin: float) -> dict[str, Any]:
    """B-rep volume and the evenness of OpenCascade's STL tessellation of the same design."""
    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.kernel.tessellation import tessellate_faces
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params)
    faces = tessellate_faces(
        propeller.shape, params.export.stl_linear_deflection, params.export.stl_angular_deflection
    )
    offsets = np.cumsum([0] + [len(face.vertices) for face in faces[:-1]])
    vertices = np.concatenate([face.vertices for face in faces])
    triangles = np.concatenate([face.triangles + offset for face, offset in zip(faces, offsets)])
    on_blade = np.concatenate(
        [
            np.full(len(face.triangles), face.surface_type not in ("PLANE", "CYLINDER"))
            for face in faces
        ]
    )
    blade = triangles[on_blade]
    away = blade[
        quality.faces_away_from_hub(vertices, blade, params.hub.radius, params.hub.length, margin)
    ]
    ratios = quality.aspect_ratios(vertices, triangles)
    return {
        "brep_volume_mm3": precise_volume(propeller.shape),
        "opencascade_stl": {
            "linear_deflection_mm": params.export.stl_linear_deflection,
            "angular_deflection_rad": params.export.stl_angular_deflection,
            "triangles": len(triangles),
            "aspect_ratio_max": float(ratios.max()),
            "triangles_aspect_ratio_over_100": int(np.sum(ratios > 100.0)),
            "blades_away_from_junctions": quality.evenness(vertices, away).to_dict(),
        },
    }


def quality_report(result: SurfaceMesh, comparison: dict[str, Any] | None = None) -> dict[str, Any]:
    """The mesh's quality as a JSON-ready dict (see docs, 'Mesh for CFD'), with ``comparison`` (the
    :func:`opencascade_comparison` of the same design) and the volume difference from it, if
    given."""
    mesh, params, table = result.mesh, result.parameters, result.parameters.mesh
    margin = _junction_margin(result.geometry.hub.radius_mm)
    topology = result.topology
    blade = np.flatnonzero(mesh.part > 0)
    away = blade[
        quality.faces_away_from_hub(
            mesh.vertices, mesh.faces[blade], params.hub.radius, params.hub.length, margin
        )
    ]
    lengths, ratios = quality.triangle_measures(mesh.vertices, mesh.faces)
    sag_mm, sag_relative = blade_cell_sag(result)
    grid_cell = cell_size(result.blade_grid)
    report: dict[str, Any] = {
        "name": params.name,
        "settings": {
            "sections": table.sections,
            "points": table.points,
            "spacing": table.spacing.value,
            "formats": [item.value for item in selected_formats(table)],
        },
        "triangles": len(mesh.faces),
        "vertices": len(mesh.vertices),
        "estimated_triangles": result.estimated_triangles,
        "junction_cleanup": asdict(result.cleanup),
        "triangles_per_part": dict(
            zip(mesh.part_names, np.bincount(mesh.part, minlength=len(mesh.part_names)).tolist())
        ),
        "topology": topology.to_dict(),
        "blade_cell_mm": {"around": grid_cell.around, "along": grid_cell.along},
        "hub_cell_mm": result.hub_cell_mm,
        "junction_margin_mm": margin,
        "blades_away_from_junctions": quality.evenness(
            mesh.vertices, mesh.faces[away], (lengths[away], ratios[away])
        ).to_dict(),
        "aspect_ratio_max": float(ratios.max()),
        "triangles_aspect_ratio_over_100": int(np.sum(ratios > 100.0)),
        "aspect_ratio_max_hub": float(ratios[mesh.part == 0].max()),
        "volume_mm3": mesh.triangle_mesh.volume,
        "vertex_distance_max_mm": float(vertex_distances(result).max()),
        "cell_sag_max_mm": sag_mm,
        "cell_sag_max_relative_chord": sag_relative,
        "self_intersections": result.crossings.pairs,
        "self_intersection_check": {
            "scope": result.crossings.scope,
            "checked_triangles": result.crossings.checked_triangles,
            "library": "meshlib",
        },
        "hub_features": _features(result),
    }
    if comparison is not None:
        report.update(comparison)
        report["volume_relative_difference"] = (
            report["volume_mm3"] / report["brep_volume_mm3"] - 1.0
        )
    return report


def _features(result: SurfaceMesh) -> dict[str, Any]:
    mounting, blade = result.mounting, result.parameters.airfoil
    return {
        "bore_diameter_mm": mounting.bore_diameter_mm,
        "bore_flat_depth_mm": mounting.bore_flat_depth_mm,
        "set_screw_diameter_mm": mounting.set_screw_diameter_mm,
        "set_screw_angle_deg": mounting.set_screw_angle_deg
        if mounting.set_screw_diameter_mm
        else None,
        "chamfer_mm": mounting.chamfer_mm,
        "trailing_edge_thickness_mm": blade.trailing_edge_thickness,
        "trailing_edge_shape": blade.trailing_edge_shape.value
        if result.blade_grid.lower_corner_index is not None
        else "sharp",
        "handedness": result.parameters.handedness.value,
    }


def summary_line(report: dict[str, Any]) -> str:
    """One terminal line: triangles, closedness, evenness, aspect ratio, volume, distance."""
    topology = report["topology"]
    away = report["blades_away_from_junctions"]
    closed = "closed 2-manifold" if topology["closed_2_manifold"] else "NOT CLOSED"
    crossing = (
        "no intersecting triangles"
        if report["self_intersections"] == 0
        else f"{report['self_intersections']} INTERSECTING TRIANGLE PAIRS"
    )
    line = (
        f"mesh: {report['triangles']:,} triangles, {closed} ({topology['open_edges']} open, "
        f"{topology['non_manifold_edges']} non-manifold edges), {crossing}; blade edge ratio "
        f"{away['edge_ratio']:.2f}"
    )
    if "opencascade_stl" in report:
        line += (
            " (OpenCascade STL "
            f"{report['opencascade_stl']['blades_away_from_junctions']['edge_ratio']:.1f})"
        )
    line += (
        f", worst aspect ratio {report['aspect_ratio_max']:.3g}"
        f" ({report['triangles_aspect_ratio_over_100']} "
        f"triangles over 100), volume {report['volume_mm3']:.2f} mm^3"
    )
    if "brep_volume_mm3" in report:
        line += (
            f" (B-rep {report['brep_volume_mm3']:.2f}, {report['volume_relative_difference']:+.3%})"
        )
    line += (
        f", vertices within {report['vertex_distance_max_mm']:.2g} mm and cells within "
        f"{report['cell_sag_max_mm']:.2g} mm of the surface"
    )
    return line


def mirrored_mesh(mesh: LabeledMesh) -> LabeledMesh:
    """``mesh`` reflected through the XZ plane (the 'ccw' propeller, as torus_cad.kernel.mirror
    makes the B-rep's), faces turned to stay outward."""
    return LabeledMesh(
        mesh.vertices * np.array([1.0, -1.0, 1.0]), mesh.faces[:, ::-1], mesh.part, mesh.part_names
    )


def _write_one(
    mesh: LabeledMesh, name: str, file_format: MeshFormat, folder: Path
) -> dict[str, Path]:
    """One mesh file into an output set's staging ``folder``: ``{format: path}``."""
    return {
        item.value: path
        for item, path in write_mesh_files(mesh, folder, name, (file_format,), atomic=False).items()
    }


def write_surface_mesh(
    params: PropellerParameters,
    out_dir: str | Path,
    compare: bool = True,
    progress: Callable[[str], None] | None = None,
) -> tuple[dict[str, Any], dict[str, Path]]:
    """Build, measure and write at ``params.mesh``: the mesh files and ``<name>_mesh.json`` as one
    output set (torus_cad.outputs.output_set: staged, sealed by the report, published whole or not
    at all).

    Returns the report as sealed and the published paths by format (and ``"json"``, last).
    Nothing is written when a check refuses the design or the resolution.
    """
    from torus_cad.outputs.output_set import OutputSet

    formats = selected_formats(params.mesh)
    margin_mm = _junction_margin(params.hub.radius)
    with contextlib.ExitStack() as stack:
        # The B-rep to compare with is built in a child meanwhile, on the second core, where that is
        # safe.
        beside = compare and fork_is_safe_for_opencascade()
        child = (
            stack.enter_context(
                IsolatedCall(
                    opencascade_comparison,
                    params,
                    margin_mm,
                    what="the B-rep to compare the mesh with",
                )
            )
            if beside
            else None
        )
        result = build_surface_mesh(params, progress, compare)
        timer = StageTimer[MeshStage](progress)
        with timer.stage(MeshStage.QUALITY):
            comparison = (
                child.result(MESH_COMPARISON_TIME_LIMIT_S)
                if child is not None
                else opencascade_comparison(params, margin_mm)
                if compare
                else None
            )
            report = quality_report(result, comparison)
    mesh = mirrored_mesh(result.mesh) if params.handedness == Handedness.CCW else result.mesh
    with OutputSet(out_dir, f"{params.name}_mesh") as output:
        with timer.stage(MeshStage.WRITE):
            for file_format in formats:
                output.write_files(functools.partial(_write_one, mesh, params.name, file_format))
        result.stage_seconds.update(timer.seconds)
        report["stage_seconds"] = result.stage_seconds
        paths = output.publish(report)
        report = output.sealed_report
    return report, {str(kind): path for kind, path in paths.items()}


__all__ = [
    "MeshFormat",
    "MeshStage",
    "SurfaceMesh",
    "build_surface_mesh",
    "quality_report",
    "summary_line",
    "write_surface_mesh",
]
