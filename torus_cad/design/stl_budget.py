"""The STL budget: a design whose STL would have too many triangles is refused before anything is
built.

The count is estimated from the blade surface and the deflections
(torus_cad.geometry.analysis.triangle_estimate, a few milliseconds, no tessellation) and refused
above :data:`torus_cad.tolerances.STL_TRIANGLE_LIMIT`, with the estimate, the deflections and the
limit. (The other budgets sit with their inputs too: the surface mesh's memory in
torus_cad.mesh.resolution, the CFD mesh's tetrahedra in torus_cad.cfd_domain.estimate; the B-rep
itself is bounded by the resolution ranges.)
"""

from __future__ import annotations

from torus_cad.design.described_geometry import sampled_blade_surface
from torus_cad.errors import BudgetError
from torus_cad.geometry.analysis.triangle_estimate import estimate_stl_triangles
from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.parameters.design import PropellerParameters
from torus_cad.tolerances import STL_TRIANGLE_LIMIT

__all__ = ["check_stl_budget", "estimated_stl_triangles"]

#: Fewer samples than this (sections, points) do not resolve the blade's curvature for the
#: estimate; such a surface is sampled again at the default resolution.
_ESTIMATE_MIN_SAMPLES = (12, 40)
_ESTIMATE_SAMPLES = (25, 80)
#: Poles around a section of the blade's B-spline (the section fit doubles its knots from 24 as
#: needed; 56 poles on the default design and at 200 x 800 samples).
_USUAL_POLES_AROUND = 56


def estimated_stl_triangles(
    params: PropellerParameters,
    surface: BladeSurface | None = None,
    pole_grid: tuple[int, int] | None = None,
) -> int:
    """The STL triangle estimate of ``params``.

    ``surface`` is blade 0's sampled surface and ``pole_grid`` its B-spline's (sections, poles
    around), if the blade is already built; otherwise the surface is sampled here and the pole grid
    taken as the section fit's usual one.
    """
    if surface is None or any(
        have < need for have, need in zip(surface.points.shape, _ESTIMATE_MIN_SAMPLES)
    ):
        surface = sampled_blade_surface(
            params, sections=_ESTIMATE_SAMPLES[0], points=_ESTIMATE_SAMPLES[1]
        )
    if pole_grid is None:
        pole_grid = (params.resolution.sections, min(params.resolution.points, _USUAL_POLES_AROUND))
    export = params.export
    return estimate_stl_triangles(
        surface.points,
        surface.trailing_edge_index,
        params.blades,
        params.hub.radius,
        export.stl_linear_deflection,
        export.stl_angular_deflection,
        pole_grid,
    )


def check_stl_budget(
    params: PropellerParameters,
    surface: BladeSurface | None = None,
    pole_grid: tuple[int, int] | None = None,
    limit: int = STL_TRIANGLE_LIMIT,
) -> int:
    """The estimate, or BudgetError (exit 2) naming it, the deflections and the limit when it is
    over ``limit``."""
    estimate = estimated_stl_triangles(params, surface, pole_grid)
    if estimate > limit:
        export = params.export
        raise BudgetError(
            f"the STL would have about {estimate:,} triangles (export.stl_linear_deflection = "
            f"{export.stl_linear_deflection:g} mm, "
            f"export.stl_angular_deflection = {export.stl_angular_deflection:g} "
            f"rad), over the limit of {limit:,}; raise the deflections or build with --no-stl"
        )
    return estimate
