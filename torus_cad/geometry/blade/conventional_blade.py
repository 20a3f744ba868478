"""A conventional (open-tip) propeller blade from a station table, sampled as a
:class:`BladeSurface`.

Blade 0 runs along +x (radially out); the spin axis is z. At radius r (mm) the section (the
design's chord-unit airfoil, its thickness scaled to the station's t/c when given) has chord c(r)
and lies in the plane x = r with its chord line at the local pitch angle beta(r) to the plane of
rotation, so that the geometric pitch is 2 pi r tan beta:

* chord direction (leading edge -> trailing edge): N = (0, cos beta, -sin beta);
* thickness direction (the airfoil's upper side): B = T x N = (0, sin beta, cos beta), T = +x.

The leading edge thus points toward -y and up (+z): turning clockwise seen from +z (blade 0 moving
toward -y) the blade pushes air toward -z, the 'cw' of the toroidal default
(:mod:`torus_cad.geometry.blade.handedness`); 'ccw' is the pipeline's mirror image.

Stacking: the section's point at chord fraction ``stacking`` lies in the plane z = 0; without a
sweep it lies on the x axis; with a sweep (APC's definition) the section moves along y so that its
leading edge lies ``sweep`` ahead (toward -y) of the x axis.

Root: stations below the table's first radius r_1 hold the first station's beta and thickness; the
blade continues down to r_0 =
:data:`~torus_cad.geometry.blade.conventional_blade.CONVENTIONAL_ROOT_RADIUS_FRACTION` x the hub
radius, with the chord blended (smoothstep in r on [r_0, max(r_1, R_hub)]) to a root chord that fits
inside the hub, and the section's mid chord blended onto the x axis there. The hub swallows that
blend. Tip: the last section (r = R, the table's tip chord) is the blade's open end; the kernel caps
it with a planar face.

Laws in r are monotone cubic (PCHIP, scipy) through the stations; the sections are spaced in
r(s) = r_0 + (R - r_0) ((1 - a) s + a sin(pi s / 2)), s uniform in [0, 1], a =
:data:`~torus_cad.geometry.blade.conventional_blade.CONVENTIONAL_TIP_CLUSTERING`, densest at the
tip.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PchipInterpolator

from torus_cad.errors import GeometryError
from torus_cad.geometry.blade.blade_surface import BladeSurface, place_on_frames
from torus_cad.geometry.blade.frames import Frames
from torus_cad.geometry.blade.propeller_geometry import HubGeometry, blade_angle_deg
from torus_cad.geometry.blade.station_table import StationTable
from torus_cad.geometry.blade.trailing_edge import TRAILING_EDGE_THICKNESS_LIMIT, blunt_sections
from torus_cad.geometry.section.airfoil import Naca5Airfoil, NacaAirfoil
from torus_cad.geometry.section.arc_length import equal_arc_length_section
from torus_cad.geometry.section.section import (
    RoundTrailingEdge,
    Section,
    closed_points,
    max_thickness,
)

#: The blended root section fits inside this fraction of the hub's half-width and half-length.
CONVENTIONAL_ROOT_FIT_MARGIN = 0.8

#: The root section of a conventional blade sits at this fraction of the hub's radius (well inside
#: the hub, so that the hub swallows the root's blend); the stations below the table's first one are
#: blended down to it.
CONVENTIONAL_ROOT_RADIUS_FRACTION = 0.5

#: Share of sine clustering in the conventional blade's section radii (0: uniform in r; 1: a quarter
#: sine, sections densest at the tip).
CONVENTIONAL_TIP_CLUSTERING = 0.6


#: Step in the half parameter u of the central difference that gives a scaled section's speed.
_SPEED_STEP = 1e-6


@dataclass(frozen=True)
class ScaledThickness:
    """``section`` with its thickness scaled by ``factor`` about its mean line (a :class:`Section`).

    At each half parameter u the mean of the upper and lower points stays and their half
    difference is multiplied by ``factor``: for a NACA section with the thickness normal to the
    camber line this is exactly the same section with its thickness ratio times ``factor``.
    """

    section: Section
    factor: float

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """``(len(u), 2)`` chord units."""
        u = np.atleast_1d(np.asarray(root_chord, dtype=float))
        top, bottom = self.section.points_on_half(u, True), self.section.points_on_half(u, False)
        sign = 1.0 if upper else -1.0
        return np.asarray(
            0.5 * (top + bottom) + sign * self.factor * 0.5 * (top - bottom), dtype=float
        )

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """|d f / du| by a central difference (one-sided at the ends), shape of ``u``."""
        u = np.asarray(root_chord, dtype=float)
        low, high = np.clip(u - _SPEED_STEP, 0.0, 1.0), np.clip(u + _SPEED_STEP, 0.0, 1.0)
        step = np.maximum(high - low, 1e-300)
        difference = self.points_on_half(high.ravel(), upper) - self.points_on_half(
            low.ravel(), upper
        )
        return np.asarray(np.linalg.norm(difference, axis=-1).reshape(u.shape) / step, dtype=float)

    @property
    def kinks(self) -> tuple[float, ...]:
        """As ``section``'s."""
        return self.section.kinks

    def with_trailing_edge_gap(self, gap: float) -> ScaledThickness:
        """``section`` opened so that the scaled section's trailing edge is ``gap`` thick."""
        return ScaledThickness(self.section.with_trailing_edge_gap(gap / self.factor), self.factor)


