"""Settings of ``torus-cad mesh``: resolution, how sections are spaced, file formats, and their limits."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from typing import TypeVar

from torus_cad.errors import ParameterError

#: Allowed ranges of the mesh resolution (the triangle ceiling usually binds first).
SECTIONS_RANGE = (4, 20000)
POINTS_RANGE = (16, 50000)

_Choice = TypeVar("_Choice", bound=StrEnum)


class SectionSpacing(StrEnum):
    """How the sections are spread along a blade.

    ``parameter``: evenly in the centerline parameter s (what ``blade_surface`` does); cells
    then stretch where the centerline runs fast. ``arc_length``: evenly in the centerline's
    arc length, so every row of cells along the blade has the same length.
    """

    PARAMETER = "parameter"
    ARC_LENGTH = "arc_length"


class MeshFormat(StrEnum):
    """Mesh file formats; the suffix of each file is given by :data:`SUFFIXES`."""

    STL = "stl"              # binary STL, the whole surface
    STL_ASCII = "stl_ascii"  # ASCII STL, one named solid per part
    OBJ = "obj"              # Wavefront OBJ, one group per part (snappyHexMesh regions)
    PLY = "ply"              # binary PLY with a per-face part index
    VTK = "vtk"              # legacy VTK with a per-face part index (meshio)


#: File name ending of each format, appended to ``<name>_mesh``.
SUFFIXES = {MeshFormat.STL: ".stl", MeshFormat.STL_ASCII: "_ascii.stl", MeshFormat.OBJ: ".obj",
            MeshFormat.PLY: ".ply", MeshFormat.VTK: ".vtk"}


@dataclass(frozen=True)
class MeshSettings:
    """Resolution and output of the surface mesh.

    Attributes:
        sections: sections along each blade (rows of the structured grid).
        points: points around each section, equally spaced in arc length (spec §5).
        spacing: how the sections are spread along the blade.
        formats: files to write.
        compare: also build the B-rep and OpenCascade's tessellation for the quality report
            (volume, distance to the surface, OpenCascade's edge ratio); False skips them.
    """

    sections: int = 100
    points: int = 400
    spacing: SectionSpacing = SectionSpacing.ARC_LENGTH
    formats: tuple[MeshFormat, ...] = field(default=(MeshFormat.STL, MeshFormat.OBJ))
    compare: bool = True

    def __post_init__(self) -> None:
        for label, value, (low, high) in (("sections", self.sections, SECTIONS_RANGE),
                                          ("points", self.points, POINTS_RANGE)):
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise ParameterError(f"mesh.{label} = {value!r} is out of range; allowed whole numbers "
                                     f"[{low}, {high}]")
        object.__setattr__(self, "spacing", _choice(SectionSpacing, self.spacing, "mesh.spacing"))
        formats = tuple(_choice(MeshFormat, item, "mesh.formats") for item in self.formats)
        if not formats:
            raise ParameterError("mesh.formats is empty; allowed: one or more of "
                                 + ", ".join(item.value for item in MeshFormat))
        object.__setattr__(self, "formats", tuple(dict.fromkeys(formats)))


def _choice(kind: type[_Choice], value: object, label: str) -> _Choice:
    try:
        return kind(value)
    except ValueError:
        allowed = ", ".join(repr(item.value) for item in kind)
        raise ParameterError(f"{label} = {value!r} is not allowed; allowed: {allowed}") from None
