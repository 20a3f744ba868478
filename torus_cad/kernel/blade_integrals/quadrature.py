"""Gauss-Legendre quadrature over one blade face trimmed to r > R: along each v line the two
crossings a(u), b(u) of the cylinder (sampling and safeguarded Newton), the integrands of the
divergence theorem's fields (see :mod:`torus_cad.kernel.blade_integrals`), adaptive rules per
knot span in v and then in u, and the footprints' line densities."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from OCP.BRepTools import BRepTools
from OCP.Geom import Geom_BSplineSurface
from OCP.TopoDS import TopoDS_Face

from torus_cad.kernel.blade_integrals.bspline import (
    SurfaceArrays,
    VLines,
    basis,
    evaluate,
    surface_arrays,
    tensor_evaluate,
    v_lines,
)
from torus_cad.kernel.blade_integrals.extremes import box_extremes

_Array = NDArray[np.float64]


#: Integrands at surface points: (points, d/du, d/dv), each (n, 3) -> (n, 6).
_Integrands = Callable[[_Array, _Array, _Array], _Array]


#: Gauss-Legendre points per knot span, in u and in v. On the default propeller 4 x 4 is
#: ~4e-10 relative in volume (as 8 x 8: the rest is the B-rep's own trimming curves), 3 x 3 ~8e-9.
GAUSS_POINTS_PER_SPAN = 4


#: Adaptive integration over u: an interval's Gauss rules of GAUSS_POINTS_PER_SPAN and one point
#: less must agree to this fraction of each quantity times the interval's share of the u range,
#: else the interval is halved, at most U_MAX_HALVINGS times (then BRepGProp takes over).
U_RELATIVE_TOLERANCE, U_MAX_HALVINGS = 1e-6, 12


#: The same along each v line, relative to the line's own integrals.
V_RELATIVE_TOLERANCE, V_MAX_HALVINGS = 1e-6, 12


#: Quantities integrated along each v line: volume, x, y, z moments, spin-axis inertia, area,
#: the root and tip footprints' line densities, then ∫xz, ∫yz, ∫xy, ∫(x² - y²).
QUANTITIES = 12


#: Integrated over the face (v, then u): the QUANTITIES but the footprints'.
_INTEGRANDS = QUANTITIES - 2


#: Samples per v knot span when looking for the crossings of r = R along a v line.
ROOT_SAMPLES_PER_SPAN = 4


#: A blade face's u bounds (from its trimming curves) must be the surface's whole u range to this
#: fraction; its v bounds the computed [min a, max b] to the looser second fraction (the roots
#: are known at the u Gauss points only).
U_BOUNDS_RELATIVE, V_BOUNDS_RELATIVE = 1e-6, 1e-2


@dataclass(frozen=True)
class FaceIntegrals:
    """Integrals over the part outside r = R of one blade, from its face alone.

    Attributes:
        volume_mm3: volume outside the cylinder, mm^3.
        first_moment_mm4: ``(3,)`` ∫x, ∫y, ∫z dV over it, mm^4.
        spin_inertia_mm5: ∫ (x² + y²) dV over it, mm^5.
        area_mm2: the face's area, mm^2.
        footprints_mm2: ``(2,)`` R ∫ z dθ along the face's root and tip crossing curves, mm^2,
            signed: summed over the faces of one blade, their absolute values are the areas of the
            holes the blade leaves in the cylinder (one face: the whole closed curve).
        second_moments_mm5: ``(4,)`` ∫xz, ∫yz, ∫xy, ∫(x² - y²) dV over it, mm^5.
        extremes_mm: ``(6,)`` largest -x, x, -y, y, -z, z over the rotated copies of the face, mm
            (an extreme on the cylinder, if that is one, is inside the hub's box anyway).
        v_range: ``(2,)`` smallest a(u) and largest b(u) over the u Gauss points.
        u_range: ``(2,)`` the surface's u range (the face spans all of it).
    """

    volume_mm3: float
    first_moment_mm4: NDArray[np.float64]
    spin_inertia_mm5: float
    second_moments_mm5: NDArray[np.float64]
    area_mm2: float
    footprints_mm2: NDArray[np.float64]
    extremes_mm: NDArray[np.float64]
    v_range: NDArray[np.float64]
    u_range: NDArray[np.float64]


def face_integrals(
    geom: Geom_BSplineSurface,
    reversed_face: bool,
    radius: float,
    angles: NDArray[np.float64],
    gauss_points: int,
) -> FaceIntegrals | None:
    """Integrals of the face on ``geom`` trimmed to r > ``radius``, for copies rotated by
    ``angles`` (radians) about z; None unless every v line crosses r = radius exactly twice."""
    surface = surface_arrays(geom)
    integrated = _integrate_over_u(surface, radius, reversed_face, gauss_points)
    if integrated is None:
        return None
    totals, samples = integrated
    volume, moment_x, moment_y, moment_z, inertia, area, root_footprint, tip_footprint = totals[:8]
    points = np.concatenate([sample.points for sample in samples])
    return FaceIntegrals(
        volume_mm3=float(volume),
        first_moment_mm4=np.array([moment_x, moment_y, moment_z]),
        spin_inertia_mm5=float(inertia),
        second_moments_mm5=totals[8:].copy(),
        area_mm2=float(area),
        footprints_mm2=np.array([root_footprint, tip_footprint]),
        extremes_mm=box_extremes(
            surface,
            points,
            np.concatenate([sample.u for sample in samples]),
            np.concatenate([sample.v for sample in samples]),
            radius,
            angles,
        ),
        v_range=np.array(
            [
                min(sample.roots[:, 0].min() for sample in samples),
                max(sample.roots[:, 1].max() for sample in samples),
            ]
        ),
        u_range=np.array([surface.u_knots[0], surface.u_knots[-1]]),
    )


def _integrate_over_u(
    surface: SurfaceArrays, radius: float, reversed_face: bool, gauss_points: int
) -> tuple[NDArray[np.float64], list[_LineSamples]] | None:
    """∫ over u of :func:`_line_densities`, adaptively: on each interval (at first the knot
    spans) Gauss rules of ``gauss_points`` and one point less; where they differ by more than
    U_RELATIVE_TOLERANCE the interval is halved. The v integral at fixed u is smooth, but where
    a crossing curve runs nearly along v (a blade entering the hub at a grazing angle) the
    domain's edge b(u) is steep, and so is the integral as a function of u."""
    spans = np.unique(surface.u_knots[surface.u_degree : -surface.u_degree])
    low, high = spans[:-1], spans[1:]
    rules = [np.polynomial.legendre.leggauss(points) for points in (gauss_points, gauss_points - 1)]
    totals, scale, kept = np.zeros(QUANTITIES), None, []
    for _ in range(U_MAX_HALVINGS + 1):
        nodes = [(low[:, None] + (high - low)[:, None] * (x + 1.0) / 2.0).ravel() for x, _ in rules]
        sample = _line_densities(
            surface, np.concatenate(nodes), radius, reversed_face, gauss_points
        )
        if sample is None:
            return None
        kept.append(sample)
        fine_count = nodes[0].size
        estimates = [
            (
                (high - low)[:, None, None]
                * w[None, :, None]
                / 2.0
                * values.reshape(len(low), len(w), QUANTITIES)
            ).sum(axis=1)
            for (_, w), values in zip(
                rules, (sample.densities[:fine_count], sample.densities[fine_count:])
            )
        ]
        if scale is None:  # the size of each quantity, for relative errors (moments may sum to ~0)
            scale = np.maximum(np.abs(estimates[0]).sum(axis=0), np.finfo(float).tiny)
        error = (np.abs(estimates[0] - estimates[1]) / scale).max(axis=1)
        done = error <= U_RELATIVE_TOLERANCE * (high - low) / (spans[-1] - spans[0])
        totals += estimates[0][done].sum(axis=0)
        middle = (low + high)[~done] / 2.0
        low, high = np.concatenate([low[~done], middle]), np.concatenate([middle, high[~done]])
        if not len(low):
            return totals, kept
    return None


@dataclass(frozen=True)
class _LineSamples:
    """What the v lines at some u give: per line ``densities`` ``(k, 8)`` (the v integrals of
    the QUANTITIES, per unit u) and ``roots`` ``(k, 2)``; the integration nodes' ``points``
    ``(n, 3)`` and their ``u``, ``v`` ``(n,)`` (kept for the box)."""

    densities: NDArray[np.float64]
    roots: NDArray[np.float64]
    points: NDArray[np.float64]
    u: NDArray[np.float64]
    v: NDArray[np.float64]


def _line_densities(
    surface: SurfaceArrays,
    u: NDArray[np.float64],
    radius: float,
    reversed_face: bool,
    gauss_points: int,
) -> _LineSamples | None:
    """Along the v line at each ``u``, the integrals over v in [a(u), b(u)] of the volume, the
    x, y, z moments, the spin inertia and the area densities (see the module), and the two
    footprints' line densities R z dθ/du at a(u) and b(u). None unless every line crosses
    r = ``radius`` exactly twice."""
    lines = v_lines(surface, u)
    roots = _crossings(lines, surface.v_knots, surface.v_degree, radius)
    if roots is None:
        return None
    sign = -1.0 if reversed_face else 1.0
    integrals = _v_integrals(
        lines,
        surface,
        roots,
        lambda point, d_u, d_v: _integrands(point, d_u, d_v, radius, sign),
        gauss_points,
    )
    if integrals is None:
        return None
    line_integrals, points, rows, v_nodes = integrals
    densities = np.zeros((len(u), QUANTITIES))
    densities[:, :6], densities[:, 8:] = line_integrals[:, :6], line_integrals[:, 6:]
    for column, root in enumerate(roots.T):
        densities[:, 6 + column] = _footprint_density(lines, root, surface, radius)
    return _LineSamples(densities, roots, points, u[rows], v_nodes)


def bounds_match(face: TopoDS_Face, part: FaceIntegrals) -> bool:
    """The face's own parameter bounds (from its trimming curves) are the computed domain: the
    whole u range and v in [min a, max b]. Rules out a face that is some other piece."""
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face)
    u_span = part.u_range[1] - part.u_range[0]
    v_span = part.v_range[1] - part.v_range[0]
    return (
        abs(u_min - part.u_range[0]) <= U_BOUNDS_RELATIVE * u_span
        and abs(u_max - part.u_range[1]) <= U_BOUNDS_RELATIVE * u_span
        and abs(v_min - part.v_range[0]) <= V_BOUNDS_RELATIVE * v_span
        and abs(v_max - part.v_range[1]) <= V_BOUNDS_RELATIVE * v_span
    )


