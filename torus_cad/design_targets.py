"""The designer's inputs turned into the spec's parameters: airfoil by name, diameter, pitch.

The spec's parameters stay the truth; these inputs are converted into them before anything
is built, in this order:

1. ``airfoil.naca`` "MPTT" sets ``max_camber``, ``camber_position`` and ``thickness``
   (5-digit designations and ``airfoil.file`` have no spec numbers; they stay as they are).
2. ``diameter`` scales the radial coordinates z_L of ``centerline.p2`` and ``p3`` until the
   tip diameter is met (:mod:`torus_cad.geometry.diameter`).
3. ``pitch`` refits ``transforms.angle_of_attack`` (:mod:`torus_cad.geometry.pitch`) on the
   centerline that step 2 left.

:func:`resolve_design_targets` returns the resolved parameters (the targets removed, so they
build the same propeller without solving again) and what each step achieved.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import GeometryError, ParameterError
from torus_cad.geometry.airfoil import naca4_numbers
from torus_cad.geometry.blade_elements import BladeElements, blade_angles, blade_elements
from torus_cad.geometry.centerline import Centerline
from torus_cad.geometry.diameter import radial_scale_for_diameter, tip_radius
from torus_cad.geometry.frames import FrameKind, Frames, frenet_from_derivatives
from torus_cad.geometry.handedness import Handedness
from torus_cad.geometry.pitch import (
    PITCH_FIT_SECTIONS,
    ChordModel,
    PitchFit,
    chord_model,
    fit_pitch,
    pitch_report,
)
from torus_cad.geometry.section import closed_points, has_base, parameter_end
from torus_cad.geometry.surface import (
    BladeSurface,
    blade_frames,
    place_sections,
    sections_along,
    sections_at,
)
from torus_cad.geometry.trailing_edge import trailing_edge_thickness_mm
from torus_cad.geometry.transforms import evaluate_quartic

#: At most this many rounds of (pitch fit, diameter fit); they stop when the diameter fit no longer moves.
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
        """For the JSON report: the targets, what was achieved, and the spec values that resulted."""
        report: dict[str, Any] = {"requested": dict(self.requested),
                                  "tip_diameter_mm": self.tip_diameter_mm}
        if self.radial_scale is not None:
            report["radial_scale"] = self.radial_scale
            report["centerline_p2"] = list(self.parameters.centerline.p2)
            report["centerline_p3"] = list(self.parameters.centerline.p3)
        if self.pitch_fit is not None:
            report["pitch_at_75_percent_radius_mm"] = [float(v) for v in self.pitch_fit.pitch_at_75_mm]
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
    requested = {key: _value(params, key, None) for key in ("airfoil.naca", "airfoil.file", "diameter", "pitch")}
    return {key: value for key, value in requested.items() if value not in (None, "", 0, 0.0)}


def tip_radius_mm(params: Any) -> float:
    """Largest distance of blade 0's analytic surface from the spin axis (mm)."""
    geometry = params.geometry()
    blade, centerline = geometry.blade, geometry.centerline(0)
    blade_frames(blade, centerline, [0.0])  # checks once that the frame exists on the whole centerline
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
    return Frames(np.asarray(s, dtype=float), derivatives[:, 0],
                  *frenet_from_derivatives(derivatives[:, 1], derivatives[:, 2]))


def with_radial_scale(params: Any, scale: float) -> Any:
    """``params`` with z_L of the free control points p2 and p3 multiplied by ``scale``."""
    p2, p3 = params.centerline.p2, params.centerline.p3
    return params.with_values({"centerline.p2": [p2[0], p2[1], p2[2] * scale],
                               "centerline.p3": [p3[0], p3[1], p3[2] * scale]})


def _tip_radius_at_scale(params: Any, scale: float) -> float:
    try:
        return tip_radius_mm(with_radial_scale(params, scale))
    except ParameterError as error:  # a scaled control point out of its range: not reachable
        raise GeometryError(str(error)) from None


def fit_diameter(params: Any, diameter_mm: float) -> tuple[Any, float]:
    """``params`` scaled radially to the tip diameter ``diameter_mm``, and the scale."""
    scale = radial_scale_for_diameter(lambda k: _tip_radius_at_scale(params, k), diameter_mm)
    return with_radial_scale(params, scale), scale


