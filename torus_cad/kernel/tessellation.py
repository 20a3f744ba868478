"""OpenCascade's tessellation of a shape as arrays, face by face: the one tessellation of the
package (the STL's comparison, the 3MF file, the preview picture and the studio's display all read
it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS_Face

from torus_cad.errors import KernelError
from torus_cad.kernel.topology import AnyShape, copied, faces_in_order, occ, surface_kind


@dataclass(frozen=True)
class FaceTriangles:
    """The triangles of one B-rep face.

    Attributes:
        vertices: ``(v, 3)`` float, mm.
        triangles: ``(f, 3)`` int vertex indices, counter-clockwise seen from outside the solid.
        surface_type: the face's surface kind as cadquery names it ("PLANE", "CYLINDER", "BSPLINE",
            ...).
        face_index: the face's position in ``shape.Faces()``.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    surface_type: str
    face_index: int


def tessellate_faces(
    shape: AnyShape, linear_deflection: float, angular_deflection: float, parallel: bool = True
) -> list[FaceTriangles]:
    """Tessellate a copy of ``shape`` exactly as ``write_stl`` does (absolute deflection in mm,
    angular in radians; the shape's own triangulation is left alone) and return the triangles of
    every face that has some, in ``shape.Faces()`` order. ``parallel``: OpenCascade's mesher
    threads."""
    copy = copied(occ(shape))
    # meshes here
    mesher = BRepMesh_IncrementalMesh(copy, linear_deflection, False, angular_deflection, parallel)
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid")
    faces = []
    for index, face in enumerate(faces_in_order(copy)):
        vertices, triangles = face_triangulation(face)
        if len(triangles):
            faces.append(FaceTriangles(vertices, triangles, surface_kind(face), index))
    return faces


def face_triangulation(face: TopoDS_Face) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The vertices ``(k, 3)`` and outward triangles ``(m, 3)`` of a meshed face (empty if
    unmeshed)."""
    location = TopLoc_Location()
    mesh = BRep_Tool.Triangulation_s(face, location)
    if mesh is None or mesh.NbTriangles() == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    transform = location.Transformation()
    vertices = np.array(
        [mesh.Node(i).Transformed(transform).Coord() for i in range(1, mesh.NbNodes() + 1)],
        dtype=float,
    )
    triangles = (
        np.array(
            [mesh.Triangle(i).Get() for i in range(1, mesh.NbTriangles() + 1)], dtype=np.int64
        ).reshape(-1, 3)
        - 1
    )
    if face.Orientation() == TopAbs_REVERSED:
        triangles = triangles[:, ::-1]  # outward for a reversed face
    return vertices, triangles
