"""The section protocol: what every 2D blade section (NACA 4- and 5-digit, .dat file, blunt edge) offers.

A section is a closed curve in chord units: the leading edge at (0, 0), the chord along +x
to the trailing edge near (1, 0). It is made of two *halves*, the upper and the lower
surface, each running from the leading edge (u = 0) to the trailing edge (u = 1) with a
bounded speed |df/du| (for the NACA sections u = sqrt(chord position), spec §5's cure for
the sqrt(t) leading edge). When the two halves end at different points, the section also
has a *base*: the straight trailing-edge edge from the upper half's end to the lower half's
end (a blunt trailing edge, issue 13 part 3), and the closed curve has two corners there.

The closed parameter ``t`` of :func:`closed_points` extends the spec's f(t) (§1.3):

* sharp sections (no base): t in [0, 1] upper surface at u^2 = t, t in (1, 2] lower surface
  at u^2 = 2 - t, exactly the spec;
* sections with a base: t in [0, 1] upper surface, t in (1, 2) the base (t - 1 is the
  fraction of the way from the upper corner to the lower corner), t in [2, 3] the lower
  surface at u^2 = 3 - t.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Trailing-edge gaps (chord units) below this count as a sharp trailing edge (no base).
SHARP_TRAILING_EDGE_GAP = 1e-9


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
        """u values in (0, 1) where the curvature jumps; the arc-length table puts a grid point there."""
        ...

    def with_trailing_edge_gap(self, gap: float) -> Section:
        """The same section with its thickness law changed so the trailing edge is ``gap`` thick (chord units)."""
        ...


def trailing_edge_vector(section: Section) -> NDArray[np.float64]:
    """Upper trailing-edge point minus lower one, ``(2,)`` chord units: (0, 0) for a sharp edge."""
    ends = [section.points_on_half(np.array([1.0]), upper)[0] for upper in (True, False)]
    return ends[0] - ends[1]


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
        corners = [section.points_on_half(np.array([1.0]), upper)[0] for upper in (True, False)]
        fraction = (t[on_base] - 1.0)[:, None]
        points[on_base] = (1.0 - fraction) * corners[0] + fraction * corners[1]
    return points


def chord_positions(t: ArrayLike, base: bool) -> NDArray[np.float64]:
    """Half parameter u^2 of closed parameters ``t`` (the chord position for NACA sections; 1 on the base)."""
    t = np.asarray(t, dtype=float)
    lower_start = 2.0 if base else 1.0
    return np.where(t <= 1.0, t, np.where(t >= lower_start, lower_start + 1.0 - t, 1.0))


def max_thickness(section: Section, samples: int = 401) -> float:
    """The section's largest thickness across the chord (upper minus lower y at the same root-chord
    parameter u, t = u^2), in chord units; sampled, so exact to the sampling."""
    u = np.linspace(0.0, 1.0, samples)
    upper, lower = section.points_on_half(u, True), section.points_on_half(u, False)
    return float(np.max(upper[:, 1] - lower[:, 1]))
