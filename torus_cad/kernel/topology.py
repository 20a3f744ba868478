"""Small OpenCascade helpers shared by the kernel: walking a shape's sub-shapes, running booleans,
and taking a shape either as OpenCascade's own (``TopoDS_Shape``) or as cadquery's wrapper of one.

The build's own path (``torus-cad build``) works on OpenCascade's shapes and never imports cadquery,
whose import loads VTK (through ``OCP.IVtkOCC``), ezdxf and more: over a second of a cold start
(docs: measurements, cold start). The kernel's functions take either kind (:func:`occ`); those that
make a shape give it back as the kind they were given (:func:`like`), so code that continues in
cadquery keeps getting cadquery's shapes.

Importing this module quiets OpenCascade's default message printers to failures only, as importing
cadquery does: otherwise the STEP writer prints its transfer statistics on stdout.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import TYPE_CHECKING, TypeVar, Union, cast

from OCP.BinTools import BinTools
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_BooleanOperation, BRepAlgoAPI_Cut
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy, BRepBuilderAPI_Transform
from OCP.GeomAbs import (
    GeomAbs_BezierSurface,
    GeomAbs_BSplineSurface,
    GeomAbs_Cone,
    GeomAbs_Cylinder,
    GeomAbs_OffsetSurface,
    GeomAbs_OtherSurface,
    GeomAbs_Plane,
    GeomAbs_Sphere,
    GeomAbs_SurfaceOfExtrusion,
    GeomAbs_SurfaceOfRevolution,
    GeomAbs_Torus,
)
from OCP.gp import gp_Trsf
from OCP.Message import Message, Message_Gravity
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_ShapeEnum, TopAbs_SHELL, TopAbs_SOLID
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape, TopTools_ListOfShape

from torus_cad.errors import KernelError

if TYPE_CHECKING:
    import cadquery as cq

for _printer in Message.DefaultMessenger_s().Printers():
    _printer.SetTraceLevel(Message_Gravity.Message_Fail)

#: A shape as the kernel takes it: OpenCascade's own, or cadquery's wrapper of one.
AnyShape = Union[TopoDS_Shape, "cq.Shape"]

#: The kind of shape a kernel function was given, and gives back (:func:`like`).
ShapeT = TypeVar("ShapeT", bound="TopoDS_Shape | cq.Shape")

#: cadquery's names of the surface kinds (``Face.geomType()``), for messages and the tessellation's
#: faces.
_SURFACE_KINDS = {
    GeomAbs_Plane: "PLANE",
    GeomAbs_Cylinder: "CYLINDER",
    GeomAbs_Cone: "CONE",
    GeomAbs_Sphere: "SPHERE",
    GeomAbs_Torus: "TORUS",
    GeomAbs_BezierSurface: "BEZIER",
    GeomAbs_BSplineSurface: "BSPLINE",
    GeomAbs_SurfaceOfRevolution: "REVOLUTION",
    GeomAbs_SurfaceOfExtrusion: "EXTRUSION",
    GeomAbs_OffsetSurface: "OFFSET",
    GeomAbs_OtherSurface: "OTHER",
}


def occ(shape: AnyShape) -> TopoDS_Shape:
    """OpenCascade's shape of ``shape`` (itself, or the one a cadquery shape wraps)."""
    return shape if isinstance(shape, TopoDS_Shape) else shape.wrapped


def like(template: ShapeT, shape: TopoDS_Shape) -> ShapeT:
    """``shape`` as the kind ``template`` is: itself for an OpenCascade shape, cadquery's wrapper of
    it (the subclass of its type: Solid, Compound, ...) for a cadquery shape."""
    if isinstance(template, TopoDS_Shape):
        return cast(ShapeT, shape)
    import cadquery as cq

    return cast(ShapeT, cq.Shape.cast(shape))


def distinct(shape: TopoDS_Shape, kind: TopAbs_ShapeEnum) -> list[TopoDS_Shape]:
    """The distinct sub-shapes of ``kind`` in ``shape`` in TopExp's indexed map's order (cadquery's
    ``Shape.Faces()``, ``Solids()``, ... order)."""
    found = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, kind, found)
    return [found.FindKey(index) for index in range(1, found.Extent() + 1)]


def solids(shape: TopoDS_Shape) -> list[TopoDS_Shape]:
    """The solids of ``shape`` (itself if it is one), as cadquery's ``Shape.Solids()`` lists
    them."""
    return distinct(shape, TopAbs_SOLID)


