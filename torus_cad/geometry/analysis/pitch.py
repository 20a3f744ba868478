"""Pitch target: fit the alpha(s) quartic so the blade's outer half has a given geometric pitch.

The blade element at s has the geometric pitch P(s) = 2 pi r(s) tan beta(s)
(:mod:`torus_cad.geometry.analysis.blade_elements`). A pitch P asks for beta*(s) = atan(P / (2 pi
r(s))) at every section in the outer half of the radius (r >= half the tip radius). alpha(s) turns
each section in its plane, and with it the chord and beta; the spec's alpha stays a quartic
(§2.4 chose that form), so the quartic is fitted by nonlinear least squares
(scipy.optimize.least_squares) to

    sum over the outer sections of w_i (beta_i - beta*_i)^2
        +  lambda^2 sum over the others of (alpha_i - alpha0_i)^2,

with w_i = 1 - radial_fraction_i^2 (clipped at 0): sections whose chord runs nearly radially,
where beta says little, barely count; the second term keeps the inner sections, which no target
constrains, near the design's own alpha. It is solved in three stages, so it cannot run off
into whole turns of alpha where a section cannot reach its beta at all (near a loop's tip the
section plane can be the plane of rotation itself): (1) per section, the alpha within 90
degrees of the design's that brings beta closest to its target, and how strongly alpha moves
beta there; (2) a weighted linear least-squares quartic through those angles; (3) a nonlinear
polish of (2) on beta itself, held near (2). A quartic cannot hold the pitch exactly
everywhere: the fit reports the pitch it achieves at 75 % of the tip radius, where designers
quote it, and the weighted rms miss of beta.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from torus_cad.errors import GeometryError
from torus_cad.geometry.analysis.blade_elements import blade_angles
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.transforms import evaluate_quartic

#: Sections with r >= this fraction of the tip radius take part in the pitch fit.
PITCH_FIT_RADIUS_FRACTION = 0.5

#: Where the achieved pitch is reported, as a fraction of the tip radius.
PITCH_REPORT_RADIUS_FRACTION = 0.75

#: Weight of keeping alpha at the inner sections (radians of alpha against radians of beta).
INNER_ALPHA_WEIGHT = 0.1

#: Sections sampled along s for the fit.
PITCH_FIT_SECTIONS = 61


@dataclass(frozen=True)
class PitchFit:
    """The fitted alpha(s) and how well it meets the pitch.

    Attributes:
        angle_of_attack: the fitted quartic, degrees, highest power first.
        target_pitch_mm: the pitch asked for.
        pitch_at_75_mm: achieved geometric pitch where r(s) = 0.75 r_tip, ``(c,)`` one per crossing.
        rms_beta_error_deg: weighted root-mean-square of beta - beta* over the outer sections.
        sections_used: how many sections the target constrained.
    """

    angle_of_attack: tuple[float, float, float, float, float]
    target_pitch_mm: float
    pitch_at_75_mm: NDArray[np.float64]
    rms_beta_error_deg: float
    sections_used: int


ChordModel = Callable[[NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]]


def chord_model(
    origin: NDArray[np.float64],
    normal: NDArray[np.float64],
    binormal: NDArray[np.float64],
    leading: NDArray[np.float64],
    trailing: NDArray[np.float64],
    scale_x: ArrayLike,
    scale_y: ArrayLike,
    pivot: float = 0.0,
) -> ChordModel:
    """A function alpha (k,) degrees -> (chord mid points (k, 3), chord vectors (k, 3)) in mm.

    Args:
        origin, normal, binormal: ``(k, 3)`` the section frames (fixed: alpha does not move the
            centerline).
        leading, trailing: ``(k, 2)`` chord-unit leading edge and trailing edge (middle of a base)
            per section.
        scale_x, scale_y: ``(k,)`` Sx(s), Sy(s) in mm; pivot: chord fraction at the centre of alpha.
    """
    scales = np.stack([np.asarray(scale_x, float), np.asarray(scale_y, float)], axis=-1)
    shift = np.array([pivot, 0.0])

    def placed(
        planar_points: NDArray[np.float64], angle: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        cos, sin = np.cos(angle), np.sin(angle)
        x, y = (planar_points - shift).T
        rotated = np.stack([cos * x - sin * y, sin * x + cos * y], axis=-1) * scales
        return origin + rotated[:, :1] * normal + rotated[:, 1:] * binormal

    def model(angle_deg: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        angle = np.radians(angle_deg)
        front, back = placed(leading, angle), placed(trailing, angle)
        return 0.5 * (front + back), back - front

    return model


def fit_pitch(
    model: ChordModel,
    s: NDArray[np.float64],
    initial_quartic: ArrayLike,
    pitch_mm: float,
    tip_radius_mm: float,
    spin: Handedness = Handedness.CW,
) -> PitchFit:
    """Fit alpha(s) (a quartic) so the outer sections' geometric pitch is ``pitch_mm`` (module
    docstring)."""
    initial = np.asarray(initial_quartic, dtype=float)
    alpha0 = _quartic_at(initial, s)

    def evaluate(
        alpha_deg: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        middle, chord = model(alpha_deg)
        radius = np.hypot(middle[:, 0], middle[:, 1])
        beta, radial = blade_angles(middle, chord, spin)
        target = np.arctan2(pitch_mm, 2.0 * np.pi * radius)
        miss = np.angle(np.exp(1j * (np.radians(beta) - target)))  # wrapped to (-pi, pi]
        return radius, miss, np.sqrt(np.clip(1.0 - radial**2, 0.0, 1.0))

    radius0, _, _ = evaluate(alpha0)
    outer = radius0 >= PITCH_FIT_RADIUS_FRACTION * tip_radius_mm
    if not np.any(outer):
        raise GeometryError(
            "no section lies in the outer half of the radius; the pitch cannot be fitted"
        )
    best_alpha, sensitivity = _best_angles(evaluate, alpha0)
    # Stage 2: a linear least-squares quartic through the best angles, each weighted by how much
    # alpha moves beta there; unconstrained (inner, insensitive) sections stay near the design's
    # alpha.
    weight = np.where(outer, sensitivity, 0.0) + INNER_ALPHA_WEIGHT
    goal = np.where(outer & (sensitivity > 0.0), best_alpha, alpha0)
    powers = np.vander(s, 5)
    coefficients = np.asarray(
        np.linalg.lstsq(powers * weight[:, None], goal * weight, rcond=None)[0], dtype=float
    )
    stage_two = _quartic_at(coefficients, s)

    def residuals(candidate: NDArray[np.float64]) -> NDArray[np.float64]:
        alpha = _quartic_at(candidate, s)
        _, miss, tangential = evaluate(alpha)
        keep = INNER_ALPHA_WEIGHT * np.radians(alpha - stage_two)
        return np.concatenate([(tangential * miss)[outer], keep])

    # Stage 3: polish the quartic on beta itself, held near stage 2 so it cannot wander off in
    # turns.
    solution = least_squares(
        residuals, coefficients, x_scale=np.full(5, 10.0), method="trf", max_nfev=200
    )
    if np.sum(solution.fun**2) < np.sum(residuals(coefficients) ** 2):
        coefficients = np.asarray(solution.x, dtype=float)
    return pitch_report(model, s, coefficients, pitch_mm, tip_radius_mm, spin)


def pitch_report(
    model: ChordModel,
    s: NDArray[np.float64],
    quartic: ArrayLike,
    pitch_mm: float,
    tip_radius_mm: float,
    spin: Handedness = Handedness.CW,
) -> PitchFit:
    """How well the alpha(s) ``quartic`` meets ``pitch_mm`` (nothing is fitted): a
    :class:`PitchFit`."""
    coefficients = np.asarray(quartic, dtype=float)
    alpha = _quartic_at(coefficients, s)
    middle, chord = model(alpha)
    radius = np.hypot(middle[:, 0], middle[:, 1])
    beta, radial = blade_angles(middle, chord, spin)
    outer = radius >= PITCH_FIT_RADIUS_FRACTION * tip_radius_mm
    miss = np.angle(np.exp(1j * (np.radians(beta) - np.arctan2(pitch_mm, 2.0 * np.pi * radius))))
    used = np.clip(1.0 - radial**2, 0.0, 1.0)[outer]
    rms = float(
        np.degrees(np.sqrt(np.sum(used * miss[outer] ** 2) / max(float(np.sum(used)), 1e-300)))
    )
    pitch = 2.0 * np.pi * radius * np.tan(np.radians(beta))
    at_75 = _values_at_radius(radius, pitch, PITCH_REPORT_RADIUS_FRACTION * tip_radius_mm)
    a, b, c, d, e = (float(value) for value in coefficients)
    return PitchFit((a, b, c, d, e), float(pitch_mm), at_75, rms, int(np.count_nonzero(outer)))


def _quartic_at(coefficients: NDArray[np.float64], s: NDArray[np.float64]) -> NDArray[np.float64]:
    return evaluate_quartic([float(value) for value in coefficients], s)


Evaluation = Callable[
    [NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
]


def _best_angles(
    evaluate: Evaluation,
    alpha0: NDArray[np.float64],
    half_range_deg: float = 90.0,
    steps: int = 361,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per section, the alpha within +-half_range of alpha0 that brings beta closest to its target,
    and |d beta / d alpha| there (0 where alpha cannot move beta)."""
    offsets = np.linspace(-half_range_deg, half_range_deg, steps)
    misses = np.array([evaluate(alpha0 + offset)[1] for offset in offsets])  # (steps, k)
    # Prefer the smallest turn among near-equal misses: add a tiny cost per degree turned.
    cost = np.abs(misses) + 1e-6 * np.abs(offsets)[:, None]
    index = np.argmin(cost, axis=0)
    columns = np.arange(len(alpha0))
    step = offsets[1] - offsets[0]
    ahead, behind = np.clip(index + 1, 0, steps - 1), np.clip(index - 1, 0, steps - 1)
    slope = np.abs(misses[ahead, columns] - misses[behind, columns]) / np.radians(
        (ahead - behind) * step
    )
    return alpha0 + offsets[index], np.clip(slope, 0.0, 1.0)


def _values_at_radius(
    radius: NDArray[np.float64], values: NDArray[np.float64], at: float
) -> NDArray[np.float64]:
    """``values`` linearly interpolated where ``radius`` crosses ``at`` (one per crossing)."""
    found = []
    for index in np.flatnonzero(np.diff(np.sign(radius - at)) != 0):
        weight = (at - radius[index]) / (radius[index + 1] - radius[index])
        found.append(values[index] + weight * (values[index + 1] - values[index]))
    return np.array(found)
