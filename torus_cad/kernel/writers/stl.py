"""STL writer: OpenCascade's tessellation at the given deflections, and the checked STL, refined
until its triangles cross nowhere (torus_cad.kernel.mesh_check).
"""


from __future__ import annotations

from pathlib import Path

import cadquery as cq
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.StlAPI import StlAPI_Writer

from torus_cad.errors import KernelError
from torus_cad.kernel.files import atomic_path
from torus_cad.kernel.mesh_check import MeshCheck, intersecting_pairs_in_file, refined_until_intersection_free
from torus_cad.kernel.writers.failures import write_failure

__all__ = ["write_checked_stl", "write_stl"]

_STL_HEADER_BYTES, _STL_TRIANGLE_BYTES = 84, 50


def _stl_whole(temp: Path) -> bool:
    """Whether ``temp``'s size is a binary STL's: 84 bytes + 50 per triangle it declares."""
    size = temp.stat().st_size
    with open(temp, "rb") as handle:
        header = handle.read(_STL_HEADER_BYTES)
    triangles = int.from_bytes(header[80:84], "little") if len(header) == _STL_HEADER_BYTES else -1
    return triangles > 0 and size == _STL_HEADER_BYTES + _STL_TRIANGLE_BYTES * triangles


def write_stl(shape: cq.Shape, path: str | Path, linear_deflection: float, angular_deflection: float) -> Path:
    """Tessellate ``shape`` (deflections in mm and radians) and write a binary STL."""
    path = Path(path)
    with atomic_path(path) as temp:
        _write_stl_to(shape, temp, path, linear_deflection, angular_deflection)
    return path


def write_checked_stl(shape: cq.Shape, path: str | Path, linear_deflection: float,
                      angular_deflection: float) -> MeshCheck:
    """:func:`write_stl`, with the written file read back by meshlib and re-tessellated at half the
    linear deflection until no two of its triangles intersect (torus_cad.kernel.mesh_check)."""
    path = Path(path)
    with atomic_path(path) as temp:
        def write(deflection: float) -> tuple[int, int]:
            _write_stl_to(shape, temp, path, deflection, angular_deflection)
            return intersecting_pairs_in_file(temp)

        return refined_until_intersection_free(write, linear_deflection, angular_deflection, "STL")


def _write_stl_to(shape: cq.Shape, temp: Path, path: Path, linear_deflection: float, angular_deflection: float) -> None:
    mesher = BRepMesh_IncrementalMesh(shape.wrapped, linear_deflection, False, angular_deflection, True)
    mesher.Perform()
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid for STL")
    writer = StlAPI_Writer()
    writer.ASCIIMode = False
    if not writer.Write(shape.wrapped, str(temp)) or not _stl_whole(temp):
        raise write_failure("STL", path, temp)
