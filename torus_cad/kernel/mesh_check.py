"""The one crossing check of the package: the triangle pairs of a mesh that intersect, by meshlib's
``findSelfCollidingTriangles`` (:func:`crossing_pairs`; its meshes hold single-precision
coordinates, the precision of a binary STL). Triangles that only share an edge or a vertex do not
count. The tessellation's repair (torus_cad.kernel.uncrossed), the surface mesh of ``torus-cad
mesh`` (torus_cad.mesh.crossings) and the CFD domain's surface (torus_cad.cfd_domain.surface_check)
all use it.

Every mesh the build writes (STL, 3MF) is the uncrossed tessellation
(torus_cad.kernel.uncrossed: OpenCascade's, any crossing triangles repaired by meshlib),
and the written file is read back and checked again with meshlib's ``findSelfCollidingTriangles``
(a maintained checker; imported only here, when a mesh is checked, as importing it takes about a
second). A written mesh that crosses itself is a KernelError.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import KernelError


@dataclass(frozen=True)
class MeshCheck:
    """A written mesh that passed the check.

    Attributes:
        linear_deflection_mm: the linear deflection of its tessellation, mm (the design's).
        angular_deflection_rad: its angular deflection, rad.
        triangles: how many triangles it has.
        self_intersecting_pairs: intersecting triangle pairs meshlib found in it (always 0).
        repaired_pairs: crossing pairs of the tessellation that meshlib repaired (0: none crossed).
        repair: meshlib's repair method used ("Relax", "CutAndFill"; "" if none was needed).
        repair_deviation_mm: the largest distance of the tessellation from the written mesh, mm.
    """

    linear_deflection_mm: float
    angular_deflection_rad: float
    triangles: int
    self_intersecting_pairs: int
    repaired_pairs: int = 0
    repair: str = ""
    repair_deviation_mm: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """For the JSON report."""
        return {
            "linear_deflection_mm": self.linear_deflection_mm,
            "angular_deflection_rad": self.angular_deflection_rad,
            "triangles": self.triangles,
            "self_intersecting_pairs": self.self_intersecting_pairs,
            "repaired_pairs": self.repaired_pairs,
            "repair": self.repair,
            "repair_deviation_mm": self.repair_deviation_mm,
            "checker": "meshlib findSelfCollidingTriangles",
        }


def import_meshlib() -> Any:
    """meshlib's mesh module, or MissingExtraError naming the install command."""
    from torus_cad.errors import MissingExtraError
    from torus_cad.runtime.extras import install_line

    try:
        import meshlib.mrmeshpy as mr
    except ImportError:  # meshlib is a dependency of the package itself
        raise MissingExtraError(f"meshlib is not installed: {install_line()}") from None
    return mr


def meshlib_mesh(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> Any:
    """meshlib's mesh of ``(t, 3)`` ``triangles`` over ``(v, 3)`` ``vertices`` (mm; meshlib stores
    them in single precision)."""
    import meshlib.mrmeshnumpy as mrn

    import_meshlib()
    return mrn.meshFromFacesVerts(
        np.ascontiguousarray(triangles, dtype=np.int32),
        np.ascontiguousarray(vertices, dtype=np.float64),
    )


def crossing_pairs(
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int64],
    region: NDArray[np.bool_] | None = None,
) -> NDArray[np.int64]:
    """``(p, 2)`` indices of the triangle pairs that cross among the ``(t, 3)`` ``triangles`` over
    ``(v, 3)`` ``vertices`` (mm), or among the triangles where ``region`` ``(t,)`` is True (indices
    into ``triangles``)."""
    mr = import_meshlib()
    chosen = np.arange(len(triangles)) if region is None else np.flatnonzero(region)
    if region is not None:  # a mesh of the region alone: meshlib's tree would cover the whole mesh
        used = np.unique(triangles[chosen])
        vertices, triangles = vertices[used], np.searchsorted(used, triangles[chosen])
    mesh = meshlib_mesh(vertices, triangles)
    pairs = np.array(
        [(pair.aFace.get(), pair.bFace.get()) for pair in mr.findSelfCollidingTriangles(mesh)],
        dtype=np.int64,
    ).reshape(-1, 2)
    return chosen[pairs]


def intersecting_pairs(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> int:
    """How many triangle pairs of a mesh (``(v, 3)`` mm, ``(t, 3)`` indices) cross each other."""
    return len(crossing_pairs(vertices, triangles))


def intersecting_pairs_in_file(path: str | Path) -> tuple[int, int]:
    """(crossing triangle pairs, triangles) of a binary STL file, read and checked by meshlib."""
    mr = import_meshlib()
    # by its content: a staged file's name has no .stl suffix
    mesh = mr.MeshLoad.fromBinaryStl(str(path))
    return len(mr.findSelfCollidingTriangles(mesh)), int(mesh.topology.numValidFaces())


def checked(pairs: int, triangles: int, what: str, mesh: Any) -> MeshCheck:
    """The MeshCheck of a written ``what`` mesh (an UncrossedMesh) whose read-back check found
    ``pairs``; KernelError if any."""
    if pairs:
        raise KernelError(
            f"the written {what} file has {pairs} pairs of intersecting triangles (meshlib) "
            "although its tessellation had none"
        )
    return MeshCheck(
        mesh.linear_deflection_mm,
        mesh.angular_deflection_rad,
        triangles,
        0,
        mesh.repaired_pairs,
        mesh.repair,
        mesh.repair_deviation_mm,
    )
