"""Face provenance: the part (the hub or blade i) every face of the propeller's solid came from.

Each kernel step passes the parts on from OpenCascade's own history: a face put into an assembled
shell has its part by construction; a boolean's or a fillet's result face takes the part of the
input face it was ``Modified`` from (or kept); a fillet face is ``Generated`` by a junction edge or
a corner vertex and belongs to that junction's blade; a face ShapeFix mended is found through its
re-shape context's history, or, where that history stops, by the face it lies on. The preview's
colours and the studio's parts read the result (``Propeller.face_parts``).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import NDArray
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeShape
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepTools import BRepTools
from OCP.ShapeBuild import ShapeBuild_ReShape
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape, TopTools_IndexedMapOfShape

from torus_cad.errors import KernelError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.checks import distances_to_shape
from torus_cad.kernel.topology import explore, faces

#: (face, part) pairs: where the faces of a step's result came from.
Origins = list[tuple[TopoDS_Shape, int]]


def labelled_faces(shape: TopoDS_Shape, face_parts: Sequence[int]) -> Origins:
    """``shape``'s faces with their parts (``face_parts`` in the order of :func:`face_parts`)."""
    indexed = _indexed_faces(shape)
    if indexed.Extent() != len(face_parts):
        raise KernelError(
            f"{len(face_parts)} face parts given for a shape of {indexed.Extent()} faces"
        )
    return [(indexed.FindKey(index + 1), part) for index, part in enumerate(face_parts)]


def through_history(
    operation: BRepBuilderAPI_MakeShape, origins: Iterable[tuple[TopoDS_Shape, int]]
) -> Origins:
    """Where each (input face, part) went in ``operation``'s result: its pieces if the operation
    changed it (``Modified``), itself if it kept it, nothing if it removed it (``IsDeleted``)."""
    found: Origins = []
    for face, part in origins:
        pieces = list(operation.Modified(face))
        if not pieces and not operation.IsDeleted(face):
            pieces = [face]
        found.extend((piece, part) for piece in pieces)
    return found


def fillet_faces(
    fillet: BRepFilletAPI_MakeFillet, solid: TopoDS_Shape, face_parts: Sequence[int]
) -> Origins:
    """The faces a fillet of ``solid`` (faces labelled ``face_parts``) generated, each with its
    junction's blade: the part of the edge's faces that is not the hub, for the faces
    ``Generated`` by every edge of the fillet's contours (the edges it was given and those it
    followed on along a tangent chain) and by their vertices (the corner blends)."""
    indexed = _indexed_faces(solid)
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid, TopAbs_EDGE, TopAbs_FACE, ancestors)
    found: Origins = []
    for contour in range(1, fillet.NbContours() + 1):
        for index in range(1, fillet.NbEdges(contour) + 1):
            edge = fillet.Edge(contour, index)
            parts = {
                face_parts[indexed.FindIndex(face) - 1] for face in ancestors.FindFromKey(edge)
            } - {HUB_PART}
            if len(parts) != 1:
                raise KernelError(f"a filleted edge lies between {len(parts)} blades instead of 1")
            part = parts.pop()
            for generator in [edge, *explore(edge, TopAbs_VERTEX)]:
                found.extend(
                    (face, part)
                    for face in fillet.Generated(generator)
                    if face.ShapeType() == TopAbs_FACE
                )
    return found


def through_reshape(
    context: ShapeBuild_ReShape, origins: Iterable[tuple[TopoDS_Shape, int]], mended: TopoDS_Shape
) -> Origins:
    """Where each (face, part) went when ShapeFix mended the shape into ``mended``: the faces its
    re-shape context's history made of the face, itself when it kept it, nothing when it removed it.

    ShapeFix's history does not record every face it rebuilds, so a face of ``mended`` it reaches
    from no origin takes the part of the origin face that passes nearest its middle (on it: the
    face it was rebuilt from)."""
    origins = list(origins)
    history = context.History()
    found: Origins = []
    for face, part in origins:
        if history.IsRemoved(face):
            continue
        pieces = [piece for modified in history.Modified(face) for piece in faces(modified)]
        found.extend((piece, part) for piece in pieces or faces(context.Value(face)))
    indexed = _indexed_faces(mended)
    reached = {indexed.FindIndex(face) for face, _ in found}
    for index in range(1, indexed.Extent() + 1):
        if index not in reached:
            face = TopoDS.Face_s(indexed.FindKey(index))
            middle = _middle(face)
            found.append(
                (face, min(origins, key=lambda origin: distances_to_shape(origin[0], middle)[0])[1])
            )
    return found


def face_parts(shape: TopoDS_Shape, origins: Iterable[tuple[TopoDS_Shape, int]]) -> tuple[int, ...]:
    """The part of each face of ``shape``, in the order of ``shape.Faces()`` (TopExp's indexed
    map of faces), from (face, part) pairs; KernelError when a face came from no known part."""
    indexed = _indexed_faces(shape)
    parts: list[int | None] = [None] * indexed.Extent()
    for face, part in origins:
        index = indexed.FindIndex(face)
        if index:
            parts[index - 1] = part
    known = [part for part in parts if part is not None]
    if len(known) != len(parts):
        raise KernelError(
            f"{len(parts) - len(known)} faces of the propeller came from no known part"
        )
    return tuple(known)


def _indexed_faces(shape: TopoDS_Shape) -> TopTools_IndexedMapOfShape:
    indexed = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, indexed)
    return indexed


def _middle(face: TopoDS_Face) -> NDArray[np.float64]:
    """``(1, 3)``: the point at the middle of ``face``'s parameter box (mm)."""
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face)
    point = BRepAdaptor_Surface(face).Value((u_min + u_max) / 2.0, (v_min + v_max) / 2.0)
    return np.array([[point.X(), point.Y(), point.Z()]])
