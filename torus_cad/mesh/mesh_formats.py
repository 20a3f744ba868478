"""Mesh file formats and how the ``[mesh]`` table (``torus_cad.parameters.design.Mesh``) selects
them."""

from __future__ import annotations

from collections.abc import Iterable
from enum import StrEnum
from typing import TYPE_CHECKING, Any

from torus_cad.errors import ParameterError

if TYPE_CHECKING:  # the command line builds its parser from this module before the schema is loaded
    from torus_cad.parameters.design import Mesh


class MeshFormat(StrEnum):
    """Mesh file formats; each value is also the ``[mesh]`` key that switches the format on."""

    STL = "stl"  # binary STL, the whole surface
    STL_ASCII = "stl_ascii"  # ASCII STL, one named solid per part
    OBJ = "obj"  # Wavefront OBJ, one group per part (snappyHexMesh regions)
    PLY = "ply"  # binary PLY with a per-face part index
    VTK = "vtk"  # legacy VTK with a per-face part index (meshio)


#: File name ending of each format, appended to ``<name>_mesh``.
SUFFIXES = {
    MeshFormat.STL: ".stl",
    MeshFormat.STL_ASCII: "_ascii.stl",
    MeshFormat.OBJ: ".obj",
    MeshFormat.PLY: ".ply",
    MeshFormat.VTK: ".vtk",
}


def selected_formats(table: Mesh) -> tuple[MeshFormat, ...]:
    """The formats the ``[mesh]`` table switches on; ParameterError when none is."""
    formats = tuple(item for item in MeshFormat if getattr(table, item.value))
    if not formats:
        raise ParameterError(
            "no mesh format is switched on; set one of "
            + ", ".join(f"mesh.{item.value}" for item in MeshFormat)
            + " = true"
        )
    return formats


def format_overrides(names: Iterable[str]) -> dict[str, Any]:
    """``{"mesh.<format>": bool}`` that switches exactly ``names`` on (for ``--format``);
    ParameterError naming the allowed formats for an unknown one."""
    chosen = []
    for name in names:
        try:
            chosen.append(MeshFormat(name.strip().lower()))
        except ValueError:
            allowed = ", ".join(item.value for item in MeshFormat)
            raise ParameterError(
                f"--format {name!r} is not a mesh format; allowed: {allowed}"
            ) from None
    if not chosen:
        raise ParameterError(
            "--format is empty; allowed: " + ", ".join(item.value for item in MeshFormat)
        )
    return {f"mesh.{item.value}": item in chosen for item in MeshFormat}


__all__ = ["SUFFIXES", "MeshFormat", "format_overrides", "selected_formats"]
