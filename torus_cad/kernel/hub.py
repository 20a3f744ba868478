"""Hub (spec §6.2): a cylinder of radius R and length L on the z axis, centred at the origin,
with the workshop's mounting features: chamfered ends, a bore with an optional
D-flat, and a radial set-screw hole.

The features are made on the hub *before* the blades are joined: the hub is small, so its
booleans are cheap, and the shared-intersection fuse (:mod:`torus_cad.kernel.fuse`) still
meets only the hub's outer cylinder, because the geometry layer refuses features that would
reach a blade (:mod:`torus_cad.geometry.hub.mounting`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeEdge,
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeWire,
)
from OCP.BRepPrimAPI import (
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakePrism,
    BRepPrimAPI_MakeRevol,
)
from OCP.GC import GC_MakeArcOfCircle
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt, gp_Vec
from OCP.TopoDS import TopoDS_Shape

from torus_cad.errors import KernelError
from torus_cad.geometry.hub.mounting import SET_SCREW_OVERSHOOT_MM, HubMounting
from torus_cad.kernel.edge_curves import refit_intersection_edges
from torus_cad.kernel.topology import cut, faces, solids

if TYPE_CHECKING:
    import cadquery as cq

_Z = gp_Dir(0.0, 0.0, 1.0)


def hub_solid(
    radius: float, length: float, seam_angle_deg: float = 0.0, mounting: HubMounting | None = None
) -> cq.Solid:
    """:func:`hub_shape` as cadquery's solid."""
    import cadquery as cq

    return cq.Solid(hub_shape(radius, length, seam_angle_deg, mounting))


def hub_shape(
    radius: float, length: float, seam_angle_deg: float = 0.0, mounting: HubMounting | None = None
) -> TopoDS_Shape:
    """Cylinder r <= radius, |z| <= length / 2 (mm), its lateral face's seam at ``seam_angle_deg``.

    The seam (u = 0 of the lateral face) lies in the half-plane at ``seam_angle_deg`` about +z
    from +x; u grows counter-clockwise about +z. The solid is the same for every seam angle.
    ``mounting`` adds the chamfers, the bore (with its flat) and the set-screw hole.
    """
    mounting = mounting or HubMounting()
    angle = math.radians(seam_angle_deg)
    if mounting.chamfer_mm > 0.0:
        outer = _chamfered_cylinder(radius, length, mounting.chamfer_mm, angle)
    else:
        frame = gp_Ax2(
            gp_Pnt(0.0, 0.0, -length / 2.0), _Z, gp_Dir(math.cos(angle), math.sin(angle), 0.0)
        )
        outer = BRepPrimAPI_MakeCylinder(frame, radius, length).Solid()
    tools = []
    if mounting.bore_diameter_mm > 0.0:
        tools.append(_bore(mounting, length))
    if mounting.set_screw_diameter_mm > 0.0:
        tools.append(_set_screw_hole(mounting, radius))
    if not tools:
        return outer
    made = solids(cut(outer, tools, "cut the bore and set-screw hole into the hub"))
    if len(made) != 1:
        raise KernelError(
            f"cutting the bore and set-screw hole into the hub gave {len(made)} solids instead of 1"
        )
    # The set screw's intersection curves with the bore (B-splines) part from a cylinder by up to
    # about 1.4e-7 mm, more than a STEP file's 1e-7 mm reads back: rebuilt from exact points
    # (kernel.edge_curves).
    refit_intersection_edges(made[0], faces(made[0]))
    return made[0]


