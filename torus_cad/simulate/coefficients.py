"""The numbers a designer uses, from a run's force history: thrust, torque, power and their
coefficients.

Propeller convention: n in rev/s, D the tip diameter, CT = T / (rho n^2 D^4), CP = P / (rho n^3
D^5), advance ratio J = V / (n D), efficiency J CT / CP (undefined at J = 0), figure of merit (the
ideal power of momentum theory over the power, at J = 0): T^1.5 / sqrt(2 rho A) / P with A = pi D^2
/ 4, which in these coefficients is CT^1.5 / (sqrt(pi / 2) CP) (the helicopter form CT^1.5 /
(sqrt(2) CP) holds for coefficients on rho A (Omega R)^2, not on rho n^2 D^4).

Signs: thrust is positive when the propeller pushes the fluid the way the design means to (toward
-z for both 'cw' and its mirror image 'ccw', which turn opposite ways): the fluid pushes the
propeller toward +z. Torque is positive when the fluid resists the design's rotation (what the
motor must supply); power = torque x |omega|.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from torus_cad.parameters.design import Handedness
from torus_cad.simulate.history import History
from torus_cad.simulate.settings import OperatingPoint

#: Simulations: a run counts as converged when thrust and torque vary by at most this fraction of
#: their mean over the last 10 % of its iterations.
SIMULATE_CONVERGED_VARIATION = 0.02


#: The share of the last iterations whose force variation decides convergence.
CONVERGENCE_WINDOW = 0.1


def thrust_and_torque(
    force_n: np.ndarray, moment_nm: np.ndarray, handedness: Handedness
) -> tuple[Any, Any]:
    """(thrust N, torque N m) from the propeller's force and moment (..., 3) about the origin."""
    # the design's sense of rotation about +z
    rotation = -1.0 if handedness == Handedness.CW else 1.0
    return force_n[..., 2], -rotation * moment_nm[..., 2]


def force_variation(values: np.ndarray, window: float = CONVERGENCE_WINDOW) -> float:
    """(max - min) / |mean| over the last ``window`` of ``values`` (at least 2 samples); 0 when all
    are 0."""
    count = max(2, math.ceil(window * len(values)))
    tail = np.asarray(values[-count:], dtype=float)
    spread = float(tail.max() - tail.min()) if len(tail) else 0.0
    mean = abs(float(tail.mean())) if len(tail) else 0.0
    if spread == 0.0:
        return 0.0
    return spread / mean if mean > 0.0 else math.inf


@dataclass(frozen=True)
class Performance:
    """Thrust N, torque N m, power W at an operating point; coefficients (None where undefined)."""

    thrust_n: float
    torque_nm: float
    power_w: float
    advance_ratio: float | None
    ct: float | None
    cp: float | None
    efficiency: float | None
    figure_of_merit: float | None


def performance(
    thrust_n: float, torque_nm: float, point: OperatingPoint, diameter_m: float
) -> Performance:
    """Coefficients of ``thrust_n`` and ``torque_nm`` at ``point`` for tip diameter
    ``diameter_m``."""
    rho, n = point.fluid.density_kg_m3, point.rpm / 60.0
    power = torque_nm * 2.0 * math.pi * n
    if n == 0.0:
        return Performance(thrust_n, torque_nm, power, None, None, None, None, None)
    advance = point.airspeed_m_s / (n * diameter_m)
    ct = thrust_n / (rho * n**2 * diameter_m**4)
    cp = power / (rho * n**3 * diameter_m**5)
    efficiency = advance * ct / cp if advance > 0.0 and cp != 0.0 else None
    merit = (
        ct**1.5 / (math.sqrt(math.pi / 2.0) * cp)
        if advance == 0.0 and ct > 0.0 and cp > 0.0
        else None
    )
    return Performance(thrust_n, torque_nm, power, advance, ct, cp, efficiency, merit)


