"""Where a blade bends too tightly for the fillet's rolling ball, and the reduced radii that avoid
it.

Where a blade face bends concavely (seen from outside) tighter than the radius along a junction
edge, a ball of that radius cannot stay in contact along the whole bend (its centre path would
have a cusp). The bend is the design's (the analytic surface bends so, not only the loft), so no
try of torus_cad.kernel.fillet.root_fillet helps; with ``hub.root_fillet_tight_bends = 'reduce'``
those edges get REDUCED_FILLET_FRACTION of the bend's radius and OpenCascade blends it with the
requested radius along the rest of that junction loop.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cadquery as cq
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.kernel.topology import BLADE_SURFACES
from torus_cad.tolerances import REDUCED_FILLET_FRACTION

#: Points per junction edge at which the blade face's bend is measured for the reduced fillet.
REDUCED_FILLET_SAMPLES = 40


def reduced_edge_radii(
    solid: cq.Solid, edges: Sequence[TopoDS_Edge], radius_mm: float
) -> list[float]:
    """A fillet radius per junction edge (mm): ``radius_mm``, or, where the edge's blade face bends
    concavely (seen from outside) tighter than ``radius_mm`` / REDUCED_FILLET_FRACTION along the
    edge, REDUCED_FILLET_FRACTION x the tightest bend's radius there.

    A rolling ball of radius r cannot stay in contact along a face that bends concavely tighter
    than r (its centre path would have a cusp; a short enough bend is bridged). On fuzz designs
    whose blade sections are a millimetre or two long where they meet the hub, a cambered section's
    own concave stretch is that tight (the analytic surface, not the loft's fit, bends so: measured
    against
    :func:`torus_cad.geometry.blade.blade_surface.surface_points`)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    radii = []
    for edge in edges:
        faces = [TopoDS.Face_s(face) for face in ancestors.FindFromKey(edge)]
        blade_face = next(
            face for face in faces if BRepAdaptor_Surface(face).GetType() in BLADE_SURFACES
        )
        bend_mm = _tightest_concave_radius_along(edge, blade_face)
        radii.append(min(radius_mm, REDUCED_FILLET_FRACTION * bend_mm))
    return radii


def varying_junction_mm(
    solid: cq.Solid, edges: Sequence[TopoDS_Edge], radii: Sequence[float], radius_mm: float
) -> float:
    """Length (mm) of the fillet contours (chains of tangent junction edges, as OpenCascade forms
    them) that hold an edge whose radius is below ``radius_mm``."""
    if min(radii, default=radius_mm) >= radius_mm:
        return 0.0
    contours = BRepFilletAPI_MakeFillet(solid.wrapped)
    for edge in edges:
        contours.Add(radius_mm, edge)
    varying = {contours.Contour(edge) for edge, radius in zip(edges, radii) if radius < radius_mm}
    return sum(cq.Edge(edge).Length() for edge in edges if contours.Contour(edge) in varying)


def concave_bend_radius_mm(
    face: TopoDS_Face, surface: BRepAdaptor_Surface, u: float, v: float
) -> float:
    """Radius (mm) of ``face``'s tightest concave bend (seen from outside, from the material's
    outward side) at surface parameters (u, v); inf where it bends only convexly there or its
    curvature is not defined. ``surface`` is ``BRepAdaptor_Surface(face)``."""
    props = BRepLProp_SLProps(surface, u, v, 2, 1e-7)
    if not props.IsCurvatureDefined():
        return math.inf
    outward = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0  # concave: positive curvature
    concave = max(outward * props.MaxCurvature(), outward * props.MinCurvature())
    return 1.0 / concave if concave > 0.0 else math.inf


def _tightest_concave_radius_along(edge: TopoDS_Edge, face: TopoDS_Face) -> float:
    """The smallest radius (mm) of a concave bend (seen from outside) of ``face`` at
    REDUCED_FILLET_SAMPLES points along ``edge``; inf where it bends only convexly."""
    surface = BRepAdaptor_Surface(face)
    projector = ShapeAnalysis_Surface(BRep_Tool.Surface_s(face))
    curve = BRepAdaptor_Curve(edge)
    first, last = curve.FirstParameter(), curve.LastParameter()
    uvs = (
        projector.ValueOfUV(
            curve.Value(first + (last - first) * index / (REDUCED_FILLET_SAMPLES - 1)), 1e-7
        )
        for index in range(REDUCED_FILLET_SAMPLES)
    )
    return min(
        (concave_bend_radius_mm(face, surface, uv.X(), uv.Y()) for uv in uvs), default=math.inf
    )