def _pitch_model(params: Any) -> tuple[NDArray[np.float64], ChordModel]:
    """The sections' s and the chord model alpha -> (chord mid points, chord vectors) of blade 0."""
    geometry = params.geometry()
    blade = geometry.blade
    s = np.linspace(0.0, 1.0, PITCH_FIT_SECTIONS)
    frames = blade_frames(blade, geometry.centerline(0), s)
    section = blade.airfoil
    base = parameter_end(section) == 3.0
    leading = np.repeat(closed_points(section, [0.0], base), len(s), axis=0)
    ends = closed_points(section, [1.0, 2.0] if base else [1.0], base)
    trailing = np.repeat(ends.mean(axis=0, keepdims=True), len(s), axis=0)  # the chord line ignores the base's size
    laws = blade.laws
    return s, chord_model(frames.origin, frames.normal, frames.binormal, leading, trailing,
                          evaluate_quartic(laws.scale_x_mm, s), evaluate_quartic(laws.scale_y_mm, s), laws.pivot)


def fit_angle_of_attack(params: Any, pitch_mm: float, spin: Handedness = Handedness.CW) -> tuple[Any, PitchFit]:
    """``params`` with alpha(s) refitted so the outer half has geometric pitch ``pitch_mm``."""
    s, model = _pitch_model(params)
    fit = fit_pitch(model, s, params.transforms.angle_of_attack, pitch_mm, tip_radius_mm(params), spin)
    return params.with_values({"transforms.angle_of_attack": list(fit.angle_of_attack)}), fit


def achieved_pitch(params: Any, pitch_mm: float, spin: Handedness = Handedness.CW) -> PitchFit:
    """How well ``params``' own alpha(s) meets ``pitch_mm`` (no fit)."""
    s, model = _pitch_model(params)
    return pitch_report(model, s, params.transforms.angle_of_attack, pitch_mm, tip_radius_mm(params), spin)


def _without_targets(params: Any) -> Any:
    changes: dict[str, Any] = {}
    for key, empty in (("diameter", 0.0), ("pitch", 0.0)):
        if _value(params, key, None):
            changes[key] = empty
    return params.with_values(changes) if changes else params


def resolve_design_targets(params: Any, spin: Handedness = Handedness.CW) -> DesignTargets:
    """Apply ``airfoil.naca`` (4-digit), ``diameter`` and ``pitch`` (module docstring) to ``params``."""
    requested = requested_targets(params)
    if not requested:
        return DesignTargets(params)
    naca = requested.get("airfoil.naca", "")
    if naca and len(str(naca).strip()) == 4:
        m, p, thickness = naca4_numbers(naca)
        params = params.with_values({"airfoil.naca": "", "airfoil.max_camber": m,
                                     "airfoil.camber_position": p if m > 0 else params.airfoil.camber_position,
                                     "airfoil.thickness": thickness})
    diameter_mm, pitch_mm = float(requested.get("diameter", 0.0)), float(requested.get("pitch", 0.0))
    if not (diameter_mm or pitch_mm):
        return DesignTargets(params, requested=requested)
    scale = 1.0
    # alpha turns the sections, which moves the outermost point, and the radius sets the pitch's
    # beta targets: alternate the fits, and end with the diameter (met exactly; the pitch the
    # last alpha gives is reported on the final geometry).
    for _ in range(TARGET_ROUNDS if pitch_mm and diameter_mm else 1):
        if pitch_mm:
            params, _ = fit_angle_of_attack(params, pitch_mm, spin)
        if diameter_mm:
            params, round_scale = fit_diameter(params, diameter_mm)
            scale *= round_scale
            if abs(round_scale - 1.0) < 1e-6:
                break
    params = _without_targets(params)
    fit = achieved_pitch(params, pitch_mm, spin) if pitch_mm else None
    diameter = 2.0 * tip_radius_mm(params)
    return DesignTargets(params, scale if diameter_mm else None, diameter, fit, requested)


def elements_of(surface: BladeSurface, spin: Handedness = Handedness.CW) -> BladeElements:
    """The blade-element table of a sampled blade surface."""
    frames = surface.frames
    return blade_elements(surface.s, surface.points, frames.origin, frames.normal, frames.binormal,
                          surface.trailing_edge_index or 0, surface.lower_corner_index, spin)


def design_elements(params: Any, points: int = 400, spin: Handedness = Handedness.CW) -> BladeElements:
    """The blade-element table at the design's own sections (``resolution.sections``), finely sampled around."""
    return elements_of(params.blade_surface(points=points), spin)


