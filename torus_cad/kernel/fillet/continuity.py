"""The root fillet's faces and edges made C1, and its edges' tolerances made to cover their curves.

OpenCascade's fillet (BRepFilletAPI_MakeFillet) approximates each fillet face by one B-spline
surface of degree 10-11 along the junction, with an inner knot of full multiplicity: the surface and
its two contact edges are only C0 there (FreeCAD's check with BOP, ``BOPAlgo_ArgumentAnalyzer``'s
continuity test, reports each as ``GeomAbs_C0``: 6 faces and 12 edges on workshop_fillet). The knot
is a real kink, not a removable one (knot removal fails even at 1e-5 mm), so each such face and edge
is split there (``ShapeUpgrade_ShapeDivideContinuity``, C1 criterion for surfaces and 3D curves),
the split edges made same-range and same-parameter again (``ShapeFix_Edge``), and every edge whose
3D curve leaves one of its faces' p-curves by more than its tolerance (as the analyzer measures,
GeomLib_CheckCurveOnSurface: 1.4e-4 mm against 1e-4 mm on three fillet contact edges on the hub)
gets a tolerance that covers it.

A fillet face's contact edges keep a real gap to the blade or hub surface they roll on (the
fillet surface is an approximation: up to 2.3e-5 mm on workshop_fillet), which the edge's tolerance
covers in memory; a STEP file cannot carry that tolerance (torus_cad.kernel.step_readback): the
edges are then made to read back as they are (torus_cad.kernel.readable_edges).
"""

from __future__ import annotations

from collections.abc import Sequence

import cadquery as cq
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.GeomAbs import GeomAbs_C0, GeomAbs_C1
from OCP.ShapeFix import ShapeFix_Edge
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideContinuity
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel import face_provenance
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.edge_curves import curve_on_surface_deviation, distinct_faces
from torus_cad.kernel.topology import explore

#: A root-fillet edge whose 3D curve leaves a face's p-curve by more than its tolerance (as
#: BOPAlgo_ArgumentAnalyzer measures; 1.4e-4 mm against 1e-4 mm on workshop_fillet) gets this many
#: times that deviation as tolerance (torus_cad.kernel.fillet.continuity).
FILLET_EDGE_TOLERANCE_MARGIN = 1.1


__all__ = ["c1_fillet"]


def c1_fillet(solid: cq.Solid, face_parts: Sequence[int]) -> tuple[cq.Solid, tuple[int, ...]]:
    """``solid`` (a filleted propeller, its faces' parts ``face_parts``) with its C0 faces and edges
    split at their kinks and its edge tolerances covering their curves (module doc); the solid,
    checked (BRepCheck_Analyzer), and its faces' parts. Unchanged when nothing is C0."""
    if not _has_c0(solid.wrapped):
        _cover_deviations(solid.wrapped)
        return solid, tuple(face_parts)
    divide = ShapeUpgrade_ShapeDivideContinuity(solid.wrapped)
    divide.SetSurfaceCriterion(GeomAbs_C1)
    divide.SetBoundaryCriterion(GeomAbs_C1)
    # p-curves' own knots are no fault: splitting them makes tiny edges
    divide.SetPCurveCriterion(GeomAbs_C0)
    if not divide.Perform():
        raise KernelError(
            "OpenCascade could not split the root fillet's "
            "C0 faces (ShapeUpgrade_ShapeDivideContinuity)"
        )
    divided = divide.Result()
    context = divide.GetContext()
    fixer = ShapeFix_Edge()
    for edge in explore(divided, TopAbs_EDGE):
        edge = TopoDS.Edge_s(edge)
        if not BRep_Tool.SameRange_s(edge) or not BRep_Tool.SameParameter_s(edge):
            fixer.FixSameParameter(edge)
    _cover_deviations(divided)
    checked = single_valid_solid(cq.Shape.cast(divided), "splitting the root fillet's C0 faces")
    origins = face_provenance.through_reshape(
        context, face_provenance.labelled_faces(solid.wrapped, face_parts), checked.wrapped
    )
    return checked, face_provenance.face_parts(checked.wrapped, origins)


def _has_c0(shape: TopoDS_Shape) -> bool:
    return any(
        BRep_Tool.Surface_s(TopoDS.Face_s(face)).Continuity() == GeomAbs_C0
        for face in explore(shape, TopAbs_FACE)
    ) or any(
        curve is not None and curve.Continuity() == GeomAbs_C0
        for curve in (
            BRep_Tool.Curve_s(TopoDS.Edge_s(edge), 0.0, 0.0) for edge in explore(shape, TopAbs_EDGE)
        )
    )


def _cover_deviations(shape: TopoDS_Shape) -> None:
    """Every edge of ``shape`` whose 3D curve leaves its p-curve on a face by more than its
    tolerance (as BOPAlgo_ArgumentAnalyzer measures) gets that deviation, times
    FILLET_EDGE_TOLERANCE_MARGIN, as tolerance (its vertices at least as much)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, ancestors)
    builder = BRep_Builder()
    for index in range(1, ancestors.Extent() + 1):
        edge = TopoDS.Edge_s(ancestors.FindKey(index))
        if BRep_Tool.Degenerated_s(edge):
            continue
        tolerance = BRep_Tool.Tolerance_s(edge)
        deviation = max(
            curve_on_surface_deviation(edge, face)
            for face in distinct_faces(ancestors.FindFromIndex(index))
        )
        if deviation > tolerance:
            covered = deviation * FILLET_EDGE_TOLERANCE_MARGIN
            builder.UpdateEdge(edge, covered)
            for vertex in explore(edge, TopAbs_VERTEX):
                vertex = TopoDS.Vertex_s(vertex)
                if BRep_Tool.Tolerance_s(vertex) < covered:
                    builder.UpdateVertex(vertex, covered)
