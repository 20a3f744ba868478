"""Assemble the propeller's mesh: only what meets the hub goes through the union, the rest is joined
back.

Most of a blade lies well clear of the hub, and the union would copy it triangle for triangle.
So each blade's grid is cut at the first and last sections wholly clear of the hub
(``grids.blade_pieces``): the two root pieces, each closed by a flat cap at the cut, are united
with the hub (manifold3d) and the junctions cleaned up; then the caps at the cuts are dropped
and the open band between the cuts is put back, its end rings joined vertex for vertex to the
rings the union left untouched (their coordinates are bit-identical). The result is the same
closed 2-manifold as a union of the whole blades, for a fraction of the union's time and memory.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.mesh.cleanup import Cleanup, collapse_keeping
from torus_cad.mesh.grids import BladePieces, blade_pieces, rotated_about_axis
from torus_cad.mesh.quality import find_rows
from torus_cad.mesh.union import LabeledMesh, MeshBooleanError, unite

#: The cuts go where a whole section is at least this many cells (the larger of the blade's and the
#: hub's) outside the hub: beyond every triangle the union and the junction cleanup touch.
CUT_MARGIN_CELLS = 4.0


@dataclass(frozen=True)
class Assembled:
    """The united mesh and how it was made.

    Attributes:
        mesh: the closed, labelled mesh; its first ``united_faces`` faces came out of the union.
        united_faces: faces that went through the union (hub, blade roots, junctions).
        united_vertices: vertices of those (the first ones); the others are blade grid vertices.
        cleanup: what the junction cleanup did.
        cut: the sections where the blades were cut (None: whole blades went through the union).
    """

    mesh: LabeledMesh
    united_faces: int
    united_vertices: int
    cleanup: Cleanup
    cut: tuple[int, int] | None


def _compact(vertices: NDArray[np.float64], faces: NDArray[np.int64]) -> TriangleMesh:
    used = np.unique(faces)
    return TriangleMesh(vertices[used], np.searchsorted(used, faces))


def assemble(
    geometry: PropellerGeometry, grid: BladeSurface, hub: TriangleMesh, cell_mm: float
) -> Assembled:
    """Hub and every blade (blade 0's grid turned to theta_i) as one closed, labelled mesh."""
    names = ("hub", *(f"blade_{index}" for index in range(geometry.blades)))
    pieces = blade_pieces(
        grid, geometry.hub.radius_mm, geometry.hub.length_mm, CUT_MARGIN_CELLS * cell_mm
    )
    first = geometry.blade_angle_deg(0)
    grid_vertices = grid.points.reshape(-1, 3)
    turned = [
        rotated_about_axis(grid_vertices, geometry.blade_angle_deg(index) - first)
        for index in range(geometry.blades)
    ]
    inputs, part_of = [hub], [0]
    dropped: list[NDArray[np.bool_] | None] = [None]
    for index, vertices in enumerate(turned):
        for faces, caps in zip(pieces.near, pieces.cut_cap_faces, strict=True):
            inputs.append(_compact(vertices, faces))
            part_of.append(index + 1)
            dropped.append(caps)
    united, cut_caps = unite(inputs, names, part_of, dropped)
    del inputs
    united, cleanup, kept = collapse_keeping(united)
    cut_caps = cut_caps[kept]
    if cut_caps.any():  # the caps at the cuts go; the bands close the rings again
        united = LabeledMesh(
            united.vertices, united.faces[~cut_caps], united.part[~cut_caps], united.part_names
        )
    if pieces.far is None:
        return Assembled(united, len(united.faces), len(united.vertices), cleanup, None)
    return Assembled(
        _join_bands(united, pieces, turned, grid.points.shape[1]),
        len(united.faces),
        len(united.vertices),
        cleanup,
        pieces.cut,
    )


def _join_bands(
    united: LabeledMesh, pieces: BladePieces, turned: list[NDArray[np.float64]], count: int
) -> LabeledMesh:
    """``united`` with every blade's open band between the cuts joined at its two end rings."""
    assert pieces.far is not None and pieces.cut is not None
    first, last = pieces.cut
    rings = np.concatenate([first * count + np.arange(count), last * count + np.arange(count)])
    interior = np.arange((first + 1) * count, last * count)
    found = find_rows(np.concatenate([vertices[rings] for vertices in turned]), united.vertices)
    if np.any(found < 0):
        raise MeshBooleanError(
            f"mesh union, step 'join': {int(np.sum(found < 0))} vertices of the cut rings are "
            "not in the union's result"
        )
    vertices, faces, parts = [united.vertices], [united.faces], [united.part]
    offset = len(united.vertices)
    index_of = np.empty(len(turned[0]), dtype=np.int64)
    for blade, blade_vertices in enumerate(turned):
        index_of[rings] = found[blade * len(rings) : (blade + 1) * len(rings)]
        index_of[interior] = offset + np.arange(len(interior))
        vertices.append(blade_vertices[interior])
        faces.append(index_of[pieces.far])
        parts.append(np.full(len(pieces.far), blade + 1, dtype=np.int16))
        offset += len(interior)
    return LabeledMesh(
        np.concatenate(vertices), np.concatenate(faces), np.concatenate(parts), united.part_names
    )


__all__ = ["CUT_MARGIN_CELLS", "Assembled", "assemble"]
