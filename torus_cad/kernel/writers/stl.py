"""STL writers: OpenCascade's tessellation at the given deflections (``write_stl``, for the
simulation's own use), and the build's STL, the uncrossed tessellation (torus_cad.kernel.uncrossed)
read back and checked by meshlib (``write_checked_stl``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.StlAPI import StlAPI_Writer

from torus_cad.errors import KernelError
from torus_cad.kernel.mesh_check import MeshCheck, checked, intersecting_pairs_in_file
from torus_cad.kernel.topology import AnyShape, occ
from torus_cad.kernel.uncrossed import UncrossedMesh, uncrossed_mesh
from torus_cad.runtime.files import atomic_path, write_failure

__all__ = ["write_checked_stl", "write_stl"]

_STL_HEADER_BYTES, _STL_TRIANGLE_BYTES = 84, 50


def _stl_whole(temp: Path) -> bool:
    """Whether ``temp``'s size is a binary STL's: 84 bytes + 50 per triangle it declares."""
    size = temp.stat().st_size
    with open(temp, "rb") as handle:
        header = handle.read(_STL_HEADER_BYTES)
    triangles = int.from_bytes(header[80:84], "little") if len(header) == _STL_HEADER_BYTES else -1
    return triangles > 0 and size == _STL_HEADER_BYTES + _STL_TRIANGLE_BYTES * triangles


def _not_written(path: Path) -> KernelError:
    return KernelError(f"OpenCascade could not write STL file {str(path)!r}")


def write_stl(
    shape: AnyShape, path: str | Path, linear_deflection: float, angular_deflection: float
) -> Path:
    """Tessellate ``shape`` (deflections in mm and radians) and write a binary STL.

    The file is written atomically: nothing appears at ``path`` unless it is written whole.

    Args:
        shape: the solid (OpenCascade's or cadquery's), mm; OpenCascade's tessellation is
            stored on it.
        path: the STL file to write; its folder is made if missing.
        linear_deflection: the tessellation's largest distance from the surface, mm.
        angular_deflection: the tessellation's largest angle between neighbouring facets, rad.

    Returns:
        ``path``, as a ``Path``.

    Raises:
        KernelError: OpenCascade could not tessellate the solid or write the file.
        OSError: the file system refused the file (full disk, size limit) or its folder,
            naming ``path``.
    """
    path = Path(path)
    with atomic_path(path) as temp:
        _write_stl_to(shape, temp, path, linear_deflection, angular_deflection)
    return path


def write_checked_stl(
    shape: AnyShape,
    path: str | Path,
    linear_deflection: float,
    angular_deflection: float,
    mesh: UncrossedMesh | None = None,
) -> MeshCheck:
    """Write the uncrossed tessellation of ``shape`` (``mesh`` if given, else made at the
    deflections, mm and rad) as a binary STL, read it back with meshlib and check that no two
    triangles intersect.

    Raises KernelError when the mesh cannot be made uncrossed (naming the face and where).

    Args:
        shape: the solid (OpenCascade's or cadquery's), mm; used only when ``mesh`` is None.
        path: the STL file to write (atomically); its folder is made if missing.
        linear_deflection: the tessellation's largest distance from the surface, mm.
        angular_deflection: the tessellation's largest angle between neighbouring facets, rad.
        mesh: an uncrossed tessellation already made (``vertices`` ``(v, 3)`` mm,
            ``triangles`` ``(t, 3)`` int); None to make it here.

    Returns:
        The check of the written file: its deflections (mm, rad), triangle count, and the
        repair meshlib made (pairs, method, deviation in mm).

    Raises:
        KernelError: the tessellation cannot be made uncrossed (naming the face and where), or
            the written file has intersecting triangles.
        MissingExtraError: meshlib is not installed.
        OSError: the file system refused the file (full disk, size limit) or its folder.
    """
    mesh = uncrossed_mesh(shape, linear_deflection, angular_deflection) if mesh is None else mesh
    path = Path(path)
    with atomic_path(path) as temp:
        _write_binary_stl(temp, path, mesh.vertices, mesh.triangles)
        return checked(*intersecting_pairs_in_file(temp), "STL", mesh)


def _write_binary_stl(temp: Path, path: Path, vertices: np.ndarray, triangles: np.ndarray) -> None:
    """A binary STL of the triangles (facet normals from their corners, single precision)."""
    corners = vertices[triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0)
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(triangles), dtype=record)
    data["normal"], data["corners"] = normals, corners
    header = b"binary STL written by torus_cad".ljust(80, b" ")
    with open(temp, "wb") as handle:
        handle.write(header + np.uint32(len(triangles)).tobytes())
        handle.write(data.tobytes())
    if not _stl_whole(temp):
        raise write_failure(path, temp, _not_written(path))


def _write_stl_to(
    shape: AnyShape, temp: Path, path: Path, linear_deflection: float, angular_deflection: float
) -> None:
    # meshes here
    mesher = BRepMesh_IncrementalMesh(
        occ(shape), linear_deflection, False, angular_deflection, True
    )
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid for STL")
    writer = StlAPI_Writer()
    writer.ASCIIMode = False
    if not writer.Write(occ(shape), str(temp)) or not _stl_whole(temp):
        raise write_failure(path, temp, _not_written(path))
