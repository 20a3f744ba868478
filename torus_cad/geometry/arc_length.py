"""Equal arc-length resampling of the closed airfoil section (spec §5).

Method, as the spec's §5.2: the arc length s(t) is tabulated on a fine grid by adaptive
Gauss-Kronrod quadrature of |f'| (QUADPACK's method, through ``scipy.integrate.quad_vec``,
all grid intervals in one vectorised call), then t(s) is read off the table by linear
interpolation.

The leading edge needs care: y_t grows like sqrt(t), so |f'(t)| is infinite at t = 0 and a
uniform grid in t is far too coarse there. Both the quadrature and the table therefore run
in u = sqrt(t) on each surface, where |df/du| is bounded; the spec's t is recovered as
t = u^2 (upper) and t = 2 - u^2 (lower).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import quad_vec

from torus_cad.errors import ParameterError
from torus_cad.geometry.airfoil import NacaAirfoil, airfoil_points
from torus_cad.tolerances import ARC_LENGTH_FINE_SAMPLES, ARC_LENGTH_QUAD_ABS


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
        """u at the given arc lengths from the leading edge (linear interpolation, spec §5.2 step 4)."""
        return np.interp(arc_length, self.arc_length, self.root_chord)


@dataclass(frozen=True)
class SectionSampling:
    """Points of one section equally spaced in arc length, starting at the leading edge.

    Attributes:
        t: ``(n,)`` float, the spec's closed-curve parameter in [0, 2).
        points: ``(n, 2)`` float, chord units, order of f(t): upper surface first.
        perimeter: arc length of the closed section, chord units.
        trailing_edge_index: index of the exact trailing-edge point, or None when the
            spacing is the spec's single uniform spacing (which need not hit it).
    """

    t: NDArray[np.float64]
    points: NDArray[np.float64]
    perimeter: float
    trailing_edge_index: int | None


def surface_arc_length_table(airfoil: NacaAirfoil, upper: bool,
                             fine_samples: int = ARC_LENGTH_FINE_SAMPLES // 2) -> ArcLengthTable:
    """Tabulate the arc length of the upper or lower surface on ``fine_samples`` intervals in u."""
    edges = np.linspace(0.0, 1.0, fine_samples + 1)
    if airfoil.max_camber > 0.0 and 0.0 < airfoil.camber_position < 1.0:
        # The camber line's curvature jumps at p: make sqrt(p) a grid point so that no
        # quadrature interval (and no interpolation interval) straddles the kink.
        kink = np.sqrt(airfoil.camber_position)
        edges = np.union1d(edges[np.abs(edges - kink) > 0.25 / fine_samples], kink)
    starts, widths = edges[:-1], np.diff(edges)

    def interval_speeds(fraction: float) -> NDArray[np.float64]:
        return airfoil.speed_on_half(starts + fraction * widths, upper) * widths

    pieces, _ = quad_vec(interval_speeds, 0.0, 1.0, epsabs=ARC_LENGTH_QUAD_ABS, epsrel=1e-10, norm="max")
    return ArcLengthTable(edges, np.concatenate([[0.0], np.cumsum(pieces)]))


@lru_cache(maxsize=64)
def equal_arc_length_section(airfoil: NacaAirfoil, count: int, anchor_trailing_edge: bool = True,
                             fine_samples: int = ARC_LENGTH_FINE_SAMPLES // 2) -> SectionSampling:
    """``count`` points around the closed section, equally spaced in arc length (spec §5).

    With ``anchor_trailing_edge=False`` this is the spec's procedure exactly: one spacing
    Delta s = S_total / count around the whole section. With ``True`` (used for the solid
    and the mesh) the points are shared between the surfaces in proportion to their arc
    lengths, each surface is spaced equally, and the sharp trailing edge is always a point,
    so the section never cuts its corner. The two spacings then differ by less than 1/count.
    """
    if count < 8:
        raise ParameterError(f"points = {count} is out of range; allowed [8, inf)")
    upper = surface_arc_length_table(airfoil, True, fine_samples)
    lower = surface_arc_length_table(airfoil, False, fine_samples)
    perimeter = upper.total + lower.total
    if anchor_trailing_edge:
        upper_count = int(np.clip(round(count * upper.total / perimeter), 2, count - 2))
        lower_count = count - upper_count
        upper_u = upper.root_chord_at(np.arange(upper_count) * upper.total / upper_count)
        lower_u = lower.root_chord_at(lower.total - np.arange(lower_count) * lower.total / lower_count)
        trailing_edge_index: int | None = upper_count
    else:
        arc = np.arange(count) * perimeter / count
        on_upper = arc <= upper.total
        upper_u = upper.root_chord_at(arc[on_upper])
        lower_u = lower.root_chord_at(perimeter - arc[~on_upper])
        trailing_edge_index = None
    t = np.concatenate([upper_u**2, 2.0 - lower_u**2])
    points = np.concatenate([airfoil.points_on_half(upper_u, True), airfoil.points_on_half(lower_u, False)])
    return SectionSampling(t=t, points=points, perimeter=perimeter, trailing_edge_index=trailing_edge_index)


def spacing_deviation(points: NDArray[np.float64]) -> float:
    """Max relative deviation of consecutive chord lengths of a closed polygon ``(n, 2)``: max |d/mean(d) - 1|."""
    gaps = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return float(np.max(np.abs(gaps / gaps.mean() - 1.0)))


__all__ = ["ArcLengthTable", "SectionSampling", "airfoil_points", "equal_arc_length_section",
           "spacing_deviation", "surface_arc_length_table"]
