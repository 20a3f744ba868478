"""A design's blade as the vortex solver sees it: its camber surface outside the hub, in metres, and
its sections' shapes for the polars.

A toroidal blade's lattice spans the centerline from where it leaves the hub's cylinder to where it
enters it again (both ends attached to the hub, no free tip); a conventional blade's, its station
table from the root station to the tip. A 'ccw' design is the mirror image of the 'cw' one (y ->
-y), turning the other way.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from torus_cad.design.described_geometry import (
    hub_geometry,
    propeller_geometry,
    sampled_blade_surface,
)
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.geometry.analysis.camber_surface import (
    camber_surface,
    cosine_fractions,
    section_coordinates,
)
from torus_cad.geometry.blade.blade_surface import BladeSurface, blade_surface_at
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.parameters.design import DesignKind, PropellerParameters
from torus_cad.tolerances import VORTEX_CHORDWISE_DEFAULT, VORTEX_SPANWISE_DEFAULT
from torus_cad.vortex.lattice import WakeShape

#: Points around each section the camber surface is taken from (equal arc length).
SECTION_POINTS = 161
#: Centerline samples on which a toroidal blade's way out of and back into the hub is looked for ...
_HUB_CROSSING_SAMPLES = 2001
#: ... refined by this many bisections.
_BISECTIONS = 40


@dataclass(frozen=True)
class Discretisation:
    """The lattice's resolution.

    Attributes:
        chordwise: rings across the chord.
        spanwise: strips along the blade.
        wake: the wake's length and steps.
    """

    chordwise: int = VORTEX_CHORDWISE_DEFAULT
    spanwise: int = VORTEX_SPANWISE_DEFAULT
    wake: WakeShape = field(default_factory=WakeShape)


@dataclass(frozen=True)
class RotorBlade:
    """Blade 0 of a design for the vortex solver.

    Attributes:
        camber_m: ``(K, C + 1, 3)`` its camber surface outside the hub, m.
        chord_m: ``(K,)`` the sections' chords, m.
        sections: the K sections' shapes ``(p, 2)``, chord 0..1, Selig order (for the polars).
        s: ``(K,)`` the sections' centerline parameters.
        blades: blade count; spin: +1 for 'cw' (clockwise seen from +z), -1 for 'ccw'.
        tip_radius_m: the largest radius of the blade surface.
        surface_m: ``(K, P, 3)`` the blade's surface (the K sections' P points each), m: its
            thickness noise.
    """

    camber_m: NDArray[np.float64]
    chord_m: NDArray[np.float64]
    sections: tuple[NDArray[np.float64], ...]
    s: NDArray[np.float64]
    blades: int
    spin: float
    tip_radius_m: float
    surface_m: NDArray[np.float64] = field(repr=False)


def rotor_blade(params: PropellerParameters, discretisation: Discretisation) -> RotorBlade:
    """Blade 0 of ``params`` sampled for ``discretisation`` (module doc), with its design targets
    (``diameter``, ``pitch``, ``airfoil.naca``) applied as the build applies them: the blade that is
    built."""
    params = resolve_design_targets(params).parameters
    sections = discretisation.spanwise + 1
    surface = _surface(params, sections)
    camber = camber_surface(surface, cosine_fractions(discretisation.chordwise))
    points = camber.points / 1000.0
    outline = surface.points / 1000.0
    spin = 1.0
    if params.handedness == Handedness.CCW:
        points = points * np.array([1.0, -1.0, 1.0])
        outline = outline * np.array([1.0, -1.0, 1.0])
        spin = -1.0
    shapes = tuple(section_coordinates(surface, k) for k in range(sections))
    tip = float(np.hypot(surface.points[..., 0], surface.points[..., 1]).max()) / 1000.0
    return RotorBlade(
        points, camber.chord_mm / 1000.0, shapes, camber.s, params.blades, spin, tip, outline
    )


def _surface(params: PropellerParameters, sections: int) -> BladeSurface:
    if params.kind == DesignKind.CONVENTIONAL:
        return sampled_blade_surface(params, 0, sections, SECTION_POINTS)
    geometry = propeller_geometry(params)
    centerline = geometry.centerline(0)
    hub = hub_geometry(params)
    first, last = _outside_the_hub(centerline.points, hub.radius_mm)
    return blade_surface_at(
        geometry.blade, centerline, np.linspace(first, last, sections), SECTION_POINTS
    )


def _outside_the_hub(points: object, hub_radius_mm: float) -> tuple[float, float]:
    """The centerline parameters where the centerline first leaves the hub's cylinder and last
    enters it."""
    s = np.linspace(0.0, 1.0, _HUB_CROSSING_SAMPLES)

    def outside(values: NDArray[np.float64]) -> NDArray[np.bool_]:
        xyz = points(values)  # type: ignore[operator]
        return np.hypot(xyz[:, 0], xyz[:, 1]) > hub_radius_mm

    flags = outside(s)
    where = np.flatnonzero(flags)
    if not len(where):
        return 0.0, 1.0
    low, high = where[0], where[-1]
    return (
        _crossing(outside, s[max(low - 1, 0)], s[low]) if low > 0 else 0.0,
        _crossing(outside, s[min(high + 1, len(s) - 1)], s[high]) if high < len(s) - 1 else 1.0,
    )


def _crossing(outside: object, inside_s: float, outside_s: float) -> float:
    """Bisection between a parameter inside the hub and one outside: the last one found outside."""
    for _ in range(_BISECTIONS):
        middle = 0.5 * (inside_s + outside_s)
        if outside(np.array([middle]))[0]:  # type: ignore[operator]
            outside_s = middle
        else:
            inside_s = middle
    return outside_s
