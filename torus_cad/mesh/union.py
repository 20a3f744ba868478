"""Unite the parts' meshes into one closed 2-manifold with manifold3d, keeping each face's part.

manifold3d gives every input mesh an original ID (``as_original``) and reports, for each run
of output triangles, the ID of the input it came from (``run_original_id`` / ``run_index``
of the output MeshGL64), so the part labels survive the union without any geometric guess.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import KernelError
from torus_cad.geometry.mesh import TriangleMesh


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


def _manifold(mesh: TriangleMesh, name: str) -> Any:
    import manifold3d as mf

    body = mf.Manifold(mf.Mesh64(vert_properties=np.ascontiguousarray(mesh.vertices, dtype=np.float64),
                                 tri_verts=np.ascontiguousarray(mesh.faces, dtype=np.uint64)))
    if body.status() != mf.Error.NoError:
        raise MeshBooleanError(f"mesh union, step 'load {name}': manifold3d refused the {name} mesh "
                               f"({body.status().name})")
    return body.as_original()


def unite(parts: Sequence[TriangleMesh], names: Sequence[str]) -> LabeledMesh:
    """Union of closed, outward ``parts`` (named ``names``) as one labelled mesh.

    Raises MeshBooleanError naming the step (loading a part, the union, reading the result)
    when manifold3d fails or the result does not trace back to the parts.
    """
    import manifold3d as mf

    bodies = [_manifold(mesh, name) for mesh, name in zip(parts, names, strict=True)]
    part_of_id = {body.original_id(): index for index, body in enumerate(bodies)}
    union = mf.Manifold.batch_boolean(bodies, mf.OpType.Add)
    if union.status() != mf.Error.NoError or union.is_empty():
        raise MeshBooleanError(f"mesh union, step 'union': manifold3d failed ({union.status().name})")
    result = union.to_mesh64()
    vertices = np.asarray(result.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(result.tri_verts, dtype=np.int64)
    run_start = np.asarray(result.run_index, dtype=np.int64) // 3
    run_ids = np.asarray(result.run_original_id, dtype=np.int64)
    unknown = sorted(set(run_ids.tolist()) - set(part_of_id))
    if unknown:
        raise MeshBooleanError(f"mesh union, step 'labels': output runs come from unknown meshes {unknown}")
    run_part = np.array([part_of_id[run_id] for run_id in run_ids.tolist()], dtype=np.int16)
    part = np.repeat(run_part, np.diff(run_start))
    if len(part) != len(faces):
        raise MeshBooleanError(f"mesh union, step 'labels': runs cover {len(part)} of {len(faces)} triangles")
    return LabeledMesh(vertices, faces, part, tuple(names))
