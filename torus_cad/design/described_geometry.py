"""The kernel-free geometry a design's parameters describe: the hub, the blade, its sampled surface.

The parameters (:mod:`torus_cad.parameters`) are the validated schema and nothing more; this module
turns them into the geometry layer's objects (:mod:`torus_cad.geometry`), for either kind of blade
(toroidal: a centerline with its sections; conventional: a station table). Everything downstream
(the build, ``check``, the mesh, the CFD domain, the vortex solver, the studio) asks here::

    from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
    geometry = propeller_geometry(params)           # hub, blade (airfoil, laws, frame), pattern
    surface = sampled_blade_surface(params)         # blade 0 at the design's resolution (mm)
"""

from __future__ import annotations

from torus_cad.errors import GeometryError
from torus_cad.geometry.analysis.either_kind import (
    DescribedPropeller,
    feasibility_margins,
    propeller_printability,
    sampled_surface,
)
from torus_cad.geometry.analysis.feasibility import Margins, check_root_fillet_edge
from torus_cad.geometry.analysis.printability import Printability
from torus_cad.geometry.blade.blade_surface import BladeSurface, with_thin_file_edge_closed
from torus_cad.geometry.blade.conventional_blade import ConventionalBlade, ConventionalPropeller
from torus_cad.geometry.blade.propeller_geometry import (
    BladeGeometry,
    HubGeometry,
    PropellerGeometry,
)
from torus_cad.geometry.blade.transforms import SectionLaws
from torus_cad.geometry.hub.mounting import HubMounting
from torus_cad.parameters.design import DesignKind, PropellerParameters, TrailingEdgeShape

__all__ = [
    "check_design_feasible",
    "conventional_blade",
    "described_propeller",
    "hub_geometry",
    "hub_mounting",
    "propeller_geometry",
    "sampled_blade_surface",
    "wall_printability",
]


def hub_geometry(params: PropellerParameters) -> HubGeometry:
    """The hub's cylinder (mm), of either kind."""
    return HubGeometry(params.hub.radius, params.hub.length)


def hub_mounting(params: PropellerParameters) -> HubMounting:
    """The hub's bore, flat, set screw and chamfer as geometry (mm); the set screw's direction is
    chosen later, from the blades (:func:`torus_cad.geometry.analysis.either_kind.mounting_placed`).
    """
    hub = params.hub
    return HubMounting(hub.bore_diameter, hub.bore_flat_depth, hub.set_screw_diameter, hub.chamfer)


def conventional_blade(params: PropellerParameters) -> ConventionalBlade:
    """The conventional blade ``params`` describe (kind = 'conventional'; mm, degrees)."""
    hub = hub_geometry(params)
    airfoil, conventional = params.airfoil, params.conventional
    return ConventionalBlade(
        conventional.stations(),
        conventional.diameter / 2.0,
        airfoil.section(),
        conventional.stacking,
        hub,
        airfoil.trailing_edge_thickness,
        airfoil.trailing_edge_shape == TrailingEdgeShape.ROUND,
    )


def propeller_geometry(params: PropellerParameters) -> PropellerGeometry:
    """The kernel-free geometry ``params`` describe (mm, degrees); toroidal designs only (a
    conventional one has :func:`conventional_blade`).

    A coordinate file's open trailing edge that is too thin to mesh outside the hub is closed here
    (``BladeGeometry.closed_file_edge_mm`` says so).

    Args:
        params: the validated design.

    Returns:
        The hub (mm), the blade (section, quartic laws, control points in frame L, frame kind,
        trailing edge in mm), the number of blades and the phase (degrees).

    Raises:
        GeometryError: ``kind`` is 'conventional' (it has no centerline).
    """
    if params.kind == DesignKind.CONVENTIONAL:
        raise GeometryError(
            "this step is toroidal-only (it needs the blade's centerline); "
            "kind = 'conventional' has none"
        )
    hub = hub_geometry(params)
    line, transforms, airfoil = params.centerline, params.transforms, params.airfoil
    section = airfoil.section()
    laws = SectionLaws(
        transforms.angle_of_attack, transforms.scale_x, transforms.scale_y, airfoil.pivot
    )
    local = ((0.0, 0.0, 0.0), line.p2, line.p3, (*line.p4, 0.0))
    blade = BladeGeometry(
        section,
        laws,
        local,
        line.frame,
        airfoil.trailing_edge_thickness,
        airfoil.trailing_edge_shape == TrailingEdgeShape.ROUND,
    )
    geometry = PropellerGeometry(hub, blade, params.blades, params.phase_deg)
    if airfoil.trailing_edge_thickness > 0.0:
        return geometry
    return with_thin_file_edge_closed(geometry)


