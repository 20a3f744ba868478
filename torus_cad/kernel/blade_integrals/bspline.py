"""Non-rational B-spline surfaces as arrays, and their v lines at given u: the basis (scipy's
design matrix, or Cox-de Boor on the few nonzero functions), derivative poles, and points with
their u and v derivatives evaluated node by node or as a tensor product over whole knot spans."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.Geom import Geom_BSplineSurface
from scipy.interpolate import BSpline

_Array = NDArray[np.float64]


@dataclass(frozen=True)
class SurfaceArrays:
    """A non-rational B-spline surface as arrays: poles ``(nu, nv, 3)``, full knot vectors."""

    poles: NDArray[np.float64]
    u_knots: NDArray[np.float64]
    v_knots: NDArray[np.float64]
    u_degree: int
    v_degree: int
    geom: Geom_BSplineSurface


@dataclass(frozen=True)
class VLines:
    """The surface's v lines at the u Gauss nodes: B-spline curves in v with poles ``(U, nv, 3)``,
    the poles of their u derivative (same shape) and of their v derivative ``(U, nv - 1, 3)``."""

    poles: NDArray[np.float64]
    u_derivative_poles: NDArray[np.float64]
    v_derivative_poles: NDArray[np.float64]


def surface_arrays(geom: Geom_BSplineSurface) -> SurfaceArrays:
    nu, nv = geom.NbUPoles(), geom.NbVPoles()
    poles = np.array(
        [[geom.Pole(i, j).Coord() for j in range(1, nv + 1)] for i in range(1, nu + 1)]
    )
    return SurfaceArrays(
        poles,
        np.array(list(geom.UKnotSequence())),
        np.array(list(geom.VKnotSequence())),
        geom.UDegree(),
        geom.VDegree(),
        geom,
    )


def v_lines(surface: SurfaceArrays, u_nodes: NDArray[np.float64]) -> VLines:
    d_poles, d_knots, d_degree = derivative_poles(surface.poles, surface.u_knots, surface.u_degree)
    poles = np.einsum(
        "ai,ijc->ajc", basis(u_nodes, surface.u_knots, surface.u_degree), surface.poles
    )
    v_poles, _, _ = derivative_poles(poles, surface.v_knots, surface.v_degree, axis=1)
    return VLines(
        poles, np.einsum("ai,ijc->ajc", basis(u_nodes, d_knots, d_degree), d_poles), v_poles
    )


def tensor_evaluate(
    lines: VLines,
    spans: NDArray[np.float64],
    x: NDArray[np.float64],
    knots: NDArray[np.float64],
    degree: int,
    line_index: NDArray[np.int64],
    span_index: NDArray[np.int64],
) -> tuple[_Array, _Array, _Array]:
    """Point, d/du, d/dv at the Gauss nodes ``x`` (on [-1, 1]) of the v knot spans ``span_index``
    of lines ``line_index``: each ``(len(line_index) * len(x), 3)``, node-major per piece."""
    nodes = (spans[:-1, None] + np.diff(spans)[:, None] * (x + 1.0) / 2.0).ravel()
    values, d_values = basis(nodes, knots, degree), basis(nodes, knots[1:-1], degree - 1)
    take = (span_index[:, None] * len(x) + np.arange(len(x))).ravel()
    rows = np.repeat(line_index, len(x))
    return (
        np.matmul(values, lines.poles)[rows, take],
        np.matmul(values, lines.u_derivative_poles)[rows, take],
        np.matmul(d_values, lines.v_derivative_poles)[rows, take],
    )


def evaluate(
    lines: VLines,
    rows: NDArray[np.int64],
    v: NDArray[np.float64],
    knots: NDArray[np.float64],
    degree: int,
    u_derivative: bool = True,
) -> tuple[_Array, _Array, _Array]:
    """Point, d/du (zeros unless ``u_derivative``) and d/dv of line ``rows[i]`` at ``v[i]``, each
    ``(m, 3)``."""
    columns, values = local_basis(v, knots, degree)
    d_columns, d_values = local_basis(v, knots[1:-1], degree - 1)
    point = np.einsum("ml,mlc->mc", values, lines.poles[rows[:, None], columns])
    d_v = np.einsum("ml,mlc->mc", d_values, lines.v_derivative_poles[rows[:, None], d_columns])
    d_u = (
        np.einsum("ml,mlc->mc", values, lines.u_derivative_poles[rows[:, None], columns])
        if u_derivative
        else np.zeros_like(point)
    )
    return point, d_u, d_v


# scipy sparse array
def _design_matrix(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int) -> Any:
    return BSpline.design_matrix(np.clip(x, knots[degree], knots[-degree - 1]), knots, degree)


def basis(x: NDArray[np.float64], knots: NDArray[np.float64], degree: int) -> NDArray[np.float64]:
    """Dense ``(len(x), n)`` B-spline basis (scipy's design matrix), x clipped into the knot
    range."""
    return _design_matrix(x, knots, degree).toarray()


def local_basis(
    x: NDArray[np.float64], knots: NDArray[np.float64], degree: int
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The ``degree + 1`` basis functions that can be nonzero at each x (clipped into the knot
    range): their indices and values, both ``(len(x), degree + 1)``.

    Cox-de Boor (The NURBS Book, A2.2), vectorised over x. It is what scipy's design matrix
    stores per row, without its per-call checks, which cost more than the evaluation here
    (this runs ~50 times per blade face, on a few hundred to a few ten thousand points).
    """
    x = np.clip(np.asarray(x, dtype=float), knots[degree], knots[-degree - 1])
    span = np.clip(np.searchsorted(knots, x, side="right") - 1, degree, len(knots) - degree - 2)
    values = np.zeros((len(x), degree + 1))
    values[:, 0] = 1.0
    left = np.empty((len(x), degree + 1))
    right = np.empty((len(x), degree + 1))
    for j in range(1, degree + 1):
        left[:, j] = x - knots[span + 1 - j]
        right[:, j] = knots[span + j] - x
        saved = np.zeros(len(x))
        for r in range(j):
            temp = values[:, r] / (right[:, r + 1] + left[:, j - r])
            values[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        values[:, j] = saved
    return span[:, None] - degree + np.arange(degree + 1), values


def derivative_poles(
    poles: NDArray[np.float64], knots: NDArray[np.float64], degree: int, axis: int = 0
) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Poles, knots and degree of the derivative along ``axis`` of a B-spline with these poles."""
    moved = np.moveaxis(poles, axis, 0)
    count = moved.shape[0]
    scale = degree / (knots[degree + 1 : count + degree] - knots[1:count])
    derivative = (moved[1:] - moved[:-1]) * scale.reshape(-1, *([1] * (moved.ndim - 1)))
    return np.moveaxis(derivative, 0, axis), knots[1:-1], degree - 1
