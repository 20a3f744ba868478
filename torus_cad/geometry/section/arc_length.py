"""Equal arc-length resampling of the closed airfoil section (spec §5).

Method, as the spec's §5.2: the arc length s(t) is tabulated on a fine grid by Gauss-Legendre
quadrature of |f'| on every grid interval (ARC_LENGTH_GAUSS_POINTS nodes each, numpy's
``leggauss``, all intervals in one vectorised evaluation), then t(s) is read off the table by
linear interpolation. The table agrees with QUADPACK's adaptive Gauss-Kronrod quadrature
(``scipy.integrate.quad_vec``, used before) within ARC_LENGTH_QUAD_ABS for NACA sections, blunt
and round trailing edges and coordinate files (tests/test_arc_length.py); scipy.integrate is
not loaded.

The leading edge needs care: y_t grows like sqrt(t), so |f'(t)| is infinite at t = 0 and a
uniform grid in t is far too coarse there. Both the quadrature and the table therefore run
in u = sqrt(t) on each surface, where |df/du| is bounded; the spec's t is recovered as
t = u^2 (upper) and t = 2 - u^2 (lower).

Any :class:`~torus_cad.geometry.section.section.Section` is sampled this way (NACA 4- and 5-digit,
.dat files). A section with a blunt trailing edge has a third piece, the base between the two
surfaces' ends (straight, or a round cap, :mod:`torus_cad.geometry.section.section`); it takes its
share of the points like the surfaces, equally spaced in its own arc length, so the spacing covers
it too, and both of its ends are sample points.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import ParameterError
from torus_cad.geometry.section.airfoil import airfoil_points
from torus_cad.geometry.section.section import (
    RoundTrailingEdge,
    Section,
    cap_length,
    cap_parameter_at,
    cap_points,
    has_base,
)

#: Gauss-Legendre nodes per interval of the arc-length table: 10 keep
#: the table within 1.1e-11 chord of adaptive Gauss-Kronrod quadrature at ARC_LENGTH_QUAD_ABS on
#: coordinate files (2e-16 on NACA sections), where 5 leave 1.3e-10 (tests/test_arc_length.py).
ARC_LENGTH_GAUSS_POINTS = 10
#: Absolute tolerance of the arc-length quadrature of |f'(t)| (chord units): the table agrees within
#: it with QUADPACK's adaptive Gauss-Kronrod quadrature run to it (tests/test_arc_length.py).
ARC_LENGTH_QUAD_ABS = 1e-10

#: Fine grid of the arc-length table, both surfaces together (spec §5.2: n_fine, whose default
#: is 1000); 4000 keeps the spacing even for strongly cambered sections (cost and spacing measured:
#: the docs' measurements page).
ARC_LENGTH_FINE_SAMPLES = 4000


@dataclass(frozen=True)
class ArcLengthTable:
    """Cumulative arc length of one surface against u = sqrt(chord position).

    Attributes:
        root_chord: ``(k,)`` float, u from 0 (leading edge) to 1 (trailing edge).
        arc_length: ``(k,)`` float, arc length from the leading edge, chord units.
    """

    root_chord: NDArray[np.float64]
    arc_length: NDArray[np.float64]

    @property
    def total(self) -> float:
        """Arc length of the whole surface, leading edge to trailing edge (chord units)."""
        return float(self.arc_length[-1])

    def root_chord_at(self, arc_length: NDArray[np.float64]) -> NDArray[np.float64]:
        """u at the given arc lengths from the leading edge (linear interpolation, spec §5.2
        step 4).

        Args:
            arc_length: float array of any shape, arc lengths from the leading edge, chord units
                (clamped to [0, :attr:`total`]).

        Returns:
            u = sqrt(chord position), in [0, 1], the shape of ``arc_length``.
        """
        return np.interp(arc_length, self.arc_length, self.root_chord)


@dataclass(frozen=True)
class SectionSampling:
    """Points of one section equally spaced in arc length, starting at the leading edge.

    Attributes:
        t: ``(n,)`` float, the closed-curve parameter (the spec's, in [0, 2), for a sharp
            section; in [0, 3) with a base, see
            :func:`torus_cad.geometry.section.section.closed_points`).
        points: ``(n, 2)`` float, chord units, order of f(t): upper surface first.
        perimeter: arc length of the closed section, chord units.
        trailing_edge_index: index of the exact trailing-edge point (the upper corner of a
            blunt edge), or None when the spacing is the spec's single uniform spacing (which
            need not hit it).
        lower_corner_index: index of the lower corner of a blunt trailing edge (the base runs
            from ``trailing_edge_index`` to it); None for a sharp edge or the uniform spacing.
        base: whether the section has a blunt trailing edge (and ``t`` the extended parameter).
    """

    t: NDArray[np.float64]
    points: NDArray[np.float64]
    perimeter: float
    trailing_edge_index: int | None
    lower_corner_index: int | None = None
    base: bool = False


def surface_arc_length_table(
    airfoil: Section, upper: bool, fine_samples: int = ARC_LENGTH_FINE_SAMPLES // 2
) -> ArcLengthTable:
    """Tabulate the arc length of the upper or lower surface on ``fine_samples`` intervals in u.

    Args:
        airfoil: the section, in chord units.
        upper: the upper surface (True) or the lower one (False).
        fine_samples: intervals of the table in u = sqrt(chord position); each of the
            section's kinks becomes a grid point as well.

    Returns:
        The table: ``root_chord`` and ``arc_length``, ``(k,)`` float arrays with k about
        ``fine_samples + 1``; arc lengths in chord units from the leading edge.
    """
    edges = np.linspace(0.0, 1.0, fine_samples + 1)
    for kink in airfoil.kinks:
        # E.g. the camber line's curvature jumps at p: make sqrt(p) a grid point so that no
        # quadrature interval (and no interpolation interval) straddles the kink.
        edges = np.union1d(edges[np.abs(edges - kink) > 0.25 / fine_samples], kink)
    starts, widths = edges[:-1], np.diff(edges)
    nodes, weights = _gauss_legendre(ARC_LENGTH_GAUSS_POINTS)
    speeds = airfoil.speed_on_half(
        (starts[:, None] + nodes[None, :] * widths[:, None]).ravel(), upper
    )
    pieces = (speeds.reshape(len(starts), len(nodes)) @ weights) * widths
    return ArcLengthTable(edges, np.concatenate([[0.0], np.cumsum(pieces)]))


@lru_cache(maxsize=4)
def _gauss_legendre(count: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Gauss-Legendre nodes and weights of ``count`` points on [0, 1] (exact for degree 2 count -
    1)."""
    nodes, weights = np.polynomial.legendre.leggauss(count)
    return 0.5 * (nodes + 1.0), 0.5 * weights


