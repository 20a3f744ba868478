"""The designer's inputs turned into the spec's parameters: airfoil by name, diameter, pitch.

The spec's parameters stay the truth; these inputs are converted into them before anything
is built, in this order:

1. ``airfoil.naca`` "MPTT" sets ``max_camber``, ``camber_position`` and ``thickness``
   (5-digit designations and ``airfoil.file`` have no spec numbers; they stay as they are).
2. ``diameter`` scales the radial coordinates z_L of ``centerline.p2`` and ``p3`` until the
   tip diameter is met (:mod:`torus_cad.geometry.analysis.diameter`).
3. ``pitch`` refits ``transforms.angle_of_attack`` (:mod:`torus_cad.geometry.analysis.pitch`) on the
   centerline that step 2 left.

:func:`resolve_design_targets` returns the resolved parameters (the targets removed, so they
build the same propeller without solving again) and what each step achieved.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError, ParameterError
from torus_cad.geometry.analysis.diameter import radial_scale_for_diameter, tip_radius
from torus_cad.geometry.analysis.pitch import (
    PITCH_FIT_SECTIONS,
    ChordModel,
    PitchFit,
    chord_model,
    fit_pitch,
    pitch_report,
)
from torus_cad.geometry.blade.blade_surface import (
    blade_frames,
    place_sections,
    sections_along,
    sections_at,
)
from torus_cad.geometry.blade.centerline import Centerline
from torus_cad.geometry.blade.frames import FrameKind, Frames, frenet_from_derivatives
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.transforms import Quartic, evaluate_quartic
from torus_cad.geometry.section.airfoil import naca4_numbers
from torus_cad.geometry.section.section import closed_points, parameter_end
from torus_cad.parameters.design import free_point_z_bounds
from torus_cad.parameters.schema import check_in_bounds

#: At most this many rounds of (pitch fit, diameter fit); they stop when the diameter fit no longer
#: moves.
TARGET_ROUNDS = 4


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
        points = params.blade_surface(0, CONVENTIONAL_TIP_GRID[0], CONVENTIONAL_TIP_GRID[1]).points
        return float(np.hypot(points[..., 0], points[..., 1]).max())
    return tip_radius_of(params.geometry())


#: Sections and points of a conventional blade's sampling for its tip radius.
CONVENTIONAL_TIP_GRID = (21, 400)


def tip_radius_of(geometry: PropellerGeometry) -> float:
    """Largest distance of blade 0's analytic surface from the spin axis (mm)."""
    blade, centerline = geometry.blade, geometry.centerline(0)
    # checks once that the frame exists on the whole centerline
    blade_frames(blade, centerline, [0.0])
    end = parameter_end(sections_along(blade, [0.5])[0])

    def surface_at(s: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
        frames = section_frames_unchecked(blade, centerline, s)
        return place_sections(blade, frames, sections_at(sections_along(blade, s), t))

    return tip_radius(surface_at, end)[0]


def section_frames_unchecked(blade: Any, centerline: Centerline, s: NDArray[np.float64]) -> Frames:
    """Frames at ``s`` without re-scanning the whole centerline (the caller has checked it once)."""
    if blade.frame != FrameKind.FRENET:
        return blade_frames(blade, centerline, s)
    derivatives = centerline.derivatives(np.asarray(s, dtype=float), order=2)
    return Frames(
        np.asarray(s, dtype=float),
        derivatives[:, 0],
        *frenet_from_derivatives(derivatives[:, 1], derivatives[:, 2]),
    )


def with_radial_scale(
    geometry: PropellerGeometry, scale: float, hub_radius_mm: float
) -> PropellerGeometry:
    """``geometry`` with z_L of the free control points p2 and p3 multiplied by ``scale``;
    GeometryError (not reachable) when a scaled point leaves the range the parameters allow it."""
    p1, p2, p3, p4 = geometry.blade.local_control_points
    scaled = [(point[0], point[1], point[2] * scale) for point in (p2, p3)]
    for name, point in zip(("p2", "p3"), scaled, strict=True):
        try:  # as PropellerParameters checks the control points
            check_in_bounds(
                f"centerline.{name}[2]", point[2], free_point_z_bounds(hub_radius_mm), "mm"
            )
        except ParameterError as error:
            raise GeometryError(str(error)) from None
    blade = dataclasses.replace(geometry.blade, local_control_points=(p1, scaled[0], scaled[1], p4))
    return dataclasses.replace(geometry, blade=blade)


def fit_diameter(
    geometry: PropellerGeometry, diameter_mm: float, hub_radius_mm: float
) -> tuple[PropellerGeometry, float]:
    """``geometry`` scaled radially to the tip diameter ``diameter_mm``, and the scale."""
    scale = radial_scale_for_diameter(
        lambda k: tip_radius_of(with_radial_scale(geometry, k, hub_radius_mm)), diameter_mm
    )
    return with_radial_scale(geometry, scale, hub_radius_mm), scale


def _pitch_model(geometry: PropellerGeometry) -> tuple[NDArray[np.float64], ChordModel]:
    """The sections' s and the chord model alpha -> (chord mid points, chord vectors) of blade 0."""
    blade = geometry.blade
    s = np.linspace(0.0, 1.0, PITCH_FIT_SECTIONS)
    frames = blade_frames(blade, geometry.centerline(0), s)
    section = blade.airfoil
    base = parameter_end(section) == 3.0
    leading = np.repeat(closed_points(section, [0.0], base), len(s), axis=0)
    ends = closed_points(section, [1.0, 2.0] if base else [1.0], base)
    # the chord line ignores the base's size
    trailing = np.repeat(ends.mean(axis=0, keepdims=True), len(s), axis=0)
    laws = blade.laws
    return s, chord_model(
        frames.origin,
        frames.normal,
        frames.binormal,
        leading,
        trailing,
        evaluate_quartic(laws.scale_x_mm, s),
        evaluate_quartic(laws.scale_y_mm, s),
        laws.pivot,
    )


def fit_angle_of_attack(
    geometry: PropellerGeometry, pitch_mm: float, spin: Handedness = Handedness.CW
) -> tuple[PropellerGeometry, PitchFit]:
    """``geometry`` with alpha(s) refitted so the outer half has geometric pitch ``pitch_mm``."""
    s, model = _pitch_model(geometry)
    laws = geometry.blade.laws
    fit = fit_pitch(model, s, laws.angle_of_attack_deg, pitch_mm, tip_radius_of(geometry), spin)
    blade = dataclasses.replace(
        geometry.blade,
        laws=dataclasses.replace(laws, angle_of_attack_deg=_quartic(fit.angle_of_attack)),
    )
    return dataclasses.replace(geometry, blade=blade), fit


def _quartic(values: Any) -> Quartic:
    a, b, c, d, e = (float(value) for value in values)
    return (a, b, c, d, e)


def achieved_pitch(
    geometry: PropellerGeometry, pitch_mm: float, spin: Handedness = Handedness.CW
) -> PitchFit:
    """How well ``geometry``'s own alpha(s) meets ``pitch_mm`` (no fit)."""
    s, model = _pitch_model(geometry)
    return pitch_report(
        model, s, geometry.blade.laws.angle_of_attack_deg, pitch_mm, tip_radius_of(geometry), spin
    )


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
    scale = 1.0
    # Fitted on the geometry objects, validated once at the end. alpha turns the sections, which
    # moves the outermost point, and the radius sets the pitch's beta targets: alternate the fits,
    # and end with the diameter (met exactly; the pitch the last alpha gives is reported on the
    # final geometry).
    geometry = params.geometry()
    for _ in range(TARGET_ROUNDS if pitch_mm and diameter_mm else 1):
        if pitch_mm:
            geometry, _ = fit_angle_of_attack(geometry, pitch_mm, spin)
        if diameter_mm:
            geometry, round_scale = fit_diameter(geometry, diameter_mm, params.hub.radius)
            scale *= round_scale
            if abs(round_scale - 1.0) < 1e-6:
                break
    params = _without_targets(params, geometry)
    geometry = params.geometry()
    fit = achieved_pitch(geometry, pitch_mm, spin) if pitch_mm else None
    diameter = 2.0 * tip_radius_of(geometry)
    return DesignTargets(params, scale if diameter_mm else None, diameter, fit, requested)
