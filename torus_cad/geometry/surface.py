"""The blade surface: sections transformed (spec §2) and placed on the frames (spec §4.2).

X_final(s, t) = C(s) + X_scaled(s, t) N(s) + Y_scaled(s, t) B(s), evaluated exactly at any
resolution; blade i is built on its own centerline at theta_0 + 360 i / n (spec §6.1), which
:meth:`torus_cad.geometry.propeller.PropellerGeometry.centerline` gives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.geometry.airfoil import airfoil_points
from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.frames import Frames, section_frames
from torus_cad.geometry.propeller import BladeGeometry


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

    @property
    def trailing_edge_column(self) -> int:
        """The column of the sharp trailing edge, for surfaces sampled with it as a point (mm arrays' axis 1)."""
        if self.trailing_edge_index is None:
            raise ValueError("this surface was sampled without the trailing edge as a point")
        return self.trailing_edge_index


def place_on_frames(frames: Frames, planar: NDArray[np.float64]) -> NDArray[np.float64]:
    """X along N, Y along B (spec §4.2): ``(k, p, 2)`` section coordinates -> ``(k, p, 3)`` mm."""
    return (frames.origin[:, None, :] + planar[..., 0:1] * frames.normal[:, None, :]
            + planar[..., 1:2] * frames.binormal[:, None, :])


def place_sections(blade: BladeGeometry, frames: Frames, section: NDArray[np.float64]) -> NDArray[np.float64]:
    """Transform a chord-unit section ``(p, 2)`` for every frame and place it: ``(k, p, 3)`` mm."""
    return place_on_frames(frames, blade.laws.apply(section, frames.s))


def blade_frames(blade: BladeGeometry, centerline: Centerline, s: ArrayLike) -> Frames:
    """Frames of the blade's kind on ``centerline`` at ``s``."""
    return section_frames(centerline, s, blade.frame)


def surface_points(blade: BladeGeometry, centerline: Centerline, s: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    """The analytic surface at every (s, t) pair of the grid: ``(len(s), len(t), 3)`` mm."""
    frames = blade_frames(blade, centerline, np.atleast_1d(np.asarray(s, dtype=float)))
    return place_sections(blade, frames, airfoil_points(blade.airfoil, t))


def blade_surface(blade: BladeGeometry, centerline: Centerline, sections: int, points: int,
                  anchor_trailing_edge: bool = True) -> BladeSurface:
    """Sample the blade on ``centerline`` at ``sections`` x ``points``.

    Sections are uniform in s; points are equally spaced in arc length around the airfoil
    (spec §5), with the trailing edge kept as a point unless ``anchor_trailing_edge`` is False.
    """
    sampling = equal_arc_length_section(blade.airfoil, points, anchor_trailing_edge)
    frames = blade_frames(blade, centerline, np.linspace(0.0, 1.0, sections))
    return BladeSurface(place_sections(blade, frames, sampling.points), frames.s, sampling.t,
                        sampling.trailing_edge_index, frames)