@lru_cache(maxsize=64)
def equal_arc_length_section(
    airfoil: Section,
    count: int,
    anchor_trailing_edge: bool = True,
    fine_samples: int = ARC_LENGTH_FINE_SAMPLES // 2,
) -> SectionSampling:
    """``count`` points around the closed section, equally spaced in arc length (spec §5).

    With ``anchor_trailing_edge=False`` this is the spec's procedure exactly: one spacing
    Delta s = S_total / count around the whole section. With ``True`` (used for the solid
    and the mesh) the points are shared between the surfaces (and the base of a blunt
    trailing edge) in proportion to their arc lengths, each piece is spaced equally, and the
    trailing edge's corners are always points, so the section never cuts a corner. The two
    spacings then differ by less than 1/count.

    Args:
        airfoil: the section, in chord units (any
            :class:`~torus_cad.geometry.section.section.Section`, blunt or sharp).
        count: number of points around the closed section, at least 8.
        anchor_trailing_edge: share the points between the pieces and keep the trailing edge's
            corners as points (True), or one uniform spacing, the spec's (False).
        fine_samples: intervals of each surface's arc-length table.

    Returns:
        The sampling: ``t`` ``(count,)`` float array of closed-curve parameters, ``points``
        ``(count, 2)`` float array in chord units, upper surface first, the perimeter (chord
        units) and the trailing edge's indices.

    Raises:
        ParameterError: ``count`` is below 8.
    """
    if count < 8:
        raise ParameterError(f"points = {count} is out of range; allowed [8, inf)")
    upper = surface_arc_length_table(airfoil, True, fine_samples)
    lower = surface_arc_length_table(airfoil, False, fine_samples)
    base = has_base(airfoil)
    # |U - L| unless round: below SHARP_TRAILING_EDGE_GAP when sharp
    base_length = cap_length(airfoil)
    perimeter = upper.total + base_length + lower.total
    if anchor_trailing_edge:
        lengths = np.array([upper.total, base_length, lower.total])
        counts = _shares(
            count, lengths, minimum=np.array([2, _base_minimum(airfoil) if base else 0, 2])
        )
        upper_arc = np.arange(counts[0]) * upper.total / counts[0]
        base_fraction = np.arange(counts[1]) / max(counts[1], 1)
        lower_arc = lower.total - np.arange(counts[2]) * lower.total / counts[2]
        trailing_edge_index: int | None = int(counts[0])
        lower_corner_index = int(counts[0] + counts[1]) if base else None
    else:
        arc = np.arange(count) * perimeter / count
        upper_arc = arc[arc <= upper.total]
        on_base = (arc > upper.total) & (arc < upper.total + base_length)
        base_fraction = (arc[on_base] - upper.total) / base_length if base else arc[:0]
        lower_arc = perimeter - arc[arc >= upper.total + base_length]
        trailing_edge_index = lower_corner_index = None
    upper_u, lower_u = upper.root_chord_at(upper_arc), lower.root_chord_at(lower_arc)
    lower_start = 2.0 if base else 1.0
    base_parameter = cap_parameter_at(airfoil, base_fraction)  # = the fraction on a flat base
    t = np.concatenate([upper_u**2, 1.0 + base_parameter, lower_start + 1.0 - lower_u**2])
    points = np.concatenate(
        [
            airfoil.points_on_half(upper_u, True),
            cap_points(airfoil, base_parameter),
            airfoil.points_on_half(lower_u, False),
        ]
    )
    return SectionSampling(
        t=t,
        points=points,
        perimeter=perimeter,
        trailing_edge_index=trailing_edge_index,
        lower_corner_index=lower_corner_index,
        base=base,
    )


