"""The STEP writer's fix for an edge whose curve hooks into a neighbouring face at its vertex.

A root fillet's contact edge can leave its vertex the wrong way: its 3D curve and p-curves run up to
2e-5 mm into the next fillet face and turn back, hidden in memory by the vertex's tolerance (1.9e-5
mm, from the fillet's construction). The STEP file carries no tolerances; read back, the vertex gets
the few 1e-6 mm its curves' ends need, and the self-interference test (FreeCAD's check with BOP)
finds the edge inside the face: ``SelfIntersect`` (measured on ``python
scripts/step_readback_tally.py --replay 3078 --freecad``).

:func:`edge_interference` is the self-interference test of a file the writer wrote again
(BOPAlgo_CheckerSI without its face/face half, :data:`EDGE_CHECK_LEVEL`); it finds each such edge
(an edge-face interference whose edge and face share a vertex and whose common range ends within
:data:`HOOK_LIMIT_MM` of it), and :func:`hook_trimmed_copy` cuts the hook off: the edge's 3D
curve and p-curves are segmented to start where the edge has left the face, and the vertex's
tolerance covers the cut. The reader of the file written from it closes the cut as it reads (with
a tolerance or an edge as short as the cut).
"""

from __future__ import annotations

from dataclasses import dataclass

from OCP.BOPAlgo import BOPAlgo_CheckerSI
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepTools import BRepTools_ReShape
from OCP.Geom import Geom_TrimmedCurve
from OCP.Geom2d import Geom2d_TrimmedCurve
from OCP.Geom2dConvert import Geom2dConvert
from OCP.GeomConvert import GeomConvert
from OCP.ShapeBuild import ShapeBuild_Edge
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape, TopoDS_Vertex
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape, TopTools_ListOfShape

from torus_cad.kernel.edge_curves import distinct_faces

#: A hook ends this near its vertex at most (mm): fifty times the deepest measured (the in-memory
#: vertex tolerance, 1.9e-5 mm, lets a curve hook 2e-5 mm deep and end 4.3e-5 mm from its vertex);
#: an edge that meets a face further from its vertex is a real self-intersection, not cut.
HOOK_LIMIT_MM = 1e-3

#: The vertex's tolerance is raised to this times the cut's length.
CUT_MARGIN = 1.1

#: BOPAlgo_CheckerSI's level of check that tests every pair of sub-shapes but face/face (0 vertex/
#: vertex ... 4 edge/face, 5 face/face too). A file written again carries the checked solid's
#: surfaces unchanged, only its edges' curves and tolerances are the reader's: an interference it
#: gains starts at an edge or a vertex, so face/face, half to two thirds of the check's time,
#: finds none the lower levels miss.
EDGE_CHECK_LEVEL = 4


@dataclass(frozen=True)
class Hook:
    """One edge's hook into a face it does not bound.

    Attributes:
        edge: the edge.
        face: the face it hooks into.
        vertex: its end the hook starts at (shared with the face).
        cut: the edge's parameter where the hook ends (the common range's far end from the vertex).
    """

    edge: TopoDS_Edge
    face: TopoDS_Face
    vertex: TopoDS_Vertex
    cut: float


@dataclass(frozen=True)
class EdgeInterference:
    """What BOPAlgo_CheckerSI finds on a shape at :data:`EDGE_CHECK_LEVEL`.

    Attributes:
        hooks: the edges that hook into a face at a vertex they share with it, one per edge.
        pairs: every other interfering pair of sub-shapes (vertices, edges, faces): real
            self-intersections.
    """

    hooks: tuple[Hook, ...]
    pairs: tuple[tuple[TopoDS_Shape, TopoDS_Shape], ...]


