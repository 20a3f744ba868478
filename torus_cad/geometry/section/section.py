"""The section protocol: what every 2D blade section (NACA 4- and 5-digit, .dat file, blunt edge)
offers.

A section is a closed curve in chord units: the leading edge at (0, 0), the chord along +x
to the trailing edge near (1, 0). It is made of two *halves*, the upper and the lower
surface, each running from the leading edge (u = 0) to the trailing edge (u = 1) with a
bounded speed |df/du| (for the NACA sections u = sqrt(chord position), spec §5's cure for
the sqrt(t) leading edge). When the two halves end at different points, the section also
has a *base*: the trailing-edge edge from the upper half's end to the lower half's end (a
blunt trailing edge). The base is straight (``flat``: the closed curve has
two corners there) unless the section is a :class:`RoundTrailingEdge`, whose base is a *round
cap*: the cubic Bezier curve with poles

    U,  U + h_u T_u,  L + h_l T_l,  L

(U, L the upper and lower half's ends, T_u, T_l their unit tangents there pointing aft, h_u, h_l
> 0 the handle lengths), which leaves each half along its own tangent, so the closed curve is
smooth (G1, no corner) all round. Its width where it meets the halves is |U - L|, the
trailing-edge thickness. With both handles 2/3 |U - L| and parallel tangents this is the standard
cubic approximation of a half circle of diameter |U - L| (within 1.8 % of its radius): the
blade sets the handle lengths so that the cap is that near half circle in mm, after the
section transform (:mod:`torus_cad.geometry.blade.trailing_edge`). A Bezier cap is exact in the
kernel (an affine map of a Bezier curve is the Bezier curve of the mapped poles), so the
section curves there carry it as one span (:mod:`torus_cad.kernel.wires`).

The closed parameter ``t`` of :func:`closed_points` extends the spec's f(t) (§1.3):

* sharp sections (no base): t in [0, 1] upper surface at u^2 = t, t in (1, 2] lower surface
  at u^2 = 2 - t, exactly the spec;
* sections with a base: t in [0, 1] upper surface, t in (1, 2) the base (t - 1 is the
  fraction of the way from the upper corner to the lower corner on a flat base, the cap's
  Bezier parameter on a round one), t in [2, 3] the lower surface at u^2 = 3 - t.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Trailing-edge gaps (chord units) below this count as a sharp trailing edge (no base).
SHARP_TRAILING_EDGE_GAP = 1e-9

#: A round cap's handles, as a fraction of the trailing-edge thickness (mm): the cubic Bezier
#: approximation of a half circle (4/3 x the radius).
ROUND_CAP_HANDLE_FRACTION = 2.0 / 3.0

#: Chord positions at which a section's thickness is evaluated (:func:`section_thickness`).
THICKNESS_STATIONS = 801


@runtime_checkable
class Section(Hashable, Protocol):
    """A closed 2D section in chord units (see the module docstring for the conventions).

    Sections are hashable (equal sections share the arc-length sampling cache)."""

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """Points of the upper or lower half at u in [0, 1] (0 = leading edge): ``(len(u), 2)``."""
        ...

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """|d f / du| on the upper or lower half, shape of ``u``; finite everywhere."""
        ...

    @property
    def kinks(self) -> tuple[float, ...]:
        """u values in (0, 1) where the curvature jumps; the arc-length table puts a grid point
        there."""
        ...

    def with_trailing_edge_gap(self, gap: float) -> Section:
        """The same section with its thickness law changed so the trailing edge is ``gap`` thick
        (chord units)."""
        ...


def trailing_edge_vector(section: Section) -> NDArray[np.float64]:
    """Upper trailing-edge point minus lower one, ``(2,)`` chord units: (0, 0) for a sharp edge."""
    upper_end, lower_end = half_ends(section)
    return upper_end - lower_end


def has_base(section: Section) -> bool:
    """Whether the section has a blunt trailing edge (a base between two corners)."""
    return bool(np.linalg.norm(trailing_edge_vector(section)) > SHARP_TRAILING_EDGE_GAP)


def parameter_end(section: Section) -> float:
    """End of the closed parameter: 2 for a sharp section, 3 with a base."""
    return 3.0 if has_base(section) else 2.0


def closed_points(section: Section, t: ArrayLike, base: bool | None = None) -> NDArray[np.float64]:
    """The closed section at closed parameters ``t`` (module docstring), shape ``(len(t), 2)``.

    ``base`` says which parametrisation ``t`` uses (default: whether ``section`` has a base),
    so a blade whose sections all have bases can share one ``t``.
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    base = has_base(section) if base is None else base
    lower_start = 2.0 if base else 1.0
    on_upper = t <= 1.0
    on_lower = t >= lower_start
    on_base = ~on_upper & ~on_lower
    points = np.empty((len(t), 2))
    points[on_upper] = section.points_on_half(np.sqrt(np.clip(t[on_upper], 0.0, 1.0)), True)
    lower_u = np.sqrt(np.clip(lower_start + 1.0 - t[on_lower], 0.0, 1.0))
    points[on_lower] = section.points_on_half(lower_u, False)
    if np.any(on_base):
        points[on_base] = cap_points(section, t[on_base] - 1.0)
    return points


