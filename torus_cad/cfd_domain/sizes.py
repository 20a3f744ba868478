"""The fluid domain's sizes and the propeller's trailing-edge lines, kernel-free (numpy only).

The gmsh mesher (torus_cad.cfd_domain.domain) builds and sizes the domain from these; the estimate
(torus_cad.cfd_domain.estimate) counts its tetrahedra from the same numbers before any work.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from torus_cad.design.described_geometry import (
    conventional_blade,
    propeller_geometry,
    sampled_blade_surface,
)
from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.transforms import evaluate_quartic
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Cfd, DesignKind, Handedness, InletSide

#: Elements around the rotating zone's and the outer cylinder's circumference, at least.
CYLINDER_SEGMENTS = 64
#: Smallest element allowed, as a fraction of the surface size (bounds curvature refinement).
MIN_SIZE_FRACTION = 0.1
#: Sections sampled along each trailing edge.
TRAILING_EDGE_SECTIONS = 41
#: Element size on a blunt trailing edge, in edge thicknesses.
TRAILING_EDGE_SIZE_PER_THICKNESS = 1.0


@dataclass(frozen=True)
class Domain:
    """Sizes of the fluid domain and its mesh, mm (z along the spin axis).

    Attributes:
        tip_diameter: D, twice the largest distance of the blade surface from the axis.
        propeller_z: (low, high) axial extent of the propeller.
        outer_radius, outer_z: the outer cylinder; inlet at one end of ``outer_z``, outlet at the
            other.
        zone_radius, zone_z: the rotating-zone cylinder.
        inlet_z, outlet_z: axial positions of the inlet and outlet caps.
        surface_size: element size on the propeller (smallest chord / cells_per_chord).
        far_size: the largest element.
    """

    tip_diameter: float
    propeller_z: tuple[float, float]
    outer_radius: float
    outer_z: tuple[float, float]
    zone_radius: float
    zone_z: tuple[float, float]
    inlet_z: float
    outlet_z: float
    surface_size: float
    far_size: float

    @property
    def outer_volume(self) -> float:
        """Volume of the outer cylinder (the whole domain before the propeller is removed), mm^3."""
        return float(np.pi * self.outer_radius**2 * (self.outer_z[1] - self.outer_z[0]))

    @property
    def zone_volume(self) -> float:
        """Volume of the rotating-zone cylinder, mm^3."""
        return float(np.pi * self.zone_radius**2 * (self.zone_z[1] - self.zone_z[0]))


#: Grid on which the analytic blade is sampled for the tip radius.
TIP_RADIUS_GRID = (201, 200)


def tip_radius(params: PropellerParameters) -> float:
    """Largest distance of the blade surface from the spin axis, mm (analytic surface, sampled
    densely)."""
    points = sampled_blade_surface(params, 0, *TIP_RADIUS_GRID).points
    return float(max(np.hypot(points[..., 0], points[..., 1]).max(), params.hub.radius))


def smallest_chord(params: PropellerParameters) -> float:
    """Smallest chord over the blade, mm: Sx(s) of a toroidal blade, c(r) of a conventional one
    (root blend included)."""
    if params.kind == DesignKind.CONVENTIONAL:
        blade = conventional_blade(params)
        return float(blade.chord_mm(blade.section_radii_mm(201)[1]).min())
    return float(
        evaluate_quartic(
            propeller_geometry(params).blade.laws.scale_x_mm, np.linspace(0.0, 1.0, 201)
        ).min()
    )


def domain_for(
    params: PropellerParameters, settings: Cfd, propeller_z: tuple[float, float]
) -> Domain:
    """The domain's sizes for a designed propeller spanning ``propeller_z`` (mm) axially."""
    return domain_from_sizes(
        2.0 * tip_radius(params), smallest_chord(params), settings, propeller_z
    )


def domain_from_sizes(
    diameter: float, chord: float, settings: Cfd, propeller_z: tuple[float, float]
) -> Domain:
    """The domain's sizes for a propeller of tip diameter ``diameter`` (mm) whose smallest chord is
    ``chord`` (mm; sets the surface size, ``chord / cells_per_chord``), spanning ``propeller_z``
    (mm) along +z."""
    centre = 0.5 * (propeller_z[0] + propeller_z[1])
    clearance = settings.zone_clearance * diameter
    zone_z = (propeller_z[0] - clearance, propeller_z[1] + clearance)
    upstream, downstream = settings.upstream * diameter, settings.downstream * diameter
    if settings.inlet_side == InletSide.PLUS_Z:
        inlet_z, outlet_z = centre + upstream, centre - downstream
    else:
        inlet_z, outlet_z = centre - upstream, centre + downstream
    outer_z = (min(inlet_z, outlet_z), max(inlet_z, outlet_z))
    if outer_z[0] >= zone_z[0] - clearance or outer_z[1] <= zone_z[1] + clearance:
        raise ParameterError(
            f"cfd.upstream = {settings.upstream:g} / cfd.downstream "
            f"= {settings.downstream:g} put an end of the domain "
            f"inside the rotating zone (it spans z = {zone_z[0]:.1f} .. "
            f"{zone_z[1]:.1f} mm, D = {diameter:.1f} mm); "
            "make them larger"
        )
    return Domain(
        tip_diameter=diameter,
        propeller_z=propeller_z,
        outer_radius=settings.domain_radius * diameter,
        outer_z=outer_z,
        zone_radius=settings.zone_radius * diameter,
        zone_z=zone_z,
        inlet_z=inlet_z,
        outlet_z=outlet_z,
        surface_size=chord / settings.cells_per_chord,
        far_size=settings.far_size * diameter,
    )


@dataclass(frozen=True)
class TrailingEdges:
    """The propeller's trailing edges: where a coarse surface mesh crosses itself first.

    Attributes:
        curves_mm: ``(sections, 3)`` polylines, one per blade (two, the corners, for a blunt edge).
        thickness_mm: the edge's thickness (0 for a knife edge).
    """

    curves_mm: tuple[np.ndarray, ...]
    thickness_mm: float


def trailing_edges(params: PropellerParameters) -> TrailingEdges:
    """The trailing edges of every blade of ``params`` from the analytic surface (mirrored for
    'ccw')."""
    curves = []
    for index in range(params.blades):
        surface = sampled_blade_surface(params, index, sections=TRAILING_EDGE_SECTIONS)
        columns = [surface.trailing_edge_index, surface.lower_corner_index]
        for column in (c for c in columns if c is not None):
            curve = surface.points[:, column, :].copy()
            if params.handedness == Handedness.CCW:
                curve[:, 1] *= -1.0
            curves.append(curve)
    return TrailingEdges(tuple(curves), params.airfoil.trailing_edge_thickness)