def viscous_part(
    history: History, handedness: Handedness, thrust_n: float, torque_nm: float
) -> dict[str, float | None] | None:
    """The wall shear's part of the last iteration's thrust (N) and torque (N m), and its share of
    the totals ``thrust_n`` and ``torque_nm`` (None where a total is zero): how much a skin-friction
    error (a laminar or turbulent boundary layer, the wall treatment) can move the result. None when
    the history has no viscous
    columns."""
    if not len(history.viscous_force_n):
        return None
    viscous_thrust, viscous_torque = thrust_and_torque(
        history.viscous_force_n[-1], history.viscous_moment_nm[-1], handedness
    )
    return {
        "thrust_n": float(viscous_thrust),
        "torque_nm": float(viscous_torque),
        "thrust_share": float(viscous_thrust / thrust_n) if thrust_n else None,
        "torque_share": float(viscous_torque / torque_nm) if torque_nm else None,
    }


def run_summary(
    history: History,
    point: OperatingPoint,
    handedness: Handedness,
    diameter_m: float,
    window: float = CONVERGENCE_WINDOW,
) -> dict[str, Any]:
    """The report's numbers: the last iteration's performance, the force variation over the last
    ``window`` of the run and whether it is within ``SIMULATE_CONVERGED_VARIATION``."""
    thrust, torque = thrust_and_torque(history.force_n, history.moment_nm, handedness)
    variation = {
        "thrust": force_variation(thrust, window),
        "torque": force_variation(torque, window),
    }
    result = performance(float(thrust[-1]), float(torque[-1]), point, diameter_m)
    converged = max(variation.values()) <= SIMULATE_CONVERGED_VARIATION
    return {
        **result.__dict__,
        "converged": converged,
        "viscous": viscous_part(history, handedness, result.thrust_n, result.torque_nm),
        "force_variation_last_10_percent": {
            key: (value if math.isfinite(value) else None) for key, value in variation.items()
        },
        "convergence_limit": SIMULATE_CONVERGED_VARIATION,
    }


#: Roache's factor of safety of the grid convergence index for three grids (an observed order).
GCI_SAFETY_FACTOR = 1.25
#: The factor of safety on the levels' spread when they do not converge monotonically: without an
#: observed order, Eca and Hoekstra (J. Comput. Phys. 262, 2014) bound the numerical error by three
#: times the largest difference between the levels.
SPREAD_SAFETY_FACTOR = 3.0
#: The levels count as in the asymptotic range when GCI_medium / (r^p GCI_fine) is within this of 1.
ASYMPTOTIC_RANGE_TOLERANCE = 0.1


class UncertaintyMethod(StrEnum):
    """How a convergence study's numerical uncertainty of the fine level is estimated."""

    GCI = "gci"  #: Roache's GCI_fine: the levels converge monotonically
    SPREAD = "spread"  #: SPREAD_SAFETY_FACTOR times the levels' spread: they do not


