"""Handedness: the clockwise propeller is the exact mirror image of the counter-clockwise one."""

from __future__ import annotations

import cadquery as cq
from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf

from torus_cad.errors import KernelError
from torus_cad.kernel.checks import single_valid_solid


def mirror_trsf() -> gp_Trsf:
    """Reflection through the XZ plane (y -> -y): a plane that contains the spin axis z."""
    mirror = gp_Trsf()
    mirror.SetMirror(gp_Ax2(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 1.0, 0.0)))
    return mirror


def mirrored(solid: cq.Solid, check: bool = True) -> cq.Solid:
    """``solid`` reflected through the XZ plane, as a new valid solid with outward faces.

    The geometry is copied and transformed (not just given a negative location), so the
    result's surfaces are the reflected ones and its faces keep pointing out of the material;
    the volume is the same. A reflection through any plane that contains the axis gives the
    same part up to a turn about the axis. ``check=False`` skips the validity check (for
    parts already checked before the reflection).
    """
    transform = BRepBuilderAPI_Transform(solid.wrapped, mirror_trsf(), True)
    if not transform.IsDone():
        raise KernelError("OpenCascade could not mirror the propeller")
    shape = cq.Shape.cast(transform.Shape())
    if not check:
        return shape.Solids()[0]
    return single_valid_solid(shape, "mirroring the propeller (handedness cw)")