def _crossings(
    lines: VLines, knots: NDArray[np.float64], degree: int, radius: float
) -> NDArray[np.float64] | None:
    """``(U, 2)``: the two v where each v line crosses r = ``radius``; None unless every line
    starts and ends inside (r < radius) and crosses exactly twice."""
    spans = np.unique(knots[degree:-degree])
    grid = np.concatenate(
        [
            np.linspace(low, high, ROOT_SAMPLES_PER_SPAN, endpoint=False)
            for low, high in itertools.pairwise(spans)
        ]
        + [spans[-1:]]
    )
    samples = np.matmul(basis(grid, knots, degree), lines.poles[..., :2])  # (U, samples, 2)
    excess = (samples**2).sum(axis=-1) - radius**2  # r^2 - R^2
    change = np.signbit(excess[:, :-1]) != np.signbit(excess[:, 1:])
    if not (
        np.all(change.sum(axis=1) == 2)
        and np.all(excess[:, 0] < 0.0)
        and np.all(excess[:, -1] < 0.0)
    ):
        return None
    rows, columns = np.nonzero(change)  # row-major: each line's lower crossing first
    low, high = grid[columns], grid[columns + 1]
    f_low, f_high = excess[rows, columns], excess[rows, columns + 1]
    v = low + (high - low) * f_low / (f_low - f_high)
    for _ in range(60):  # Newton, kept inside the bracket (bisection where it would leave it)
        point, _, tangent = evaluate(lines, rows, v, knots, degree, u_derivative=False)
        f = (point[:, :2] ** 2).sum(axis=1) - radius**2
        slope = 2.0 * (point[:, :2] * tangent[:, :2]).sum(axis=1)
        same_side = np.signbit(f) == np.signbit(f_low)
        low, high = np.where(same_side, v, low), np.where(same_side, high, v)
        proposal = v - f / np.where(slope != 0.0, slope, np.inf)
        proposal = np.where((proposal >= low) & (proposal <= high), proposal, (low + high) / 2.0)
        converged = np.abs(proposal - v).max() <= 1e-13 * (knots[-1] - knots[0])
        v = proposal
        if converged:
            return v.reshape(-1, 2)
    return None