@dataclass(frozen=True)
class Extrapolation:
    """Richardson extrapolation and Roache's grid convergence index over three levels (coarse,
    medium, fine) refined by ``ratio`` r (element size divided by r from one level to the next).

    ``order`` (observed order p), ``extrapolated`` (the value at zero element size, the unit of the
    values), ``gci_fine`` and ``gci_medium`` (GCI = Fs |e| / (r^p - 1), e the relative change to the
    next coarser level, Fs = ``GCI_SAFETY_FACTOR``: a fraction of the value, an error band) and
    ``asymptotic_ratio`` (GCI_medium / (r^p GCI_fine), 1 in the asymptotic range) are None unless
    ``converges_monotonically``: both changes (coarse to medium, medium to fine) of one sign, the
    second the smaller. :attr:`spread` is always given, so that levels which do not converge still
    get an uncertainty (:attr:`uncertainty_fine`).
    """

    values: tuple[float, float, float]
    ratio: float
    order: float | None
    extrapolated: float | None
    converges_monotonically: bool
    gci_fine: float | None = None
    gci_medium: float | None = None
    asymptotic_ratio: float | None = None

    @property
    def spread(self) -> float | None:
        """(max - min) / |fine| over the three values, a fraction; None when the fine value is 0."""
        fine = self.values[2]
        return (max(self.values) - min(self.values)) / abs(fine) if fine != 0.0 else None

    @property
    def uncertainty_method(self) -> UncertaintyMethod:
        return UncertaintyMethod.GCI if self.converges_monotonically else UncertaintyMethod.SPREAD

    @property
    def uncertainty_fine(self) -> float | None:
        """The fine value's numerical uncertainty, a fraction of it: GCI_fine where the levels
        converge monotonically, else ``SPREAD_SAFETY_FACTOR`` x ``spread`` (a band that holds every
        level)."""
        if self.converges_monotonically:
            return self.gci_fine
        return None if self.spread is None else SPREAD_SAFETY_FACTOR * self.spread

    @property
    def in_asymptotic_range(self) -> bool | None:
        """``asymptotic_ratio`` within ``ASYMPTOTIC_RANGE_TOLERANCE`` of 1 (None without one)."""
        if self.asymptotic_ratio is None:
            return None
        return abs(self.asymptotic_ratio - 1.0) <= ASYMPTOTIC_RANGE_TOLERANCE

    def report(self) -> dict[str, Any]:
        """The study's JSON entry of one force (fractions for the GCIs, the spread and the
        uncertainty)."""
        return {
            "extrapolated": self.extrapolated,
            "observed_order": self.order,
            "converges_monotonically": self.converges_monotonically,
            "gci_fine": self.gci_fine,
            "gci_medium": self.gci_medium,
            "gci_asymptotic_ratio": self.asymptotic_ratio,
            "in_asymptotic_range": self.in_asymptotic_range,
            "spread": self.spread,
            "uncertainty_fine": self.uncertainty_fine,
            "uncertainty_method": self.uncertainty_method.value,
        }


def convergence_report(
    name: str, point: OperatingPoint, ratio: float, levels: dict[str, dict[str, Any]]
) -> dict[str, Any]:
    """A convergence study's report (``<name>_convergence.json``), the same for either solver.

    Args:
        name: the design's name.
        point: the operating point every level ran at.
        ratio: the refinement ratio between two levels.
        levels: each level's entry by its name, coarsest first, each with ``thrust_n`` (N) and
            ``torque_nm`` (N m).

    Returns:
        The point, the ratio, ``levels``, and for thrust and torque Richardson's extrapolation and
        Roache's GCI (:meth:`Extrapolation.report`).
    """
    report: dict[str, Any] = {
        "name": name,
        "rpm": point.rpm,
        "gci_safety_factor": GCI_SAFETY_FACTOR,
        "airspeed_m_s": point.airspeed_m_s,
        "refinement_ratio": ratio,
        "levels": levels,
    }
    for key in ("thrust_n", "torque_nm"):
        coarse, medium, fine = (float(level[key]) for level in levels.values())
        report[key] = richardson(coarse, medium, fine, ratio).report()
    return report


def richardson(coarse: float, medium: float, fine: float, ratio: float) -> Extrapolation:
    """Observed order p = ln((f_c - f_m) / (f_m - f_f)) / ln r, f = f_f + (f_f - f_m) / (r^p - 1),
    and Roache's GCI: GCI_fine = Fs |(f_m - f_f) / f_f| / (r^p - 1), GCI_medium = Fs |(f_c - f_m) /
    f_m| / (r^p - 1), asymptotic ratio GCI_medium / (r^p GCI_fine); all undefined (None) unless the
    three converge monotonically (a GCI also needs nonzero f_f and f_m)."""
    values = (coarse, medium, fine)
    first, second = medium - coarse, fine - medium
    monotone = first != 0.0 and second != 0.0 and first * second > 0.0 and abs(second) < abs(first)
    if not monotone:
        return Extrapolation(values, ratio, None, None, False)
    order = math.log(first / second) / math.log(ratio)
    growth = ratio**order - 1.0
    gci_fine = GCI_SAFETY_FACTOR * abs(second / fine) / growth if fine != 0.0 else None
    gci_medium = GCI_SAFETY_FACTOR * abs(first / medium) / growth if medium != 0.0 else None
    asymptotic = (
        gci_medium / (ratio**order * gci_fine)
        if gci_fine is not None and gci_medium is not None
        else None
    )
    return Extrapolation(
        values, ratio, order, fine + second / growth, True, gci_fine, gci_medium, asymptotic
    )
