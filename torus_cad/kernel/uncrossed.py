"""The uncrossed tessellation: one closed triangle mesh of a solid whose triangles intersect
nowhere, which the STL and the 3MF writers both write.

OpenCascade's mesher (BRepMesh) triangulates face by face within the linear and angular
deflections. Two faces that meet at a knife edge (a sharp trailing edge: zero thickness) share
the edge's nodes, but inside each face the triangles are laid out independently and are long and
thin along the edge: a triangle of one side sags from its surface by up to the deflection while
the other side's surface is only ``distance x wedge angle`` away, so near a knife edge the two
sides' triangles cross although the surfaces do not. Halving the deflection only moves the
crossing (the gap goes to zero at the edge): on fuzz seed 7, 3 halvings left 128 crossing pairs.
Splitting the crossing triangles on the exact surfaces (new nodes on the faces and on the edge
curve) did not converge either: 732, 1112, 2828, 7112, 15352, 40460 pairs in 5 rounds.

So the crossings are repaired with a maintained tool, meshlib's ``SelfIntersections.fix``: it
finds the crossing triangles, grows the region a few rings (``maxExpand``), and relaxes it
(``Relax``), or cuts it out and fills the hole (``CutAndFill``), pass after pass
(MESH_REPAIR_PASSES) until nothing crosses.
The result is checked again by meshlib, must be closed, and may leave the tessellation by at most
MESH_REPAIR_MAX_DEVIATION_MM (Hausdorff, one way); the writers then check the file they wrote.
A mesh that cannot be repaired within that is a KernelError naming the face and the place.

BRepMesh can also leave the tessellation open: where two boundary edges of a face come closer than
the deflection (fuzz seed 55: each blade's footprint on the hub is a crescent 0.86 mm long and
0.03 mm wide, at a 0.048 mm deflection), the chords of the two edges cross in the face's
parameter plane and the face's triangulation leaves a gap beside them (7 holes, one per blade).
An open tessellation is made again at half the deflection, as a coarse one that the repair would
move too far is (seed 55 closes at the first halving).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.TopoDS import TopoDS_Face
from scipy.spatial import cKDTree

from torus_cad.errors import KernelError
from torus_cad.geometry.blade.triangle_mesh import side_use_counts
from torus_cad.kernel.mesh_check import crossing_pairs, meshlib_mesh
from torus_cad.kernel.tessellation import face_triangulation
from torus_cad.kernel.topology import AnyShape, copied, faces_in_order, occ, surface_kind
from torus_cad.tolerances import MESH_REPAIR_MAX_DEVIATION_MM

#: Tessellation nodes closer than this (mm) are one vertex of the written mesh (the faces store
#: their shared boundary nodes each in its own placement, equal to the last bits).
MESH_MERGE_DISTANCE_MM = 1e-6

#: A repair that would move the tessellation further is tried again on a finer one: the linear
#: deflection halved, at most this many times (a user's coarse deflection crosses far: the docs'
#: measurements page).
MESH_REFINE_HALVINGS = 3

#: meshlib's SelfIntersections.fix passes tried in turn on a crossing tessellation, each on the last
#: one's result, until no triangle crosses.
MESH_REPAIR_PASSES = ("Relax", "Relax", "Relax", "CutAndFill", "Relax", "CutAndFill")


__all__ = ["UncrossedMesh", "uncrossed_mesh"]


@dataclass(frozen=True)
class UncrossedMesh:
    """A closed triangle mesh of a solid, no two of its triangles crossing (meshlib).

    Attributes:
        vertices: ``(v, 3)`` float, mm.
        triangles: ``(t, 3)`` int vertex indices, counter-clockwise seen from outside.
        linear_deflection_mm: the mesher's linear deflection, mm.
        angular_deflection_rad: its angular deflection, rad.
        repaired_pairs: crossing triangle pairs of the tessellation that meshlib repaired (0: none
            crossed).
        repair: meshlib's passes that repaired them (e.g. "Relax+Relax"; "" if none).
        repair_deviation_mm: the largest distance of the tessellation from the repaired mesh, mm.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    linear_deflection_mm: float
    angular_deflection_rad: float
    repaired_pairs: int = 0
    repair: str = ""
    repair_deviation_mm: float = 0.0


def uncrossed_mesh(
    shape: AnyShape, linear_deflection: float, angular_deflection: float
) -> UncrossedMesh:
    """OpenCascade's tessellation of a copy of ``shape`` (absolute deflection, mm; angular, rad),
    its faces' shared nodes merged, with any crossing triangles repaired by meshlib (see the module
    doc). Where the repair would move a coarse tessellation further than
    MESH_REPAIR_MAX_DEVIATION_MM (a user's large
    deflection: long triangles cross far), or where OpenCascade's tessellation is open (module doc),
    the linear deflection is halved, up to MESH_REFINE_HALVINGS times, and the finer tessellation
    used instead.

    Raises KernelError when OpenCascade cannot tessellate the solid or the crossings cannot be
    repaired into a closed mesh within MESH_REPAIR_MAX_DEVIATION_MM (naming the face and where)."""
    for halving in range(MESH_REFINE_HALVINGS + 1):
        try:
            return _uncrossed_at(shape, linear_deflection / 2.0**halving, angular_deflection)
        except _TooCoarse as error:
            too_far = error
    raise KernelError(
        f"{too_far} (also at linear deflection "
        f"{linear_deflection / 2.0**MESH_REFINE_HALVINGS:g} mm, "
        f"{MESH_REFINE_HALVINGS} halvings of {linear_deflection:g} mm)"
    )


class _TooCoarse(KernelError):
    """A tessellation to be made again at a smaller deflection (:func:`uncrossed_mesh`)."""