def run_out_hub(
    radius: float,
    length: float,
    seam_angle_deg: float,
    mounting: HubMounting,
    extension: float,
    reach: float,
) -> tuple[cq.Solid, list[TopoDS_Shape]]:
    """A plain hub ``extension`` mm longer at each end, and the tools that cut it back to the real
    one.

    The tools: two end slabs (radius ``reach``, beyond |z| = length / 2) first, then the bore and
    set-screw hole of ``mounting`` (no chamfer: a chamfered hub has no run-out). For the root
    fillet's run-out (torus_cad.kernel.fillet.pattern.fillet_pattern).
    """
    if mounting.chamfer_mm > 0.0:
        raise KernelError("a chamfered hub has no run-out for the root fillet")
    extended = hub_solid(radius, length + 2.0 * extension, seam_angle_deg)
    half, depth = length / 2.0, extension + 1.0
    slabs = [
        BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0.0, 0.0, z), _Z), reach, depth).Solid()
        for z in (half, -half - depth)
    ]
    tools = list(slabs)
    if mounting.bore_diameter_mm > 0.0:
        tools.append(_bore(mounting, length))
    if mounting.set_screw_diameter_mm > 0.0:
        tools.append(_set_screw_hole(mounting, radius))
    return extended, tools


def _chamfered_cylinder(
    radius: float, length: float, chamfer: float, seam_angle_rad: float
) -> TopoDS_Shape:
    """The hub's (r, z) profile with 45-degree chamfers, revolved about z starting at the seam
    angle."""
    half = length / 2.0
    direction = (math.cos(seam_angle_rad), math.sin(seam_angle_rad))
    profile = [
        (0.0, -half),
        (radius - chamfer, -half),
        (radius, -half + chamfer),
        (radius, half - chamfer),
        (radius - chamfer, half),
        (0.0, half),
    ]
    wire = BRepBuilderAPI_MakeWire()
    corners = [gp_Pnt(r * direction[0], r * direction[1], z) for r, z in profile]
    for start, end in zip(corners, corners[1:] + corners[:1]):
        wire.Add(BRepBuilderAPI_MakeEdge(start, end).Edge())
    face = BRepBuilderAPI_MakeFace(wire.Wire(), True)
    revolved = BRepPrimAPI_MakeRevol(face.Face(), gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), _Z), 2.0 * math.pi)
    if not revolved.IsDone():
        raise KernelError("OpenCascade could not revolve the chamfered hub profile")
    return revolved.Shape()


def _bore(mounting: HubMounting, length: float) -> TopoDS_Shape:
    """The bore as a tool solid reaching past both end faces: a cylinder, or a D with its flat
    facing the set screw at ``bore_flat_depth_mm`` into the circle."""
    bore_radius = mounting.bore_diameter_mm / 2.0
    bottom = gp_Pnt(0.0, 0.0, -length / 2.0 - 1.0)
    if mounting.bore_flat_depth_mm == 0.0:
        return BRepPrimAPI_MakeCylinder(gp_Ax2(bottom, _Z), bore_radius, length + 2.0).Solid()
    angle = math.radians(mounting.set_screw_angle_deg)
    toward, across = (math.cos(angle), math.sin(angle)), (-math.sin(angle), math.cos(angle))
    flat = bore_radius - mounting.bore_flat_depth_mm  # distance of the flat from the axis
    half_chord = math.sqrt(bore_radius**2 - flat**2)
    z = bottom.Z()

    def point(along: float, side: float) -> gp_Pnt:
        return gp_Pnt(along * toward[0] + side * across[0], along * toward[1] + side * across[1], z)

    arc = GC_MakeArcOfCircle(
        point(flat, -half_chord), point(-bore_radius, 0.0), point(flat, half_chord)
    ).Value()
    wire = BRepBuilderAPI_MakeWire(
        BRepBuilderAPI_MakeEdge(arc).Edge(),
        BRepBuilderAPI_MakeEdge(point(flat, half_chord), point(flat, -half_chord)).Edge(),
    )
    face = BRepBuilderAPI_MakeFace(wire.Wire(), True).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0.0, 0.0, length + 2.0)).Shape()


def _set_screw_hole(mounting: HubMounting, radius: float) -> TopoDS_Shape:
    """A cylinder on the radial line at ``set_screw_angle_deg``, z = 0, from the axis to just
    outside the hub."""
    angle = math.radians(mounting.set_screw_angle_deg)
    axis = gp_Ax2(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(math.cos(angle), math.sin(angle), 0.0))
    return BRepPrimAPI_MakeCylinder(
        axis, mounting.set_screw_diameter_mm / 2.0, radius + SET_SCREW_OVERSHOOT_MM
    ).Solid()
