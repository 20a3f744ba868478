"""Unite the parts' meshes into one closed 2-manifold with manifold3d, keeping each face's part.

Every input triangle carries a face ID (manifold3d's ``face_id``, kept through the boolean for
every output triangle that comes from it) that encodes its triangle index, its part and whether
it is to be dropped after the union, so the part labels survive the union without any
geometric guess. The triangle index keeps neighbouring IDs distinct, so manifold3d merges no
neighbouring coplanar triangles of the structured grids.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import KernelError
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh


class MeshBooleanError(KernelError):
    """The mesh boolean (manifold3d) failed; the message names the step."""


@dataclass(frozen=True)
class LabeledMesh:
    """A triangle mesh whose faces know the part they belong to.

    Attributes:
        vertices: ``(v, 3)`` float64, mm.
        faces: ``(f, 3)`` int64 vertex indices, counter-clockwise seen from outside.
        part: ``(f,)`` int16, index into ``part_names`` of each face.
        part_names: ``("hub", "blade_0", ...)``.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    part: NDArray[np.int16]
    part_names: tuple[str, ...]

    @property
    def triangle_mesh(self) -> TriangleMesh:
        return TriangleMesh(self.vertices, self.faces)

    def faces_of(self, index: int) -> NDArray[np.int64]:
        """``(k, 3)`` faces of part ``index``."""
        return self.faces[self.part == index]


#: Face ID = (triangle mod 2^23) << 8 | part << 1 | marked: manifold3d keeps face IDs as 32-bit
#: ints.
_PART_BITS = 7
_TRIANGLE_BITS = 23


def _manifold(mesh: TriangleMesh, name: str, part: int, dropped: NDArray[np.bool_] | None) -> Any:
    import manifold3d as mf

    triangle = np.arange(len(mesh.faces), dtype=np.uint64) % np.uint64(1 << _TRIANGLE_BITS)
    face_id = (triangle << np.uint64(_PART_BITS + 1)) | np.uint64(part << 1)
    if dropped is not None:
        face_id |= dropped.astype(np.uint64)
    body = mf.Manifold(
        mf.Mesh64(
            vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
            tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint64),
            face_id=face_id,
        )
    )
    if body.status() != mf.Error.NoError:
        raise MeshBooleanError(
            f"mesh union, step 'load {name}': manifold3d refused the {name} mesh "
            f"({body.status().name})"
        )
    return body


def unite(
    parts: Sequence[TriangleMesh],
    names: Sequence[str],
    part_of: Sequence[int] | None = None,
    marked: Sequence[NDArray[np.bool_] | None] | None = None,
) -> tuple[LabeledMesh, NDArray[np.bool_]]:
    """Union of closed, outward ``parts`` as one labelled mesh whose part names are ``names``, and
    ``(f,)`` True for its faces that come from faces where ``marked`` (one mask per input, or None)
    is True.

    ``part_of`` gives each input's index into ``names`` (default: one input per name).

    Raises MeshBooleanError naming the step (loading a part, the union) when manifold3d fails.
    """
    import manifold3d as mf

    part_of = list(range(len(parts))) if part_of is None else list(part_of)
    dropped = [None] * len(parts) if marked is None else list(marked)
    if len(names) >= 1 << _PART_BITS:
        raise MeshBooleanError(
            f"mesh union, step 'labels': {len(names)} parts, more than {(1 << _PART_BITS) - 1}"
        )
    bodies = [
        _manifold(mesh, names[part], part, mask)
        for mesh, part, mask in zip(parts, part_of, dropped, strict=True)
    ]
    union = mf.Manifold.batch_boolean(bodies, mf.OpType.Add)
    if union.status() != mf.Error.NoError or union.is_empty():
        raise MeshBooleanError(
            f"mesh union, step 'union': manifold3d failed ({union.status().name})"
        )
    result = union.to_mesh64()
    face_id = np.asarray(result.face_id, dtype=np.uint64)
    part = ((face_id >> np.uint64(1)) & np.uint64((1 << _PART_BITS) - 1)).astype(np.int16)
    vertices = np.array(result.vert_properties, dtype=np.float64)[:, :3]
    faces = np.array(result.tri_verts, dtype=np.int64)
    return LabeledMesh(np.ascontiguousarray(vertices), faces, part, tuple(names)), (
        face_id & np.uint64(1)
    ) == 1
