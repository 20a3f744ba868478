"""The box of a blade face's rotated copies: the best integration node along each box direction,
refined on the surface by a projected ascent (OpenCascade's second derivatives)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from OCP.Geom import Geom_BSplineSurface
from OCP.gp import gp_Pnt, gp_Vec

from torus_cad.kernel.blade_integrals.bspline import SurfaceArrays

#: Box: the copies whose best integration node along a direction comes within this fraction of
#: the face's extent of the best copy's are refined on the surface (the nodes are far closer);
#: about BOX_START_NODES evenly picked integration nodes are the candidate starts.
BOX_REFINE_MARGIN, BOX_START_NODES = 0.02, 8000


#: Steps of the ascent that refines a box extreme on the surface.
ASCENT_ITERATIONS = 100


#: The six box directions, in the order of
#: :attr:`~torus_cad.kernel.blade_integrals.quadrature.FaceIntegrals.extremes_mm`: -x, x, -y, y, -z,
#: z.
BOX_DIRECTIONS = np.array(
    [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], dtype=float
)


def box_extremes(
    surface: SurfaceArrays,
    points: NDArray[np.float64],
    u: NDArray[np.float64],
    v: NDArray[np.float64],
    radius: float,
    angles: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``(6,)``: the largest -x, x, -y, y, -z, z over the copies of the face rotated by ``angles``.

    A copy's extreme along a direction is the face's support along that direction rotated
    back: the best integration node, refined on the surface (:func:`_refined_maximum`) for the
    copies whose best node comes within BOX_REFINE_MARGIN of the best copy's. A refinement that
    ends inside r < R is dropped: the face's extreme then lies on its boundary on the
    cylinder, inside the hub's box."""
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    x, y, z = BOX_DIRECTIONS.T
    directions = np.stack(
        [cos * x + sin * y, -sin * x + cos * y, np.broadcast_to(z, (len(angles), 6))], axis=-1
    )  # (copies, 6, 3): each box direction rotated by -angle
    # the nodes are far denser than the refinement needs
    step = max(1, len(points) // BOX_START_NODES)
    points, u, v = points[::step], u[::step], v[::step]
    values = points @ directions.reshape(-1, 3).T  # (nodes, copies * 6)
    best = values.argmax(axis=0).reshape(len(angles), 6)
    best_values = values[best.ravel(), np.arange(values.shape[1])].reshape(len(angles), 6)
    margin = BOX_REFINE_MARGIN * float((points.max(axis=0) - points.min(axis=0)).max())
    bounds = (
        (float(surface.u_knots[0]), float(surface.u_knots[-1])),
        (float(surface.v_knots[0]), float(surface.v_knots[-1])),
    )
    extremes = best_values.max(axis=0)
    for copy, side in zip(*np.nonzero(best_values >= extremes - margin), strict=True):
        start = best[copy, side]
        refined = _refined_maximum(
            surface.geom, directions[copy, side], float(u[start]), float(v[start]), bounds, radius
        )
        if refined is not None:
            extremes[side] = max(extremes[side], refined)
    return extremes


def _refined_maximum(
    geom: Geom_BSplineSurface,
    direction: NDArray[np.float64],
    u: float,
    v: float,
    bounds: tuple[tuple[float, float], tuple[float, float]],
    radius: float,
) -> float | None:
    """The local maximum of direction . S(u, v) from (u, v) in the surface's parameter box, if
    it lies outside the cylinder; else None.

    Projected ascent: a parameter at its bound with the gradient pushing out is held there;
    the free ones take a Newton step (second derivatives from OpenCascade) where the function
    is concave in them, else a gradient step of a growing length; every step is halved until
    the function does not decrease."""
    point, d_u, d_v, d_uu, d_vv, d_uv = gp_Pnt(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec(), gp_Vec()
    axis = gp_Vec(*(float(value) for value in direction))
    low, high = np.array(bounds).T
    uv, reach = np.array([u, v]), 1e-2 * float((high - low).min())

    def support(at: NDArray[np.float64]) -> float:
        geom.D0(float(at[0]), float(at[1]), point)
        return float(gp_Vec(point.XYZ()).Dot(axis))

    for _ in range(ASCENT_ITERATIONS):
        geom.D2(float(uv[0]), float(uv[1]), point, d_u, d_v, d_uu, d_vv, d_uv)
        value = float(gp_Vec(point.XYZ()).Dot(axis))
        gradient = np.array([d_u.Dot(axis), d_v.Dot(axis)])
        hessian = np.array([[d_uu.Dot(axis), d_uv.Dot(axis)], [d_uv.Dot(axis), d_vv.Dot(axis)]])
        free = ~(((uv <= low) & (gradient < 0.0)) | ((uv >= high) & (gradient > 0.0)))
        if not free.any():
            break  # a corner of the parameter box
        step = np.zeros(2)
        block = hessian[np.ix_(free, free)]
        if np.all(np.linalg.eigvalsh(block) < 0.0):
            step[free] = -np.linalg.solve(block, gradient[free])
        else:
            step[free] = gradient[free] * reach / np.linalg.norm(gradient[free])
            reach *= 2.0
        for _ in range(60):
            candidate = np.clip(uv + step, low, high)
            if support(candidate) >= value:
                break
            step /= 2.0
        else:
            break
        moved = np.abs(candidate - uv).max()
        uv = candidate
        if moved <= 1e-14:
            break
    return _support_outside(geom, axis, uv, radius)


def _support_outside(
    geom: Geom_BSplineSurface, axis: gp_Vec, uv: NDArray[np.float64], radius: float
) -> float | None:
    point = gp_Pnt()
    geom.D0(float(uv[0]), float(uv[1]), point)
    return (
        None
        if point.X() ** 2 + point.Y() ** 2 < radius**2
        else float(gp_Vec(point.XYZ()).Dot(axis))
    )
