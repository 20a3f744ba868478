"""The designer's inputs turned into the spec's parameters: airfoil by name, diameter, pitch.

The spec's parameters stay the truth; these inputs are converted into them before anything
is built, in this order:

1. ``airfoil.naca`` "MPTT" sets ``max_camber``, ``camber_position`` and ``thickness``
   (5-digit designations and ``airfoil.file`` have no spec numbers; they stay as they are).
2. ``diameter`` scales the radial coordinates z_L of ``centerline.p2`` and ``p3`` until the
   tip diameter is met, and ``pitch`` refits ``transforms.angle_of_attack``, the two fits
   alternating on the geometry (:mod:`torus_cad.geometry.analysis.target_fit`).

:func:`resolve_design_targets` returns the resolved parameters (the targets removed, so they
build the same propeller without solving again) and what each step achieved.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.geometry.analysis.pitch import PitchFit
from torus_cad.geometry.analysis.target_fit import achieved, fitted_to_targets, tip_radius_of
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.section.airfoil import naca4_numbers


@dataclass(frozen=True)
class DesignTargets:
    """What the designer's inputs resolved to.

    Attributes:
        parameters: the resolved spec parameters (targets removed).
        radial_scale: factor applied to z_L of p2 and p3 (None without a diameter target).
        tip_diameter_mm: the tip diameter of the resolved design (analytic surface; None when
            no diameter or pitch was asked for: not computed, to keep the default build fast).
        pitch_fit: the alpha(s) fit (None without a pitch target).
        requested: the targets as given (``{"diameter": mm, "pitch": mm, "naca": "2412", ...}``).
    """

    parameters: Any
    radial_scale: float | None = None
    tip_diameter_mm: float | None = None
    pitch_fit: PitchFit | None = None
    requested: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """For the JSON report: the targets, what was achieved, and the spec values that
        resulted."""
        report: dict[str, Any] = {
            "requested": dict(self.requested),
            "tip_diameter_mm": self.tip_diameter_mm,
        }
        if self.radial_scale is not None:
            report["radial_scale"] = self.radial_scale
            report["centerline_p2"] = list(self.parameters.centerline.p2)
            report["centerline_p3"] = list(self.parameters.centerline.p3)
        if self.pitch_fit is not None:
            report["pitch_at_75_percent_radius_mm"] = [
                float(v) for v in self.pitch_fit.pitch_at_75_mm
            ]
            report["pitch_rms_beta_error_deg"] = self.pitch_fit.rms_beta_error_deg
            report["angle_of_attack"] = list(self.pitch_fit.angle_of_attack)
        return report


def _value(params: Any, dotted: str, default: Any) -> Any:
    target = params
    for part in dotted.split("."):
        target = getattr(target, part, None)
        if target is None:
            return default
    return target


def requested_targets(params: Any) -> dict[str, Any]:
    """The designer's inputs set in ``params`` (empty when none is)."""
    requested = {
        key: _value(params, key, None)
        for key in ("airfoil.naca", "airfoil.file", "diameter", "pitch")
    }
    return {key: value for key, value in requested.items() if value not in (None, "", 0, 0.0)}


def tip_radius_mm(params: Any) -> float:
    """Largest distance of blade 0's analytic surface from the spin axis (mm); a conventional
    blade's sampled densely (its sections are planar, x = r: the tip section's points are the
    farthest)."""
    if str(params.kind) == "conventional":
        points = sampled_blade_surface(
            params, 0, CONVENTIONAL_TIP_GRID[0], CONVENTIONAL_TIP_GRID[1]
        ).points
        return float(np.hypot(points[..., 0], points[..., 1]).max())
    return tip_radius_of(propeller_geometry(params))


#: Sections and points of a conventional blade's sampling for its tip radius.
CONVENTIONAL_TIP_GRID = (21, 400)


def _without_targets(params: Any, geometry: PropellerGeometry) -> Any:
    """``params`` with the fitted control points and alpha(s) of ``geometry``, and the targets
    removed."""
    _, p2, p3, _ = geometry.blade.local_control_points
    changes: dict[str, Any] = {
        "centerline.p2": list(p2),
        "centerline.p3": list(p3),
        "transforms.angle_of_attack": list(geometry.blade.laws.angle_of_attack_deg),
    }
    for key, empty in (("diameter", 0.0), ("pitch", 0.0)):
        if _value(params, key, None):
            changes[key] = empty
    return params.with_values(changes)


def resolve_design_targets(params: Any, spin: Handedness = Handedness.CW) -> DesignTargets:
    """Apply ``airfoil.naca`` (4-digit), ``diameter`` and ``pitch`` (module docstring) to
    ``params``."""
    requested = requested_targets(params)
    if not requested:
        return DesignTargets(params)
    naca = requested.get("airfoil.naca", "")
    if naca and len(str(naca).strip()) == 4:
        m, p, thickness = naca4_numbers(naca)
        params = params.with_values(
            {
                "airfoil.naca": "",
                "airfoil.max_camber": m,
                "airfoil.camber_position": p if m > 0 else params.airfoil.camber_position,
                "airfoil.thickness": thickness,
            }
        )
    diameter_mm, pitch_mm = (
        float(requested.get("diameter", 0.0)),
        float(requested.get("pitch", 0.0)),
    )
    if not (diameter_mm or pitch_mm):
        return DesignTargets(params, requested=requested)
    # fitted on the geometry objects, validated once as parameters
    geometry, scale = fitted_to_targets(
        propeller_geometry(params), diameter_mm, pitch_mm, spin, params.hub.radius
    )
    params = _without_targets(params, geometry)
    fit, diameter = achieved(propeller_geometry(params), pitch_mm, spin)
    return DesignTargets(params, scale if diameter_mm else None, diameter, fit, requested)
