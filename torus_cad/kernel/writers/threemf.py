"""3MF export: the fused propeller as ONE mesh object in millimetres, written atomically.

A 3MF file is a zip package (OPC) holding ``3D/3dmodel.model``, an XML mesh: vertices and
triangles with outward (counter-clockwise) winding, and ``unit="millimeter"``. The mesh is the
STL's, the uncrossed tessellation at the STL deflections (torus_cad.kernel.uncrossed), with the
faces' shared boundary nodes merged into one vertex each, so the object is a closed, manifold mesh
a slicer takes as it is.
One object, the fused solid (not one per part): the part a printer makes is the union.

Hand-written (a zip and a short XML): CadQuery's 3MF writer tessellates the shape itself, not the
mesh made free of crossing triangles here, and trimesh's needs lxml and networkx at run time.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from torus_cad.kernel.mesh_check import MeshCheck, checked, intersecting_pairs
from torus_cad.kernel.topology import AnyShape
from torus_cad.kernel.uncrossed import UncrossedMesh, uncrossed_mesh
from torus_cad.runtime.files import atomic_path

#: Decimals of the millimetre coordinates written (a micrometre's thousandth).
_DECIMALS = 6

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


def write_3mf(
    shape: AnyShape,
    path: str | Path,
    name: str,
    linear_deflection: float,
    angular_deflection: float,
    version: str,
    mesh: UncrossedMesh | None = None,
) -> MeshCheck:
    """Write the uncrossed tessellation of ``shape`` (``mesh`` if given, else made at the
    deflections, mm and rad) as a 3MF package with one mesh object named ``name`` (millimetres),
    checked again with meshlib at the precision written; return its check."""
    mesh = uncrossed_mesh(shape, linear_deflection, angular_deflection) if mesh is None else mesh
    written = np.round(mesh.vertices, _DECIMALS)
    check = checked(intersecting_pairs(written, mesh.triangles), len(mesh.triangles), "3MF", mesh)
    _write_package(path, name, version, written, mesh.triangles)
    return check


def _write_package(
    path: str | Path,
    name: str,
    version: str,
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int64],
) -> Path:
    vertex_lines = "".join(
        f'    <vertex x="{x:.{_DECIMALS}f}" y="{y:.{_DECIMALS}f}" z="{z:.{_DECIMALS}f}"/>\n'
        for x, y, z in vertices.tolist()
    )
    triangle_lines = "".join(
        f'    <triangle v1="{a}" v2="{b}" v3="{c}"/>\n' for a, b, c in triangles.tolist()
    )
    model = (
        _MODEL_HEAD.format(name=name, version=version)
        + "    <vertices>\n"
        + vertex_lines
        + "    </vertices>\n"
        + "    <triangles>\n"
        + triangle_lines
        + "    </triangles>\n"
        + _MODEL_TAIL
    )
    path = Path(path)
    with (
        atomic_path(path) as temp,
        zipfile.ZipFile(temp, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=6) as package,
    ):
        package.writestr("[Content_Types].xml", _CONTENT_TYPES)
        package.writestr("_rels/.rels", _RELATIONSHIPS)
        package.writestr("3D/3dmodel.model", model)
    return path
