"""A propeller of either kind through one set of functions: the toroidal
:class:`~torus_cad.geometry.blade.propeller_geometry.PropellerGeometry` and the conventional
:class:`~torus_cad.geometry.blade.conventional_blade.ConventionalPropeller`.

Each function picks the kind's own routine (sampling, the pre-kernel checks, the walls, the hub's
mounting against the blades), so that a caller holding a described propeller needs no branch on its
kind (:mod:`torus_cad.design.described_geometry` makes one from the parameters).
"""

from __future__ import annotations

from torus_cad.geometry.analysis.feasibility import Margins, check_feasible
from torus_cad.geometry.analysis.printability import (
    Printability,
    conventional_printability,
    printability,
)
from torus_cad.geometry.blade.blade_surface import BladeSurface, blade_surface
from torus_cad.geometry.blade.conventional_blade import (
    ConventionalPropeller,
    check_conventional_feasible,
    conventional_surface,
    rotated_surface,
)
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.hub.mounting import HubMounting, place_mounting

__all__ = [
    "DescribedPropeller",
    "feasibility_margins",
    "mounting_placed",
    "propeller_printability",
    "sampled_surface",
]

#: A kernel-free propeller of either kind (mm, degrees).
DescribedPropeller = PropellerGeometry | ConventionalPropeller


def sampled_surface(
    propeller: DescribedPropeller, blade_index: int, sections: int, points: int
) -> BladeSurface:
    """Blade ``blade_index`` sampled at ``sections`` x ``points``.

    Args:
        propeller: the propeller, either kind.
        blade_index: which blade, 0 to ``blades - 1`` (a conventional blade is blade 0 turned
            about +z to its angle).
        sections: sections along the blade (s uniform in [0, 1]).
        points: points around each section, equally spaced in arc length, at least 8.

    Returns:
        The sampled surface: ``points`` ``(sections, points, 3)`` float array, mm; ``s``
        ``(sections,)``; ``t`` ``(points,)``; the frames and the trailing edge's columns.

    Raises:
        GeometryError: the blade's frames are undefined (a Frenet frame where the centerline's
            curvature vanishes or its normal flips).
        ParameterError: ``points`` is below 8.
    """
    if isinstance(propeller, ConventionalPropeller):
        surface = conventional_surface(propeller.blade, sections, points)
        return rotated_surface(surface, propeller.blade_angle_deg(blade_index))
    centerline = propeller.centerline(blade_index)
    return blade_surface(propeller.blade, centerline, sections, points)


def feasibility_margins(propeller: DescribedPropeller, surface: BladeSurface) -> Margins | None:
    """The kind's pre-kernel checks on blade 0's ``surface``: raises on the first that fails.

    Args:
        propeller: the propeller, either kind.
        surface: blade 0 sampled at the design's resolution.

    Returns:
        A toroidal propeller's margins to the fold and resolution limits
        (:func:`torus_cad.geometry.analysis.feasibility.check_feasible`); None for a conventional
        one (:func:`torus_cad.geometry.blade.conventional_blade.check_conventional_feasible`).

    Raises:
        GeometryError: the propeller is not sound (the line names the check).
    """
    if isinstance(propeller, ConventionalPropeller):
        check_conventional_feasible(propeller.blade, surface, propeller.blades)
        return None
    return check_feasible(propeller, surface)


def propeller_printability(propeller: DescribedPropeller, min_wall_mm: float) -> Printability:
    """The blade's thinnest wall and trailing edge against ``min_wall_mm``, from the analytic
    section.

    Args:
        propeller: the propeller, either kind.
        min_wall_mm: the thinnest wall a printer makes, mm.

    Returns:
        The thinnest wall and trailing edge (mm), where along the blade (s) they are, and whether
        they reach ``min_wall_mm``.
    """
    if isinstance(propeller, ConventionalPropeller):
        return conventional_printability(propeller.blade, min_wall_mm)
    return printability(propeller, min_wall_mm)


def mounting_placed(
    mounting: HubMounting,
    propeller: DescribedPropeller,
    samples: tuple[int, int],
    root_fillet_radius_mm: float,
) -> HubMounting:
    """``mounting`` checked against the blades, sampled densely, and its set screw placed.

    Args:
        mounting: the hub's bore, flat, set screw and chamfer (mm).
        propeller: the propeller, either kind.
        samples: (sections, points around) of blade 0's sampling: dense enough that its points
            bound the blade (the check uses them as they are).
        root_fillet_radius_mm: the root fillet's radius, mm, which the set screw must clear.

    Returns:
        ``mounting`` with the set screw's angle chosen away from the blades (unchanged when it has
        no feature).

    Raises:
        GeometryError: a feature reaches a blade (the line names the field).
    """
    if not mounting.any:
        return mounting
    dense = sampled_surface(propeller, 0, *samples)
    hub = propeller.hub
    return place_mounting(
        mounting,
        dense.points,
        propeller.blades,
        hub.radius_mm,
        hub.length_mm,
        root_fillet_radius_mm,
    )
