"""The blade geometry fitted to a tip diameter and a geometric pitch (kernel-free).

The designer's ``diameter`` scales the radial coordinates z_L of the free control points p2 and p3
until the tip diameter is met (:mod:`.diameter`); ``pitch`` refits alpha(s) so the outer half has
that geometric pitch (:mod:`.pitch`). :func:`fitted_to_targets` alternates the two fits on the
geometry objects, as :func:`torus_cad.design.design_targets.resolve_design_targets` asks, which
turns the fitted geometry back into validated parameters.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError
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
from torus_cad.geometry.blade.centerline import Centerline, free_point_z_range_mm
from torus_cad.geometry.blade.frames import FrameKind, Frames, frenet_from_derivatives
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.propeller_geometry import PropellerGeometry
from torus_cad.geometry.blade.transforms import Quartic, evaluate_quartic
from torus_cad.geometry.section.section import closed_points, parameter_end

#: At most this many rounds of (pitch fit, diameter fit); they stop when the diameter fit no longer
#: moves.
TARGET_ROUNDS = 4


def fitted_to_targets(
    geometry: PropellerGeometry,
    diameter_mm: float,
    pitch_mm: float,
    spin: Handedness,
    hub_radius_mm: float,
) -> tuple[PropellerGeometry, float]:
    """``geometry`` fitted to the tip diameter ``diameter_mm`` and the pitch ``pitch_mm`` (either
    0: not fitted), and the radial scale applied (1 without a diameter).

    alpha turns the sections, which moves the outermost point, and the radius sets the pitch's beta
    targets: the fits alternate, ending with the diameter (met exactly; the pitch the last alpha
    gives is what :func:`achieved` reports).

    Args:
        geometry: the propeller's kernel-free geometry, mm.
        diameter_mm: the tip diameter to meet, mm (0: none).
        pitch_mm: the outer half's geometric pitch to meet, mm (0: none).
        spin: the rotation the pitch is meant for.
        hub_radius_mm: the hub's radius, mm: the free control points' z_L range
            (free_point_z_range_mm).

    Returns:
        The fitted geometry and the radial scale.

    Raises:
        GeometryError: a scaled control point would leave ``z_range_mm``.
    """
    scale, z_range_mm = 1.0, free_point_z_range_mm(hub_radius_mm)
    for _ in range(TARGET_ROUNDS if pitch_mm and diameter_mm else 1):
        if pitch_mm:
            geometry, _ = fit_angle_of_attack(geometry, pitch_mm, spin)
        if diameter_mm:
            geometry, round_scale = fit_diameter(geometry, diameter_mm, z_range_mm)
            scale *= round_scale
            if abs(round_scale - 1.0) < 1e-6:
                break
    return geometry, scale


def achieved(
    geometry: PropellerGeometry, pitch_mm: float, spin: Handedness
) -> tuple[PitchFit | None, float]:
    """How well ``geometry``'s own alpha(s) meets ``pitch_mm`` (None when 0), and its tip diameter
    (mm)."""
    fit = achieved_pitch(geometry, pitch_mm, spin) if pitch_mm else None
    return fit, 2.0 * tip_radius_of(geometry)


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
    geometry: PropellerGeometry, scale: float, z_range_mm: tuple[float, float]
) -> PropellerGeometry:
    """``geometry`` with z_L of the free control points p2 and p3 multiplied by ``scale``;
    GeometryError (not reachable) when a scaled point leaves ``z_range_mm`` (low excluded), the
    range the parameters allow it."""
    p1, p2, p3, p4 = geometry.blade.local_control_points
    scaled = [(point[0], point[1], point[2] * scale) for point in (p2, p3)]
    low, high = z_range_mm
    for name, point in zip(("p2", "p3"), scaled, strict=True):
        if not low < point[2] <= high:  # as PropellerParameters checks the control points
            raise GeometryError(
                f"centerline.{name}[2] = {point[2]:g} is out of range; "
                f"allowed ({low:g}, {high:g}] mm"
            )
    blade = dataclasses.replace(geometry.blade, local_control_points=(p1, scaled[0], scaled[1], p4))
    return dataclasses.replace(geometry, blade=blade)


def fit_diameter(
    geometry: PropellerGeometry, diameter_mm: float, z_range_mm: tuple[float, float]
) -> tuple[PropellerGeometry, float]:
    """``geometry`` scaled radially to the tip diameter ``diameter_mm``, and the scale."""
    scale = radial_scale_for_diameter(
        lambda k: tip_radius_of(with_radial_scale(geometry, k, z_range_mm)), diameter_mm
    )
    return with_radial_scale(geometry, scale, z_range_mm), scale


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