def thickness_scaled(section: Section, factor: float) -> Section:
    """``section`` with its thickness times ``factor``: a NACA section with its thickness number
    scaled (the same as :class:`ScaledThickness` with the thickness normal to the camber line, and
    analytic), any other section as a :class:`ScaledThickness`; ``section`` itself for a factor of
    1."""
    if factor == 1.0:
        return section
    if isinstance(section, NacaAirfoil | Naca5Airfoil) and section.camber_normal:
        return dataclasses.replace(section, thickness=section.thickness * factor)
    return ScaledThickness(section, factor)


@dataclass(frozen=True)
class ConventionalBlade:
    """One conventional blade (module docstring).

    Attributes:
        stations: the station table (r/R, c/R, beta, optional t/c and sweep).
        tip_radius_mm: R = D / 2, mm.
        airfoil: the chord-unit section; its thickness is scaled to the stations' t/c when given.
        stacking: chord fraction of the stacking point (0 = leading edge).
        hub: the hub the root sits in.
        trailing_edge_thickness_mm: a blunt trailing edge this thick on every section (0 = the
            airfoil's own edge).
        round_trailing_edge: that edge ends in a round cap (else a flat base), as the toroidal
            blade's
            (:mod:`torus_cad.geometry.blade.trailing_edge`).
    """

    stations: StationTable
    tip_radius_mm: float
    airfoil: Section
    stacking: float
    hub: HubGeometry
    trailing_edge_thickness_mm: float = 0.0
    round_trailing_edge: bool = False

    @property
    def root_radius_mm(self) -> float:
        """r_0: the radius of the blade's root section, inside the hub, mm."""
        return CONVENTIONAL_ROOT_RADIUS_FRACTION * self.hub.radius_mm

    @property
    def blend_end_mm(self) -> float:
        """Where the root blend ends and the table's laws hold: max(r_1, R_hub), mm."""
        return max(float(self.stations.r_over_r[0]) * self.tip_radius_mm, self.hub.radius_mm)

    def _law(self, values: NDArray[np.float64], r_mm: NDArray[np.float64]) -> NDArray[np.float64]:
        """A station column interpolated (PCHIP) at ``r_mm``, held constant beyond the table's
        ends."""
        stations_mm = self.stations.r_over_r * self.tip_radius_mm
        if len(stations_mm) < 3:
            return np.interp(r_mm, stations_mm, values)
        clipped = np.clip(r_mm, stations_mm[0], stations_mm[-1])
        return np.asarray(PchipInterpolator(stations_mm, values)(clipped), dtype=float)

    def beta_deg(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """The local pitch angle at ``r_mm`` ``(k,)``, degrees."""
        return self._law(self.stations.beta_deg, np.atleast_1d(np.asarray(r_mm, dtype=float)))

    def table_chord_mm(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """The table's chord at ``r_mm`` ``(k,)`` (without the root blend), mm."""
        r = np.atleast_1d(np.asarray(r_mm, dtype=float))
        return self.tip_radius_mm * self._law(self.stations.chord_over_r, r)

    def thickness_factor(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """The stations' t/c over the airfoil's own maximum thickness at ``r_mm`` ``(k,)`` (1
        without t/c)."""
        r = np.atleast_1d(np.asarray(r_mm, dtype=float))
        if self.stations.thickness_ratio is None:
            return np.ones_like(r)
        return self._law(self.stations.thickness_ratio, r) / max_thickness(self.airfoil)

    def blend(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """The root blend's weight at ``r_mm``: 0 at r_0, 1 from :attr:`blend_end_mm` out
        (smoothstep)."""
        r = np.atleast_1d(np.asarray(r_mm, dtype=float))
        x = np.clip((r - self.root_radius_mm) / (self.blend_end_mm - self.root_radius_mm), 0.0, 1.0)
        return x * x * (3.0 - 2.0 * x)

    def root_chord_mm(self) -> float:
        """The largest chord (up to the table's first one) whose section fits inside the hub at r_0,
        mm."""
        r0 = self.root_radius_mm
        beta = np.radians(float(self.beta_deg([r0])[0]))
        thickness = float(self.thickness_factor([r0])[0]) * max_thickness(self.airfoil)
        half_width = CONVENTIONAL_ROOT_FIT_MARGIN * np.sqrt(self.hub.radius_mm**2 - r0**2)
        half_length = CONVENTIONAL_ROOT_FIT_MARGIN * self.hub.length_mm / 2.0
        fits_width = half_width / (0.5 * abs(np.cos(beta)) + thickness * abs(np.sin(beta)))
        fits_length = half_length / (0.5 * abs(np.sin(beta)) + thickness * abs(np.cos(beta)))
        return float(min(self.table_chord_mm([self.blend_end_mm])[0], fits_width, fits_length))

    def chord_mm(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """The blade's chord at ``r_mm`` ``(k,)``, the root blend included, mm."""
        root, weight = self.root_chord_mm(), self.blend(r_mm)
        return root + weight * (self.table_chord_mm(r_mm) - root)

    def mid_chord_offset_mm(self, r_mm: ArrayLike) -> NDArray[np.float64]:
        """``(k, 2)`` the (y, z) of the section's mid chord (module docstring's stacking, root blend
        included), mm."""
        r = np.atleast_1d(np.asarray(r_mm, dtype=float))
        beta = np.radians(self.beta_deg(r))
        chord = self.chord_mm(r)
        along = np.stack([np.cos(beta), -np.sin(beta)], axis=-1)  # the chord direction in (y, z)
        offset = (0.5 - self.stacking) * chord[:, None] * along
        if self.stations.sweep_over_r is not None:
            leading_y = -self.tip_radius_mm * self._law(self.stations.sweep_over_r, r)
            offset[:, 0] = leading_y + 0.5 * chord * np.cos(beta)
        return np.asarray(self.blend(r)[:, None] * offset, dtype=float)

    def section_radii_mm(self, sections: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(s, r)``, each ``(sections,)``: s uniform in [0, 1], r(s) clustered at the tip (module
        docstring), mm."""
        s = np.linspace(0.0, 1.0, sections)
        a = CONVENTIONAL_TIP_CLUSTERING
        fraction = (1.0 - a) * s + a * np.sin(0.5 * np.pi * s)
        return s, self.root_radius_mm + (self.tip_radius_mm - self.root_radius_mm) * fraction

    def frames(self, s: NDArray[np.float64], r_mm: NDArray[np.float64]) -> Frames:
        """The sections' frames: origin at the mid chord on the chord line, T = +x, N the chord
        direction, B = T x N."""
        beta = np.radians(self.beta_deg(r_mm))
        offset = self.mid_chord_offset_mm(r_mm)
        zeros, ones = np.zeros_like(beta), np.ones_like(beta)
        origin = np.stack([r_mm, offset[:, 0], offset[:, 1]], axis=-1)
        tangent = np.stack([ones, zeros, zeros], axis=-1)
        normal = np.stack([zeros, np.cos(beta), -np.sin(beta)], axis=-1)
        binormal = np.stack([zeros, np.sin(beta), np.cos(beta)], axis=-1)
        return Frames(s, origin, tangent, normal, binormal)

    def section_at(self, r_mm: float) -> Section:
        """The chord-unit section at radius ``r_mm``: the airfoil with its thickness scaled to the
        station's t/c (itself without t/c), opened to the blunt trailing edge in mm when there is
        one."""
        section = thickness_scaled(self.airfoil, float(self.thickness_factor([r_mm])[0]))
        if self.trailing_edge_thickness_mm <= 0.0:
            return section
        chord = self.chord_mm([r_mm])
        return blunt_sections(
            section, self.trailing_edge_thickness_mm, [0.0], chord, chord, self.round_trailing_edge
        )[0]

    def check_trailing_edge(self, r_mm: NDArray[np.float64]) -> None:
        """GeometryError when the blunt trailing edge is thicker than TRAILING_EDGE_THICKNESS_LIMIT
        x a section's own largest thickness at the radii ``r_mm`` (mm)."""
        if self.trailing_edge_thickness_mm <= 0.0:
            return
        own_mm = self.chord_mm(r_mm) * self.thickness_factor(r_mm) * max_thickness(self.airfoil)
        thin = own_mm * TRAILING_EDGE_THICKNESS_LIMIT < self.trailing_edge_thickness_mm
        if np.any(thin):
            where = float(r_mm[int(np.argmax(thin))])
            raise GeometryError(
                "airfoil.trailing_edge_thickness = "
                f"{self.trailing_edge_thickness_mm:g} mm is thicker "
                f"than {TRAILING_EDGE_THICKNESS_LIMIT:g} x the section's own thickness near r = "
                f"{where:.1f} mm ({float(own_mm[int(np.argmax(thin))]):.3f} mm); make it thinner"
            )


def conventional_surface(blade: ConventionalBlade, sections: int, points: int) -> BladeSurface:
    """Blade 0 sampled at ``sections`` x ``points``: ``points`` ``(sections, points, 3)`` mm.

    Every section is sampled at the closed parameters t of the section at 0.75 R, spaced equally
    in its arc length (spec §5), the trailing edge kept as a point.
    """
    s, r_mm = blade.section_radii_mm(sections)
    reference = blade.section_at(0.75 * blade.tip_radius_mm)
    sampling = equal_arc_length_section(reference, points)
    planar = np.stack(
        [closed_points(blade.section_at(float(r)), sampling.t, sampling.base) for r in r_mm]
    )
    chord = blade.chord_mm(r_mm)
    scaled = np.stack(
        [(planar[..., 0] - 0.5) * chord[:, None], planar[..., 1] * chord[:, None]], axis=-1
    )
    frames = blade.frames(s, r_mm)
    return BladeSurface(
        place_on_frames(frames, scaled),
        s,
        sampling.t,
        sampling.trailing_edge_index,
        frames,
        sampling.lower_corner_index,
        isinstance(reference, RoundTrailingEdge),
    )


@dataclass(frozen=True)
class ConventionalPropeller:
    """A conventional propeller: its blade and the pattern, as the toroidal kind's
    :class:`~torus_cad.geometry.blade.propeller_geometry.PropellerGeometry`.

    Attributes:
        blade: blade 0 (its hub, stations, section; mm, degrees).
        blades: the number of blades, n.
        phase_deg: theta_0, blade 0's angle about +z, degrees.
    """

    blade: ConventionalBlade
    blades: int
    phase_deg: float = 0.0

    @property
    def hub(self) -> HubGeometry:
        """The hub the blades' roots sit in (mm)."""
        return self.blade.hub

    def blade_angle_deg(self, blade_index: int) -> float:
        """theta_i = theta_0 + 360 i / n (spec §6.1), degrees."""
        return blade_angle_deg(self.phase_deg, blade_index, self.blades)


def check_conventional_feasible(
    blade: ConventionalBlade, surface: BladeSurface, blades: int
) -> None:
    """Refuse a blade whose root section leaves the hub, whose blunt trailing edge is too thick, or
    whose neighbours would meet outside the hub (``surface``: blade 0, at any angle about the axis).

    The root must lie inside the hub (r < R_hub, |z| < L/2) so that the fuse hides it. Blades meet
    when, at some radius outside the hub, one blade's angular extent about the axis exceeds the
    blade spacing 360 / n degrees.
    """
    radius_mm = np.hypot(surface.frames.origin[:, 0], surface.frames.origin[:, 1])
    outside = radius_mm > blade.hub.radius_mm
    blade.check_trailing_edge(radius_mm[outside])
    root = surface.points[0]
    reach, height = float(np.hypot(root[:, 0], root[:, 1]).max()), float(np.abs(root[:, 2]).max())
    if reach >= blade.hub.radius_mm or height >= blade.hub.length_mm / 2.0:
        raise GeometryError(
            f"the conventional blade's root section leaves the hub (reaches r = {reach:.3f} mm of "
            f"R = {blade.hub.radius_mm:g}, |z| = {height:.3f} mm "
            f"of L/2 = {blade.hub.length_mm / 2:g}); "
            "make the hub larger"
        )
    if blades < 2:
        return
    origin = surface.frames.origin
    turned = (
        (surface.points[..., 0] + 1j * surface.points[..., 1])
        # each section's centre at angle 0
        * np.exp(-1j * np.arctan2(origin[:, 1], origin[:, 0]))[:, None]
    )
    angles = np.degrees(np.angle(turned))
    spans = angles.max(axis=1) - angles.min(axis=1)
    if np.any(spans[outside] >= 360.0 / blades):
        where = float(radius_mm[outside][int(np.argmax(spans[outside]))])
        raise GeometryError(
            "the conventional blades would meet each other "
            f"near r = {where:.1f} mm: a section spans "
            f"{spans[outside].max():.1f} degrees about the axis, more than the blade spacing "
            f"{360.0 / blades:.1f} degrees; use fewer blades or smaller chords"
        )


def rotated_surface(surface: BladeSurface, angle_deg: float) -> BladeSurface:
    """``surface`` (points and frames) rotated by ``angle_deg`` about +z (a blade at another
    angle)."""
    if angle_deg == 0.0:
        return surface
    angle = np.radians(angle_deg)
    cos, sin = np.cos(angle), np.sin(angle)
    rows = np.array([[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]])

    def turn(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(vectors @ rows.T, dtype=float)

    frames = surface.frames
    turned = Frames(
        frames.s,
        turn(frames.origin),
        turn(frames.tangent),
        turn(frames.normal),
        turn(frames.binormal),
    )
    return dataclasses.replace(surface, points=turn(surface.points), frames=turned)
