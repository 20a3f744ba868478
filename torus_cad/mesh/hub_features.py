"""The hub's mounting features in the mesh: chamfers in the hub's grid, the bore (with its D-flat)
and the set-screw hole cut out of it with manifold3d, as the B-rep's hub (torus_cad.kernel.hub) has
them.

The features are placed and checked against the blades exactly as for the B-rep
(torus_cad.geometry.hub.mounting.place_mounting on the same dense sampling), so the set screw
points the same way. The circles are polygons inscribed in them, with at least
:data:`BORE_MIN_SEGMENTS` / :data:`SET_SCREW_MIN_SEGMENTS` sides and sides no longer than the
hub's cells: their vertices lie on the B-rep's surfaces. The root fillet has no structured mesh:
it is refused with one line (:func:`check_meshable`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.geometry.hub.mounting import SET_SCREW_OVERSHOOT_MM, HubMounting
from torus_cad.parameters import PropellerParameters

#: Fewest sides of the bore's polygon (its area is then within 0.16 % of the circle's).
BORE_MIN_SEGMENTS = 64
#: Fewest sides of the set-screw hole's polygon.
SET_SCREW_MIN_SEGMENTS = 32
#: Bit of the face IDs that marks the hub grid's own triangles through the cuts (manifold3d keeps
#: face IDs as 32-bit ints; the tools' primitives number theirs from 0).
_GRID_BIT = 30


def check_meshable(params: PropellerParameters) -> None:
    """ParameterError (exit 2) naming a feature the structured mesh cannot carry: the root fillet,
    or the conventional kind (its grids follow the toroidal blade's centerline, and the open tip
    needs a cap)."""
    if params.kind.value == "conventional":
        raise ParameterError(
            "kind = 'conventional': torus-cad mesh makes "
            "the toroidal kind's structured grids only; "
            "use the STL of 'torus-cad build' or the tetrahedral mesh of 'torus-cad cfd'"
        )
    radius = params.hub.root_fillet_radius
    if radius > 0.0:
        raise ParameterError(
            f"hub.root_fillet_radius = {radius:g} mm: torus-cad mesh cannot mesh the root fillet "
            "(its surface is OpenCascade's, not the spec's); set hub.root_fillet_radius = 0 for "
            "the mesh, or use the STL of 'torus-cad build'"
        )


def _segments(radius_mm: float, cell_mm: float, minimum: int) -> int:
    return max(minimum, math.ceil(2.0 * math.pi * radius_mm / cell_mm))


def bore_outline(mounting: HubMounting, cell_mm: float) -> NDArray[np.float64]:
    """``(k, 2)`` mm, counter-clockwise: the bore's cross-section, a circle's inscribed polygon cut
    straight by the D-flat, which faces the set screw's direction at ``bore_flat_depth_mm`` into the
    circle."""
    radius = mounting.bore_diameter_mm / 2.0
    count = _segments(radius, cell_mm, BORE_MIN_SEGMENTS)
    if mounting.bore_flat_depth_mm == 0.0:
        theta = 2.0 * math.pi * np.arange(count) / count
    else:  # the arc away from the flat, both its ends on the flat's line
        edge = math.acos((radius - mounting.bore_flat_depth_mm) / radius)
        steps = max(2, math.ceil(count * (2.0 * math.pi - 2.0 * edge) / (2.0 * math.pi)))
        theta = np.linspace(edge, 2.0 * math.pi - edge, steps + 1)
    theta = theta + math.radians(mounting.set_screw_angle_deg)
    return np.stack([radius * np.cos(theta), radius * np.sin(theta)], axis=-1)


def _tools(
    mounting: HubMounting, hub_radius_mm: float, hub_length_mm: float, cell_mm: float
) -> list[object]:
    """manifold3d solids to subtract: the bore prism past both ends, the set-screw cylinder from the
    axis out."""
    import manifold3d as mf

    tools = []
    if mounting.bore_diameter_mm > 0.0:
        # Rows of about a cell along the axis, half a row past each end face: no long sliver where
        # the ends cut the wall.
        rows = math.ceil(hub_length_mm / cell_mm)
        step = hub_length_mm / rows
        section = mf.CrossSection([bore_outline(mounting, cell_mm)])
        bore = mf.Manifold.extrude(section, hub_length_mm + step, rows)
        tools.append(bore.translate([0.0, 0.0, -(hub_length_mm + step) / 2.0]))
    if mounting.set_screw_diameter_mm > 0.0:
        radius = mounting.set_screw_diameter_mm / 2.0
        length = hub_radius_mm + SET_SCREW_OVERSHOOT_MM
        circle = mf.CrossSection.circle(radius, _segments(radius, cell_mm, SET_SCREW_MIN_SEGMENTS))
        hole = mf.Manifold.extrude(circle, length, math.ceil(length / cell_mm) - 1)
        tools.append(hole.rotate([0.0, 90.0, 0.0]).rotate([0.0, 0.0, mounting.set_screw_angle_deg]))
    return tools


def cut_features(
    hub: TriangleMesh,
    mounting: HubMounting,
    hub_radius_mm: float,
    hub_length_mm: float,
    cell_mm: float,
) -> TriangleMesh:
    """The hub's closed mesh with the bore and the set-screw hole of ``mounting`` cut out
    (manifold3d), the needle triangles where the holes' rims cross the grid collapsed
    (torus_cad.mesh.cleanup)."""
    import manifold3d as mf

    from torus_cad.mesh.cleanup import collapse_junction_needles
    from torus_cad.mesh.union import LabeledMesh, MeshBooleanError

    tools = _tools(mounting, hub_radius_mm, hub_length_mm, cell_mm)
    if not tools:
        return hub
    # the grid's faces: distinct IDs (no merging) with this bit set
    grid_mark = np.uint64(1 << _GRID_BIT)
    face_id = (np.arange(len(hub.faces), dtype=np.uint64) % grid_mark) | grid_mark
    body = mf.Manifold(
        mf.Mesh64(
            vert_properties=np.ascontiguousarray(hub.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(hub.faces, dtype=np.uint64),
            face_id=face_id,
        )
    )
    for tool in tools:
        body = body - tool
    if body.status() != mf.Error.NoError or body.is_empty():
        raise MeshBooleanError(
            f"mesh union, step 'hub features': manifold3d failed ({body.status().name})"
        )
    result = body.to_mesh64()
    from_tool = (np.asarray(result.face_id, dtype=np.uint64) & grid_mark) == 0
    cut = LabeledMesh(
        np.array(result.vert_properties, dtype=np.float64)[:, :3].copy(),
        np.array(result.tri_verts, dtype=np.int64),
        from_tool.astype(np.int16),
        ("grid", "features"),
    )
    # the needles where the features' rims cross the grid
    cleaned, _ = collapse_junction_needles(cut)
    return cleaned.triangle_mesh


def feature_surface_distance(
    points: NDArray[np.float64], mounting: HubMounting, hub_radius_mm: float, hub_length_mm: float
) -> NDArray[np.float64]:
    """``(k,)`` mm: distance of each point from the nearest of the hub's surfaces, each taken
    unbounded (cylinder r = R, end planes, chamfer cones, bore cylinder, D-flat plane, set-screw
    cylinder).

    A lower bound of the distance from the hub's surface; for a vertex made on one of those
    surfaces (every hub vertex of the mesh), 0 up to rounding, which is what the report checks.
    """
    r = np.hypot(points[:, 0], points[:, 1])
    z = np.abs(points[:, 2])
    half = hub_length_mm / 2.0
    candidates = [np.abs(r - hub_radius_mm), np.abs(z - half)]
    if mounting.chamfer_mm > 0.0:  # the cone r + |z| = R + L/2 - c, at 45 degrees
        candidates.append(
            np.abs(r + z - (hub_radius_mm + half - mounting.chamfer_mm)) / math.sqrt(2.0)
        )
    angle = math.radians(mounting.set_screw_angle_deg)
    toward = points[:, 0] * math.cos(angle) + points[:, 1] * math.sin(angle)
    if mounting.bore_diameter_mm > 0.0:
        candidates.append(np.abs(r - mounting.bore_diameter_mm / 2.0))
    if mounting.bore_flat_depth_mm > 0.0:
        candidates.append(
            np.abs(toward - (mounting.bore_diameter_mm / 2.0 - mounting.bore_flat_depth_mm))
        )
    if mounting.set_screw_diameter_mm > 0.0:
        across = -points[:, 0] * math.sin(angle) + points[:, 1] * math.cos(angle)
        candidates.append(
            np.abs(np.hypot(across, points[:, 2]) - mounting.set_screw_diameter_mm / 2.0)
        )
    return np.asarray(np.min(np.stack(candidates), axis=0))


__all__ = [
    "bore_outline",
    "check_meshable",
    "cut_features",
    "feature_surface_distance",
]
