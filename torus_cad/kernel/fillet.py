"""Root fillet (issue 13): a constant-radius fillet along every blade-hub junction (BRepFilletAPI_MakeFillet).

What makes OpenCascade's rolling-ball fillet work on these blades (measured, see the README):

* The lofted blade's side is one B-spline face, closed in u with its seam on the sharp
  trailing edge. A fillet along a junction that runs round such a face fails; the face is
  therefore split into three (u in thirds, ShapeUpgrade_ShapeDivideClosed) before the fuse, so
  the trailing edge is a true edge between two faces, where the fillet's two ends meet.
  A split vertex near the leading edge (u = 1/2), where the section turns tightly, makes the
  fillet fail again, so it is not split in halves.
* The junction edges are the edges between a blade face (B-spline) and a hub face (the hub is
  made of planes, cylinders and cones only).
* OpenCascade's fillet can crash the process on some inputs (a segmentation fault in a few
  per cent of random designs), so it runs in a forked child process with a time limit; the
  result comes back as a BRep string.

When the fillet fails, smaller radii are tried to name one that works in the error message.
"""

from __future__ import annotations

import io
import os
import select
import signal
import time

import cadquery as cq
from OCP.BRep import BRep_Builder
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_OffsetSurface,
)
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideClosed
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel.checks import precise_volume, single_valid_solid
from torus_cad.tolerances import FILLET_TIME_LIMIT_S, VOLUME_CHECK_RELATIVE_PRECISION

#: Faces of these surface types belong to a blade; every other face (plane, cylinder, cone) to the hub.
_BLADE_SURFACES = (GeomAbs_BSplineSurface, GeomAbs_BezierSurface, GeomAbs_OffsetSurface)

#: Pieces the blade's closed side face is split into (see the module docstring).
_SIDE_FACE_PIECES = 3

#: Radii tried, as fractions of the requested one, to suggest a radius that works.
_FALLBACK_FRACTIONS = (0.5, 0.25, 0.1)


def prepare_blade_for_fillet(blade: cq.Solid) -> cq.Solid:
    """The same blade with its closed side face split into thirds in u (the trailing edge becomes an edge)."""
    divide = ShapeUpgrade_ShapeDivideClosed(blade.wrapped)
    divide.SetNbSplitPoints(_SIDE_FACE_PIECES - 1)
    divide.Perform()
    solids = cq.Shape.cast(divide.Result()).Solids()
    if len(solids) != 1:
        raise KernelError("splitting the blade's side face for the root fillet did not give one solid")
    return solids[0]


def junction_edges(solid: cq.Solid) -> list[TopoDS_Edge]:
    """Edges of ``solid`` between a blade face and a hub face (module docstring)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    edges = []
    for index in range(1, ancestors.Extent() + 1):
        kinds = {BRepAdaptor_Surface(TopoDS.Face_s(face)).GetType() in _BLADE_SURFACES
                 for face in ancestors.FindFromIndex(index)}
        if kinds == {True, False}:
            edges.append(TopoDS.Edge_s(ancestors.FindKey(index)))
    return edges


def fillet_blade_roots(solid: cq.Solid, radius_mm: float) -> cq.Solid:
    """``solid`` with a fillet of ``radius_mm`` along every blade-hub junction; one valid solid.

    Raises KernelError ("root fillet failed ...", with a radius that works when one of the
    smaller radii tried does) when OpenCascade cannot make it.
    """
    edges = junction_edges(solid)
    if not edges:
        raise KernelError("root fillet failed: no blade-hub junction edges found")
    filleted = _fillet_in_child(solid, edges, radius_mm)
    if filleted is not None:
        return filleted
    works = next((radius_mm * fraction for fraction in _FALLBACK_FRACTIONS
                  if _fillet_in_child(solid, edges, radius_mm * fraction) is not None), None)
    smallest = radius_mm * min(_FALLBACK_FRACTIONS, default=1.0)
    hint = f"; hub.root_fillet_radius = {works:.3g} mm works" if works is not None else f"; {smallest:.3g} mm fails as well"
    raise KernelError(f"root fillet failed: OpenCascade could not fillet the blade roots at "
                      f"hub.root_fillet_radius = {radius_mm:g} mm{hint}")


def fillet_edges(solid: cq.Solid, edges: list[TopoDS_Edge], radius_mm: float) -> cq.Solid | None:
    """The fillet in this process: the checked solid, or None when OpenCascade fails or the result is unsound."""
    fillet = BRepFilletAPI_MakeFillet(solid.wrapped)
    for edge in edges:
        fillet.Add(radius_mm, edge)
    try:
        fillet.Build()
    except Exception:  # noqa: BLE001 - OCCT raises Standard_Failure subclasses through OCP
        return None
    if not fillet.IsDone():
        return None
    try:
        result = single_valid_solid(cq.Shape.cast(fillet.Shape()), "the root fillet")
    except KernelError:
        return None
    # A concave fillet only adds material: a smaller volume means a wrong result.
    if precise_volume(result, VOLUME_CHECK_RELATIVE_PRECISION) < precise_volume(solid, VOLUME_CHECK_RELATIVE_PRECISION):
        return None
    return result


def _fillet_in_child(solid: cq.Solid, edges: list[TopoDS_Edge], radius_mm: float) -> cq.Solid | None:
    """:func:`fillet_edges` in a forked child (a crash or a hang there is a failed fillet, not a dead process)."""
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: fillet, send the BRep text, leave without cleanup handlers
        os.close(read_end)
        status = 1
        try:
            result = fillet_edges(solid, edges, radius_mm)
            if result is not None:
                with os.fdopen(write_end, "wb") as pipe:
                    pipe.write(_to_brep(result.wrapped))
                status = 0
        finally:
            os._exit(status)
    os.close(write_end)
    data = _read_with_limit(read_end, pid, FILLET_TIME_LIMIT_S)
    _, status = os.waitpid(pid, 0)
    if data is None or os.WIFSIGNALED(status) or os.WEXITSTATUS(status) != 0 or not data:
        return None
    return single_valid_solid(cq.Shape.cast(_from_brep(data)), "the root fillet")


def _read_with_limit(descriptor: int, pid: int, limit_s: float) -> bytes | None:
    """Everything the child writes, or None (the child killed) when it takes longer than ``limit_s``."""
    chunks, deadline = [], time.monotonic() + limit_s
    with os.fdopen(descriptor, "rb") as pipe:
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([pipe], [], [], remaining)[0]:
                os.kill(pid, signal.SIGKILL)
                return None
            chunk = pipe.read1(1 << 20)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)


def _to_brep(shape: TopoDS_Shape) -> bytes:
    stream = io.BytesIO()
    BRepTools.Write_s(shape, stream)
    return stream.getvalue()


def _from_brep(data: bytes) -> TopoDS_Shape:
    shape = TopoDS_Shape()
    BRepTools.Read_s(shape, io.BytesIO(data), BRep_Builder())
    return shape
