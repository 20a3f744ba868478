"""Parameters in, closed surface mesh and quality report out: the ``torus-cad mesh`` pipeline.

Stages: checks (triangle budget, resolution, design) -> grids (each blade's structured grid at
exactly the requested resolution, capped; the hub's §6.2 grid at the blades' cell size) ->
union (manifold3d, part labels kept) -> quality report -> files.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.feasibility import (check_blades_clear, check_centerline_leaves_through_side,
                                            check_ends_inside_hub, check_leaves_hub, check_no_fold,
                                            check_no_self_intersection, coarsen, sample_tube, tube_grid)
from torus_cad.geometry.frames import section_frames
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.surface import BladeSurface, airfoil_of, blade_surface, place_sections
from torus_cad.geometry.airfoil import airfoil_points
from torus_cad.kernel.export import atomic_path
from torus_cad.mesh.grids import blade_grid, blade_meshes, cell_size, hub_mesh
from torus_cad.mesh.quality import (Evenness, aspect_ratios, cell_deviation, edge_topology, evenness,
                                    faces_away_from_hub, hub_surface_distance, outside_hub)
from torus_cad.mesh.resolution import check_budget, check_resolution, estimate_triangles
from torus_cad.mesh.settings import MeshFormat, MeshSettings
from torus_cad.mesh.union import LabeledMesh, unite
from torus_cad.mesh.writers import write_mesh_files
from torus_cad.propeller import StageTimer
from torus_cad.tolerances import MESH_JUNCTION_MARGIN_RELATIVE


@dataclass
class SurfaceMesh:
    """The united surface mesh of a propeller and how it was made.

    Attributes:
        parameters: the design.
        settings: the mesh settings.
        mesh: one closed 2-manifold, faces labelled hub / blade_i.
        blade_grid: blade 0's structured grid (sections x points x 3, mm) and its parameters.
        hub_cell_mm: edge length of the hub grid's cells.
        estimated_triangles: the estimate the budget was checked against.
        stage_seconds: seconds per stage.
    """

    parameters: PropellerParameters
    settings: MeshSettings
    mesh: LabeledMesh
    blade_grid: BladeSurface
    hub_cell_mm: float
    estimated_triangles: int
    stage_seconds: dict[str, float] = field(default_factory=dict)


def check_design(params: PropellerParameters) -> None:
    """The pre-kernel design checks of ``geometry.feasibility`` that concern the shape (not the loft's resolution)."""
    surface = blade_surface(params)
    centerline = Centerline.for_blade(params)
    check_ends_inside_hub(params, surface)
    check_centerline_leaves_through_side(params, centerline)
    s, _ = tube_grid(len(surface.s))
    fine = sample_tube(params, centerline, s, surface.t)
    check_no_fold(fine)
    check_leaves_hub(params, fine)
    tube = coarsen(fine)
    check_no_self_intersection(params, tube)
    check_blades_clear(params, tube)


def build_surface_mesh(params: PropellerParameters, settings: MeshSettings,
                       progress: Callable[[str], None] | None = None) -> SurfaceMesh:
    """Check, grid and unite: the propeller's closed, labelled surface mesh.

    Raises ParameterError (budget, resolution), GeometryError (design), MeshBooleanError (union).
    """
    timer = StageTimer(progress)
    with timer.stage("checks"):
        estimate = estimate_triangles(params, settings)
        check_budget(estimate)
        check_resolution(params, settings)
        check_design(params)
    with timer.stage("grids"):
        grid = blade_grid(params, settings.sections, settings.points, settings.spacing)
        cell = cell_size(grid).matched
        parts = [hub_mesh(params.hub.radius, params.hub.length, cell), *blade_meshes(params, grid)]
    with timer.stage("union"):
        mesh = unite(parts, ["hub", *(f"blade_{index}" for index in range(params.blades))])
    return SurfaceMesh(params, settings, mesh, grid, cell, estimate.total, timer.seconds)


# -- quality report ---------------------------------------------------------------------------------

def _junction_margin(params: PropellerParameters) -> float:
    return MESH_JUNCTION_MARGIN_RELATIVE * params.hub.radius


def vertex_distances(result: SurfaceMesh) -> NDArray[np.float64]:
    """``(v,)`` distance (mm) of each mesh vertex from the analytic surface, or an upper bound of it.

    Hub vertices and the junction vertices the union created lie on hub triangles: their exact
    distance from the hub's cylinder bounds their distance from the propeller's surface. Every
    other vertex is a blade grid vertex, evaluated on the analytic surface (distance 0); a vertex
    that is neither gets its distance from the nearest grid vertex, again an upper bound.
    """
    mesh, params = result.mesh, result.parameters
    on_hub = np.zeros(len(mesh.vertices), dtype=bool)
    on_hub[mesh.faces_of(0).ravel()] = True
    distance = np.zeros(len(mesh.vertices))
    distance[on_hub] = np.abs(hub_surface_distance(mesh.vertices[on_hub], params.hub.radius, params.hub.length))
    others = np.flatnonzero(~on_hub)
    blade_vertices = np.concatenate([part.vertices for part in blade_meshes(params, result.blade_grid)])
    row = np.dtype((np.void, 24))
    exact = np.isin(np.ascontiguousarray(mesh.vertices[others]).view(row).ravel(),
                    np.ascontiguousarray(blade_vertices).view(row).ravel())
    strays = others[~exact]
    if len(strays):
        from scipy.spatial import cKDTree

        distance[strays], _ = cKDTree(blade_vertices).query(mesh.vertices[strays])
    return distance


def blade_cell_sag(result: SurfaceMesh) -> tuple[float, float]:
    """Largest distance (mm, and as a fraction of the local chord) of the analytic blade at its
    cells' parameter midpoints from the cells' triangles, over the cells outside the hub."""
    params, grid = result.parameters, result.blade_grid
    s_mid = 0.5 * (grid.s[:-1] + grid.s[1:])
    t_mid = 0.5 * (grid.t + np.append(grid.t[1:], 2.0))
    frames = section_frames(Centerline.for_blade(params, 0), s_mid, params.centerline.frame)
    centres = place_sections(params, frames, airfoil_points(airfoil_of(params), t_mid))
    sag = cell_deviation(grid.points, centres)
    outside = outside_hub(centres.reshape(-1, 3), params.hub.radius, params.hub.length,
                          _junction_margin(params)).reshape(sag.shape)
    chord = 2.0 * np.linalg.norm(centres - frames.origin[:, None, :], axis=-1).max(axis=1)
    if not outside.any():
        return 0.0, 0.0
    relative = np.where(outside, sag / chord[:, None], 0.0)
    return float(np.where(outside, sag, 0.0).max()), float(relative.max())


def _blade_faces(mesh: LabeledMesh) -> NDArray[np.int64]:
    return mesh.faces[mesh.part > 0]


def opencascade_comparison(params: PropellerParameters, margin: float) -> dict[str, Any]:
    """B-rep volume and the evenness of OpenCascade's STL tessellation of the same design."""
    from torus_cad.kernel.checks import precise_volume
    from torus_cad.kernel.tessellation import tessellate_faces
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params)
    faces = tessellate_faces(propeller.solid, params.export.stl_linear_deflection,
                             params.export.stl_angular_deflection)
    offsets = np.cumsum([0] + [len(face.vertices) for face in faces[:-1]])
    vertices = np.concatenate([face.vertices for face in faces])
    triangles = np.concatenate([face.triangles + offset for face, offset in zip(faces, offsets)])
    on_blade = np.concatenate([np.full(len(face.triangles), face.surface_type not in ("PLANE", "CYLINDER"))
                               for face in faces])
    blade = triangles[on_blade]
    away = blade[faces_away_from_hub(vertices, blade, params.hub.radius, params.hub.length, margin)]
    return {"brep_volume_mm3": precise_volume(propeller.solid),
            "opencascade_stl": {"linear_deflection_mm": params.export.stl_linear_deflection,
                                "angular_deflection_rad": params.export.stl_angular_deflection,
                                "triangles": len(triangles),
                                "aspect_ratio_max": float(aspect_ratios(vertices, triangles).max()),
                                "blades_away_from_junctions": evenness(vertices, away).to_dict()}}


