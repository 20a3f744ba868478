"""Section wires: each sampled section becomes one closed cubic B-spline (arrays in, wire out).

Every section is fitted by least squares with the *same* knot vector and the same parameter
values, so all section curves are compatible and the loft needs no knot insertion (which
keeps the blade surface light and the boolean fast). Each curve starts and ends exactly at
the sharp trailing edge: the corner is the curve's end point, a C0 joint, so the spline
never has to turn through it and cannot overshoot or self-intersect there.

The wire of a sharp section is two edges, the lower surface (trailing edge to leading edge)
and the upper one (back to the trailing edge), split at the leading edge's curve parameter
(:attr:`SectionCurves.leading_edge_parameter`, the same in every section): the loft then
gives each surface its own face and the trailing edge is a true edge between them. One
closed edge would loft into one face closed in u with its C0 crease inside the face, which
OpenCascade's self-interference check (BRepAlgoAPI_Check) flags as a self-intersecting face.

A blunt trailing edge has a base between the surfaces' ends U (upper) and L (lower). The curve
then starts at U, runs along the base to L (one Bezier span), and on over the lower surface,
the leading edge and the upper surface back to U; L is a knot of multiplicity 3. The wire is
split there into two edges, the base and the airfoil, so the loft gives the base its own face.

* A flat base is a span with collinear poles: U and L are corners (C0).
* A round cap (:mod:`torus_cad.geometry.extensions.trailing_edge`) is the span U, U + h T_u, L + h T_l, L
  with h = 2/3 |U - L| (mm) and T_u, T_l the airfoil curve's own end tangents (the directions of
  its end poles, which the fit takes from the sampled surfaces): the cap's inner poles are
  collinear with the airfoil's end poles, so the curve is G1 at U and L (no corner), and the
  blade's cap face meets its airfoil face tangentially. The geometry's cap is the same Bezier
  span with the surfaces' exact end tangents; the two differ by the fit's tangent error times
  h, and the fit's error check covers the cap's sample points.

For the root fillet, :meth:`SectionCurves.wires` can also split the airfoil edge into equal
pieces in parameter (exact copies of its spans, :meth:`Geom_BSplineCurve.Segment`): with a
round cap the blade's airfoil face is not closed, so the fillet's split of closed side faces
(:mod:`torus_cad.kernel.fillet`) does not apply, and the fillet rolls round the cap only with
the airfoil face in pieces (measured: README, "Root fillet").
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
from OCP.Geom import Geom_BSplineCurve
from OCP.gp import gp_Pnt
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopoDS import TopoDS_Edge
from scipy.interpolate import BSpline, make_lsq_spline

from torus_cad.errors import GeometryError, KernelError
from torus_cad.geometry.extensions.trailing_edge import ROUND_CAP_HANDLE_FRACTION
from torus_cad.geometry.section import round_cap_poles
from torus_cad.tolerances import WIRE_FIT_INITIAL_KNOTS, WIRE_FIT_MAXIMUM_KNOTS, WIRE_FIT_RELATIVE_TOLERANCE

DEGREE = 3


@dataclass(frozen=True)
class SectionCurves:
    """Compatible cubic B-splines of all sections, kept as plain arrays.

    Attributes:
        poles: ``(sections, m, 3)`` float, mm; pole 0 and pole m-1 are the trailing edge (its
            upper corner when blunt; the lower corner is pole 3, the base poles 0-3).
        knots: ``(m + 4,)`` float, clamped knot vector on [0, 1] shared by every section;
            a blunt edge's lower corner is an interior knot of multiplicity 3.
        fit_error: largest distance (mm) from a sampled point to its section's curve.
        round_trailing_edge: whether the base (poles 0-3) is a round cap, G1 with the airfoil.
        leading_edge_parameter: the curves' parameter (in [0, 1]) at the leading edge, where a
            sharp section's wire is split into its lower and upper edges.
    """

    poles: NDArray[np.float64]
    knots: NDArray[np.float64]
    fit_error: float
    round_trailing_edge: bool = False
    leading_edge_parameter: float = 0.5

    def wires(self, airfoil_pieces: int = 1, split_sharp: bool = True) -> list[cq.Wire]:
        """One closed wire per section.

        Sharp trailing edge: with ``airfoil_pieces`` 1, two edges (lower and upper surface, split
        at the leading edge; one closed edge with ``split_sharp`` False, for the root fillet, which
        splits the closed face itself: torus_cad.kernel.fillet); otherwise ``airfoil_pieces`` edges
        of equal parameter ranges. Blunt: the base and the airfoil edge, the latter split into
        ``airfoil_pieces`` equal ranges.
        """
        split = self.leading_edge_parameter if split_sharp else None
        return [bspline_wire(poles, self.knots, airfoil_pieces, split) for poles in self.poles]


def _closed_from_trailing_edge(section_points: NDArray[np.float64], trailing_edge_index: int) -> NDArray[np.float64]:
    """Reorder ``(sections, p, 3)`` rings to start at the trailing edge and repeat it at the end."""
    rolled = np.roll(section_points, -trailing_edge_index, axis=1)
    return np.concatenate([rolled, rolled[:, :1]], axis=1)


def _fit(points: NDArray[np.float64], parameters: NDArray[np.float64], interior_knots: int
         ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Open clamped cubic least-squares fits of ``(sections, q, 3)`` with pinned ends: poles, knots, errors."""
    inner = np.quantile(parameters[1:-1], np.linspace(0.0, 1.0, interior_knots + 2)[1:-1])
    knots = np.concatenate([np.full(DEGREE + 1, parameters[0]), inner, np.full(DEGREE + 1, parameters[-1])])
    weights = np.ones(len(parameters))
    weights[[0, -1]] = 1e4  # pull the ends onto the trailing edge; they are then set exactly
    poles = np.stack([make_lsq_spline(parameters, ring, knots, k=DEGREE, w=weights).c for ring in points])
    poles[:, 0], poles[:, -1] = points[:, 0], points[:, -1]
    fitted = np.stack([_evaluate(ring_poles, knots, parameters) for ring_poles in poles])
    return poles, knots, np.linalg.norm(fitted - points, axis=-1)


