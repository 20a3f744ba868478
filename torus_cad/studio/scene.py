"""What the studio draws, as plain arrays: the kernel-free preview of a design and the parts'
meshes.

The preview is the spec's own surface (torus_cad.geometry) at the design's resolution, run
through the same pre-kernel checks as a build, so a design the build would refuse is refused
here first, in a fraction of the build's time. What is drawn is sampled at most
:data:`PREVIEW_MAX_SAMPLES` (sections, points), so that a design asking for the largest
resolution (400 x 2000 x 12 blades: 9.6 million vertices) cannot make the server serialise
hundreds of megabytes to every page; the exact solid replaces it. No CAD kernel is imported.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.design.described_geometry import (
    check_design_feasible,
    hub_geometry,
    sampled_blade_surface,
)
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.geometry.blade.triangle_mesh import blade_mesh
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Handedness

#: Segments around the preview hub cylinder.
HUB_SEGMENTS = 96

#: Sections and points of the fine sampling that measures the tip diameter once the exact solid is
#: built (the preview uses the design's own sampling): 400 x 400 lands within 1e-5 mm of the
#: limit on the default design (25 x 80 is 0.008 mm short), in ~0.1 s.
TIP_SAMPLES = (400, 400)

#: Most (sections, points) of a blade's drawn preview (the default design's 25 x 80 is drawn as it
#: is).
PREVIEW_MAX_SAMPLES = (60, 240)

#: Handedness 'ccw' is the spec's propeller reflected through the XZ plane
#: (torus_cad.kernel.mirror).
MIRROR = np.array([1.0, -1.0, 1.0])


@dataclass(frozen=True)
class PartMesh:
    """Triangles of one part.

    Attributes:
        part: -1 the hub, i >= 0 blade i.
        vertices: ``(k, 3)`` float, mm.
        triangles: ``(m, 3)`` int, vertex indices, counter-clockwise seen from outside.
    """

    part: int
    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]


@dataclass(frozen=True)
class PreviewScene:
    """The kernel-free preview of a design.

    Attributes:
        parts: the hub, then blade 0, 1, ... (blades overlap the hub: they are not fused).
        sections: per blade, its section curves ``(sections, points, 3)`` mm, each closed.
        tip_diameter_mm: twice the largest distance of a sampled blade point from the spin axis
            (at the design's sampling: up to ~0.01 mm short; see :func:`tip_diameter_mm`).
    """

    parts: list[PartMesh]
    sections: list[NDArray[np.float64]]
    tip_diameter_mm: float


def rotation_about_z(angle_deg: float) -> NDArray[np.float64]:
    """The ``(3, 3)`` rotation by ``angle_deg`` degrees about the spin axis."""
    turn = np.radians(angle_deg)
    return np.array(
        [[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0.0, 0.0, 1.0]]
    )


def cylinder_mesh(radius: float, length: float, segments: int = HUB_SEGMENTS) -> PartMesh:
    """A closed cylinder on the z axis spanning z in [-length/2, length/2], outward triangles."""
    angles = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])
    bottom = np.column_stack([ring, np.full(segments, -length / 2.0)])
    top = np.column_stack([ring, np.full(segments, length / 2.0)])
    vertices = np.concatenate([bottom, top, [[0.0, 0.0, -length / 2.0], [0.0, 0.0, length / 2.0]]])
    i = np.arange(segments)
    j = (i + 1) % segments
    bottom_centre, top_centre = 2 * segments, 2 * segments + 1
    triangles = np.concatenate(
        [
            # side
            np.column_stack([i, j, j + segments]),
            np.column_stack([i, j + segments, i + segments]),
            np.column_stack([np.full(segments, bottom_centre), j, i]),  # bottom, facing -z
            # top, facing +z
            np.column_stack([np.full(segments, top_centre), i + segments, j + segments]),
        ]
    )
    return PartMesh(HUB_PART, vertices, triangles.astype(np.int64))


def preview_scene(params: PropellerParameters) -> PreviewScene:
    """The preview of ``params``: hub cylinder and every blade's surface mesh, checked at the
    design's resolution and drawn at most at :data:`PREVIEW_MAX_SAMPLES`.

    The design targets (diameter, pitch, NACA designation) are applied and the blade checked as a
    build does them, so a design the build refuses raises the build's one-line GeometryError or
    ParameterError here. The hub's mounting features (bore, flat, set screw, chamfer) and the root
    fillet are left to the exact solid: the preview hub is the plain cylinder.
    """
    params = resolve_design_targets(params).parameters
    hub = hub_geometry(params)
    surface = sampled_blade_surface(params)
    check_design_feasible(params, surface)
    tip = _tip_diameter(surface.points)  # at the design's sampling (a mirror keeps the radii)
    sections, points = (
        min(wanted, most)
        for wanted, most in zip(
            (params.resolution.sections, params.resolution.points), PREVIEW_MAX_SAMPLES
        )
    )
    if (sections, points) != (params.resolution.sections, params.resolution.points):
        surface = sampled_blade_surface(params, sections=sections, points=points)
    mesh = blade_mesh(surface)
    section_points, vertices, faces = surface.points, mesh.vertices, mesh.faces
    if params.handedness == Handedness.CCW:  # the mirror image: reflect, and keep the faces outward
        section_points, vertices, faces = section_points * MIRROR, vertices * MIRROR, faces[:, ::-1]
    parts = [cylinder_mesh(hub.radius_mm, hub.length_mm)]
    curves = []
    for index in range(params.blades):  # blade i is blade 0 turned about the axis (spec §6.1)
        rotation = rotation_about_z(params.blade_angle_deg(index) - params.blade_angle_deg(0))
        # mirrored angles turn back
        turn = rotation if params.handedness == Handedness.CW else rotation.T
        parts.append(PartMesh(index, vertices @ turn.T, faces))
        curves.append(section_points @ turn.T)
    return PreviewScene(parts, curves, tip)


def _tip_diameter(points: NDArray[np.float64]) -> float:
    return 2.0 * float(np.hypot(points[..., 0], points[..., 1]).max())


def tip_diameter_mm(params: PropellerParameters, samples: tuple[int, int] = TIP_SAMPLES) -> float:
    """Twice the largest distance of the blade surface from the spin axis, mm (sampled ``samples``);
    ``params`` with its design targets applied (``Propeller.parameters``)."""
    return _tip_diameter(
        sampled_blade_surface(params, sections=samples[0], points=samples[1]).points
    )