def quality_report(result: SurfaceMesh) -> dict[str, Any]:
    """The mesh's quality as a JSON-ready dict (see README, 'Meshes for simulation')."""
    mesh, params, settings = result.mesh, result.parameters, result.settings
    margin = _junction_margin(params)
    topology = edge_topology(mesh.faces)
    blade = _blade_faces(mesh)
    away = blade[faces_away_from_hub(mesh.vertices, blade, params.hub.radius, params.hub.length, margin)]
    ratios = aspect_ratios(mesh.vertices, mesh.faces)
    sag_mm, sag_relative = blade_cell_sag(result)
    grid_cell = cell_size(result.blade_grid)
    report: dict[str, Any] = {
        "name": params.name,
        "settings": {"sections": settings.sections, "points": settings.points, "spacing": settings.spacing.value,
                     "formats": [item.value for item in settings.formats]},
        "triangles": len(mesh.faces), "vertices": len(mesh.vertices),
        "estimated_triangles": result.estimated_triangles,
        "triangles_per_part": dict(zip(mesh.part_names, np.bincount(mesh.part, minlength=len(mesh.part_names))
                                       .tolist())),
        "topology": topology.to_dict(),
        "blade_cell_mm": {"around": grid_cell.around, "along": grid_cell.along}, "hub_cell_mm": result.hub_cell_mm,
        "junction_margin_mm": margin,
        "blades_away_from_junctions": evenness(mesh.vertices, away).to_dict(),
        "aspect_ratio_max": float(ratios.max()),
        "aspect_ratio_max_hub": float(ratios[mesh.part == 0].max()),
        "volume_mm3": mesh.triangle_mesh.volume,
        "vertex_distance_max_mm": float(vertex_distances(result).max()),
        "cell_sag_max_mm": sag_mm, "cell_sag_max_relative_chord": sag_relative,
    }
    if settings.compare:
        report.update(opencascade_comparison(params, margin))
        report["volume_relative_difference"] = report["volume_mm3"] / report["brep_volume_mm3"] - 1.0
    return report


