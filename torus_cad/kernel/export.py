"""STEP and STL export (and STEP import), written atomically: a temp file, then a rename.

A crash or a kill during a write leaves at most a hidden ``.<name>.tmp-*`` file that is
removed on any Python-level failure, never a partial file under the final name.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
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

_STEP_SCHEMAS = {"AP214": "AP214IS", "AP242": "AP242DIS"}


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temp path beside ``path``; on success rename it onto ``path``, on failure delete it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    for stale in path.parent.glob(f".{path.name}.tmp-*"):  # left by a process killed mid-write
        stale.unlink(missing_ok=True)
    handle, temp_name = tempfile.mkstemp(prefix=f".{path.name}.tmp-", dir=path.parent)
    os.close(handle)
    temp = Path(temp_name)
    try:
        yield temp
        os.chmod(temp, 0o666 & ~_current_umask())  # mkstemp makes 0600; give the file normal permissions
        os.replace(temp, path)
    finally:
        temp.unlink(missing_ok=True)


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_step(shape: cq.Shape, path: str | Path, product_name: str, schema: str = "AP214",
               program: str = "torus_cad") -> Path:
    """Write ``shape`` as STEP (``schema`` 'AP214' or 'AP242', millimetres, product named ``product_name``).

    The shape goes through an XCAF document so that the STEP PRODUCT carries exactly the
    design's name (the plain writer appends a counter to it).
    """
    if schema not in _STEP_SCHEMAS:
        raise KernelError(f"unknown STEP schema {schema!r}; choose AP214 or AP242")
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
        if writer.Write(str(temp)) != IFSelect_RetDone:
            raise KernelError(f"OpenCascade could not write STEP file {str(path)!r}")
    return path


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
    mesher = BRepMesh_IncrementalMesh(shape.wrapped, linear_deflection, False, angular_deflection, True)
    mesher.Perform()
    if not mesher.IsDone():
        raise KernelError("OpenCascade could not tessellate the solid for STL")
    writer = StlAPI_Writer()
    writer.ASCIIMode = False
    path = Path(path)
    with atomic_path(path) as temp:
        if not writer.Write(shape.wrapped, str(temp)):
            raise KernelError(f"OpenCascade could not write STL file {str(path)!r}")
    return path