def described_propeller(params: PropellerParameters) -> DescribedPropeller:
    """The propeller ``params`` describe, of its kind: made once, then sampled, checked and measured
    through :mod:`torus_cad.geometry.analysis.either_kind`.

    Args:
        params: the validated design.

    Returns:
        A :class:`~torus_cad.geometry.blade.propeller_geometry.PropellerGeometry` (toroidal) or a
        :class:`~torus_cad.geometry.blade.conventional_blade.ConventionalPropeller` (mm, degrees).
    """
    if params.kind == DesignKind.CONVENTIONAL:
        return ConventionalPropeller(conventional_blade(params), params.blades, params.phase_deg)
    return propeller_geometry(params)


def sampled_blade_surface(
    params: PropellerParameters,
    blade_index: int = 0,
    sections: int | None = None,
    points: int | None = None,
) -> BladeSurface:
    """Blade ``blade_index`` of ``params`` sampled at ``sections`` x ``points`` (default: the
    design's ``resolution``).

    A conventional blade is blade 0 rotated about +z to blade ``blade_index``'s angle.

    Args:
        params: the validated design.
        blade_index: which blade, 0 to ``blades - 1``; blade i sits at ``phase_deg + 360 i / n``
            degrees.
        sections: sections along the blade (s uniform in [0, 1]); None for
            ``resolution.sections``.
        points: points around each section, equally spaced in arc length, at least 8; None for
            ``resolution.points``.

    Returns:
        The sampled surface, as :func:`torus_cad.geometry.analysis.either_kind.sampled_surface`
        gives it (``points`` ``(sections, points, 3)``, mm).

    Raises:
        GeometryError: the blade's frames are undefined (a Frenet frame where the centerline's
            curvature vanishes or its normal flips).
        ParameterError: ``points`` is below 8, or a blunt trailing edge is thinner than the
            coordinate file's own trailing-edge offset.
    """
    propeller = described_propeller(params)
    resolution = params.resolution
    sections = resolution.sections if sections is None else sections
    points = resolution.points if points is None else points
    return sampled_surface(propeller, blade_index, sections, points)


def wall_printability(params: PropellerParameters) -> Printability:
    """The blade's thinnest wall and trailing edge against ``manufacturing.min_wall``, from the
    analytic section (:mod:`torus_cad.geometry.analysis.printability`), of either kind.

    Args:
        params: the validated design.

    Returns:
        The thinnest wall and trailing edge (mm), where along the blade (s) they are, and whether
        they reach ``manufacturing.min_wall``.
    """
    propeller = described_propeller(params)
    return propeller_printability(propeller, params.manufacturing.min_wall)


def check_design_feasible(params: PropellerParameters, surface: BladeSurface) -> Margins | None:
    """The pre-kernel checks of the design's kind on blade 0's ``surface``.

    First a root fillet round a knife trailing edge
    (:func:`torus_cad.geometry.analysis.feasibility.check_root_fillet_edge`), then the kind's own
    (:func:`torus_cad.geometry.analysis.either_kind.feasibility_margins`).

    Args:
        params: the validated design.
        surface: blade 0 sampled at the design's resolution (:func:`sampled_blade_surface`).

    Returns:
        A toroidal design's margins to the fold and resolution limits; None for a conventional one.

    Raises:
        GeometryError: the design describes no sound propeller (the line names the check).
    """
    check_root_fillet_edge(params.hub.root_fillet_radius, params.airfoil.trailing_edge_thickness)
    return feasibility_margins(described_propeller(params), surface)
