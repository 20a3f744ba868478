"""Recognising a hub with blade faces: one solid made of z-axis cylinder faces of one radius (and of
a smaller
one: a plain through-bore), two whole end discs (annuli round the bore) and non-rational B-spline
blade faces bounded only by the cylinder's edges, their own seam and the edges between two of them;
each blade face's untransformed surface and its rotation about z."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.Geom import Geom_BSplineSurface
from OCP.GeomAbs import GeomAbs_BSplineSurface, GeomAbs_Circle, GeomAbs_Cylinder, GeomAbs_Plane
from OCP.TopAbs import TopAbs_EDGE, TopAbs_SOLID, TopAbs_WIRE
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape

from torus_cad.kernel.topology import count, explore, faces

#: Geometric checks of the recognition (axis, radius, end discs, rotations) hold to this, mm.
RECOGNITION_TOLERANCE_MM = 1e-7


@dataclass(frozen=True)
class RecognisedHub:
    radius: float
    z_bottom: float
    z_top: float
    blade_faces: list[TopoDS_Face]
    bore_radius: float = 0.0


def recognise(shape: TopoDS_Shape) -> RecognisedHub | None:
    """The hub's radius and end planes and the blade faces, or None unless ``shape`` is one solid
    made of z-axis cylinder faces of one radius, two whole end discs and B-spline faces bounded
    only by the cylinder's edges, their own seam and the edges between two of them (a blade side
    in lower and upper faces meets itself at the leading and trailing edges; each face is still
    integrated over its whole u range, trimmed in v by the cylinder)."""
    if count(shape, TopAbs_SOLID) != 1:
        return None
    by_kind: dict[object, list[TopoDS_Face]] = {}
    for face in faces(shape):
        by_kind.setdefault(BRepAdaptor_Surface(face).GetType(), []).append(face)
    cylinders, planes, blades = (
        by_kind.pop(kind, []) for kind in (GeomAbs_Cylinder, GeomAbs_Plane, GeomAbs_BSplineSurface)
    )
    if by_kind or not cylinders or len(planes) != 2 or not blades:
        return None
    radii = _z_axis_cylinder_radii(cylinders)
    if radii is None:
        return None
    radius, bore_radius = radii
    ends = [z for z in (_end_disc_z(face, radius, bore_radius) for face in planes) if z is not None]
    if len(ends) != 2:
        return None
    z_bottom, z_top = sorted(ends)
    if z_top - z_bottom <= RECOGNITION_TOLERANCE_MM:
        return None
    cylinder_edges = TopTools_IndexedMapOfShape()
    for face in cylinders:
        TopExp.MapShapes_s(face, TopAbs_EDGE, cylinder_edges)
    for face in blades:
        if count(face, TopAbs_WIRE) != 1 or not all(
            cylinder_edges.Contains(edge)
            or BRep_Tool.IsClosed_s(TopoDS.Edge_s(edge), face)
            or _between_blade_faces(edge, blades)
            for edge in explore(face, TopAbs_EDGE)
        ):
            return None
    return RecognisedHub(radius, z_bottom, z_top, blades, bore_radius)


def _between_blade_faces(edge: TopoDS_Shape, blades: list[TopoDS_Face]) -> bool:
    """Whether ``edge`` bounds two of the blade faces (the side's faces meet there, inside the
    blade's boundary)."""
    return (
        sum(1 for face in blades if any(edge.IsSame(own) for own in explore(face, TopAbs_EDGE)))
        == 2
    )


def _z_axis_cylinder_radii(faces: list[TopoDS_Face]) -> tuple[float, float] | None:
    """(the hub's radius, the bore's radius or 0) of z-axis cylinder faces of one or two radii, else
    None."""
    radii = []
    for face in faces:
        cylinder = BRepAdaptor_Surface(face).Cylinder()
        direction, origin = cylinder.Axis().Direction(), cylinder.Axis().Location()
        if (
            abs(abs(direction.Z()) - 1.0) > 1e-12
            or math.hypot(origin.X(), origin.Y()) > RECOGNITION_TOLERANCE_MM
        ):
            return None
        radii.append(cylinder.Radius())
    outer, inner = max(radii), min(radii)
    if any(
        min(abs(value - outer), abs(value - inner)) > RECOGNITION_TOLERANCE_MM for value in radii
    ):
        return None  # a third radius
    return (outer, 0.0) if outer - inner <= RECOGNITION_TOLERANCE_MM else (outer, inner)


def _end_disc_z(face: TopoDS_Face, radius: float, bore_radius: float = 0.0) -> float | None:
    """z of a plane face that is a whole disc of ``radius`` about the z axis (an annulus round a
    bore of ``bore_radius``), else None."""
    plane = BRepAdaptor_Surface(face).Plane()
    if abs(abs(plane.Axis().Direction().Z()) - 1.0) > 1e-12 or count(face, TopAbs_WIRE) != (
        2 if bore_radius else 1
    ):
        return None
    for edge in explore(face, TopAbs_EDGE):
        curve = BRepAdaptor_Curve(TopoDS.Edge_s(edge))
        if curve.GetType() != GeomAbs_Circle:
            return None
        circle = curve.Circle()
        centre = circle.Location()
        if (
            min(
                abs(circle.Radius() - radius),
                abs(circle.Radius() - bore_radius) if bore_radius else math.inf,
            )
            > RECOGNITION_TOLERANCE_MM
            or math.hypot(centre.X(), centre.Y()) > RECOGNITION_TOLERANCE_MM
        ):
            return None
    return float(plane.Location().Z())


def base_surface_and_angle(face: TopoDS_Face) -> tuple[Geom_BSplineSurface | None, float | None]:
    """The face's surface without its location, and the location's angle about z (radians);
    None for a surface that is not a plain B-spline or a location that is not such a rotation."""
    location = TopLoc_Location()
    surface = BRep_Tool.Surface_s(face, location)
    if (
        not isinstance(surface, Geom_BSplineSurface)
        or surface.IsURational()
        or surface.IsVRational()
        or surface.IsUPeriodic()
        or surface.IsVPeriodic()
    ):
        return None, None
    matrix = np.array(
        [
            [location.Transformation().Value(row, column) for column in range(1, 5)]
            for row in range(1, 4)
        ]
    )
    angle = math.atan2(matrix[1, 0], matrix[0, 0])
    rotation = np.array(
        [
            [math.cos(angle), -math.sin(angle), 0.0, 0.0],
            [math.sin(angle), math.cos(angle), 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ]
    )
    return surface, (angle if np.abs(matrix - rotation).max() <= 1e-12 else None)
