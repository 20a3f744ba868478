"""Intersection-free tessellations: STL and 3MF meshes checked with meshlib and refined until no
two triangles cross.

A tessellation inherits every crossing of the B-rep and adds its own where it is coarse: at a
thin, sharp trailing edge the chords of the upper and lower faces' triangles can pass through
each other although the surfaces do not touch. So every mesh the build writes is checked with
meshlib's ``findSelfCollidingTriangles`` (a maintained checker; imported only here, when a mesh
is checked, as importing it takes about a second), and re-tessellated with half the linear
deflection until it has no crossing pair, at most STL_REFINE_HALVINGS times; a mesh that still
crosses itself is a KernelError.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import KernelError
from torus_cad.tolerances import STL_REFINE_HALVINGS


@dataclass(frozen=True)
class MeshCheck:
    """A written mesh that passed the check.

    Attributes:
        linear_deflection_mm: the linear deflection its tessellation used, mm (the design's, or a
            halving of it).
        angular_deflection_rad: its angular deflection, rad.
        triangles: how many triangles it has.
        self_intersecting_pairs: intersecting triangle pairs meshlib found in it (always 0).
        refinements: how many times the linear deflection was halved to get there.
    """

    linear_deflection_mm: float
    angular_deflection_rad: float
    triangles: int
    self_intersecting_pairs: int
    refinements: int

    def to_dict(self) -> dict[str, Any]:
        """For the JSON report."""
        return {"linear_deflection_mm": self.linear_deflection_mm, "angular_deflection_rad": self.angular_deflection_rad,
                "triangles": self.triangles, "self_intersecting_pairs": self.self_intersecting_pairs,
                "refinements": self.refinements, "checker": "meshlib findSelfCollidingTriangles"}


def intersecting_pairs(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> int:
    """Triangle pairs of a mesh (``(v, 3)`` mm, ``(t, 3)`` indices) that cross each other, by meshlib."""
    import meshlib.mrmeshnumpy as mrn
    import meshlib.mrmeshpy as mr

    mesh = mrn.meshFromFacesVerts(np.ascontiguousarray(triangles, dtype=np.int32),
                                  np.ascontiguousarray(vertices, dtype=np.float32))
    return len(mr.findSelfCollidingTriangles(mesh))


def intersecting_pairs_in_file(path: str | Path) -> tuple[int, int]:
    """(crossing triangle pairs, triangles) of a binary STL file, read and checked by meshlib."""
    import meshlib.mrmeshpy as mr

    mesh = mr.MeshLoad.fromBinaryStl(str(path))  # by its content: a staged file's name has no .stl suffix
    return len(mr.findSelfCollidingTriangles(mesh)), int(mesh.topology.numValidFaces())


def refined_until_intersection_free(write: Callable[[float], tuple[int, int]], linear_deflection_mm: float,
                                    angular_deflection_rad: float, what: str) -> MeshCheck:
    """Call ``write(linear deflection)`` (it tessellates, writes and returns (crossing pairs,
    triangles)) with the deflection halved until no pair crosses; KernelError after STL_REFINE_HALVINGS."""
    pairs = 0
    for refinements in range(STL_REFINE_HALVINGS + 1):
        deflection = linear_deflection_mm / 2**refinements
        pairs, triangles = write(deflection)
        if pairs == 0:
            return MeshCheck(deflection, angular_deflection_rad, triangles, 0, refinements)
    raise KernelError(f"the {what} tessellation has {pairs} pairs of intersecting triangles (meshlib) even at "
                      f"linear deflection {deflection:g} mm ({STL_REFINE_HALVINGS} halvings of "
                      f"export.stl_linear_deflection = {linear_deflection_mm:g} mm)")
