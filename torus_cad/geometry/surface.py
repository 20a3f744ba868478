"""The blade surface: sections transformed (spec §2) and placed on the frames (spec §4.2).

X_final(s, t) = C(s) + X_scaled(s, t) N(s) + Y_scaled(s, t) B(s), evaluated exactly at any
resolution; blade i is built on its own centerline at theta_0 + 360 i / n (spec §6.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.geometry.airfoil import NacaAirfoil, naca_section
from torus_cad.geometry.airfoil_file import load_airfoil_file
from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.frames import Frames, section_frames
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.section import Section, closed_points, has_base
from torus_cad.geometry.trailing_edge import blunt_sections
from torus_cad.geometry.transforms import evaluate_quartic, transform_sections


@dataclass(frozen=True)
class BladeSurface:
    """Sampled surface of one blade.

    Attributes:
        points: ``(sections, points, 3)`` float, mm; each row is a closed section starting at
            the leading edge, upper surface first (the order of f(t), spec §1.3).
        s: ``(sections,)`` centerline parameters of the sections, 0 and 1 included.
        t: ``(points,)`` closed-curve parameters shared by all sections: in [0, 2) for sharp
            sections, in [0, 3) for blunt ones (:func:`torus_cad.geometry.section.closed_points`).
        trailing_edge_index: column of the sharp trailing edge, or of the upper corner of a
            blunt one (None if not sampled exactly).
        frames: the frames the sections sit on.
        lower_corner_index: column of the lower corner of a blunt trailing edge (the base runs
            from ``trailing_edge_index`` to it); None for a sharp edge.
    """

    points: NDArray[np.float64]
    s: NDArray[np.float64]
    t: NDArray[np.float64]
    trailing_edge_index: int | None
    frames: Frames
    lower_corner_index: int | None = None


def airfoil_of(params: PropellerParameters) -> Section:
    """The section described by ``params.airfoil``: a coordinate file, a NACA designation, or the
    spec's NACA numbers (without the blunt trailing edge; see :func:`sections_along`)."""
    a = params.airfoil
    if getattr(a, "file", ""):
        return load_airfoil_file(a.file)
    if getattr(a, "naca", ""):
        return naca_section(a.naca, a.camber_normal)
    return NacaAirfoil(a.max_camber, a.camber_position, a.thickness, a.camber_normal)


def trailing_edge_thickness_of(params: PropellerParameters) -> float:
    """The blunt trailing edge's thickness in mm (0 = the spec's sharp edge)."""
    return float(getattr(params.airfoil, "trailing_edge_thickness", 0.0))


def sections_along(params: PropellerParameters, s: ArrayLike) -> list[Section]:
    """The chord-unit section at every s: the airfoil itself, or with a base of the absolute blunt thickness."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    section = airfoil_of(params)
    thickness = trailing_edge_thickness_of(params)
    if thickness <= 0.0:
        return [section] * len(s)
    transforms = params.transforms
    return blunt_sections(section, thickness, evaluate_quartic(transforms.angle_of_attack, s),
                          evaluate_quartic(transforms.scale_x, s), evaluate_quartic(transforms.scale_y, s))


def sections_at(sections: list[Section], t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Every section at the closed parameters ``t``: ``(k, len(t), 2)`` chord units (one evaluation if all are one)."""
    base = has_base(sections[0])
    if all(section is sections[0] for section in sections):
        return np.broadcast_to(closed_points(sections[0], t, base), (len(sections), len(t), 2))
    return np.stack([closed_points(section, t, base) for section in sections])


def section_coordinates(params: PropellerParameters, s: NDArray[np.float64], section: NDArray[np.float64]
                        ) -> NDArray[np.float64]:
    """Chord-unit sections ``(p, 2)`` (one for all s) or ``(k, p, 2)`` rotated and scaled for every s
    (spec §2.3): ``(k, p, 2)`` mm."""
    transforms = params.transforms
    return transform_sections(section, evaluate_quartic(transforms.angle_of_attack, s),
                              evaluate_quartic(transforms.scale_x, s), evaluate_quartic(transforms.scale_y, s),
                              params.airfoil.pivot)


def place_on_frames(frames: Frames, planar: NDArray[np.float64]) -> NDArray[np.float64]:
    """X along N, Y along B (spec §4.2): ``(k, p, 2)`` section coordinates -> ``(k, p, 3)`` mm."""
    return (frames.origin[:, None, :] + planar[..., 0:1] * frames.normal[:, None, :]
            + planar[..., 1:2] * frames.binormal[:, None, :])


def place_sections(params: PropellerParameters, frames: Frames, section: NDArray[np.float64]) -> NDArray[np.float64]:
    """Transform a chord-unit section ``(p, 2)`` for every frame and place it: ``(k, p, 3)`` mm."""
    return place_on_frames(frames, section_coordinates(params, frames.s, section))


def blade_frames(params: PropellerParameters, s: ArrayLike, blade_index: int = 0) -> Frames:
    """Frames of the configured kind on blade ``blade_index``'s centerline at ``s``."""
    return section_frames(Centerline.for_blade(params, blade_index), s, params.centerline.frame)


def surface_points(params: PropellerParameters, s: ArrayLike, t: ArrayLike, blade_index: int = 0) -> NDArray[np.float64]:
    """The analytic surface at every (s, t) pair of the grid: ``(len(s), len(t), 3)`` mm."""
    frames = blade_frames(params, np.atleast_1d(np.asarray(s, dtype=float)), blade_index)
    return place_sections(params, frames, sections_at(sections_along(params, frames.s), np.asarray(t, float)))


def blade_surface(params: PropellerParameters, blade_index: int = 0, sections: int | None = None,
                  points: int | None = None, anchor_trailing_edge: bool = True) -> BladeSurface:
    """Sample blade ``blade_index`` on ``sections`` x ``points`` (defaults: ``params.resolution``).

    Sections are uniform in s; points are equally spaced in arc length around the airfoil
    (spec §5), with the trailing edge kept as a point unless ``anchor_trailing_edge`` is False.
    With a blunt trailing edge of constant thickness in mm the chord-unit sections differ
    along s: all of them are sampled at the parameters ``t`` of the section in the middle
    (s = 0.5), spaced equally on it (and nearly so on the others), both corners included.
    """
    sections = params.resolution.sections if sections is None else sections
    points = params.resolution.points if points is None else points
    frames = blade_frames(params, np.linspace(0.0, 1.0, sections), blade_index)
    along = sections_along(params, frames.s)
    reference = along[0] if all(section is along[0] for section in along) else sections_along(params, [0.5])[0]
    sampling = equal_arc_length_section(reference, points, anchor_trailing_edge)
    planar = sampling.points if reference is along[0] else sections_at(along, sampling.t)
    return BladeSurface(place_sections(params, frames, planar), frames.s, sampling.t,
                        sampling.trailing_edge_index, frames, sampling.lower_corner_index)