def _integrands(
    points: NDArray[np.float64],
    d_u: NDArray[np.float64],
    d_v: NDArray[np.float64],
    radius: float,
    sign: float,
) -> NDArray[np.float64]:
    """``(n, _INTEGRANDS)``: the volume, x, y, z moment, spin inertia, area, xz, yz, xy and
    x² - y² integrands per du dv at surface points with these derivatives (``sign`` -1 for a
    reversed face)."""
    normal = np.cross(d_u, d_v) * sign
    x, y, z = points.T
    r2 = x * x + y * y
    radial = x * normal[:, 0] + y * normal[:, 1]  # (x, y, 0) . n
    volume_k = 0.5 - radius**2 / (2.0 * r2)
    moment_k = (1.0 - radius**3 / (r2 * np.sqrt(r2))) / 3.0
    second_k = (1.0 - radius**4 / (r2 * r2)) / 4.0
    return np.column_stack(
        [
            radial * volume_k,
            radial * x * moment_k,
            radial * y * moment_k,
            radial * z * volume_k,
            radial * r2 * second_k,
            np.linalg.norm(normal, axis=1),
            radial * x * z * moment_k,
            radial * y * z * moment_k,
            radial * x * y * second_k,
            radial * (x * x - y * y) * second_k,
        ]
    )


