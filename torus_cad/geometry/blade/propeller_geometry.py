"""The propeller's geometry as kernel-free objects: hub, blade (section, laws, centerline, frame),
pattern.

The parameter schema (:mod:`torus_cad.parameters`) converts a design into a
:class:`PropellerGeometry`; every geometry function takes these objects, not the parameter
set, and the kernel takes the arrays they produce. Units: mm and degrees.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.blade.centerline import Centerline, hub_inset_radius_mm
from torus_cad.geometry.blade.frames import FrameKind
from torus_cad.geometry.blade.transforms import SectionLaws
from torus_cad.geometry.section.section import Section

#: The hub's number where the propeller's parts are numbered (a face's part, a scene's part); blade
#: i is i.
HUB_PART = -1


@dataclass(frozen=True)
class HubGeometry:
    """The cylindrical hub on the z axis, centred at the origin: radius and length in mm."""

    radius_mm: float
    length_mm: float

    @property
    def inset_radius_mm(self) -> float:
        """R_inset = R - R/8 (spec §3.2), mm: the radius of the blade's ends."""
        return hub_inset_radius_mm(self.radius_mm)


@dataclass(frozen=True)
class BladeGeometry:
    """One blade: its section, how the section changes along s, and the frame it sits on.

    Attributes:
        airfoil: the chord-unit section (spec §1; any
            :class:`~torus_cad.geometry.section.section.Section`: NACA 4- or 5-digit, a coordinate
            file).
        laws: alpha(s), Sx(s), Sy(s) and the pivot (spec §2).
        local_control_points: ``(4, 3)`` P1..P4 in the hub's frame L ([deg, mm, mm], spec §3.1).
        frame: the moving frame's kind (spec §4).
        trailing_edge_thickness_mm: a blunt trailing edge this thick on every section (mm; 0 =
            the section's own edge, sharp for NACA sections;
            :mod:`torus_cad.geometry.blade.trailing_edge`).
        round_trailing_edge: a blunt trailing edge (the thickness above, or a coordinate file's open
            edge) ends in a round cap (True) or a flat base (False;
            :mod:`torus_cad.geometry.blade.trailing_edge`).
        closed_file_edge_mm: (thinnest, thickest) open trailing edge of the coordinate file that was
            closed to the sharp ``airfoil`` because it is too thin to mesh, mm
            (:func:`torus_cad.geometry.blade.trailing_edge.closed_if_too_thin`); None when nothing
            was closed.
    """

    airfoil: Section
    laws: SectionLaws
    local_control_points: tuple[tuple[float, float, float], ...]
    frame: FrameKind = FrameKind.FRENET
    trailing_edge_thickness_mm: float = 0.0
    round_trailing_edge: bool = False
    closed_file_edge_mm: tuple[float, float] | None = None


def blade_angle_deg(phase_deg: float, blade_index: int, blades: int) -> float:
    """theta_i = theta_0 + 360 i / n (spec §6.1), degrees: where blade ``blade_index`` of
    ``blades`` sits about +z, of either kind."""
    return phase_deg + 360.0 * blade_index / blades


@dataclass(frozen=True)
class PropellerGeometry:
    """Hub, blade and pattern: blade i sits at theta_0 + 360 i / n degrees (spec §6.1)."""

    hub: HubGeometry
    blade: BladeGeometry
    blades: int
    phase_deg: float = 0.0

    def blade_angle_deg(self, blade_index: int) -> float:
        """theta_i = theta_0 + 360 i / n (spec §6.1), degrees."""
        return blade_angle_deg(self.phase_deg, blade_index, self.blades)

    def centerline(self, blade_index: int = 0) -> Centerline:
        """Blade ``blade_index``'s centerline in global Cartesian coordinates (mm)."""
        return Centerline.in_hub_frame(
            self.local_control_points,
            self.hub.radius_mm,
            self.hub.length_mm,
            self.blade_angle_deg(blade_index),
        )

    @property
    def local_control_points(self) -> NDArray[np.float64]:
        """``(4, 3)`` P1..P4 in frame L."""
        return np.asarray(self.blade.local_control_points, dtype=float)