def shells(shape: TopoDS_Shape) -> list[TopoDS_Shape]:
    """The shells of ``shape``, as cadquery's ``Shape.Shells()`` lists them."""
    return distinct(shape, TopAbs_SHELL)


def copied(shape: TopoDS_Shape) -> TopoDS_Shape:
    """A deep copy of ``shape`` (geometry copied, no triangulation), as cadquery's
    ``Shape.copy()``."""
    return BRepBuilderAPI_Copy(shape, True, False).Shape()


def transformed(shape: TopoDS_Shape, transform: gp_Trsf) -> TopoDS_Shape:
    """``shape`` transformed into a new shape (its geometry copied), as cadquery's ``rotate`` /
    ``mirror`` do."""
    return BRepBuilderAPI_Transform(shape, transform, True).Shape()


def shape_bytes(shape: TopoDS_Shape) -> bytes:
    """``shape`` as OpenCascade's binary BRep (BinTools), as cadquery pickles its shapes."""
    data = io.BytesIO()
    BinTools.Write_s(shape, data)
    return data.getvalue()


def shape_from_bytes(data: bytes) -> TopoDS_Shape:
    """The shape of :func:`shape_bytes`."""
    shape = TopoDS_Shape()
    BinTools.Read_s(shape, io.BytesIO(data))
    return shape


def surface_kind(face: TopoDS_Face) -> str:
    """The face's surface kind as cadquery names it ("PLANE", "CYLINDER", "BSPLINE", ...)."""
    return _SURFACE_KINDS.get(BRepAdaptor_Surface(face).GetType(), "OTHER")


#: Faces of these surface types belong to a blade; every other face (plane, cylinder, cone) to the
#: hub.
BLADE_SURFACES = (GeomAbs_BSplineSurface, GeomAbs_BezierSurface, GeomAbs_OffsetSurface)


def explore(shape: TopoDS_Shape, kind: TopAbs_ShapeEnum) -> list[TopoDS_Shape]:
    """Every sub-shape of ``kind`` in ``shape``, in TopExp order (shared ones once per use)."""
    found: list[TopoDS_Shape] = []
    explorer = TopExp_Explorer(shape, kind)
    while explorer.More():
        found.append(explorer.Current())
        explorer.Next()
    return found


def faces(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    """The faces of ``shape``."""
    return [TopoDS.Face_s(face) for face in explore(shape, TopAbs_FACE)]


def faces_in_order(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    """The distinct faces of ``shape`` in the order of cadquery's ``Shape.Faces()`` (TopExp's
    indexed map)."""
    return [TopoDS.Face_s(face) for face in distinct(shape, TopAbs_FACE)]


def edges(shape: TopoDS_Shape) -> list[TopoDS_Edge]:
    """The edges of ``shape``."""
    return [TopoDS.Edge_s(edge) for edge in explore(shape, TopAbs_EDGE)]


def count(shape: TopoDS_Shape, kind: TopAbs_ShapeEnum) -> int:
    """How many sub-shapes of ``kind`` ``shape`` has."""
    return len(explore(shape, kind))


def boolean(
    operation: BRepAlgoAPI_BooleanOperation,
    arguments: Sequence[TopoDS_Shape],
    tools: Sequence[TopoDS_Shape],
) -> BRepAlgoAPI_BooleanOperation:
    """Run ``operation`` on ``arguments`` and ``tools`` (parallel, oriented bounding boxes)."""
    argument_list, tool_list = TopTools_ListOfShape(), TopTools_ListOfShape()
    for shape in arguments:
        argument_list.Append(shape)
    for shape in tools:
        tool_list.Append(shape)
    operation.SetArguments(argument_list)
    operation.SetTools(tool_list)
    operation.SetRunParallel(True)
    operation.SetUseOBB(True)
    operation.Build()
    return operation


def result(operation: BRepAlgoAPI_BooleanOperation, what: str) -> TopoDS_Shape:
    """The boolean's shape; KernelError naming ``what`` if OpenCascade reported errors."""
    if not operation.IsDone() or operation.Shape().IsNull():
        raise KernelError(f"OpenCascade could not {what} (the boolean operation reported errors)")
    return operation.Shape()


def cut(shape: TopoDS_Shape, tools: Sequence[TopoDS_Shape], what: str) -> TopoDS_Shape:
    """``shape`` minus ``tools``; KernelError naming ``what`` on failure."""
    return result(boolean(BRepAlgoAPI_Cut(), [shape], tools), what)
