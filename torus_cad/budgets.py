"""Budgets: work that would blow up is refused before it starts, with the estimate and the limit.

Only the STL has a size that the parameters can make absurd (the B-rep itself is bounded by the
resolution ranges): its triangle count is estimated from the blade surface and the deflections
(torus_cad.geometry.triangle_estimate) and refused above ``STL_TRIANGLE_LIMIT``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import BudgetError
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.triangle_estimate import estimate_stl_triangles
from torus_cad.tolerances import STL_TRIANGLE_LIMIT


def estimated_stl_triangles(params: PropellerParameters, blade_points: NDArray[np.float64] | None = None) -> int:
    """The STL triangle estimate of ``params`` (blade 0's sampled surface ``(sections, points, 3)`` mm
    if already at hand; otherwise it is computed)."""
    if blade_points is None:
        from torus_cad.geometry.surface import blade_surface

        blade_points = blade_surface(params).points
    export = params.export
    return estimate_stl_triangles(blade_points, params.blades, params.hub.radius, export.stl_linear_deflection,
                                  export.stl_angular_deflection)


def check_stl_budget(params: PropellerParameters, blade_points: NDArray[np.float64] | None = None,
                     limit: int = STL_TRIANGLE_LIMIT) -> int:
    """The estimate, or BudgetError (exit 2) naming it, the deflections and the limit when it is over ``limit``."""
    estimate = estimated_stl_triangles(params, blade_points)
    if estimate > limit:
        export = params.export
        raise BudgetError(
            f"the STL would have about {estimate:,} triangles (export.stl_linear_deflection = "
            f"{export.stl_linear_deflection:g} mm, export.stl_angular_deflection = {export.stl_angular_deflection:g} "
            f"rad), over the limit of {limit:,}; raise the deflections or build with --no-stl")
    return estimate
