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

from torus_cad.design.described_geometry import (
    described_propeller,
    propeller_geometry,
    sampled_blade_surface,
)
from torus_cad.geometry.analysis.either_kind import DescribedPropeller
from torus_cad.geometry.analysis.pitch import PitchFit
from torus_cad.geometry.analysis.target_fit import achieved, fitted_to_targets, tip_radius_of
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.section.airfoil import naca4_numbers
from torus_cad.parameters import PropellerParameters


@dataclass(frozen=True)
class DesignTargets:
    """What the designer's inputs resolved to.

    Attributes:
        parameters: the resolved spec parameters (targets removed).
        propeller: the kernel-free propeller they describe, fitted to the targets (made once: the
            build samples and checks it through :mod:`torus_cad.geometry.analysis.either_kind`).
        radial_scale: factor applied to z_L of p2 and p3 (None without a diameter target).
        tip_diameter_mm: the tip diameter of the resolved design (analytic surface; None when
            no diameter or pitch was asked for: not computed, to keep the default build fast).
        pitch_fit: the alpha(s) fit (None without a pitch target).
        requested: the targets as given (``{"diameter": mm, "pitch": mm, "naca": "2412", ...}``).
    """

    parameters: PropellerParameters
    propeller: DescribedPropeller
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


def resolve_design_targets(
    params: PropellerParameters, spin: Handedness = Handedness.CW
) -> DesignTargets:
    """Apply ``airfoil.naca`` (4-digit), ``diameter`` and ``pitch`` (module docstring) to
    ``params``.

    The propeller is described once, from ``params`` as given (a NACA designation describes the
    same section as its numbers), and the fits run on it; the parameters take the fitted values and
    are validated again.

    Args:
        params: the validated design.
        spin: the rotation the pitch is meant for.

    Returns:
        The resolved parameters (targets removed: they build the same propeller without solving
        again), the propeller they describe, and what each fit achieved.

    Raises:
        ParameterError: a target that cannot be met, or a fitted value out of its range.
    """
    requested = requested_targets(params)
    propeller = described_propeller(params)
    naca = str(requested.get("airfoil.naca", "")).strip()
    if len(naca) == 4:
        m, p, thickness = naca4_numbers(naca)
        camber_position = p if m > 0 else params.airfoil.camber_position
        params = params.with_values(
            {
                "airfoil.naca": "",
                "airfoil.max_camber": m,
                "airfoil.camber_position": camber_position,
                "airfoil.thickness": thickness,
            }
        )
    diameter_mm, pitch_mm = (
        float(requested.get("diameter", 0.0)),
        float(requested.get("pitch", 0.0)),
    )
    if not (diameter_mm or pitch_mm) or not isinstance(propeller, PropellerGeometry):
        return DesignTargets(params, propeller, requested=requested)
    # fitted on the geometry objects, validated once as parameters
    fitted, scale = fitted_to_targets(propeller, diameter_mm, pitch_mm, spin, params.hub.radius)
    _, p2, p3, _ = fitted.blade.local_control_points
    changes: dict[str, Any] = {
        "centerline.p2": list(p2),
        "centerline.p3": list(p3),
        "transforms.angle_of_attack": list(fitted.blade.laws.angle_of_attack_deg),
    }
    # the targets removed: the resolved parameters build the same propeller without solving again
    params = params.with_values(
        changes | {key: 0.0 for key in ("diameter", "pitch") if key in requested}
    )
    fit, diameter = achieved(fitted, pitch_mm, spin)
    return DesignTargets(params, fitted, scale if diameter_mm else None, diameter, fit, requested)
