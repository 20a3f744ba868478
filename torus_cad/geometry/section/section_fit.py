"""Section curves, kernel-free: each sampled section fitted by one closed cubic B-spline (arrays in,
arrays out).

The fit and its check of the trailing edge live here, below the kernel, so that a design can be
refused for them before OpenCascade is imported (:mod:`torus_cad.design.design_checks`);
:mod:`torus_cad.kernel.wires` makes the section wires from the same arrays and describes the
curves (sharp and blunt trailing edges, the round cap) in its module docstring.

Every section is fitted by least squares with the *same* knot vector and the same parameter
values, so all section curves are compatible and the loft needs no knot insertion. Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline, make_lsq_spline

from torus_cad.errors import GeometryError
from torus_cad.geometry.section.section import ROUND_CAP_HANDLE_FRACTION, round_cap_poles

#: Interior knots of the first section fit; doubled while the fit is too coarse (at most the
#: maximum).
WIRE_FIT_INITIAL_KNOTS = 24

WIRE_FIT_MAXIMUM_KNOTS = 384

#: Largest allowed deviation of a section's B-spline from its sampled points, as a fraction
#: of the section's chord. Interior knots are doubled until every section meets it.
WIRE_FIT_RELATIVE_TOLERANCE = 2e-4


DEGREE = 3


@dataclass(frozen=True)
class SectionFit:
    """Compatible cubic B-splines of all sections, kept as plain arrays.

    Attributes:
        poles: ``(sections, m, 3)`` float, mm; pole 0 and pole m-1 are the trailing edge (its
            upper corner when blunt; the lower corner is pole 3, the base poles 0-3).
        knots: ``(m + 4,)`` float, clamped knot vector on [0, 1] shared by every section;
            a blunt edge's lower corner is an interior knot of multiplicity 3.
        corners: ``(c,)`` float, the curves' C0 corners (:func:`corner_knots` of ``knots``): a
            blunt edge's lower corner, none for a sharp edge; the kernel splits the wires there.
        fit_error: largest distance (mm) from a sampled point to its section's curve.
        round_trailing_edge: whether the base (poles 0-3) is a round cap, G1 with the airfoil.
        leading_edge_parameter: the curves' parameter (in [0, 1]) at the leading edge, where a
            sharp section's wire is split into its lower and upper edges.
    """

    poles: NDArray[np.float64]
    knots: NDArray[np.float64]
    corners: NDArray[np.float64]
    fit_error: float
    round_trailing_edge: bool = False
    leading_edge_parameter: float = 0.5


def corner_knots(knots: NDArray[np.float64]) -> NDArray[np.float64]:
    """Interior knots of multiplicity DEGREE: C0 corners of the curve (a blunt trailing edge's lower
    corner)."""
    distinct, multiplicities = np.unique(knots, return_counts=True)
    return distinct[1:-1][multiplicities[1:-1] >= DEGREE]


def _closed_from_trailing_edge(
    section_points: NDArray[np.float64], trailing_edge_index: int
) -> NDArray[np.float64]:
    """Reorder ``(sections, p, 3)`` rings to start at the trailing edge and repeat it at the end."""
    rolled = np.roll(section_points, -trailing_edge_index, axis=1)
    return np.concatenate([rolled, rolled[:, :1]], axis=1)


def _fit(
    points: NDArray[np.float64], parameters: NDArray[np.float64], interior_knots: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Open clamped cubic least-squares fits of ``(sections, q, 3)`` with pinned ends: poles, knots,
    errors."""
    inner = np.quantile(parameters[1:-1], np.linspace(0.0, 1.0, interior_knots + 2)[1:-1])
    knots = np.concatenate(
        [np.full(DEGREE + 1, parameters[0]), inner, np.full(DEGREE + 1, parameters[-1])]
    )
    weights = np.ones(len(parameters))
    weights[[0, -1]] = 1e4  # pull the ends onto the trailing edge; they are then set exactly
    poles = np.stack(
        [make_lsq_spline(parameters, ring, knots, k=DEGREE, w=weights).c for ring in points]
    )
    poles[:, 0], poles[:, -1] = points[:, 0], points[:, -1]
    fitted = np.stack([_evaluate(ring_poles, knots, parameters) for ring_poles in poles])
    return poles, knots, np.linalg.norm(fitted - points, axis=-1)


