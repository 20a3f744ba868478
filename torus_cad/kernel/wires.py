"""Section wires: each sampled section becomes one closed cubic B-spline (arrays in, wire out).

Every section is fitted by least squares with the *same* knot vector and the same parameter
values, so all section curves are compatible and the loft needs no knot insertion (which
keeps the blade surface light and the boolean fast). Each curve starts and ends exactly at
the sharp trailing edge: the corner is the curve's end point, a C0 joint, so the spline
never has to turn through it and cannot overshoot or self-intersect there. The fit itself is
kernel-free (:mod:`torus_cad.geometry.section.section_fit`), so that its refusals come before the
kernel loads.

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
* A round cap (:mod:`torus_cad.geometry.blade.trailing_edge`) is the span U, U + h T_u, L + h T_l, L
  with h = 2/3 |U - L| (mm) and T_u, T_l the airfoil curve's own end tangents (the directions of
  its end poles, which the fit takes from the sampled surfaces): the cap's inner poles are
  collinear with the airfoil's end poles, so the curve is G1 at U and L (no corner), and the
  blade's cap face meets its airfoil face tangentially. The geometry's cap is the same Bezier
  span with the surfaces' exact end tangents; the two differ by the fit's tangent error times
  h, and the fit's error check covers the cap's sample points.

For the root fillet, :meth:`SectionCurves.wires` can also split the airfoil edge into equal
pieces in parameter (exact copies of its spans, :meth:`Geom_BSplineCurve.Segment`): with a
round cap the blade's airfoil face is not closed, so the fillet's split of closed side faces
(:mod:`torus_cad.kernel.fillet.root_fillet`) does not apply, and the fillet rolls round the cap only
with the airfoil face in pieces (measured: README, "Root fillet").
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire
from OCP.Geom import Geom_BSplineCurve
from OCP.gp import gp_Pnt
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopoDS import TopoDS_Edge, TopoDS_Wire

from torus_cad.errors import KernelError
from torus_cad.geometry.section.section_fit import DEGREE, SectionFit

if TYPE_CHECKING:
    import cadquery as cq

__all__ = [
    "DEGREE",
    "SectionCurves",
    "bspline_wire",
    "knot_arrays",
    "occ_bspline_wire",
    "section_curves",
]


@dataclass(frozen=True)
class SectionCurves(SectionFit):
    """Compatible cubic B-splines of all sections
    (:class:`torus_cad.geometry.section.section_fit.SectionFit`: plain arrays), and the section
    wires the loft takes."""

    def wires(self, airfoil_pieces: int = 1, split_sharp: bool = True) -> list[cq.Wire]:
        """:meth:`occ_wires` as cadquery's wires."""
        import cadquery as cq

        return [cq.Wire(wire) for wire in self.occ_wires(airfoil_pieces, split_sharp)]

    def occ_wires(self, airfoil_pieces: int = 1, split_sharp: bool = True) -> list[TopoDS_Wire]:
        """One closed wire per section (OpenCascade's).

        Sharp trailing edge: with ``airfoil_pieces`` 1, two edges (lower and upper surface, split
        at the leading edge; one closed edge with ``split_sharp`` False, for the root fillet, which
        splits the closed face itself: torus_cad.kernel.fillet.root_fillet); otherwise
        ``airfoil_pieces`` edges of equal parameter ranges. Blunt: the base and the airfoil edge,
        the latter split into ``airfoil_pieces`` equal ranges.
        """
        split = self.leading_edge_parameter if split_sharp else None
        return [
            occ_bspline_wire(poles, self.knots, self.corners, airfoil_pieces, split)
            for poles in self.poles
        ]


def section_curves(fit: SectionFit) -> SectionCurves:
    """The section curves ``fit`` (torus_cad.geometry.section.section_fit.fit_sections) as curves
    that make wires."""
    return SectionCurves(**{field.name: getattr(fit, field.name) for field in fields(fit)})


def knot_arrays(knots: NDArray[np.float64]) -> tuple[TColStd_Array1OfReal, TColStd_Array1OfInteger]:
    """OpenCascade's distinct knots and multiplicities from a full (repeated) knot vector."""
    distinct, multiplicities = np.unique(knots, return_counts=True)
    knot_array = TColStd_Array1OfReal(1, len(distinct))
    multiplicity_array = TColStd_Array1OfInteger(1, len(distinct))
    for index, (knot, multiplicity) in enumerate(zip(distinct, multiplicities), start=1):
        knot_array.SetValue(index, float(knot))
        multiplicity_array.SetValue(index, int(multiplicity))
    return knot_array, multiplicity_array