def _v_integrals(
    lines: VLines,
    surface: SurfaceArrays,
    roots: NDArray[np.float64],
    integrands: _Integrands,
    gauss_points: int,
) -> tuple[_Array, _Array, NDArray[np.int64], _Array] | None:
    """The integrals over v in [a(u), b(u)] of ``integrands`` on every line, adaptively.

    The pieces are the v knot spans clipped to [a, b] (a smooth integrand on each); each gets
    Gauss rules of ``gauss_points`` and one point less and is halved where they differ by
    more than V_RELATIVE_TOLERANCE of the line's total times the piece's share of [a, b]. The
    first round evaluates the whole spans as a tensor product (one matrix product per
    quantity, the same v nodes on every line), everything else node by node.

    Returns the ``(U, _INTEGRANDS)`` integrals and the nodes' points ``(n, 3)``, line index and v,
    or None if some piece needs more than V_MAX_HALVINGS halvings.
    """
    knots, degree = surface.v_knots, surface.v_degree
    spans = np.unique(knots[degree:-degree])
    rules = [np.polynomial.legendre.leggauss(points) for points in (gauss_points, gauss_points - 1)]
    low = np.clip(spans[:-1][None, :], roots[:, :1], roots[:, 1:])  # (U, spans)
    high = np.clip(spans[1:][None, :], roots[:, :1], roots[:, 1:])
    whole = (low == spans[:-1]) & (high == spans[1:])
    lines_whole, spans_whole = np.nonzero(whole)
    lines_cut, spans_cut = np.nonzero((high > low) & ~whole)
    row = np.concatenate([lines_whole, lines_cut])
    start = np.concatenate([spans[spans_whole], low[lines_cut, spans_cut]])
    length = np.concatenate([np.diff(spans)[spans_whole], (high - low)[lines_cut, spans_cut]])
    domain = roots[:, 1] - roots[:, 0]
    totals, scale = np.zeros((len(roots), _INTEGRANDS)), None
    kept: list[tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]] = []
    for round_ in range(V_MAX_HALVINGS + 1):
        estimates = []
        for x, w in rules:
            v = (start[:, None] + length[:, None] * (x + 1.0) / 2.0).ravel()
            rows = np.repeat(row, len(x))
            if round_ == 0:  # whole spans: a tensor product, the rest node by node
                split = len(lines_whole) * len(x)
                point, d_u, d_v = tensor_evaluate(
                    lines, spans, x, knots, degree, lines_whole, spans_whole
                )
                cut = evaluate(lines, rows[split:], v[split:], knots, degree)
                point, d_u, d_v = (np.concatenate(pair) for pair in zip((point, d_u, d_v), cut))
            else:
                point, d_u, d_v = evaluate(lines, rows, v, knots, degree)
            values = integrands(point, d_u, d_v).reshape(len(row), len(x), _INTEGRANDS)
            estimates.append((length[:, None, None] * w[None, :, None] / 2.0 * values).sum(axis=1))
            if len(x) == gauss_points:
                kept.append((point, rows, v))
        if scale is None:  # each line's size of each quantity, for relative errors
            scale = np.zeros_like(totals)
            np.add.at(scale, row, np.abs(estimates[0]))
            scale = np.maximum(scale, np.finfo(float).tiny)
        error = (np.abs(estimates[0] - estimates[1]) / scale[row]).max(axis=1)
        done = error <= V_RELATIVE_TOLERANCE * length / domain[row]
        np.add.at(totals, row[done], estimates[0][done])
        row, start, length = (
            np.concatenate([values[~done]] * 2) for values in (row, start, length / 2.0)
        )
        start[len(start) // 2 :] += length[len(start) // 2 :]
        if not len(row):
            points, rows, v = (np.concatenate(parts) for parts in zip(*kept))
            return totals, points, rows, v
    return None


def _footprint_density(
    lines: VLines, root: NDArray[np.float64], surface: SurfaceArrays, radius: float
) -> NDArray[np.float64]:
    """R z dθ/du along a crossing curve v = root(u): integrated over u, ± the area of the hole
    the curve cuts in the cylinder (R ∮ z dθ; the curve is closed, u runs once around the
    section and both ends are at the trailing edge). Along the curve v'(u) = -∂u(r²)/∂v(r²),
    and dθ = (x dy - y dx) / r²."""
    point, d_u, d_v = evaluate(lines, np.arange(len(root)), root, surface.v_knots, surface.v_degree)
    x, y, z = point.T
    slope = -(x * d_u[:, 0] + y * d_u[:, 1]) / (x * d_v[:, 0] + y * d_v[:, 1])
    tangent = d_u + d_v * slope[:, None]
    return radius * z * (x * tangent[:, 1] - y * tangent[:, 0]) / (x * x + y * y)
