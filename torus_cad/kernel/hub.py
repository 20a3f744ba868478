"""Hub (spec §6.2): a cylinder of radius R and length L on the z axis, centred at the origin."""

from __future__ import annotations

import math

import cadquery as cq
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt


def hub_solid(radius: float, length: float, seam_angle_deg: float = 0.0) -> cq.Solid:
    """Cylinder r <= radius, |z| <= length / 2 (mm), its lateral face's seam at ``seam_angle_deg``.

    The seam (u = 0 of the lateral face) lies in the half-plane at ``seam_angle_deg`` about +z
    from +x; u grows counter-clockwise about +z. The solid is the same for every seam angle.
    """
    angle = math.radians(seam_angle_deg)
    frame = gp_Ax2(gp_Pnt(0.0, 0.0, -length / 2.0), gp_Dir(0.0, 0.0, 1.0), gp_Dir(math.cos(angle), math.sin(angle), 0.0))
    return cq.Solid(BRepPrimAPI_MakeCylinder(frame, radius, length).Solid())