def chord_positions(t: ArrayLike, base: bool) -> NDArray[np.float64]:
    """Half parameter u^2 of closed parameters ``t`` (the chord position for NACA sections; 1 on the
    base)."""
    t = np.asarray(t, dtype=float)
    lower_start = 2.0 if base else 1.0
    return np.where(t <= 1.0, t, np.where(t >= lower_start, lower_start + 1.0 - t, 1.0))


def max_thickness(section: Section, samples: int = 401) -> float:
    """The section's largest thickness across the chord (upper minus lower y at the same root-chord
    parameter u, t = u^2), in chord units; sampled, so exact to the sampling."""
    u = np.linspace(0.0, 1.0, samples)
    upper, lower = section.points_on_half(u, True), section.points_on_half(u, False)
    return float(np.max(upper[:, 1] - lower[:, 1]))


#: Step (in the half parameter u) of the one-sided difference that gives a half's end tangent;
#: the second-order formula's error is ~ step^2 x the curve's third derivative (< 1e-7 rad).
_TANGENT_STEP = 1e-4

#: Gauss-Legendre nodes of the cap's arc-length table (a cubic's speed is smooth: 1e-12 relative).
_CAP_QUADRATURE_NODES = 16

#: Samples of the cap's arc-length table (arc length -> Bezier parameter).
_CAP_TABLE_SAMPLES = 257


@dataclass(frozen=True)
class RoundTrailingEdge:
    """A section with a base whose base is a round cap (module docstring); a :class:`Section`.

    Attributes:
        section: the section with a base (its halves and their ends U, L).
        upper_handle: h_u, chord units, > 0: the cap's second pole is U + h_u T_u.
        lower_handle: h_l, chord units, > 0: the cap's third pole is L + h_l T_l.
    """

    section: Section
    upper_handle: float
    lower_handle: float

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """The halves are those of :attr:`section`."""
        return self.section.points_on_half(root_chord, upper)

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """As :attr:`section`'s."""
        return self.section.speed_on_half(root_chord, upper)

    @property
    def kinks(self) -> tuple[float, ...]:
        """As :attr:`section`'s."""
        return self.section.kinks

    def with_trailing_edge_gap(self, gap: float) -> RoundTrailingEdge:
        """:attr:`section` opened by ``gap``, capped with the same handle lengths."""
        return RoundTrailingEdge(
            self.section.with_trailing_edge_gap(gap), self.upper_handle, self.lower_handle
        )

    def cap_poles(self) -> NDArray[np.float64]:
        """The cap's Bezier poles U, U + h_u T_u, L + h_l T_l, L: ``(4, 2)`` chord units."""
        return round_cap_poles(
            half_ends(self.section),
            end_tangents(self.section),
            np.array([self.upper_handle, self.lower_handle]),
        )


def round_cap_poles(
    ends: ArrayLike, tangents: ArrayLike, handles: ArrayLike
) -> NDArray[np.float64]:
    """A round cap's Bezier poles U, U + h_u T_u, L + h_l T_l, L (module docstring): ``(..., 4,
    d)``.

    ``ends`` ``(..., 2, d)`` are U and L, ``tangents`` ``(..., 2, d)`` the unit T_u, T_l (pointing
    aft), ``handles`` ``(..., 2)`` h_u, h_l, all in one unit (chord units or mm)."""
    ends, tangents = np.asarray(ends, dtype=float), np.asarray(tangents, dtype=float)
    inner = ends + np.asarray(handles, dtype=float)[..., None] * tangents
    return np.stack([ends[..., 0, :], inner[..., 0, :], inner[..., 1, :], ends[..., 1, :]], axis=-2)


def half_ends(section: Section) -> NDArray[np.float64]:
    """The upper and the lower half's trailing-edge ends U and L: ``(2, 2)`` chord units."""
    return np.array([section.points_on_half(np.array([1.0]), upper)[0] for upper in (True, False)])


def end_derivatives(section: Section) -> NDArray[np.float64]:
    """d f / du of the upper and the lower half at u = 1 (pointing aft): ``(2, 2)`` chord units.

    Second-order one-sided differences; each half is smooth up to its end."""
    u = 1.0 - _TANGENT_STEP * np.arange(3.0)
    ends = np.stack([section.points_on_half(u, upper) for upper in (True, False)])
    return (3.0 * ends[:, 0] - 4.0 * ends[:, 1] + ends[:, 2]) / (2.0 * _TANGENT_STEP)


def end_tangents(section: Section) -> NDArray[np.float64]:
    """Unit tangents T_u, T_l of the halves at their trailing-edge ends, pointing aft: ``(2,
    2)``."""
    derivatives = end_derivatives(section)
    return derivatives / np.linalg.norm(derivatives, axis=-1, keepdims=True)


