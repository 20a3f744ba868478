"""STEP and STL export (and STEP import). Writers write the file they are given, atomically.

Each writer writes a hidden temp file beside the path (torus_cad.kernel.files.atomic_path), checks
it is whole (a STEP file's end marker, an STL's size from its triangle count) and renames it onto
the path. A writer that fails says why when it can: a full file system or the file size limit is
an OSError naming the path, anything else a KernelError. A whole build's files are published
together by torus_cad.outputs.output_set.
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
from pathlib import Path

import cadquery as cq
from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPCAFControl import STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader
from OCP.StlAPI import StlAPI_Writer
from OCP.TCollection import TCollection_ExtendedString, TCollection_HAsciiString
from OCP.TDataStd import TDataStd_Name
from OCP.TDocStd import TDocStd_Document
from OCP.XCAFDoc import XCAFDoc_DocumentTool

from torus_cad.errors import KernelError
from torus_cad.formats import StepSchema
from torus_cad.kernel.files import atomic_path
from torus_cad.kernel.mesh_check import MeshCheck, intersecting_pairs_in_file, refined_until_intersection_free
from torus_cad.tolerances import DISK_FULL_FREE_BYTES

__all__ = ["atomic_path", "read_step", "write_checked_stl", "write_step", "write_stl"]

#: OpenCascade's write.step.schema value of each protocol.
_STEP_SCHEMAS = {StepSchema.AP214: "AP214IS", StepSchema.AP242: "AP242DIS"}
_STEP_END_MARKER = b"END-ISO-10303-21;"
_STL_HEADER_BYTES, _STL_TRIANGLE_BYTES = 84, 50


def write_step(shape: cq.Shape, path: str | Path, product_name: str, schema: StepSchema = StepSchema.AP214,
               program: str = "torus_cad") -> Path:
    """Write ``shape`` as STEP (application protocol ``schema``, millimetres, product named ``product_name``).

    The shape goes through an XCAF document so that the STEP PRODUCT carries exactly the
    design's name (the plain writer appends a counter to it).
    """
    document = TDocStd_Document(TCollection_ExtendedString("torus_cad"))
    label = XCAFDoc_DocumentTool.ShapeTool_s(document.Main()).AddShape(shape.wrapped, False)
    TDataStd_Name.Set_s(label, TCollection_ExtendedString(product_name))
    writer = STEPCAFControl_Writer()  # creating the writer initialises the statics; set them after
    for key, value in (("write.step.schema", _STEP_SCHEMAS[schema]), ("write.step.unit", "MM")):
        if not Interface_Static.SetCVal_s(key, value):
            raise KernelError(f"OpenCascade refused the STEP setting {key} = {value!r}")
    if not writer.Transfer(document, STEPControl_AsIs):
        raise KernelError("OpenCascade could not translate the solid to STEP")
    _name_the_author(writer, product_name, program)
    path = Path(path)
    with atomic_path(path) as temp:
        if writer.Write(str(temp)) != IFSelect_RetDone or not _step_whole(temp):
            raise _write_failure("STEP", path, temp)
    return path


def _step_whole(temp: Path) -> bool:
    """Whether ``temp`` ends with the STEP end marker (a writer can lose its tail without saying so)."""
    with open(temp, "rb") as handle:
        handle.seek(max(0, temp.stat().st_size - 256))
        return _STEP_END_MARKER in handle.read()


def _stl_whole(temp: Path) -> bool:
    """Whether ``temp``'s size is a binary STL's: 84 bytes + 50 per triangle it declares."""
    size = temp.stat().st_size
    with open(temp, "rb") as handle:
        header = handle.read(_STL_HEADER_BYTES)
    triangles = int.from_bytes(header[80:84], "little") if len(header) == _STL_HEADER_BYTES else -1
    return triangles > 0 and size == _STL_HEADER_BYTES + _STL_TRIANGLE_BYTES * triangles


def _write_failure(kind: str, path: Path, temp: Path) -> Exception:
    """Why OpenCascade, which reports only that it failed, could not write ``temp`` (published as ``path``).

    Looked at while the partial file is still there: a full file system or the process's file size
    limit (``ulimit -f``) is an OSError naming ``path``; anything else is a KernelError.
    """
    with contextlib.suppress(OSError):
        if shutil.disk_usage(temp.parent).free < DISK_FULL_FREE_BYTES:
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    with contextlib.suppress(OSError, ValueError, ImportError):
        import resource

        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY and temp.stat().st_size >= limit:
            return OSError(errno.EFBIG, os.strerror(errno.EFBIG), str(path))
    return KernelError(f"OpenCascade could not write {kind} file {str(path)!r}")


def _name_the_author(writer: STEPCAFControl_Writer, product_name: str, program: str) -> None:
    """The STEP header's FILE_NAME: the design's name, and ``program`` (torus_cad and its version) as
    author, organisation and originating system, instead of OpenCascade's placeholders."""
    header = APIHeaderSection_MakeHeader(writer.ChangeWriter().Model())
    header.SetName(TCollection_HAsciiString(product_name))
    header.SetAuthorValue(1, TCollection_HAsciiString(program))
    header.SetOrganizationValue(1, TCollection_HAsciiString(program.split()[0]))
    header.SetOriginatingSystem(TCollection_HAsciiString(program))
    header.SetAuthorisation(TCollection_HAsciiString(program))


def read_step(path: str | Path) -> cq.Shape:
    """Read a STEP file back as one shape; raise KernelError if it does not read."""
    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise KernelError(f"cannot read STEP file {str(path)!r}")
    reader.TransferRoots()
    return cq.Shape.cast(reader.OneShape())


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
        raise _write_failure("STL", path, temp)
