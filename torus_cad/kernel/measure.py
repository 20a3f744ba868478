"""Measurements on a built B-rep: its bounding radius about the spin axis, plane sections, chords.

Used to check design targets on the solid itself (tests/test_design_targets.py,
scripts/measure_targets.py), independently of the geometry layer that made it.
"""

from __future__ import annotations

import cadquery as cq
import numpy as np
from numpy.typing import ArrayLike, NDArray
from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.gp import gp_Ax3, gp_Dir, gp_Pln, gp_Pnt

from torus_cad.errors import KernelError
from torus_cad.kernel.tessellation import tessellate_faces


def max_radius_mm(solid: cq.Shape) -> float:
    """Largest distance of the solid from the z axis, by BRepExtrema against a coaxial cylinder
    around it."""
    box = solid.BoundingBox()
    outer = 2.0 * max(abs(box.xmin), abs(box.xmax), abs(box.ymin), abs(box.ymax)) + 10.0
    cylinder = cq.Solid.makeCylinder(outer, box.zlen + 20.0, cq.Vector(0, 0, box.zmin - 10.0))
    lateral = next(face for face in cylinder.Faces() if face.geomType() == "CYLINDER")
    extrema = BRepExtrema_DistShapeShape(solid.wrapped, lateral.wrapped)
    if not extrema.IsDone():
        raise KernelError(
            "BRepExtrema could not measure the solid's distance from a coaxial cylinder"
        )
    return float(outer - extrema.Value())


def vertex_radius_mm(solid: cq.Shape, tolerance: float = 0.05) -> float:
    """Largest radius of a tessellation's vertices: a lower bound of :func:`max_radius_mm` within
    ~``tolerance``."""
    vertices = np.concatenate([face.vertices for face in tessellate_faces(solid, tolerance, 0.2)])
    return float(np.hypot(vertices[:, 0], vertices[:, 1]).max())


def plane_section_edges(
    solid: cq.Shape, origin: ArrayLike, normal: ArrayLike, half_size: float
) -> list[cq.Edge]:
    """Edges where the solid meets a square of ``2 half_size`` around ``origin`` normal to
    ``normal``."""
    x, y, z = (float(value) for value in np.asarray(origin, dtype=float))
    u, v, w = (float(value) for value in np.asarray(normal, dtype=float))
    plane = gp_Pln(gp_Ax3(gp_Pnt(x, y, z), gp_Dir(u, v, w)))
    face = BRepBuilderAPI_MakeFace(plane, -half_size, half_size, -half_size, half_size).Face()
    section = BRepAlgoAPI_Section(solid.wrapped, face)
    section.Build()
    if not section.IsDone():
        raise KernelError("OpenCascade could not cut the solid with a section plane")
    return list(cq.Shape.cast(section.Shape()).Edges())


def straight_edges(edges: list[cq.Edge], relative: float = 1e-6) -> list[cq.Edge]:
    """The edges that are straight: length equal to the distance between their ends."""
    straight = []
    for edge in edges:
        chord = (edge.endPoint() - edge.startPoint()).Length
        if chord > 0.0 and edge.Length() - chord <= relative * chord:
            straight.append(edge)
    return straight


def farthest_middle_edge(edges: list[cq.Edge], point: ArrayLike) -> cq.Edge:
    """The edge whose middle (half its parameter range) is farthest from ``point``: in a section
    plane's cut of a blade with a round trailing edge, measured from the leading edge, the cap's
    cut."""
    x, y, z = (float(value) for value in np.asarray(point, dtype=float))
    return max(edges, key=lambda edge: (edge.positionAt(0.5) - cq.Vector(x, y, z)).Length)


def edge_points(edges: list[cq.Edge], per_edge: int = 2000) -> NDArray[np.float64]:
    """``(n, 3)`` points along the edges, ``per_edge`` each."""
    points = []
    for edge in edges:
        for u in np.linspace(0.0, 1.0, per_edge):
            p = edge.positionAt(float(u))
            points.append((p.x, p.y, p.z))
    return np.array(points)


def contour_through(
    edges: list[cq.Edge], point: ArrayLike, tolerance: float = 1e-3
) -> list[cq.Edge]:
    """The edges of the closed contour (wire) among ``edges`` that passes nearest ``point``."""
    wires = cq.Wire.combine(edges, tol=tolerance)
    x, y, z = (float(value) for value in np.asarray(point, dtype=float))
    target = cq.Vertex.makeVertex(x, y, z)
    return list(min(wires, key=lambda wire: wire.distance(target)).Edges())