#: Fewest points on a round cap: its polygon (the mesh's, the plots') then turns round the edge in
#: four steps (a flat base needs one: its upper corner).
ROUND_CAP_MINIMUM_POINTS = 4


def _base_minimum(airfoil: Section) -> int:
    return ROUND_CAP_MINIMUM_POINTS if isinstance(airfoil, RoundTrailingEdge) else 1


def _shares(
    count: int, lengths: NDArray[np.float64], minimum: NDArray[np.int64]
) -> NDArray[np.int64]:
    """``count`` points split between pieces in proportion to their lengths (largest remainders),
    each >= its minimum."""
    exact = count * lengths / lengths.sum()
    shares = np.maximum(np.floor(exact).astype(int), minimum)
    while shares.sum() > count:  # the minimums took points: give them back from the largest piece
        shares[int(np.argmax(shares - minimum))] -= 1
    remainder = exact - shares
    while shares.sum() < count:
        index = int(np.argmax(remainder))
        shares[index] += 1
        remainder[index] -= 1.0
    return shares


def spacing_deviation(points: NDArray[np.float64]) -> float:
    """Max relative deviation of consecutive chord lengths of a closed polygon ``(n, 2)``:
    max |d/mean(d) - 1|.

    Args:
        points: ``(n, 2)`` float array, the polygon's vertices in order (any length unit; the
            last joins the first).

    Returns:
        The largest |d / mean(d) - 1| over the n sides, dimensionless (0 for equal spacing).
    """
    gaps = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return float(np.max(np.abs(gaps / gaps.mean() - 1.0)))


__all__ = [
    "ArcLengthTable",
    "SectionSampling",
    "airfoil_points",
    "equal_arc_length_section",
    "spacing_deviation",
    "surface_arc_length_table",
]
