"""The blade surface: sections transformed (spec §2) and placed on the frames (spec §4.2).

X_final(s, t) = C(s) + X_scaled(s, t) N(s) + Y_scaled(s, t) B(s), evaluated exactly at any
resolution; blade i is built on its own centerline at theta_0 + 360 i / n (spec §6.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.geometry.airfoil import NacaAirfoil, airfoil_points
from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.frames import Frames, section_frames
from torus_cad.geometry.parameters import PropellerParameters
from torus_cad.geometry.transforms import evaluate_quartic, transform_sections


@dataclass(frozen=True)
class BladeSurface:
    """Sampled surface of one blade.

    Attributes:
        points: ``(sections, points, 3)`` float, mm; each row is a closed section starting at
            the leading edge, upper surface first (the order of f(t), spec §1.3).
        s: ``(sections,)`` centerline parameters of the sections, 0 and 1 included.
        t: ``(points,)`` airfoil parameters in [0, 2) shared by all sections.
        trailing_edge_index: column of the sharp trailing edge (None if not sampled exactly).
        frames: the frames the sections sit on.
    """

    points: NDArray[np.float64]
    s: NDArray[np.float64]
    t: NDArray[np.float64]
    trailing_edge_index: int | None
    frames: Frames


def airfoil_of(params: PropellerParameters) -> NacaAirfoil:
    """The NacaAirfoil described by ``params.airfoil``."""
    a = params.airfoil
    return NacaAirfoil(a.max_camber, a.camber_position, a.thickness, a.camber_normal)


def section_coordinates(params: PropellerParameters, s: NDArray[np.float64], section: NDArray[np.float64]
                        ) -> NDArray[np.float64]:
    """A chord-unit section ``(p, 2)`` rotated and scaled for every s (spec §2.3): ``(k, p, 2)`` mm."""
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
    return place_sections(params, frames, airfoil_points(airfoil_of(params), t))


def blade_surface(params: PropellerParameters, blade_index: int = 0, sections: int | None = None,
                  points: int | None = None, anchor_trailing_edge: bool = True) -> BladeSurface:
    """Sample blade ``blade_index`` on ``sections`` x ``points`` (defaults: ``params.resolution``).

    Sections are uniform in s; points are equally spaced in arc length around the airfoil
    (spec §5), with the trailing edge kept as a point unless ``anchor_trailing_edge`` is False.
    """
    sections = params.resolution.sections if sections is None else sections
    points = params.resolution.points if points is None else points
    sampling = equal_arc_length_section(airfoil_of(params), points, anchor_trailing_edge)
    frames = blade_frames(params, np.linspace(0.0, 1.0, sections), blade_index)
    return BladeSurface(place_sections(params, frames, sampling.points), frames.s, sampling.t,
                        sampling.trailing_edge_index, frames)
