"""The design's front door: from a design (parameters, a TOML path or None) to everything the kernel
is handed, checked, with no OpenCascade.

:func:`prepare_design` runs, in order, each step the build takes before the kernel: the parameters
and their cross-field rules (:mod:`torus_cad.parameters`), the design targets and the propeller the
parameters describe, made once (:mod:`torus_cad.design.design_targets`), then on that description
(:mod:`torus_cad.geometry.analysis.either_kind`) blade 0's sampled surface, the geometric checks and
the hub's mounting features placed against the blades, the hub's seam, and the section fit
(:mod:`torus_cad.geometry.section.section_fit`). ``torus-cad build``
(:func:`torus_cad.propeller.build_propeller`) hands the result to the kernel; ``torus-cad
check`` (:func:`torus_cad.design.design_checks.check_design`) stops there, so the two refuse the
same designs with the same line.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from torus_cad.build_stages import Stage
from torus_cad.design.described_geometry import described_propeller, hub_mounting
from torus_cad.design.design_targets import DesignTargets, resolve_design_targets
from torus_cad.geometry.analysis.either_kind import (
    feasibility_margins,
    mounting_placed,
    sampled_surface,
)
from torus_cad.geometry.analysis.feasibility import Margins, check_root_fillet_edge
from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.geometry.hub.mounting import HubMounting, set_screw_arc_deg
from torus_cad.geometry.hub.seam import seam_angle_deg
from torus_cad.geometry.section.section_fit import SectionFit, fit_sections
from torus_cad.parameters import PropellerParameters, resolve_parameters
from torus_cad.runtime.stage_timer import StageTimer

__all__ = ["PreparedDesign", "placed_mounting", "prepare_design"]

#: Sampling (sections, points around) of the blade surface for the mounting checks: dense enough
#: that a bore, flat or set screw reaching a blade is found (the check uses the points as they are).
MOUNTING_SAMPLES = (200, 160)


@dataclass(frozen=True)
class PreparedDesign:
    """A design that passed every check before the kernel, with what the kernel is handed (mm).

    Attributes:
        parameters: the spec parameters the design resolved to (design targets applied).
        targets: what the designer's inputs (``airfoil.naca``, ``diameter``, ``pitch``) resolved to.
        surface: blade 0's sampled surface at ``resolution``: ``points`` ``(sections, points, 3)``.
        margins: the largest fold ratio and section sag (toroidal designs; None for a conventional
            one).
        mounting: the hub's bore, flat, set screw and chamfer, the set screw's direction chosen.
        seam_deg: the angle (degrees about +z) of the hub's seam, where it crosses no blade root
            nor the set screw; None where every angle is crossed.
        fit: blade 0's section B-splines as arrays (poles, knots), which the kernel lofts.
    """

    parameters: PropellerParameters
    targets: DesignTargets
    surface: BladeSurface
    margins: Margins | None
    mounting: HubMounting
    seam_deg: float | None
    fit: SectionFit


def _mounting_samples(params: PropellerParameters) -> tuple[int, int]:
    """The blade's sampling for the mounting checks: the design's, or MOUNTING_SAMPLES if denser."""
    resolution = params.resolution
    return (
        max(resolution.sections, MOUNTING_SAMPLES[0]),
        max(resolution.points, MOUNTING_SAMPLES[1]),
    )


def placed_mounting(params: PropellerParameters) -> HubMounting:
    """The hub's mounting features checked against the blades, the set screw placed.

    Args:
        params: the validated design, its design targets applied.

    Returns:
        The bore, flat, set screw and chamfer (mm), the set screw's direction chosen away from the
        blades.

    Raises:
        GeometryError: a feature reaches a blade (the line names the field).
    """
    samples = _mounting_samples(params)
    mounting, propeller = hub_mounting(params), described_propeller(params)
    return mounting_placed(mounting, propeller, samples, params.hub.root_fillet_radius)


def prepare_design(
    design: PropellerParameters | str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    timer: StageTimer[Stage] | None = None,
) -> PreparedDesign:
    """Every step of the build before the kernel, in its order; the first refusal raises.

    The propeller is described once (:func:`resolve_design_targets`); every later step takes that
    description (:mod:`torus_cad.geometry.analysis.either_kind`), not the parameters again.

    Args:
        design: a :class:`PropellerParameters`, the path of a TOML design file, or None for the
            default propeller.
        overrides: optional dotted-key changes applied on top of ``design`` (mm, degrees).
        timer: times the stages (parameters, design targets, section math); None for none.

    Returns:
        The resolved parameters, the design targets, blade 0's surface, the margins, the placed
        mounting, the hub's seam angle and the section fit.

    Raises:
        ParameterError: a bad parameter, override or design file, or a design target that cannot
            be met (the message names the field).
        GeometryError: valid parameters that describe no sound propeller (the line names the check).
    """
    timer = timer if timer is not None else StageTimer[Stage]()
    with timer.stage(Stage.PARAMETERS):
        params = resolve_parameters(design, overrides)
    with timer.stage(Stage.DESIGN_TARGETS):
        samples, mounting = _mounting_samples(params), hub_mounting(params)
        # airfoil.naca, diameter, pitch -> the spec's parameters, and the propeller they describe
        targets = resolve_design_targets(params)
        params, propeller = targets.parameters, targets.propeller
    with timer.stage(Stage.SECTION_MATH):
        hub, resolution = params.hub, params.resolution
        surface = sampled_surface(propeller, 0, resolution.sections, resolution.points)
        check_root_fillet_edge(hub.root_fillet_radius, params.airfoil.trailing_edge_thickness)
        margins = feasibility_margins(propeller, surface)
        mounting = mounting_placed(mounting, propeller, samples, hub.root_fillet_radius)
        # The hub is symmetric about its axis; its seam goes where it crosses no blade root (nor
        # the set screw).
        screw_arc = set_screw_arc_deg(mounting, hub.radius)
        seam_deg = seam_angle_deg(
            surface.points, hub.radius, params.blades, () if screw_arc is None else (screw_arc,)
        )
        fit = fit_sections(
            surface.points,
            surface.trailing_edge_column,
            surface.chords_mm,
            surface.lower_corner_index,
            surface.round_trailing_edge,
        )
    return PreparedDesign(params, targets, surface, margins, mounting, seam_deg, fit)
