"""The file writers of the B-rep, together (as CadQuery keeps its exporters), and their registry.

A file format is one module here (``step``, ``stl``, ``threemf``) and one entry of :data:`WRITERS`,
keyed by its :class:`~torus_cad.formats.ExportFormat`; the build's output set
(torus_cad.outputs.output_set) writes every format of ``export.formats`` through it. The mesh
package keeps its own registry of the surface mesh's formats (torus_cad.mesh.writers.WRITERS); the
one STEP reader is torus_cad.kernel.step_readback. Each writer writes the file it is given
atomically: a hidden temp file beside the path (torus_cad.runtime.files.atomic_path), checked whole,
then renamed onto it. A writer that fails says why when it can
(torus_cad.runtime.files.write_failure): a full file system or the file size limit is an OSError
naming the path, anything else a KernelError. A build's files are published together by
torus_cad.outputs.output_set.

To add a format: a module with its writer, a value of ExportFormat, and an entry below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.build_stages import Stage
from torus_cad.formats import ExportFormat, StepSchema

if TYPE_CHECKING:
    from OCP.TopoDS import TopoDS_Shape

    from torus_cad.kernel.uncrossed import UncrossedMesh


@dataclass(frozen=True)
class ExportJob:
    """What every writer of the registry is given for one design.

    Attributes:
        shape: the solid to write.
        name: the design's name (the STEP product, the 3MF object).
        step_schema: the STEP application protocol.
        linear_deflection_mm / angular_deflection_rad: the tessellation's deflections (STL, 3MF).
        version: torus_cad's version (the STEP header's originating system, the 3MF metadata).
        mesh: the one uncrossed tessellation that every mesh format writes, made on first call.
    """

    shape: TopoDS_Shape
    name: str
    step_schema: StepSchema
    linear_deflection_mm: float
    angular_deflection_rad: float
    version: str
    mesh: Callable[[], UncrossedMesh]


@dataclass(frozen=True)
class FormatWriter:
    """How the build writes one file format.

    Attributes:
        write: writes the job's file at the path; returns the written mesh's check for the report
            (mesh formats) or None.
        stage: the build stage it is timed as.
        in_child: written in a forked child while the others are written in this process (the STEP
            file's read-back check is the longest; it runs on the second core).
    """

    write: Callable[[ExportJob, Path], dict[str, Any] | None]
    stage: Stage
    in_child: bool = False


def _step(job: ExportJob, path: Path) -> None:
    from torus_cad.kernel.writers.step import write_step

    write_step(job.shape, path, job.name, job.step_schema, f"torus_cad {job.version}")


def _stl(job: ExportJob, path: Path) -> dict[str, Any]:
    from torus_cad.kernel.writers.stl import write_checked_stl

    return write_checked_stl(
        job.shape, path, job.linear_deflection_mm, job.angular_deflection_rad, mesh=job.mesh()
    ).to_dict()


def _three_mf(job: ExportJob, path: Path) -> dict[str, Any]:
    from torus_cad.kernel.writers.threemf import write_3mf

    return write_3mf(
        job.shape,
        path,
        job.name,
        job.linear_deflection_mm,
        job.angular_deflection_rad,
        version=job.version,
        mesh=job.mesh(),
    ).to_dict()


#: Every file format the build writes, by format.
WRITERS: dict[ExportFormat, FormatWriter] = {
    ExportFormat.STEP: FormatWriter(_step, Stage.STEP_WRITE, in_child=True),
    ExportFormat.STL: FormatWriter(_stl, Stage.STL_WRITE),
    ExportFormat.THREE_MF: FormatWriter(_three_mf, Stage.THREE_MF_WRITE),
}
