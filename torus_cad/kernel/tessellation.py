"""OpenCascade's tessellation of a shape as arrays, face by face (what its STL export writes)."""

from __future__ import annotations

from dataclasses import dataclass

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.BRepMesh import BRepMesh_IncrementalMesh

from torus_cad.errors import KernelError


@dataclass(frozen=True)
class FaceTriangles:
    """The triangles of one B-rep face.

    Attributes:
        vertices: ``(v, 3)`` float, mm.
        triangles: ``(f, 3)`` int vertex indices.
        surface_type: the face's surface kind as cadquery names it ("PLANE", "CYLINDER", "BSPLINE", ...).
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    surface_type: str


def tessellate_faces(shape: cq.Shape, linear_deflection: float, angular_deflection: float) -> list[FaceTriangles]:
    """Tessellate a copy of ``shape`` exactly as ``write_stl`` does (absolute deflection in mm,
    angular in radians) and return every face's triangles."""
    copy = shape.copy()
    mesher = BRepMesh_IncrementalMesh(copy.wrapped, linear_deflection, False, angular_deflection, True)
    mesher.Perform()
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid")
    faces = []
    for face in copy.Faces():
        points, triangles = face.tessellate(linear_deflection, angular_deflection)  # reuses the mesh above
        if triangles:
            faces.append(FaceTriangles(np.array([point.toTuple() for point in points], dtype=float),
                                       np.asarray(triangles, dtype=np.int64), face.geomType()))
    return faces