def summary_line(report: dict[str, Any]) -> str:
    """One terminal line: triangles, closedness, evenness, aspect ratio, volume, distance."""
    topology = report["topology"]
    away = report["blades_away_from_junctions"]
    closed = "closed 2-manifold" if topology["closed_2_manifold"] else "NOT CLOSED"
    line = (f"mesh: {report['triangles']:,} triangles, {closed} ({topology['open_edges']} open, "
            f"{topology['non_manifold_edges']} non-manifold edges); blade edge ratio {away['edge_ratio']:.2f}")
    if "opencascade_stl" in report:
        line += f" (OpenCascade STL {report['opencascade_stl']['blades_away_from_junctions']['edge_ratio']:.1f})"
    line += f", worst aspect {report['aspect_ratio_max']:.1f}, volume {report['volume_mm3']:.2f} mm^3"
    if "brep_volume_mm3" in report:
        line += f" (B-rep {report['brep_volume_mm3']:.2f}, {report['volume_relative_difference']:+.3%})"
    line += (f", vertices within {report['vertex_distance_max_mm']:.2g} mm and cells within "
             f"{report['cell_sag_max_mm']:.2g} mm of the surface")
    return line


def write_surface_mesh(params: PropellerParameters, settings: MeshSettings, out_dir: str | Path,
                       progress: Callable[[str], None] | None = None) -> tuple[dict[str, Any], dict[str, Path]]:
    """Build, measure and write: the mesh files and ``<name>_mesh.json``. Returns the report and the paths."""
    import json
    import time

    result = build_surface_mesh(params, settings, progress)
    if progress is not None:
        progress("quality")
    start = time.perf_counter()
    report = quality_report(result)
    result.stage_seconds["quality"] = time.perf_counter() - start
    if progress is not None:
        progress("write")
    start = time.perf_counter()
    paths: dict[str, Path] = {item.value: path for item, path in
                              write_mesh_files(result.mesh, out_dir, params.name, settings.formats).items()}
    result.stage_seconds["write"] = time.perf_counter() - start
    report["files"] = {key: path.name for key, path in paths.items()}
    report["stage_seconds"] = result.stage_seconds
    json_path = Path(out_dir) / f"{params.name}_mesh.json"
    with atomic_path(json_path) as temp:
        temp.write_text(json.dumps(report, indent=2) + "\n")
    paths["json"] = json_path
    return report, paths


__all__ = ["Evenness", "MeshFormat", "SurfaceMesh", "build_surface_mesh", "quality_report", "summary_line",
           "write_surface_mesh"]