def bezier_points(poles: ArrayLike, parameter: ArrayLike) -> NDArray[np.float64]:
    """A cubic Bezier curve of ``poles`` ``(..., 4, d)`` at ``parameter`` ``(n,)``: ``(..., n,
    d)``."""
    poles = np.asarray(poles, dtype=float)
    w = np.atleast_1d(np.asarray(parameter, dtype=float))[:, None]
    bernstein = np.concatenate(
        [(1 - w) ** 3, 3 * (1 - w) ** 2 * w, 3 * (1 - w) * w**2, w**3], axis=1
    )
    return np.einsum("nj,...jd->...nd", bernstein, poles)


def cap_points(section: Section, parameter: ArrayLike) -> NDArray[np.float64]:
    """The base at ``parameter`` in [0, 1] (0 = upper corner U, 1 = lower corner L): ``(n, 2)``.

    On a flat base the parameter is the fraction of the way from U to L; on a round cap it is
    the Bezier parameter."""
    parameter = np.atleast_1d(np.asarray(parameter, dtype=float))
    if isinstance(section, RoundTrailingEdge):
        return bezier_points(section.cap_poles(), parameter)
    upper_end, lower_end = half_ends(section)
    fraction = parameter[:, None]
    return (1.0 - fraction) * upper_end + fraction * lower_end


def _cap_arc_length_table(
    poles: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Bezier parameters ``(k,)`` and the cap's arc length from U at each ``(k,)``."""
    parameters = np.linspace(0.0, 1.0, _CAP_TABLE_SAMPLES)
    nodes, weights = np.polynomial.legendre.leggauss(_CAP_QUADRATURE_NODES)
    starts, width = parameters[:-1], parameters[1] - parameters[0]
    at = (starts[:, None] + 0.5 * width * (nodes + 1.0)[None]).ravel()
    # the derivative is the quadratic Bezier of these
    derivative_poles = 3.0 * np.diff(poles, axis=0)
    w = at[:, None]
    velocity = (
        (1 - w) ** 2 * derivative_poles[0]
        + 2 * (1 - w) * w * derivative_poles[1]
        + w**2 * derivative_poles[2]
    )
    speed = np.linalg.norm(velocity, axis=-1).reshape(len(starts), -1)
    pieces = 0.5 * width * speed @ weights
    return parameters, np.concatenate([[0.0], np.cumsum(pieces)])


def cap_length(section: Section) -> float:
    """Arc length of the base, chord units: |U - L| when flat; 0 without a base."""
    if isinstance(section, RoundTrailingEdge):
        return float(_cap_arc_length_table(section.cap_poles())[1][-1])
    return float(np.linalg.norm(trailing_edge_vector(section)))


def cap_parameter_at(section: Section, arc_fraction: ArrayLike) -> NDArray[np.float64]:
    """The base's parameter (:func:`cap_points`) at fractions ``(n,)`` of its arc length from U."""
    arc_fraction = np.asarray(arc_fraction, dtype=float)
    if not isinstance(section, RoundTrailingEdge):
        return arc_fraction
    parameters, arc = _cap_arc_length_table(section.cap_poles())
    return np.interp(arc_fraction * arc[-1], arc, parameters)


def section_thickness(
    planar: NDArray[np.float64],
    trailing_edge_index: int,
    lower_corner_index: int | None,
    stations: int = THICKNESS_STATIONS,
) -> NDArray[np.float64]:
    """Largest thickness perpendicular to the chord of sections in their planes ``(k, p, 2)``:
    ``(k,)``.

    The upper surface is points 0..trailing_edge_index, the lower one from the lower corner
    (or the trailing edge) back to point 0; both are read as functions of the position along
    the chord and subtracted.
    """
    lower_start = trailing_edge_index if lower_corner_index is None else lower_corner_index
    result = np.zeros(len(planar))
    grid = np.linspace(0.0, 1.0, stations)
    for index, ring in enumerate(planar):
        leading = ring[0]
        trailing = (
            ring[trailing_edge_index]
            if lower_corner_index is None
            else 0.5 * (ring[trailing_edge_index] + ring[lower_corner_index])
        )
        chord = trailing - leading
        length = float(np.linalg.norm(chord))
        axis = chord / length
        normal = np.array([-axis[1], axis[0]])
        along, across = (ring - leading) @ axis / length, (ring - leading) @ normal
        upper = np.interp(
            grid, *_sorted(along[: trailing_edge_index + 1], across[: trailing_edge_index + 1])
        )
        lower_along = np.append(along[lower_start:], along[0])
        lower_across = np.append(across[lower_start:], across[0])
        lower = np.interp(grid, *_sorted(lower_along, lower_across))
        result[index] = float(np.max(np.abs(upper - lower)))
    return result


def _sorted(
    x: NDArray[np.float64], y: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    order = np.argsort(x, kind="stable")
    return x[order], y[order]
