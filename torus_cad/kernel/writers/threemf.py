"""3MF export: the fused propeller as ONE mesh object in millimetres, written atomically.

A 3MF file is a zip package (OPC) holding ``3D/3dmodel.model``, an XML mesh: vertices and
triangles with outward (counter-clockwise) winding, and ``unit="millimeter"``. The mesh is
OpenCascade's tessellation at the STL deflections, with the faces' shared boundary nodes merged
into one vertex each, so the object is a closed, manifold mesh a slicer takes as it is.
One object, the fused solid (not one per part): the part a printer makes is the union.

Hand-written (a zip and a short XML): CadQuery's 3MF writer tessellates the shape itself, not the
mesh checked free of crossing triangles here, and trimesh's needs lxml and networkx at run time.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from torus_cad.errors import KernelError
from torus_cad.kernel.files import atomic_path
from torus_cad.kernel.mesh_check import MeshCheck, intersecting_pairs, refined_until_intersection_free
from torus_cad.kernel.tessellation import tessellate_faces

#: Tessellation nodes closer than this (mm) are one vertex of the 3MF mesh.
_MERGE_DISTANCE_MM = 1e-6

_CONTENT_TYPES = """<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
 <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
 <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"""

_RELATIONSHIPS = """<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
 <Relationship Target="/3D/3dmodel.model" Id="rel0"
  Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"""

_MODEL_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">
 <metadata name="Title">{name}</metadata>
 <metadata name="Application">torus_cad {version}</metadata>
 <resources>
  <object id="1" name="{name}" type="model">
   <mesh>
"""

_MODEL_TAIL = """   </mesh>
  </object>
 </resources>
 <build>
  <item objectid="1"/>
 </build>
</model>
"""


def closed_mesh(shape: cq.Shape, linear_deflection: float, angular_deflection: float
                ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """OpenCascade's tessellation of ``shape`` with coincident nodes merged.

    Returns ``(vertices (v, 3) mm, triangles (t, 3) indices)``, triangles wound outward.
    """
    # The STL's tessellation (absolute deflection, on a copy): cadquery's Shape.tessellate takes the
    # deflection as relative and keeps its mesh on the shape, which left the 3MF open and crossing.
    faces = tessellate_faces(shape, linear_deflection, angular_deflection)
    if not faces:
        raise KernelError("OpenCascade could not tessellate the solid for 3MF")
    offsets = np.cumsum([0] + [len(face.vertices) for face in faces])
    points = np.concatenate([face.vertices for face in faces])
    triangles = np.concatenate([face.triangles + offset for face, offset in zip(faces, offsets, strict=False)])
    # Faces store their boundary nodes separately, each in its own placement (the blade copies
    # are rotated), so the same edge node can differ in the last bits: merge within a micrometre.
    representative = np.arange(len(points))
    for first, second in sorted(cKDTree(points).query_pairs(_MERGE_DISTANCE_MM)):
        representative[second] = representative[first]
    while True:  # follow chains to their root
        parent = representative[representative]
        if np.array_equal(parent, representative):
            break
        representative = parent
    roots, inverse = np.unique(representative, return_inverse=True)
    unique = points[roots]
    merged = inverse.reshape(-1)[np.asarray(triangles, dtype=np.int64)]
    keep = (merged[:, 0] != merged[:, 1]) & (merged[:, 1] != merged[:, 2]) & (merged[:, 0] != merged[:, 2])
    return unique, merged[keep]


def write_3mf(shape: cq.Shape, path: str | Path, name: str, linear_deflection: float,
              angular_deflection: float, version: str) -> MeshCheck:
    """Write ``shape`` as a 3MF package with one mesh object named ``name`` (millimetres), its mesh
    re-tessellated at half the linear deflection until no two triangles intersect (meshlib,
    torus_cad.kernel.mesh_check); return the deflection used."""
    found: list[tuple[NDArray[np.float64], NDArray[np.int64]]] = []

    def tessellate(deflection: float) -> tuple[int, int]:
        found[:] = [closed_mesh(shape, deflection, angular_deflection)]
        return intersecting_pairs(*found[0]), len(found[0][1])

    check = refined_until_intersection_free(tessellate, linear_deflection, angular_deflection, "3MF")
    _write_package(path, name, version, *found[0])
    return check


def _write_package(path: str | Path, name: str, version: str, vertices: NDArray[np.float64],
                   triangles: NDArray[np.int64]) -> Path:
    vertex_lines = "".join(f'    <vertex x="{x:.6f}" y="{y:.6f}" z="{z:.6f}"/>\n' for x, y, z in vertices.tolist())
    triangle_lines = "".join(f'    <triangle v1="{a}" v2="{b}" v3="{c}"/>\n' for a, b, c in triangles.tolist())
    model = (_MODEL_HEAD.format(name=name, version=version) + "    <vertices>\n" + vertex_lines + "    </vertices>\n"
             + "    <triangles>\n" + triangle_lines + "    </triangles>\n" + _MODEL_TAIL)
    path = Path(path)
    with atomic_path(path) as temp, zipfile.ZipFile(temp, "w", compression=zipfile.ZIP_DEFLATED,
                                                    compresslevel=6) as package:
        package.writestr("[Content_Types].xml", _CONTENT_TYPES)
        package.writestr("_rels/.rels", _RELATIONSHIPS)
        package.writestr("3D/3dmodel.model", model)
    return path