def _bspline_curve(poles: NDArray[np.float64], knots: NDArray[np.float64]) -> Geom_BSplineCurve:
    pole_array = TColgp_Array1OfPnt(1, len(poles))
    for index, (x, y, z) in enumerate(poles, start=1):
        pole_array.SetValue(index, gp_Pnt(float(x), float(y), float(z)))
    knot_array, multiplicity_array = knot_arrays(knots)
    return Geom_BSplineCurve(pole_array, knot_array, multiplicity_array, DEGREE)


def _segment(curve: Geom_BSplineCurve, first: float, last: float) -> Geom_BSplineCurve:
    """The part of ``curve`` on [first, last], as a B-spline of its own (the same spans, clamped
    there)."""
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


def bspline_wire(
    poles: NDArray[np.float64],
    knots: NDArray[np.float64],
    corners: NDArray[np.float64],
    last_pieces: int = 1,
    closed_split: float | None = 0.5,
) -> cq.Wire:
    """:func:`occ_bspline_wire` as cadquery's wire."""
    import cadquery as cq

    return cq.Wire(occ_bspline_wire(poles, knots, corners, last_pieces, closed_split))


def occ_bspline_wire(
    poles: NDArray[np.float64],
    knots: NDArray[np.float64],
    corners: NDArray[np.float64],
    last_pieces: int = 1,
    closed_split: float | None = 0.5,
) -> TopoDS_Wire:
    """A closed wire (OpenCascade's) from ``(m, 3)`` poles and a full knot vector of a non-rational
    cubic B-spline.

    One edge per piece between the C0 corner knots ``corners`` (``SectionFit.corners``), so that
    each piece
    lofts into its own face; the last piece (the airfoil) is further split into ``last_pieces``
    equal parameter ranges. A curve without corners (a sharp trailing edge, whose crease is the
    curve's start and end) is never left as one closed edge: with ``last_pieces`` 1 it is split
    at the parameter ``closed_split`` (the leading edge) into two (None: one closed edge).
    """
    builder = BRepBuilderAPI_MakeWire()
    pieces = _pieces(np.asarray(poles, float), np.asarray(knots, float), corners)
    for index, (piece_poles, piece_knots) in enumerate(pieces):
        edge_curve = _bspline_curve(piece_poles, piece_knots)
        count = last_pieces if index == len(pieces) - 1 else 1
        bounds = np.linspace(piece_knots[0], piece_knots[-1], count + 1)
        if len(pieces) == 1 and count == 1 and closed_split is not None:
            bounds = np.array([piece_knots[0], closed_split, piece_knots[-1]])
        for first, last in itertools.pairwise(bounds):
            segment = (
                edge_curve if len(bounds) == 2 else _segment(edge_curve, float(first), float(last))
            )
            builder.Add(_edge(segment))
    if not builder.IsDone():
        raise KernelError("OpenCascade could not make a closed section wire")
    return builder.Wire()


def _pieces(
    poles: NDArray[np.float64], knots: NDArray[np.float64], corners: NDArray[np.float64]
) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """The curve split at its C0 corner knots: ``(poles, knots)`` per piece, pieces share their
    corner pole."""
    pieces = []
    start_pole, start_knot = 0, knots[0]
    for corner in corners:
        first = int(np.searchsorted(knots, corner, side="left"))  # index of the corner's first copy
        pole = first - 1  # the one basis function alive at a knot of multiplicity DEGREE
        inner = knots[(knots > start_knot) & (knots < corner)]
        pieces.append(
            (
                poles[start_pole : pole + 1],
                np.concatenate(
                    [np.full(DEGREE + 1, start_knot), inner, np.full(DEGREE + 1, corner)]
                ),
            )
        )
        start_pole, start_knot = pole, corner
    inner = knots[(knots > start_knot) & (knots < knots[-1])]
    pieces.append(
        (
            poles[start_pole:],
            np.concatenate(
                [np.full(DEGREE + 1, start_knot), inner, np.full(DEGREE + 1, knots[-1])]
            ),
        )
    )
    return pieces