def _fit_with_base(points: NDArray[np.float64], parameters: NDArray[np.float64], corner: int, interior_knots: int,
                   round_cap: bool = False) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Like :func:`_fit`, with columns 0..corner the base (one Bezier span) before the airfoil:
    straight, or a round cap (module docstring)."""
    poles, knots, error = _fit(points[:, corner:], parameters[corner:], interior_knots)
    start, end = points[:, 0], points[:, corner]
    if round_cap:
        base_poles = _round_cap_poles(start, end, poles[:, -2], poles[:, 1])
    else:
        base_poles = np.stack([start + fraction * (end - start) for fraction in (0.0, 1 / 3, 2 / 3)], axis=1)
    all_poles = np.concatenate([base_poles, poles], axis=1)
    all_knots = np.concatenate([np.zeros(DEGREE + 1), knots[1:]])  # knots[:4] = the corner's parameter
    base_fit = np.stack([_evaluate(ring, all_knots, parameters[:corner + 1]) for ring in all_poles])
    base_error = np.linalg.norm(base_fit - points[:, :corner + 1], axis=-1)
    return all_poles, all_knots, np.concatenate([base_error[:, :-1], error], axis=1)


def _round_cap_poles(upper: NDArray[np.float64], lower: NDArray[np.float64], before_upper: NDArray[np.float64],
                     after_lower: NDArray[np.float64]) -> NDArray[np.float64]:
    """The cap's first three poles U, U + h T_u, L + h T_l: ``(sections, 3, 3)`` mm.

    ``before_upper`` and ``after_lower`` are the airfoil curve's poles next to U and L, so that
    T_u, T_l (unit, pointing aft) continue its end tangents: the curve is G1 at both ends of the cap.
    """
    handle = ROUND_CAP_HANDLE_FRACTION * np.linalg.norm(upper - lower, axis=-1)
    tangents = np.stack([upper - before_upper, lower - after_lower], axis=1)
    tangents /= np.linalg.norm(tangents, axis=-1, keepdims=True)
    return round_cap_poles(np.stack([upper, lower], axis=1), tangents, np.stack([handle, handle], axis=1))[:, :3]


def _evaluate(poles: NDArray[np.float64], knots: NDArray[np.float64], parameters: NDArray[np.float64]) -> NDArray[np.float64]:
    return BSpline(knots, poles, DEGREE)(parameters)


def fit_section_curves(section_points: NDArray[np.float64], trailing_edge_index: int,
                       chord_lengths: NDArray[np.float64], lower_corner_index: int | None = None,
                       round_trailing_edge: bool = False) -> SectionCurves:
    """Fit compatible closed B-splines to sampled sections.

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
    corner = None if lower_corner_index is None else (lower_corner_index - trailing_edge_index) % section_points.shape[1]
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
            poles, knots, error = _fit_with_base(points, parameters, corner, interior, round_trailing_edge)
        if np.all(error <= allowed) or interior >= min(WIRE_FIT_MAXIMUM_KNOTS, most):
            _check_trailing_edge_resolved(poles, knots, len(parameters) - 1)
            leading_edge = float(parameters[(len(parameters) - 1 - trailing_edge_index) % (len(parameters) - 1)])
            return SectionCurves(poles, knots, float(error.max()), corner is not None and round_trailing_edge,
                                 leading_edge)
        interior = min(2 * interior, WIRE_FIT_MAXIMUM_KNOTS, most)


