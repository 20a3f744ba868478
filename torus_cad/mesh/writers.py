"""Write a labelled surface mesh: binary STL, ASCII STL (one solid per part), OBJ (one group per
part), PLY, VTK.

Every writer works on whole arrays (text is formatted in chunks of :data:`CHUNK_TRIANGLES`
with one C-level ``%`` per chunk, binary records are built and written a chunk at a time), so
millions of triangles need no Python loop per triangle and no full-size copy. ``torus-cad mesh``
writes into its output set's staging folder (torus_cad.outputs.output_set); elsewhere each file is
written
atomically (``runtime.files.atomic_path``): a temp file, then a rename. A failed write raises
OSError naming the file it was writing.

Hand-written for STL, OBJ and PLY rather than meshio's (used for VTK): meshio's STL and OBJ writers
are 4-7 times slower on a mesh of millions of triangles and write no per-part solids or groups.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO

import numpy as np
from numpy.typing import NDArray

from torus_cad.mesh.mesh_formats import SUFFIXES, MeshFormat
from torus_cad.mesh.union import LabeledMesh
from torus_cad.runtime.files import atomic_path

#: Triangles (or vertices) formatted per chunk by the text writers.
CHUNK_TRIANGLES = 100_000

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
_ASCII_FACET = (
    "facet normal %.7e %.7e %.7e\n  outer loop\n    vertex %.9e %.9e %.9e\n"
    "    vertex %.9e %.9e %.9e\n    vertex %.9e %.9e %.9e\n  endloop\nendfacet\n"
)


def unit_normals(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    """``(f, 3)`` outward unit normals (zero for degenerate triangles)."""
    return _corner_normals(vertices[faces])


def _corner_normals(corners: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(f, 3)`` unit normals of triangles given by their corners ``(f, 3, 3)``."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)


def _chunks(count: int) -> Iterator[slice]:
    for start in range(0, count, CHUNK_TRIANGLES):
        yield slice(start, min(start + CHUNK_TRIANGLES, count))


def _write_rows(
    handle: IO[str], template: str, rows: NDArray[np.float64] | NDArray[np.int64]
) -> None:
    """Write ``template % row`` for every row of a 2-D array, a chunk at a time."""
    for part in _chunks(len(rows)):
        block = rows[part]
        handle.write((template * len(block)) % tuple(block.ravel().tolist()))


def write_binary_stl(mesh: LabeledMesh, path: Path, name: str) -> None:
    """Binary STL of the whole surface (float32, as the format requires), a chunk of records at a
    time."""
    header = f"torus_cad surface mesh {name}".encode("ascii", "replace")[:80].ljust(80, b" ")
    with path.open("wb") as handle:
        handle.write(header)
        handle.write(np.uint32(len(mesh.faces)).tobytes())
        for part in _chunks(len(mesh.faces)):
            faces = mesh.faces[part]
            records = np.zeros(len(faces), dtype=_STL_RECORD)
            corners = mesh.vertices[faces]
            records["normal"] = _corner_normals(corners)
            records["vertices"] = corners
            handle.write(records.tobytes())


def write_ascii_stl(mesh: LabeledMesh, path: Path, name: str) -> None:
    """ASCII STL with one ``solid <part>`` per part: hub, blade_0, ..."""
    normals = unit_normals(mesh.vertices, mesh.faces)
    with path.open("w", encoding="ascii") as handle:
        for index, part_name in enumerate(mesh.part_names):
            chosen = mesh.part == index
            rows = np.concatenate(
                [normals[chosen], mesh.vertices[mesh.faces[chosen]].reshape(-1, 9)], axis=1
            )
            handle.write(f"solid {part_name}\n")
            _write_rows(handle, _ASCII_FACET, rows)
            handle.write(f"endsolid {part_name}\n")


def write_obj(mesh: LabeledMesh, path: Path, name: str) -> None:
    """Wavefront OBJ: shared vertices, then one group ``g <part>`` of faces per part (1-based
    indices)."""
    with path.open("w", encoding="ascii") as handle:
        handle.write(
            f"# torus_cad surface mesh {name}: "
            f"{len(mesh.vertices)} vertices, {len(mesh.faces)} triangles, "
            f"mm; groups {' '.join(mesh.part_names)}\n"
        )
        handle.write(f"o {name}\n")
        _write_rows(handle, "v %.10g %.10g %.10g\n", mesh.vertices)
        for index, part_name in enumerate(mesh.part_names):
            handle.write(f"g {part_name}\n")
            _write_rows(handle, "f %d %d %d\n", mesh.faces[mesh.part == index] + 1)


def write_ply(mesh: LabeledMesh, path: Path, name: str) -> None:
    """Binary little-endian PLY: float64 vertices, triangles with an int ``part`` property per face
    (0 = hub)."""
    header = (
        f"ply\nformat binary_little_endian 1.0\ncomment torus_cad surface mesh {name}, mm; part: "
        + ", ".join(f"{index} = {part_name}" for index, part_name in enumerate(mesh.part_names))
        + f"\nelement vertex {len(mesh.vertices)}\nproperty "
        "double x\nproperty double y\nproperty double z\n"
        f"element face {len(mesh.faces)}\nproperty list "
        "uchar int vertex_indices\nproperty int part\n"
        "end_header\n"
    )
    with path.open("wb") as handle:
        handle.write(header.encode("ascii"))
        for part in _chunks(len(mesh.vertices)):
            handle.write(np.ascontiguousarray(mesh.vertices[part], dtype="<f8").tobytes())
        for part in _chunks(len(mesh.faces)):
            faces = np.empty(
                part.stop - part.start,
                dtype=[("count", "u1"), ("vertices", "<i4", (3,)), ("part", "<i4")],
            )
            faces["count"], faces["vertices"], faces["part"] = 3, mesh.faces[part], mesh.part[part]
            handle.write(faces.tobytes())


def write_vtk(mesh: LabeledMesh, path: Path, name: str) -> None:
    """Legacy VTK (binary) through meshio, with a per-face ``part`` index (0 = hub)."""
    import meshio

    meshio.write_points_cells(
        str(path),
        mesh.vertices,
        [("triangle", mesh.faces.astype(np.int64))],
        cell_data={"part": [mesh.part.astype(np.int32)]},
        file_format="vtk",
        binary=True,
    )


WRITERS: dict[MeshFormat, Callable[[LabeledMesh, Path, str], None]] = {
    MeshFormat.STL: write_binary_stl,
    MeshFormat.STL_ASCII: write_ascii_stl,
    MeshFormat.OBJ: write_obj,
    MeshFormat.PLY: write_ply,
    MeshFormat.VTK: write_vtk,
}


def mesh_path(out_dir: Path, name: str, file_format: MeshFormat) -> Path:
    """``out_dir/<name>_mesh<suffix>`` for a format."""
    return out_dir / f"{name}_mesh{SUFFIXES[file_format]}"


def write_mesh_files(
    mesh: LabeledMesh,
    out_dir: str | Path,
    name: str,
    formats: tuple[MeshFormat, ...],
    atomic: bool = True,
) -> dict[MeshFormat, Path]:
    """Write ``mesh`` in every format into ``out_dir`` (an existing folder); the paths by format.

    ``atomic``: each file through a temp file and a rename (off inside an output set's staging
    folder, which is published whole). An OSError (no space left, permission denied, file size
    limit) is raised again with the file's path as its ``filename``.
    """
    out = Path(out_dir)
    paths = {}
    for file_format in formats:
        path = mesh_path(out, name, file_format)
        try:
            if atomic:
                with atomic_path(path) as temp:
                    WRITERS[file_format](mesh, temp, name)
            else:
                WRITERS[file_format](mesh, path, name)
        except OSError as error:
            raise OSError(error.errno, error.strerror or str(error), str(path)) from None
        paths[file_format] = path
    return paths
