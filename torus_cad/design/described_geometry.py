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
from torus_cad.geometry.analysis.feasibility import Margins, check_feasible, check_root_fillet_edge
from torus_cad.geometry.analysis.printability import (
    Printability,
    conventional_printability,
    printability,
)
from torus_cad.geometry.blade.blade_surface import (
    BladeSurface,
    blade_surface,
    with_thin_file_edge_closed,
)
from torus_cad.geometry.blade.conventional_blade import (
    ConventionalBlade,
    check_conventional_feasible,
    conventional_surface,
    rotated_surface,
)
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
    chosen later, from the blades (:func:`torus_cad.geometry.hub.mounting.place_mounting`)."""
    hub = params.hub
    return HubMounting(hub.bore_diameter, hub.bore_flat_depth, hub.set_screw_diameter, hub.chamfer)


def conventional_blade(params: PropellerParameters) -> ConventionalBlade:
    """The conventional blade ``params`` describe (kind = 'conventional'; mm, degrees)."""
    airfoil = params.airfoil
    return ConventionalBlade(
        params.conventional.stations(),
        params.conventional.diameter / 2.0,
        airfoil.section(),
        params.conventional.stacking,
        hub_geometry(params),
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
    line, transforms, airfoil = params.centerline, params.transforms, params.airfoil
    laws = SectionLaws(
        transforms.angle_of_attack, transforms.scale_x, transforms.scale_y, airfoil.pivot
    )
    local = ((0.0, 0.0, 0.0), line.p2, line.p3, (*line.p4, 0.0))
    blade = BladeGeometry(
        airfoil.section(),
        laws,
        local,
        line.frame,
        airfoil.trailing_edge_thickness,
        airfoil.trailing_edge_shape == TrailingEdgeShape.ROUND,
    )
    geometry = PropellerGeometry(hub_geometry(params), blade, params.blades, params.phase_deg)
    if airfoil.trailing_edge_thickness > 0.0:
        return geometry
    return with_thin_file_edge_closed(geometry)


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
        The sampled surface: ``points`` ``(sections, points, 3)`` float array, mm; ``s``
        ``(sections,)``; ``t`` ``(points,)``; the frames and the trailing edge's columns.

    Raises:
        GeometryError: the blade's frames are undefined (a Frenet frame where the centerline's
            curvature vanishes or its normal flips).
        ParameterError: ``points`` is below 8, or a blunt trailing edge is thinner than the
            coordinate file's own trailing-edge offset.
    """
    sections = params.resolution.sections if sections is None else sections
    points = params.resolution.points if points is None else points
    if params.kind == DesignKind.CONVENTIONAL:
        surface = conventional_surface(conventional_blade(params), sections, points)
        return rotated_surface(surface, params.blade_angle_deg(blade_index))
    geometry = propeller_geometry(params)
    return blade_surface(geometry.blade, geometry.centerline(blade_index), sections, points)


def wall_printability(params: PropellerParameters) -> Printability:
    """The blade's thinnest wall and trailing edge against ``manufacturing.min_wall``, from the
    analytic section (:mod:`torus_cad.geometry.analysis.printability`), of either kind.

    Args:
        params: the validated design.

    Returns:
        The thinnest wall and trailing edge (mm), where along the blade (s) they are, and whether
        they reach ``manufacturing.min_wall``.
    """
    min_wall_mm = params.manufacturing.min_wall
    if params.kind == DesignKind.CONVENTIONAL:
        return conventional_printability(conventional_blade(params), min_wall_mm)
    return printability(propeller_geometry(params), min_wall_mm)


def check_design_feasible(params: PropellerParameters, surface: BladeSurface) -> Margins | None:
    """The pre-kernel checks of the design's kind on blade 0's ``surface``.

    First a root fillet round a knife trailing edge
    (:func:`torus_cad.geometry.analysis.feasibility.check_root_fillet_edge`), then
    :func:`torus_cad.geometry.analysis.feasibility.check_feasible` (toroidal) or
    :func:`torus_cad.geometry.blade.conventional_blade.check_conventional_feasible`.

    Args:
        params: the validated design.
        surface: blade 0 sampled at the design's resolution (:func:`sampled_blade_surface`).

    Returns:
        A toroidal design's margins to the fold and resolution limits; None for a conventional one.

    Raises:
        GeometryError: the design describes no sound propeller (the line names the check).
    """
    check_root_fillet_edge(params.hub.root_fillet_radius, params.airfoil.trailing_edge_thickness)
    if params.kind == DesignKind.CONVENTIONAL:
        check_conventional_feasible(conventional_blade(params), surface, params.blades)
        return None
    return check_feasible(propeller_geometry(params), surface)