def edge_interference(shape: TopoDS_Shape) -> EdgeInterference:
    """BOPAlgo_CheckerSI on ``shape`` (single-threaded) with every test but face/face
    (:data:`EDGE_CHECK_LEVEL`), its interfering pairs split into hooks and the rest.

    Args:
        shape: the solid (as read back from a STEP file), mm; not changed.

    Returns:
        The hooks (an edge-face interference whose edge and face share a vertex and whose common
        range ends within HOOK_LIMIT_MM of it) and the other pairs; both empty when the shape has
        no self-interference but possibly between faces' interiors.
    """
    checker = BOPAlgo_CheckerSI()
    arguments = TopTools_ListOfShape()
    arguments.Append(shape)
    checker.SetArguments(arguments)
    checker.SetRunParallel(False)
    checker.SetNonDestructive(True)
    checker.SetLevelOfCheck(EDGE_CHECK_LEVEL)
    checker.Perform()
    data = checker.DS()  # PDS() hands Python a pointer the checker also frees
    ranges = {}
    interferences = data.InterfEF()
    for index in range(interferences.Length()):
        interference = interferences.Value(index)
        ranges[(interference.Index1(), interference.Index2())] = interference.CommonPart().Range1()
    found: list[Hook] = []
    pairs = []
    for pair in data.Interferences():
        first, second = pair.Indices()
        hook = None
        for edge, face in ((first, second), (second, first)):
            if (edge, face) in ranges:
                hook = _hook(
                    TopoDS.Edge_s(data.Shape(edge)),
                    TopoDS.Face_s(data.Shape(face)),
                    ranges[(edge, face)],
                )
        if hook is None:
            pairs.append((data.Shape(first), data.Shape(second)))
        elif not any(hook.edge.IsSame(other.edge) for other in found):
            found.append(hook)
    return EdgeInterference(tuple(found), tuple(pairs))


def hook_trimmed_copy(shape: TopoDS_Shape, hooks: tuple[Hook, ...]) -> TopoDS_Shape:
    """A copy of ``shape`` with each of ``hooks`` (of :func:`edge_interference` on ``shape``) cut
    off.

    Args:
        shape: the solid (as read back from a STEP file), mm; the hooked vertices' tolerances are
            raised in place (they are the copy's too).
        hooks: the hooks of ``shape``'s edges.

    Returns:
        The copy, each hooked edge's curves segmented past its hook and its vertex's tolerance
        raised to cover the cut.
    """
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    reshape = BRepTools_ReShape()
    for hook in hooks:
        faces = distinct_faces(ancestors.FindFromKey(hook.edge))
        if not any(BRep_Tool.IsClosed_s(hook.edge, face) for face in faces):  # not a seam
            reshape.Replace(hook.edge, _cut(hook, faces))
    return reshape.Apply(shape)


def _hook(edge: TopoDS_Edge, face: TopoDS_Face, common: tuple[float, float]) -> Hook | None:
    """The hook of ``edge`` into ``face`` over the edge's parameter range ``common``, if the two
    share a vertex and the range ends within HOOK_LIMIT_MM of it."""
    first, last = TopExp.FirstVertex_s(edge), TopExp.LastVertex_s(edge)
    face_vertices = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(face, TopAbs_VERTEX, TopAbs_EDGE, face_vertices)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    for vertex, cut in ((first, common[1]), (last, common[0])):
        if vertex.IsNull() or not face_vertices.Contains(vertex):
            continue
        if BRep_Tool.Pnt_s(vertex).Distance(curve.Value(cut)) <= HOOK_LIMIT_MM:
            return Hook(edge, face, vertex, cut)
    return None


def _cut(hook: Hook, faces: list[TopoDS_Face]) -> TopoDS_Edge:
    """A copy of the hook's edge whose 3D curve and p-curves on ``faces`` start (or end) at the cut,
    as segmented B-splines (a STEP writer writes a curve whole: a range alone would not last)."""
    edge = hook.edge
    start, end = BRep_Tool.Range_s(edge)
    low, high = (
        (hook.cut, end) if hook.vertex.IsSame(TopExp.FirstVertex_s(edge)) else (start, hook.cut)
    )
    tolerance = BRep_Tool.Tolerance_s(edge)
    cut = TopoDS.Edge_s(ShapeBuild_Edge().Copy(edge, False))
    builder = BRep_Builder()
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    segment = GeomConvert.CurveToBSplineCurve_s(Geom_TrimmedCurve(curve, start, end))
    segment.Segment(low, high)
    builder.UpdateEdge(cut, segment, tolerance)
    for face in faces:
        pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
        flat = Geom2dConvert.CurveToBSplineCurve_s(Geom2d_TrimmedCurve(pcurve, start, end))
        flat.Segment(low, high)
        builder.UpdateEdge(cut, flat, face, tolerance)
    builder.Range(cut, low, high)
    gap = BRep_Tool.Pnt_s(hook.vertex).Distance(curve.Value(hook.cut))
    builder.UpdateVertex(hook.vertex, max(BRep_Tool.Tolerance_s(hook.vertex), CUT_MARGIN * gap))
    return cut