def _check_trailing_edge_resolved(poles: NDArray[np.float64], knots: NDArray[np.float64], points: int,
                                  samples: int = 150) -> None:
    """Refuse sections whose curve crosses itself next to the sharp trailing edge.

    With few points around a thin, strongly hooked trailing edge (camber far aft) the cubic
    through the samples overshoots there and the curve's first and last spans cross; the
    loft and the fuse then fail (found by scripts/fuzz.py). Tests, in each section's plane,
    the first tenth of the curve against the last tenth.
    """
    first = float(_corner_knots(knots)[-1]) if len(_corner_knots(knots)) else 0.0  # after a blunt edge's base
    u = np.linspace(0.0, 0.1, samples) * (1.0 - first)
    for ring in poles[:: max(1, len(poles) // 4)]:  # the sections are affine images of one airfoil
        curve = BSpline(knots, ring, DEGREE)
        start, end = curve(first + u), curve(1.0 - u)[::-1]
        centre = ring.mean(axis=0)
        basis = np.linalg.svd(ring - centre, full_matrices=False)[2][:2]
        a, b = (start - centre) @ basis.T, (end - centre) @ basis.T
        if _polylines_cross(a[1:], b[:-1]):  # skip the shared trailing-edge point itself
            raise GeometryError(
                f"resolution.points = {points} is too few for this airfoil's trailing edge: the section curve "
                "crosses itself there (a thin, hooked trailing edge); raise resolution.points "
                f"(e.g. to {max(2 * points, 48)}), the thickness, or move camber_position forward")


def _polylines_cross(first: NDArray[np.float64], second: NDArray[np.float64]) -> bool:
    """Whether two 2D polylines ``(n, 2)`` and ``(m, 2)`` have a proper segment crossing."""
    p, q = first[:-1, None, :], first[1:, None, :]
    r, t = second[None, :-1, :], second[None, 1:, :]

    def orient(a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.sign((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))

    return bool(np.any((orient(p, q, r) * orient(p, q, t) < 0) & (orient(r, t, p) * orient(r, t, q) < 0)))


def knot_arrays(knots: NDArray[np.float64]) -> tuple[TColStd_Array1OfReal, TColStd_Array1OfInteger]:
    """OpenCascade's distinct knots and multiplicities from a full (repeated) knot vector."""
    distinct, multiplicities = np.unique(knots, return_counts=True)
    knot_array = TColStd_Array1OfReal(1, len(distinct))
    multiplicity_array = TColStd_Array1OfInteger(1, len(distinct))
    for index, (knot, multiplicity) in enumerate(zip(distinct, multiplicities), start=1):
        knot_array.SetValue(index, float(knot))
        multiplicity_array.SetValue(index, int(multiplicity))
    return knot_array, multiplicity_array


def _corner_knots(knots: NDArray[np.float64]) -> NDArray[np.float64]:
    """Interior knots of multiplicity DEGREE: C0 corners of the curve (a blunt trailing edge's lower corner)."""
    distinct, multiplicities = np.unique(knots, return_counts=True)
    return distinct[1:-1][multiplicities[1:-1] >= DEGREE]


def _bspline_curve(poles: NDArray[np.float64], knots: NDArray[np.float64]) -> Geom_BSplineCurve:
    pole_array = TColgp_Array1OfPnt(1, len(poles))
    for index, (x, y, z) in enumerate(poles, start=1):
        pole_array.SetValue(index, gp_Pnt(float(x), float(y), float(z)))
    knot_array, multiplicity_array = knot_arrays(knots)
    return Geom_BSplineCurve(pole_array, knot_array, multiplicity_array, DEGREE)


def _segment(curve: Geom_BSplineCurve, first: float, last: float) -> Geom_BSplineCurve:
    """The part of ``curve`` on [first, last], as a B-spline of its own (the same spans, clamped there)."""
    piece = curve.Copy()  # OCP hands back the copy as a Geom_BSplineCurve
    if not isinstance(piece, Geom_BSplineCurve):
        raise KernelError("OpenCascade did not copy a section's B-spline as a B-spline")
    piece.Segment(first, last)
    return piece


def _edge(curve: Geom_BSplineCurve) -> TopoDS_Edge:
    edge = BRepBuilderAPI_MakeEdge(curve)
    if not edge.IsDone():
        raise KernelError("OpenCascade could not make a section edge from its B-spline")
    return edge.Edge()


def bspline_wire(poles: NDArray[np.float64], knots: NDArray[np.float64], last_pieces: int = 1,
                 closed_split: float | None = 0.5) -> cq.Wire:
    """A closed wire from ``(m, 3)`` poles and a full knot vector of a non-rational cubic B-spline.

    One edge per piece between C0 corner knots (see :func:`_corner_knots`), so that each piece
    lofts into its own face; the last piece (the airfoil) is further split into ``last_pieces``
    equal parameter ranges. A curve without corners (a sharp trailing edge, whose crease is the
    curve's start and end) is never left as one closed edge: with ``last_pieces`` 1 it is split
    at the parameter ``closed_split`` (the leading edge) into two (None: one closed edge).
    """
    builder = BRepBuilderAPI_MakeWire()
    pieces = _pieces(np.asarray(poles, float), np.asarray(knots, float))
    for index, (piece_poles, piece_knots) in enumerate(pieces):
        edge_curve = _bspline_curve(piece_poles, piece_knots)
        count = last_pieces if index == len(pieces) - 1 else 1
        bounds = np.linspace(piece_knots[0], piece_knots[-1], count + 1)
        if len(pieces) == 1 and count == 1 and closed_split is not None:
            bounds = np.array([piece_knots[0], closed_split, piece_knots[-1]])
        for first, last in itertools.pairwise(bounds):
            segment = edge_curve if len(bounds) == 2 else _segment(edge_curve, float(first), float(last))
            builder.Add(_edge(segment))
    if not builder.IsDone():
        raise KernelError("OpenCascade could not make a closed section wire")
    return cq.Wire(builder.Wire())


def _pieces(poles: NDArray[np.float64], knots: NDArray[np.float64]
            ) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """The curve split at its C0 corner knots: ``(poles, knots)`` per piece, pieces share their corner pole."""
    pieces = []
    start_pole, start_knot = 0, knots[0]
    for corner in _corner_knots(knots):
        first = int(np.searchsorted(knots, corner, side="left"))  # index of the corner's first copy
        pole = first - 1  # the one basis function alive at a knot of multiplicity DEGREE
        inner = knots[(knots > start_knot) & (knots < corner)]
        pieces.append((poles[start_pole:pole + 1],
                       np.concatenate([np.full(DEGREE + 1, start_knot), inner, np.full(DEGREE + 1, corner)])))
        start_pole, start_knot = pole, corner
    inner = knots[(knots > start_knot) & (knots < knots[-1])]
    pieces.append((poles[start_pole:], np.concatenate([np.full(DEGREE + 1, start_knot), inner,
                                                       np.full(DEGREE + 1, knots[-1])])))
    return pieces