def trailing_edge_of(params: Any, s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Thickness of the trailing edge (mm) of the sections at ``s`` (0 where sharp)."""
    blade = params.geometry().blade
    laws = blade.laws
    sections = sections_along(blade, s)
    if not any(has_base(section) for section in sections):
        return np.zeros(len(s))
    return trailing_edge_thickness_mm(sections, evaluate_quartic(laws.angle_of_attack_deg, s),
                                      evaluate_quartic(laws.scale_x_mm, s), evaluate_quartic(laws.scale_y_mm, s))


def write_sections_table(surface: BladeSurface, params: Any, out_dir: Path, spin: Handedness = Handedness.CW) -> dict[str, Path]:
    """Write ``<name>_sections.csv`` and ``<name>_sections.png`` of the built blade ``surface`` into
    ``out_dir`` (each atomically); their paths by kind (``sections_csv``, ``sections_png``).

    The table reads the surface the solid was lofted through (``resolution.points`` around each
    section): the thickness comes within 0.04 % of a 1000-point sampling at the default 80. A
    ``handedness = "ccw"`` part is that surface's mirror image through the XZ plane: the same
    table, with the position angles negated and the rotation counter-clockwise.
    """
    from torus_cad.kernel.export import atomic_path
    from torus_cad.sections_table import write_sections_csv, write_sections_png

    elements = elements_of(surface, spin)
    if str(getattr(params, "handedness", "cw")) == "ccw":  # the part is the surface's mirror image (y -> -y)
        elements = dataclasses.replace(elements, position_angle_deg=-elements.position_angle_deg,
                                       spin=elements.spin.opposite)
    paths = {"sections_csv": out_dir / f"{params.name}_sections.csv",
             "sections_png": out_dir / f"{params.name}_sections.png"}
    with atomic_path(paths["sections_csv"]) as temp:
        write_sections_csv(elements, temp, trailing_edge_of(params, elements.s))
    with atomic_path(paths["sections_png"]) as temp:
        write_sections_png(elements, temp, title=f"{params.name}: blade elements")
    return paths


# -- checking the targets on a built solid --------------------------------------------------------

def radius_crossings(params: Any, radius_mm: float, sections: int = 801) -> list[tuple[float, float]]:
    """``(s, geometric pitch mm)`` where blade 0 passes ``radius_mm`` (analytic, ``sections`` samples)."""
    fine = elements_of(params.blade_surface(sections=sections, points=48))
    found = []
    for i in np.flatnonzero(np.diff(np.sign(fine.radius_mm - radius_mm))):
        w = (radius_mm - fine.radius_mm[i]) / (fine.radius_mm[i + 1] - fine.radius_mm[i])
        found.append((float(fine.s[i] + w * (fine.s[i + 1] - fine.s[i])),
                      float(fine.pitch_mm[i] + w * (fine.pitch_mm[i + 1] - fine.pitch_mm[i]))))
    return found


def pitch_on_solid(propeller: Any, s: float, spin: Handedness = Handedness.CW) -> float:
    """Geometric pitch (mm) of the built solid's section in the plane of section ``s``.

    Measured on the B-rep: the plane cuts the solid and the contour through the centerline's
    point is sampled. The leading edge is the contour's point on the centerline (the spec's
    pivot 0 puts it there); the trailing edge is the middle of the contour's straight edge
    (a flat blunt base) if it has one, the middle of the chord of a round cap's cut (its ends are
    the surfaces' ends, as the design's trailing edge is their middle), else the contour's point
    farthest from the leading edge.
    """
    from torus_cad.kernel.measure import (
        contour_through,
        edge_points,
        farthest_middle_edge,
        plane_section_edges,
        straight_edges,
    )

    geometry = propeller.parameters.geometry()
    frames = blade_frames(geometry.blade, geometry.centerline(0), [s])
    # A ccw solid is the spec's blade mirrored (y -> -y, kernel/mirror.py): cut it in the mirrored
    # plane, and mirror what is measured back, so the pitch is the spec blade's, as designed.
    from torus_cad.parameters.design import Handedness  # here: the schema resolves design targets itself

    flip = np.array([1.0, -1.0 if propeller.parameters.handedness == Handedness.CCW else 1.0, 1.0])
    origin = frames.origin[0] * flip
    reach = 2.0 * float(np.max(evaluate_quartic(geometry.blade.laws.scale_x_mm, [s])))
    edges = contour_through(plane_section_edges(propeller.solid, origin, frames.tangent[0] * flip, reach), origin)
    points = edge_points(edges, 1000)
    leading = points[int(np.argmin(np.linalg.norm(points - origin, axis=1)))]
    bases = straight_edges(edges)
    if bases:
        trailing = np.asarray(bases[0].positionAt(0.5).toTuple(), dtype=float)
    elif propeller.surface.round_trailing_edge:
        cap = farthest_middle_edge(edges, leading)
        trailing = 0.5 * np.add(cap.startPoint().toTuple(), cap.endPoint().toTuple())
    else:
        trailing = points[int(np.argmax(np.linalg.norm(points - leading, axis=1)))]
    leading, trailing = leading * flip, trailing * flip
    middle = 0.5 * (leading + trailing)
    beta, _ = blade_angles(middle[None], (trailing - leading)[None], spin)
    return float(2.0 * np.pi * np.hypot(middle[0], middle[1]) * np.tan(np.radians(beta[0])))
