"""The blade surface: sections transformed (spec §2) and placed on the frames (spec §4.2).

X_final(s, t) = C(s) + X_scaled(s, t) N(s) + Y_scaled(s, t) B(s), evaluated exactly at any
resolution; blade i is built on its own centerline at theta_0 + 360 i / n (spec §6.1), which
:meth:`torus_cad.geometry.blade.propeller_geometry.PropellerGeometry.centerline` gives.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.geometry.blade.centerline import Centerline
from torus_cad.geometry.blade.frames import Frames, section_frames
from torus_cad.geometry.blade.propeller_geometry import BladeGeometry, PropellerGeometry
from torus_cad.geometry.blade.trailing_edge import (
    TRAILING_EDGE_CHECK_SECTIONS,
    BluntSections,
    blunt_sections,
    check_trailing_edge_fits,
    closed_if_too_thin,
)
from torus_cad.geometry.blade.transforms import evaluate_quartic
from torus_cad.geometry.section.arc_length import equal_arc_length_section
from torus_cad.geometry.section.section import RoundTrailingEdge, Section, closed_points, has_base


@dataclass(frozen=True)
class BladeSurface:
    """Sampled surface of one blade.

    Attributes:
        points: ``(sections, points, 3)`` float, mm; each row is a closed section starting at
            the leading edge, upper surface first (the order of f(t), spec §1.3).
        s: ``(sections,)`` centerline parameters of the sections, 0 and 1 included.
        t: ``(points,)`` closed-curve parameters shared by all sections: in [0, 2) for sharp
            sections, in [0, 3) for blunt ones
            (:func:`torus_cad.geometry.section.section.closed_points`).
        trailing_edge_index: column of the sharp trailing edge, or of the upper corner of a
            blunt one (None if not sampled exactly).
        frames: the frames the sections sit on.
        lower_corner_index: column of the lower corner of a blunt trailing edge (the base runs
            from ``trailing_edge_index`` to it); None for a sharp edge.
        round_trailing_edge: whether that base is a round cap (:mod:`.trailing_edge`), not flat.
    """

    points: NDArray[np.float64]
    s: NDArray[np.float64]
    t: NDArray[np.float64]
    trailing_edge_index: int | None
    frames: Frames
    lower_corner_index: int | None = None
    round_trailing_edge: bool = False

    @property
    def trailing_edge_column(self) -> int:
        """The column of the sharp trailing edge, for surfaces sampled with it as a point (mm
        arrays' axis 1)."""
        if self.trailing_edge_index is None:
            raise ValueError("this surface was sampled without the trailing edge as a point")
        return self.trailing_edge_index

    @property
    def chords_mm(self) -> NDArray[np.float64]:
        """``(sections,)`` chord of each sampled section, mm: trailing edge to the ring's first
        point."""
        return np.asarray(
            np.linalg.norm(self.points[:, self.trailing_edge_column] - self.points[:, 0], axis=-1),
            dtype=np.float64,
        )


def place_on_frames(frames: Frames, planar: NDArray[np.float64]) -> NDArray[np.float64]:
    """X along N, Y along B (spec §4.2): ``(k, p, 2)`` section coordinates -> ``(k, p, 3)`` mm."""
    return (
        frames.origin[:, None, :]
        + planar[..., 0:1] * frames.normal[:, None, :]
        + planar[..., 1:2] * frames.binormal[:, None, :]
    )


@lru_cache(maxsize=16)
def _has_own_base(airfoil: Section) -> bool:
    """:func:`has_base`, remembered: sections_along asks it of the same airfoil at every call
    (hundreds per build, from the printability and blade-element reports)."""
    return has_base(airfoil)


def sections_along(blade: BladeGeometry, s: ArrayLike) -> Sequence[Section]:
    """The chord-unit section at every s: the airfoil itself, or, with a blunt trailing edge, the
    airfoil opened to the blade's absolute trailing-edge thickness there (:mod:`.trailing_edge`),
    flat or round; an airfoil with a base of its own (a coordinate file's open edge) gets the
    blade's trailing-edge shape too (its round caps differ along s, as the section's size does)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    thickness = blade.trailing_edge_thickness_mm
    own_round = blade.round_trailing_edge and _has_own_base(blade.airfoil)
    if thickness <= 0.0 and not own_round:
        return [blade.airfoil] * len(s)
    laws = blade.laws
    return blunt_sections(
        blade.airfoil,
        thickness if thickness > 0.0 else None,
        evaluate_quartic(laws.angle_of_attack_deg, s),
        evaluate_quartic(laws.scale_x_mm, s),
        evaluate_quartic(laws.scale_y_mm, s),
        blade.round_trailing_edge,
    )


def s_outside_the_hub(
    centerline: Centerline, hub_radius_mm: float, hub_length_mm: float
) -> NDArray[np.float64]:
    """The s of TRAILING_EDGE_CHECK_SECTIONS equally spaced sections whose centre is outside the hub
    (inside, the hub swallows the section and its trailing edge): ``(k,)``."""
    s = np.linspace(0.0, 1.0, TRAILING_EDGE_CHECK_SECTIONS)
    points = centerline.points(s)
    outside = (np.hypot(points[:, 0], points[:, 1]) > hub_radius_mm) | (
        np.abs(points[:, 2]) > hub_length_mm / 2.0
    )
    return s[outside]


def with_thin_file_edge_closed(geometry: PropellerGeometry) -> PropellerGeometry:
    """``geometry``, with a coordinate file's open trailing edge closed where it is too thin to mesh
    outside the hub (:func:`.trailing_edge.closed_if_too_thin`); BladeGeometry.closed_file_edge_mm
    says so."""
    blade = geometry.blade
    if not has_base(blade.airfoil):  # a sharp section (every NACA one): nothing to close
        return geometry
    s = s_outside_the_hub(geometry.centerline(0), geometry.hub.radius_mm, geometry.hub.length_mm)
    section, closed_mm = closed_if_too_thin(blade.airfoil, blade.laws, s)
    if closed_mm is None:
        return geometry
    return dataclasses.replace(
        geometry, blade=dataclasses.replace(blade, airfoil=section, closed_file_edge_mm=closed_mm)
    )


def check_trailing_edge(
    blade: BladeGeometry, centerline: Centerline, hub_radius_mm: float, hub_length_mm: float
) -> None:
    """Refuse a blunt trailing edge thicker than the blade's sections where the blade is outside the
    hub (:func:`.trailing_edge.check_trailing_edge_fits`; inside, the hub swallows the sections)."""
    if blade.trailing_edge_thickness_mm <= 0.0:
        return
    s, laws = s_outside_the_hub(centerline, hub_radius_mm, hub_length_mm), blade.laws
    if not len(s):
        return
    check_trailing_edge_fits(
        blade.airfoil,
        blade.trailing_edge_thickness_mm,
        evaluate_quartic(laws.angle_of_attack_deg, s),
        evaluate_quartic(laws.scale_x_mm, s),
        evaluate_quartic(laws.scale_y_mm, s),
        s,
    )


def sections_at(sections: Sequence[Section], t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Every section at the closed parameters ``t``: ``(p, 2)`` if they are all one section, else
    ``(k, p, 2)``."""
    if isinstance(sections, BluntSections):
        return sections.points_at(t)
    base = has_base(sections[0])
    if all(section is sections[0] for section in sections):
        return closed_points(sections[0], t, base)
    return np.stack([closed_points(section, t, base) for section in sections])


def place_sections(
    blade: BladeGeometry, frames: Frames, section: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Transform chord-unit sections, ``(p, 2)`` for all frames or ``(k, p, 2)`` one each, and place
    them: ``(k, p, 3)`` mm."""
    return place_on_frames(frames, blade.laws.apply(section, frames.s))


def blade_frames(blade: BladeGeometry, centerline: Centerline, s: ArrayLike) -> Frames:
    """Frames of the blade's kind on ``centerline`` at ``s``."""
    return section_frames(centerline, s, blade.frame)


def surface_points(
    blade: BladeGeometry, centerline: Centerline, s: ArrayLike, t: ArrayLike
) -> NDArray[np.float64]:
    """The analytic surface at every (s, t) pair of the grid: ``(len(s), len(t), 3)`` mm."""
    frames = blade_frames(blade, centerline, np.atleast_1d(np.asarray(s, dtype=float)))
    return place_sections(
        blade, frames, sections_at(sections_along(blade, frames.s), np.asarray(t, dtype=float))
    )


def blade_surface(
    blade: BladeGeometry,
    centerline: Centerline,
    sections: int,
    points: int,
    anchor_trailing_edge: bool = True,
) -> BladeSurface:
    """Sample the blade on ``centerline`` at ``sections`` x ``points``.

    Sections are uniform in s; points are equally spaced in arc length around the airfoil
    (spec §5), with the trailing edge kept as a point unless ``anchor_trailing_edge`` is False.
    With a blunt trailing edge of constant thickness in mm the chord-unit sections differ
    along s: all of them are sampled at the parameters ``t`` of the section in the middle
    (s = 0.5), which are spaced equally on it (and nearly so on the others), both ends of the base
    included.

    Args:
        blade: the blade's section, quartic laws (degrees, mm), frame kind and trailing edge (mm).
        centerline: the blade's centerline in mm (blade i's from
            :meth:`~torus_cad.geometry.blade.propeller_geometry.PropellerGeometry.centerline`).
        sections: number of sections, s uniform in [0, 1], both ends included.
        points: points around each closed section, at least 8.
        anchor_trailing_edge: keep the trailing edge (and a blunt edge's corners) as points;
            False gives the spec's single uniform spacing.

    Returns:
        The sampled surface: ``points`` ``(sections, points, 3)`` float array, mm; ``s``
        ``(sections,)``; ``t`` ``(points,)``; the frames and the trailing edge's columns.

    Raises:
        GeometryError: the blade's Frenet frame is undefined on the centerline (its curvature
            vanishes or its normal flips; ``centerline.frame = 'rotation_minimizing'`` avoids it).
        ParameterError: ``points`` is below 8, or a blunt trailing edge is thinner than a
            coordinate file's own trailing-edge offset.
    """
    return blade_surface_at(
        blade, centerline, np.linspace(0.0, 1.0, sections), points, anchor_trailing_edge
    )


def blade_surface_at(
    blade: BladeGeometry,
    centerline: Centerline,
    s: ArrayLike,
    points: int,
    anchor_trailing_edge: bool = True,
) -> BladeSurface:
    """:func:`blade_surface` with its sections at the centerline parameters ``s`` ``(k,)``
    (increasing)."""
    frames = blade_frames(blade, centerline, s)
    along = sections_along(blade, frames.s)
    shared = all(section is along[0] for section in along)
    reference = along[0] if shared else sections_along(blade, [0.5])[0]
    sampling = equal_arc_length_section(reference, points, anchor_trailing_edge)
    planar = sampling.points if shared else sections_at(along, sampling.t)
    return BladeSurface(
        place_sections(blade, frames, planar),
        frames.s,
        sampling.t,
        sampling.trailing_edge_index,
        frames,
        sampling.lower_corner_index,
        isinstance(reference, RoundTrailingEdge),
    )