class _RepairTooFar(_TooCoarse):
    """meshlib's repair would move the tessellation further than MESH_REPAIR_MAX_DEVIATION_MM."""


class _Open(_TooCoarse):
    """BRepMesh left the tessellation open (module doc)."""


def _uncrossed_at(
    shape: AnyShape, linear_deflection: float, angular_deflection: float
) -> UncrossedMesh:
    """:func:`uncrossed_mesh` at one linear deflection; _TooCoarse when the tessellation is open or
    the repair moves it too far."""
    copy = copied(occ(shape))
    # meshes here
    mesher = BRepMesh_IncrementalMesh(copy, linear_deflection, False, angular_deflection, True)
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid")
    faces = faces_in_order(copy)
    points, triangles, owner = _merged_tessellation(faces)
    open_faces = _faces_with_holes(triangles, owner)
    if open_faces:
        named = ", ".join(f"{index} ({surface_kind(faces[index])})" for index in open_faces)
        raise _Open(
            f"OpenCascade's tessellation at linear deflection {linear_deflection:g} mm is open "
            f"(holes beside faces {named}: boundary edges closer to each other than the deflection)"
        )
    pairs = crossing_pairs(points, triangles)
    if not len(pairs):
        return UncrossedMesh(points, triangles, linear_deflection, angular_deflection)
    first, other = (int(index) for index in pairs[0])
    where = (
        f"{len(pairs)} pairs of intersecting triangles (meshlib), the first on face {owner[first]} "
        f"({surface_kind(faces[owner[first]])}) against face {owner[other]} at "
        f"({', '.join(f'{value:.3f}' for value in points[triangles[first]].mean(axis=0))}) mm"
    )
    repaired = _repaired(points, triangles)
    if repaired is None:
        raise KernelError(
            f"the tessellation has {where}; meshlib's repair ({', '.join(MESH_REPAIR_PASSES)}) "
            "leaves crossing triangles or an open mesh"
        )
    vertices, fixed, passes, deviation = repaired
    if deviation > MESH_REPAIR_MAX_DEVIATION_MM:
        raise _RepairTooFar(
            f"the tessellation has {where}; meshlib's repair moves it by {deviation:.3f} mm, over "
            f"the {MESH_REPAIR_MAX_DEVIATION_MM} mm allowed"
        )
    return UncrossedMesh(
        vertices,
        fixed,
        linear_deflection,
        angular_deflection,
        len(pairs),
        "+".join(passes),
        deviation,
    )


def _repaired(
    points: NDArray[np.float64], triangles: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64], list[str], float] | None:
    """meshlib's SelfIntersections.fix of the mesh, pass after pass of MESH_REPAIR_PASSES until
    nothing
    crosses: the vertices, triangles, the passes used and the largest distance (mm) of the
    tessellation from the result; None unless the result is closed and free of crossings."""
    import meshlib.mrmeshnumpy as mrn
    import meshlib.mrmeshpy as mr

    original, mesh = meshlib_mesh(points, triangles), meshlib_mesh(points, triangles)
    passes: list[str] = []
    for method in MESH_REPAIR_PASSES:
        settings = mr.SelfIntersections.Settings()
        settings.method = getattr(mr.SelfIntersections.Settings.Method, method)
        mr.SelfIntersections.fix(mesh, settings)
        mesh.pack()
        passes.append(method)
        if not len(mr.findSelfCollidingTriangles(mesh)):
            break
    else:
        return None
    if mesh.topology.findNumHoles() != 0:
        return None
    deviation = float(np.sqrt(mr.findMaxDistanceSqOneWay(mesh, original)))
    return (
        np.asarray(mrn.getNumpyVerts(mesh), dtype=float),
        np.asarray(mrn.getNumpyFaces(mesh.topology), dtype=np.int64),
        passes,
        deviation,
    )


def _faces_with_holes(triangles: NDArray[np.int64], owner: NDArray[np.int64]) -> list[int]:
    """The faces (indices) owning a triangle side that no other triangle shares (a hole's rim), or
    that more than two share; empty for a closed, manifold tessellation."""
    rim = side_use_counts(triangles) != 2
    return sorted({int(face) for face in np.repeat(owner, 3)[rim]})


def _merged_tessellation(
    faces: list[TopoDS_Face],
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """The meshed faces' nodes merged (points ``(v, 3)`` mm), their outward triangles ``(t, 3)`` and
    each triangle's face index."""
    points, triangles, owner = [], [], []
    offset = 0
    for index, face in enumerate(faces):
        nodes, tris = face_triangulation(face)
        if not len(tris):
            continue
        points.append(nodes)
        triangles.append(tris + offset)
        owner.append(np.full(len(tris), index))
        offset += len(nodes)
    if not points:
        raise KernelError("OpenCascade could not tessellate the solid")
    all_points = np.concatenate(points)
    merged, unique = _merge(all_points)
    corners = merged[np.concatenate(triangles)]
    keep = (
        (corners[:, 0] != corners[:, 1])
        & (corners[:, 1] != corners[:, 2])
        & (corners[:, 0] != corners[:, 2])
    )
    return all_points[unique], corners[keep], np.concatenate(owner)[keep]


def _merge(points: NDArray[np.float64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Each point's index among the merged ones (nodes closer than MESH_MERGE_DISTANCE_MM are one:
    faces store their boundary nodes each in its own placement), and the points kept."""
    representative = np.arange(len(points))
    pairs = cKDTree(points).query_pairs(MESH_MERGE_DISTANCE_MM, output_type="ndarray")
    for first, second in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))].tolist():
        representative[second] = representative[first]
    while True:  # follow chains to their root
        parent = representative[representative]
        if np.array_equal(parent, representative):
            break
        representative = parent
    roots, inverse = np.unique(representative, return_inverse=True)
    return inverse.reshape(-1).astype(np.int64), roots
