"""Small OpenCascade helpers shared by the kernel: walking a shape's sub-shapes and running booleans."""

from __future__ import annotations

from collections.abc import Sequence

from OCP.BRepAlgoAPI import BRepAlgoAPI_BooleanOperation, BRepAlgoAPI_Cut
from OCP.GeomAbs import GeomAbs_BezierSurface, GeomAbs_BSplineSurface, GeomAbs_OffsetSurface
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_ShapeEnum
from OCP.TopExp import TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_ListOfShape

from torus_cad.errors import KernelError

#: Faces of these surface types belong to a blade; every other face (plane, cylinder, cone) to the hub.
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


def edges(shape: TopoDS_Shape) -> list[TopoDS_Edge]:
    """The edges of ``shape``."""
    return [TopoDS.Edge_s(edge) for edge in explore(shape, TopAbs_EDGE)]


def count(shape: TopoDS_Shape, kind: TopAbs_ShapeEnum) -> int:
    """How many sub-shapes of ``kind`` ``shape`` has."""
    return len(explore(shape, kind))


def boolean(operation: BRepAlgoAPI_BooleanOperation, arguments: Sequence[TopoDS_Shape],
            tools: Sequence[TopoDS_Shape]) -> BRepAlgoAPI_BooleanOperation:
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
