"""Handedness: the clockwise propeller is the exact mirror image of the counter-clockwise one."""

from __future__ import annotations

from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf

from torus_cad.errors import KernelError
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.topology import ShapeT, like, occ, solids


def mirror_trsf() -> gp_Trsf:
    """Reflection through the XZ plane (y -> -y): a plane that contains the spin axis z."""
    mirror = gp_Trsf()
    mirror.SetMirror(gp_Ax2(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 1.0, 0.0)))
    return mirror


def mirrored(solid: ShapeT, check: bool = True) -> ShapeT:
    """``solid`` reflected through the XZ plane, as a new valid solid with outward faces (of the
    kind ``solid``
    is: OpenCascade's or cadquery's).

    The geometry is copied and transformed (not just given a negative location), so the
    result's surfaces are the reflected ones and its faces keep pointing out of the material;
    the volume is the same. A reflection through any plane that contains the axis gives the
    same part up to a turn about the axis. ``check=False`` skips the validity check (for
    parts already checked before the reflection).
    """
    transform = BRepBuilderAPI_Transform(occ(solid), mirror_trsf(), True)
    if not transform.IsDone():
        raise KernelError("OpenCascade could not mirror the propeller")
    if not check:
        return like(solid, solids(transform.Shape())[0])
    return like(
        solid, single_valid_solid(transform.Shape(), "mirroring the propeller (handedness cw)")
    )
