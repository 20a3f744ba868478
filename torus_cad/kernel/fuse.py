"""Pattern and fuse: n blades around the axis, joined with the hub in one boolean call."""

from __future__ import annotations

from collections.abc import Sequence

from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.TopTools import TopTools_ListOfShape

import cadquery as cq

from torus_cad.errors import KernelError


def pattern_blades(blade: cq.Solid, angles_deg: Sequence[float]) -> list[cq.Solid]:
    """Copies of ``blade`` (built for angle ``angles_deg[0]``) rotated about z to every angle.

    Blade i's centerline is blade 0's rotated by theta_i - theta_0 (spec §3.3 and §6.1), so
    rotating the solid gives exactly the solid built from blade i's own control points.
    """
    first = angles_deg[0]
    return [blade if angle == first else blade.rotate(cq.Vector(0, 0, 0), cq.Vector(0, 0, 1), angle - first)
            for angle in angles_deg]


def fuse_all(hub: cq.Solid, blades: Sequence[cq.Solid]) -> cq.Shape:
    """Hub and all blades fused in one BRepAlgoAPI_Fuse call (parallel, oriented bounding boxes)."""
    arguments, tools = TopTools_ListOfShape(), TopTools_ListOfShape()
    arguments.Append(hub.wrapped)
    for blade in blades:
        tools.Append(blade.wrapped)
    fuse = BRepAlgoAPI_Fuse()
    fuse.SetArguments(arguments)
    fuse.SetTools(tools)
    fuse.SetRunParallel(True)
    fuse.SetUseOBB(True)
    fuse.Build()
    if not fuse.IsDone() or fuse.Shape().IsNull():
        raise KernelError("OpenCascade could not fuse the blades with the hub (BRepAlgoAPI_Fuse reported errors)")
    return cq.Shape.cast(fuse.Shape())
