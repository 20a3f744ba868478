"""STEP writer (AP214 or AP242, with the product's name and author); the reader, and the check of
the file read back, are torus_cad.kernel.step_readback."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
from OCP.IFSelect import IFSelect_RetDone
from OCP.Interface import Interface_Static
from OCP.STEPCAFControl import STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_AsIs
from OCP.TCollection import TCollection_ExtendedString, TCollection_HAsciiString
from OCP.TDataStd import TDataStd_Name
from OCP.TDocStd import TDocStd_Document
from OCP.TopoDS import TopoDS_Shape
from OCP.XCAFDoc import XCAFDoc_DocumentTool

from torus_cad.errors import KernelError
from torus_cad.formats import StepSchema
from torus_cad.kernel.iso_line_edges import iso_line_copy
from torus_cad.kernel.readable_edges import readable_copy
from torus_cad.kernel.step_readback import (
    ArgumentFaults,
    argument_faults,
    read_step_shape,
    readback_refusal,
    self_intersection_faults,
    step_readback_faults,
)
from torus_cad.kernel.topology import AnyShape, occ
from torus_cad.kernel.vertex_hooks import edge_interference, hook_trimmed_copy
from torus_cad.runtime.files import atomic_path, file_ends_with, write_failure

#: OpenCascade's write.step.schema value of each protocol.
_STEP_SCHEMAS = {StepSchema.AP214: "AP214IS", StepSchema.AP242: "AP242DIS"}

#: Times a file that reads back faulty is written again, each time from the solid the reader made of
#: the last file with its edges made readable: the reader moves some edges' curves (its
#: reparametrisation, the gaps it closes at vertices), so the file converges on the reader's own
#: curves (a root fillet's edges: two or three tries).
READABLE_REWRITES = 3

#: write.precision.mode 1: the file's uncertainty is the solid's greatest tolerance. OpenCascade's
#: reader (FreeCAD's too) takes the file's uncertainty as its precision and re-approximates, as
#: cubics, the p-curves of every edge whose curves part by more (a root fillet's contact edges, a
#: few 1e-6 mm): near their ends those cubics part from the 3D curve by up to 10 % more than the
#: edge's sampled tolerance. With the greatest tolerance as the uncertainty the p-curves are read as
#: written (the default, 0, writes the average).
_PRECISION_MODE_GREATEST = 1

#: The STEP file's last line: a writer can lose its tail without saying so.
_STEP_END_MARKER = b"END-ISO-10303-21;"


def write_step(
    shape: AnyShape,
    path: str | Path,
    product_name: str,
    schema: StepSchema = StepSchema.AP214,
    program: str = "torus_cad",
    check_readback: bool = True,
) -> Path:
    """Write ``shape`` as STEP (application protocol ``schema``, millimetres, product named
    ``product_name``).

    The shape goes through an XCAF document so that the STEP PRODUCT carries exactly the
    design's name (the plain writer appends a counter to it). With ``check_readback`` (the default)
    the file is read back by OpenCascade's STEP reader and must pass BOPAlgo_ArgumentAnalyzer's
    tests (all but self-interference, which the strict check ran on the solid;
    torus_cad.kernel.step_readback) before it is published. A file that reads back with faults is
    written again from a copy of ``shape`` whose edges are made readable
    (torus_cad.kernel.readable_edges: p-curves square to their surfaces, edges split where the
    reader's samples would miss how far their curves part), then up to READABLE_REWRITES - 1 times
    more from the shape read back from the last file, made readable; then, if it still has faults,
    the same from a copy whose root fillet's contact edges are rebuilt on the fillet surface's
    iso-lines (torus_cad.kernel.iso_line_edges). A file written again is also put through the
    self-interference test as read back (its edges are no longer the checked solid's); if the file
    still reads back with faults, KernelError naming the kind of edge and the gap, and no file.

    Args:
        shape: the solid (OpenCascade's or cadquery's), mm; not changed.
        path: the file to write (atomically: nothing at ``path`` unless the whole file is
            written and checked); its folder is made if missing.
        product_name: the STEP PRODUCT's name and the header's FILE_NAME.
        schema: the application protocol, AP214 or AP242.
        program: the header's author, organisation and originating system (e.g.
            "torus_cad 1.2").
        check_readback: read the file back and check it (above).

    Returns:
        ``path``, as a ``Path``.

    Raises:
        KernelError: OpenCascade could not translate or write the solid, or the file reads
            back with faults (naming the kind of edge and the gap).
        OSError: the file system refused the file (full disk, size limit) or its folder,
            naming ``path``.
    """
    path = Path(path)
    with atomic_path(path) as temp:

        def write(source: TopoDS_Shape) -> None:
            _write(source, temp, path, product_name, schema, program)

        write(occ(shape))
        if check_readback:
            faults = rewritten_until_readable(occ(shape), temp, write)
            if faults.counts:
                raise readback_refusal(faults, f"{product_name}.step")
    return path


def rewritten_until_readable(
    shape: TopoDS_Shape, path: Path, write: Callable[[TopoDS_Shape], None]
) -> ArgumentFaults:
    """The faults of the STEP file ``path`` (``shape`` as ``write`` wrote it there) read back, after
    writing it again while it has any, up to READABLE_REWRITES times: first from a copy of ``shape``
    with readable edges, then from the shape read back from the last file, made readable (the
    module's READABLE_REWRITES). If it still has faults, the same again from a copy of ``shape``
    whose root fillet's contact edges are rebuilt on the fillet surface's iso-lines
    (torus_cad.kernel.iso_line_edges), when it has such edges.

    Args:
        shape: the solid ``write`` wrote to ``path``, mm; not changed.
        path: the STEP file, rewritten in place.
        write: writes a given solid as STEP at ``path``.

    Returns:
        The faults BOPAlgo_ArgumentAnalyzer finds in the last file read back, all tests but
        self-interference, and that too on a file written again (its edges and the tolerances
        the reader gives them are no longer the checked solid's: a root fillet's contact edge
        can cross the next fillet face within the solid's vertex tolerance but outside the one
        read back), every pair of sub-shapes but face/face (vertex_hooks.EDGE_CHECK_LEVEL: the
        faces' surfaces are the checked solid's); ``counts`` is empty when it reads back clean.

    Raises:
        KernelError: OpenCascade cannot read ``path`` back or finds no shape in it; or
            ``write`` failed.
        OSError: ``write`` could not write the file.
    """
    first = step_readback_faults(path, self_interference=False)
    faults = _rewritten(shape, path, write, first)
    if faults.counts:  # the fillet's contact edges rebuilt on its surface's iso-lines, and again
        rebuilt = iso_line_copy(shape)
        if rebuilt is not None:
            write(rebuilt)
            faults = _rewritten(
                rebuilt, path, write, step_readback_faults(path, self_interference=False)
            )
    if first.counts and not faults.counts:
        # rewritten: its edges' curves and tolerances are the reader's, not the checked solid's
        faults = _self_interference_faults(path, write)
    return faults


def _self_interference_faults(path: Path, write: Callable[[TopoDS_Shape], None]) -> ArgumentFaults:
    """The self-interference faults of the STEP file ``path`` read back (edge_interference), after
    writing it again with its hooks cut if it has only those; then with the other tests too."""
    start = time.perf_counter()
    read_back = read_step_shape(path)
    found = edge_interference(read_back)
    if found.hooks and not found.pairs:  # edges hooked into faces at their vertices: cut, again
        write(hook_trimmed_copy(read_back, found.hooks))
        read_back = read_step_shape(path)
        faults = argument_faults(read_back, self_interference=False)
        if faults.counts:
            return faults
        found = edge_interference(read_back)
    pairs = found.pairs + tuple((hook.edge, hook.face) for hook in found.hooks)
    return self_intersection_faults(read_back, pairs, time.perf_counter() - start)


def _rewritten(
    shape: TopoDS_Shape, path: Path, write: Callable[[TopoDS_Shape], None], faults: ArgumentFaults
) -> ArgumentFaults:
    """The faults of ``path`` after writing it again from readable copies while it has ``faults``
    (up to READABLE_REWRITES times), each try from the shape the reader made of the last file."""
    source = shape
    for _ in range(READABLE_REWRITES):
        if not faults.counts:
            break
        write(readable_copy(source))
        source = read_step_shape(path)  # the next try starts from the file as the reader gives it
        faults = step_readback_faults(path, self_interference=False)
    return faults


def _write(
    shape: TopoDS_Shape, temp: Path, path: Path, product_name: str, schema: StepSchema, program: str
) -> None:
    """``shape`` as STEP at ``temp`` (the staging file of ``path``), checked whole."""
    document = TDocStd_Document(TCollection_ExtendedString("torus_cad"))
    label = XCAFDoc_DocumentTool.ShapeTool_s(document.Main()).AddShape(shape, False)
    TDataStd_Name.Set_s(label, TCollection_ExtendedString(product_name))
    writer = STEPCAFControl_Writer()  # creating the writer initialises the statics; set them after
    for key, value in (("write.step.schema", _STEP_SCHEMAS[schema]), ("write.step.unit", "MM")):
        if not Interface_Static.SetCVal_s(key, value):
            raise KernelError(f"OpenCascade refused the STEP setting {key} = {value!r}")
    if not Interface_Static.SetIVal_s("write.precision.mode", _PRECISION_MODE_GREATEST):
        raise KernelError("OpenCascade refused the STEP setting write.precision.mode")
    if not writer.Transfer(document, STEPControl_AsIs):
        raise KernelError("OpenCascade could not translate the solid to STEP")
    _name_the_author(writer, product_name, program)
    if writer.Write(str(temp)) != IFSelect_RetDone or not file_ends_with(temp, _STEP_END_MARKER):
        raise write_failure(
            path, temp, KernelError(f"OpenCascade could not write STEP file {str(path)!r}")
        )


def _name_the_author(writer: STEPCAFControl_Writer, product_name: str, program: str) -> None:
    """The STEP header's FILE_NAME: the design's name, and ``program`` (torus_cad and its version)
    as author, organisation and originating system, instead of OpenCascade's placeholders."""
    header = APIHeaderSection_MakeHeader(writer.ChangeWriter().Model())
    header.SetName(TCollection_HAsciiString(product_name))
    header.SetAuthorValue(1, TCollection_HAsciiString(program))
    header.SetOrganizationValue(1, TCollection_HAsciiString(program.split()[0]))
    header.SetOriginatingSystem(TCollection_HAsciiString(program))
    header.SetAuthorisation(TCollection_HAsciiString(program))
