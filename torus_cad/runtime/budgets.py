"""Budgets: work that would blow up is refused before it starts, with the estimate and the limit.

The STL's triangle count is estimated from the blade surface and the deflections
(torus_cad.geometry.analysis.triangle_estimate) and refused above ``STL_TRIANGLE_LIMIT``. The CFD mesh's
tetrahedra and memory are estimated from the ``[cfd]`` sizes (torus_cad.cfd.estimate, a few
seconds, no meshing) and refused above ``CFD_TETRAHEDRA_LIMIT``. (The B-rep itself is bounded by
the resolution ranges.)
"""

from __future__ import annotations

import math

from torus_cad.errors import BudgetError
from torus_cad.geometry.analysis.triangle_estimate import estimate_stl_triangles
from torus_cad.geometry.blade.surface import BladeSurface
from torus_cad.parameters import PropellerParameters
from torus_cad.tolerances import STL_TRIANGLE_LIMIT

#: Peak resident memory of ``torus-cad mesh`` (binary STL, --no-compare) grows by this much per
#: triangle of its estimate (torus_cad.mesh.resolution.estimate_triangles), bytes, over a fixed
#: :data:`MESH_BASE_BYTES` (Python, numpy, manifold3d, meshlib): measured 0.77 GB at 268,260 and
#: 2.22 GB at 5,251,396 estimated triangles (`/usr/bin/time -v torus-cad mesh --sections 100 --points 400`
#: and `--sections 400 --points 2000`).
MESH_BYTES_PER_TRIANGLE = 290.0
MESH_BASE_BYTES = 0.70e9
#: The B-rep built for the comparison (``--no-compare`` skips it) adds about this much, bytes.
MESH_COMPARE_BYTES = 0.5e9
#: Most memory ``torus-cad mesh`` may plan to use, bytes: a share of the 24 GiB machine that
#: several jobs use at once.
MESH_MEMORY_LIMIT_BYTES = 4.0e9
#: The triangles that fit :data:`MESH_MEMORY_LIMIT_BYTES` with the comparison on.
MESH_TRIANGLE_LIMIT = math.floor((MESH_MEMORY_LIMIT_BYTES - MESH_BASE_BYTES - MESH_COMPARE_BYTES)
                                 / MESH_BYTES_PER_TRIANGLE)


def mesh_memory_bytes(triangles: int, compare: bool = True) -> float:
    """Estimated peak memory of ``torus-cad mesh`` for a mesh estimated at ``triangles``, bytes."""
    return MESH_BASE_BYTES + (MESH_COMPARE_BYTES if compare else 0.0) + MESH_BYTES_PER_TRIANGLE * triangles


def check_mesh_memory(triangles: int, compare: bool = True, limit_bytes: float = MESH_MEMORY_LIMIT_BYTES) -> None:
    """BudgetError (exit 2) with the estimate and the limit when the mesh would need more than ``limit_bytes``."""
    need = mesh_memory_bytes(triangles, compare)
    if need > limit_bytes:
        fits = math.floor((limit_bytes - mesh_memory_bytes(0, compare)) / MESH_BYTES_PER_TRIANGLE)
        raise BudgetError(
            f"the mesh would have about {triangles:,} triangles and need about {need / 1e9:.1f} GB of memory, over "
            f"the limit of {limit_bytes / 1e9:.1f} GB (about {fits:,} triangles); lower mesh.sections or "
            "mesh.points (--sections, --points)")


#: Surface meshes (``torus-cad mesh``) up to this many triangles are checked whole for intersecting
#: triangle pairs (meshlib, ~10 us a triangle on the 2-core machine under load); larger ones where a
#: structured mesh can cross (torus_cad.mesh.crossings).
MESH_WHOLE_CROSSING_CHECK_TRIANGLES = 1_500_000

#: Fewer samples than this (sections, points) do not resolve the blade's curvature for the
#: estimate; such a surface is sampled again at the default resolution.
_ESTIMATE_MIN_SAMPLES = (12, 40)
_ESTIMATE_SAMPLES = (25, 80)
#: Poles around a section of the blade's B-spline (the section fit doubles its knots from 24 as
#: needed; 56 poles on the default design and at 200 x 800 samples).
_USUAL_POLES_AROUND = 56


def estimated_stl_triangles(params: PropellerParameters, surface: BladeSurface | None = None,
                            pole_grid: tuple[int, int] | None = None) -> int:
    """The STL triangle estimate of ``params``.

    ``surface`` is blade 0's sampled surface and ``pole_grid`` its B-spline's (sections, poles
    around), if the blade is already built; otherwise the surface is sampled here and the pole grid
    taken as the section fit's usual one.
    """
    if surface is None or any(have < need for have, need in zip(surface.points.shape, _ESTIMATE_MIN_SAMPLES)):
        surface = params.blade_surface(sections=_ESTIMATE_SAMPLES[0], points=_ESTIMATE_SAMPLES[1])
    if pole_grid is None:
        pole_grid = (params.resolution.sections, min(params.resolution.points, _USUAL_POLES_AROUND))
    export = params.export
    return estimate_stl_triangles(surface.points, surface.trailing_edge_index, params.blades, params.hub.radius,
                                  export.stl_linear_deflection, export.stl_angular_deflection, pole_grid)


def check_stl_budget(params: PropellerParameters, surface: BladeSurface | None = None,
                     pole_grid: tuple[int, int] | None = None, limit: int = STL_TRIANGLE_LIMIT) -> int:
    """The estimate, or BudgetError (exit 2) naming it, the deflections and the limit when it is over ``limit``."""
    estimate = estimated_stl_triangles(params, surface, pole_grid)
    if estimate > limit:
        export = params.export
        raise BudgetError(
            f"the STL would have about {estimate:,} triangles (export.stl_linear_deflection = "
            f"{export.stl_linear_deflection:g} mm, export.stl_angular_deflection = {export.stl_angular_deflection:g} "
            f"rad), over the limit of {limit:,}; raise the deflections or build with --no-stl")
    return estimate