def _fit_with_base(
    points: NDArray[np.float64],
    parameters: NDArray[np.float64],
    corner: int,
    interior_knots: int,
    round_cap: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Like :func:`_fit`, with columns 0..corner the base (one Bezier span) before the airfoil:
    straight, or a round cap (module docstring)."""
    poles, knots, error = _fit(points[:, corner:], parameters[corner:], interior_knots)
    start, end = points[:, 0], points[:, corner]
    if round_cap:
        base_poles = _round_cap_poles(start, end, poles[:, -2], poles[:, 1])
    else:
        base_poles = np.stack(
            [start + fraction * (end - start) for fraction in (0.0, 1 / 3, 2 / 3)], axis=1
        )
    all_poles = np.concatenate([base_poles, poles], axis=1)
    # knots[:4] = the corner's parameter
    all_knots = np.concatenate([np.zeros(DEGREE + 1), knots[1:]])
    base_fit = np.stack(
        [_evaluate(ring, all_knots, parameters[: corner + 1]) for ring in all_poles]
    )
    base_error = np.linalg.norm(base_fit - points[:, : corner + 1], axis=-1)
    return all_poles, all_knots, np.concatenate([base_error[:, :-1], error], axis=1)


def _round_cap_poles(
    upper: NDArray[np.float64],
    lower: NDArray[np.float64],
    before_upper: NDArray[np.float64],
    after_lower: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The cap's first three poles U, U + h T_u, L + h T_l: ``(sections, 3, 3)`` mm.

    ``before_upper`` and ``after_lower`` are the airfoil curve's poles next to U and L, so that
    T_u, T_l (unit, pointing aft) continue its end tangents: the curve is G1 at both ends of the
    cap.
    """
    handle = ROUND_CAP_HANDLE_FRACTION * np.linalg.norm(upper - lower, axis=-1)
    tangents = np.stack([upper - before_upper, lower - after_lower], axis=1)
    tangents /= np.linalg.norm(tangents, axis=-1, keepdims=True)
    return round_cap_poles(
        np.stack([upper, lower], axis=1), tangents, np.stack([handle, handle], axis=1)
    )[:, :3]


def _evaluate(
    poles: NDArray[np.float64], knots: NDArray[np.float64], parameters: NDArray[np.float64]
) -> NDArray[np.float64]:
    return BSpline(knots, poles, DEGREE)(parameters)


def fit_sections(
    section_points: NDArray[np.float64],
    trailing_edge_index: int,
    chord_lengths: NDArray[np.float64],
    lower_corner_index: int | None = None,
    round_trailing_edge: bool = False,
) -> SectionFit:
    """Fit compatible closed B-splines to sampled sections (kernel-free; the kernel makes wires of
    them).

    Args:
        section_points: ``(sections, p, 3)`` float, mm; closed rings (last point != first).
        trailing_edge_index: column of the sharp trailing edge (the upper corner of a blunt
            one) in every ring.
        chord_lengths: ``(sections,)`` mm, the local chords that scale the fit tolerance.
        lower_corner_index: column of a blunt trailing edge's lower corner (the base runs
            from ``trailing_edge_index`` to it); None for a sharp edge.
        round_trailing_edge: the base is a round cap (module docstring), not straight.

    The parameter of each point is the mean normalised chord-length position over all
    sections (identical for all sections, so corresponding points match in the loft).
    Interior knots start at WIRE_FIT_INITIAL_KNOTS and double until every point lies
    within WIRE_FIT_RELATIVE_TOLERANCE x chord of its curve.
    """
    points = _closed_from_trailing_edge(section_points, trailing_edge_index)
    corner = (
        None
        if lower_corner_index is None
        else (lower_corner_index - trailing_edge_index) % section_points.shape[1]
    )
    steps = np.linalg.norm(np.diff(points, axis=1), axis=-1)
    cumulative = np.concatenate([np.zeros((len(points), 1)), np.cumsum(steps, axis=1)], axis=1)
    parameters = (cumulative / cumulative[:, -1:]).mean(axis=0)
    allowed = WIRE_FIT_RELATIVE_TOLERANCE * np.asarray(chord_lengths)[:, None]
    most = len(parameters) - (corner or 0) - DEGREE - 2
    interior = min(WIRE_FIT_INITIAL_KNOTS, most)
    while True:
        if corner is None:
            poles, knots, error = _fit(points, parameters, interior)
        else:
            poles, knots, error = _fit_with_base(
                points, parameters, corner, interior, round_trailing_edge
            )
        if np.all(error <= allowed) or interior >= min(WIRE_FIT_MAXIMUM_KNOTS, most):
            _check_trailing_edge_resolved(poles, knots, len(parameters) - 1)
            leading_edge = float(
                parameters[(len(parameters) - 1 - trailing_edge_index) % (len(parameters) - 1)]
            )
            return SectionFit(
                poles,
                knots,
                corner_knots(knots),
                float(error.max()),
                corner is not None and round_trailing_edge,
                leading_edge,
            )
        interior = min(2 * interior, WIRE_FIT_MAXIMUM_KNOTS, most)


def _check_trailing_edge_resolved(
    poles: NDArray[np.float64], knots: NDArray[np.float64], points: int, samples: int = 150
) -> None:
    """Refuse sections whose curve crosses itself next to the sharp trailing edge.

    With few points around a thin, strongly hooked trailing edge (camber far aft) the cubic
    through the samples overshoots there and the curve's first and last spans cross; the
    loft and the fuse then fail (found by scripts/fuzz.py). Tests, in each section's plane,
    the first tenth of the curve against the last tenth.
    """
    # after a blunt edge's base
    first = float(corner_knots(knots)[-1]) if len(corner_knots(knots)) else 0.0
    u = np.linspace(0.0, 0.1, samples) * (1.0 - first)
    for ring in poles[:: max(1, len(poles) // 4)]:  # the sections are affine images of one airfoil
        curve = BSpline(knots, ring, DEGREE)
        start, end = curve(first + u), curve(1.0 - u)[::-1]
        centre = ring.mean(axis=0)
        basis = np.linalg.svd(ring - centre, full_matrices=False)[2][:2]
        a, b = (start - centre) @ basis.T, (end - centre) @ basis.T
        if _polylines_cross(a[1:], b[:-1]):  # skip the shared trailing-edge point itself
            raise GeometryError(
                f"resolution.points = {points} is too few for "
                "this airfoil's trailing edge: the section curve "
                "crosses itself there (a thin, hooked trailing edge); raise resolution.points "
                f"(e.g. to {max(2 * points, 48)}), the thickness, or move camber_position forward"
            )


def _polylines_cross(first: NDArray[np.float64], second: NDArray[np.float64]) -> bool:
    """Whether two 2D polylines ``(n, 2)`` and ``(m, 2)`` have a proper segment crossing."""
    p, q = first[:-1, None, :], first[1:, None, :]
    r, t = second[None, :-1, :], second[None, 1:, :]

    def orient(
        a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )

    return bool(
        np.any((orient(p, q, r) * orient(p, q, t) < 0) & (orient(r, t, p) * orient(r, t, q) < 0))
    )
