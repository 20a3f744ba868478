"""``torus-cad simulate --thrust N``: the rpm at which the propeller gives a target thrust.

The pure part (no OpenFOAM): the first guess, the secant step and the stopping rule. Thrust grows
about as rpm^2 (a constant CT), so the search works on g(rpm) = sqrt(T(rpm)) - sqrt(T_target), which
is about linear in rpm:

* the first run is at the rpm a thrust coefficient of ``INITIAL_CT`` would need;
* after one run, the line through the origin: rpm_1 = rpm_0 sqrt(T_target / T_0) (Newton's step on
  sqrt(T) with T proportional to rpm^2);
* after two or more, the secant through the last two runs on g; a step that goes nowhere (equal
  g, a slope of the wrong sign) falls back to the line through the origin from the closest run;
* every rpm is clipped to (0, rpm limit];
* the search stops when a run is within ``tolerance`` (a fraction) of the target, or after
  ``max_runs`` runs (then the closest run is reported, marked not within the tolerance).

A target beyond reach is refused (:class:`~torus_cad.errors.ParameterError`, exit 2): before any run
when it is over the thrust at the rpm limit with CT = ``PLAUSIBLE_CT_LIMIT``; after a run, when the
thrust at the rpm limit extrapolated from it (as rpm^2) is below the target by more than the
tolerance and a run at the limit confirms it.

:func:`torus_cad.simulate.pipeline.thrust_search` runs the search (one mesh, one solver run per
rpm).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from torus_cad.errors import ParameterError
from torus_cad.tolerances import THRUST_RUNS_RANGE, THRUST_TOLERANCE_RANGE

#: The thrust coefficient CT = T / (rho n^2 D^4) of the first guess (the default design's is about
#: 0.29).
INITIAL_CT = 0.25
#: No propeller gets near this CT: a target over the thrust at the rpm limit with it is refused
#: before any run.
PLAUSIBLE_CT_LIMIT = 1.0
#: Default stopping rule: within 1 % of the target, at most 5 runs.
DEFAULT_TOLERANCE = 0.01
DEFAULT_MAX_RUNS = 5
#: Bounds of the options (--thrust-tolerance as a fraction, --thrust-runs): torus_cad.tolerances'.
TOLERANCE_RANGE = THRUST_TOLERANCE_RANGE
MAX_RUNS_RANGE = THRUST_RUNS_RANGE


@dataclass(frozen=True)
class ThrustRun:
    """One solver run of the search: rpm and the thrust it gave, N."""

    rpm: float
    thrust_n: float


def thrust_at(ct: float, rpm: float, diameter_m: float, density_kg_m3: float) -> float:
    """T = CT rho n^2 D^4, N (n = rpm / 60 in rev/s, D in m, rho in kg/m^3)."""
    return ct * density_kg_m3 * (rpm / 60.0) ** 2 * diameter_m**4


def rpm_for(ct: float, thrust_n: float, diameter_m: float, density_kg_m3: float) -> float:
    """The rpm at which a propeller of thrust coefficient ``ct`` gives ``thrust_n`` N (inverse of
    :func:`thrust_at`)."""
    return 60.0 * math.sqrt(thrust_n / (ct * density_kg_m3 * diameter_m**4))


def thrust_ceiling(rpm_limit: float, diameter_m: float, density_kg_m3: float) -> float:
    """The largest target thrust accepted, N: CT = ``PLAUSIBLE_CT_LIMIT`` at ``rpm_limit``."""
    return thrust_at(PLAUSIBLE_CT_LIMIT, rpm_limit, diameter_m, density_kg_m3)


def check_target(
    target_n: float, rpm_limit: float, diameter_m: float, density_kg_m3: float
) -> None:
    """ParameterError (exit 2) naming ``--thrust``, the value and the allowed range for a target
    that is not a positive finite number or is over :func:`thrust_ceiling`."""
    ceiling = thrust_ceiling(rpm_limit, diameter_m, density_kg_m3)
    if not (math.isfinite(target_n) and 0.0 < target_n <= ceiling):
        raise ParameterError(
            f"--thrust = {target_n:g} N is out of range; allowed (0, {ceiling:.4g}] N (CT "
            f"{PLAUSIBLE_CT_LIMIT:g} at the rpm limit {rpm_limit:.0f} rpm for D = "
            f"{diameter_m * 1000:.1f} mm)"
        )


def first_rpm(target_n: float, rpm_limit: float, diameter_m: float, density_kg_m3: float) -> float:
    """The first run's rpm: what CT = ``INITIAL_CT`` needs for ``target_n``, at most
    ``rpm_limit``."""
    return min(rpm_for(INITIAL_CT, target_n, diameter_m, density_kg_m3), rpm_limit)


def within(run: ThrustRun, target_n: float, tolerance: float) -> bool:
    """Whether ``run`` is within ``tolerance`` (a fraction) of ``target_n``."""
    return abs(run.thrust_n - target_n) <= tolerance * target_n


def closest(runs: Sequence[ThrustRun], target_n: float) -> ThrustRun:
    """The run whose thrust is closest to ``target_n`` (the first of equals)."""
    return min(runs, key=lambda run: abs(run.thrust_n - target_n))


def _through_origin(run: ThrustRun, target_n: float) -> float:
    return run.rpm * math.sqrt(target_n / run.thrust_n)


def next_rpm(runs: Sequence[ThrustRun], target_n: float, rpm_limit: float) -> float:
    """The next rpm to run: the secant on sqrt(T) (see the module doc), clipped to (0,
    ``rpm_limit``].

    ParameterError when the last run gives no positive thrust (the propeller pushes the other way
    or not at all: nothing to scale)."""
    last = runs[-1]
    if not (math.isfinite(last.thrust_n) and last.thrust_n > 0.0):
        raise ParameterError(
            f"--thrust: the propeller gives {last.thrust_n:.4g} N at {last.rpm:g} rpm, no thrust "
            "in the design's direction to scale (for --step, check --axis and --turning)"
        )
    step = None
    if len(runs) >= 2:
        previous = runs[-2]
        g_last = math.sqrt(last.thrust_n) - math.sqrt(target_n)
        g_previous = math.sqrt(max(previous.thrust_n, 0.0)) - math.sqrt(target_n)
        if g_last != g_previous and last.rpm != previous.rpm:
            slope = (g_last - g_previous) / (last.rpm - previous.rpm)
            if slope > 0.0 and math.isfinite(slope):
                step = last.rpm - g_last / slope
    if step is None or not (math.isfinite(step) and step > 0.0):
        best = closest([run for run in runs if run.thrust_n > 0.0], target_n)
        step = _through_origin(best, target_n)
    return min(step, rpm_limit)


def check_reachable(
    runs: Sequence[ThrustRun], target_n: float, tolerance: float, rpm_limit: float
) -> None:
    """ParameterError naming ``--thrust`` when a run at ``rpm_limit`` fell short of the target by
    more than ``tolerance``: the range is (0, that run's thrust]."""
    at_limit = [run for run in runs if run.rpm >= rpm_limit * (1.0 - 1e-9)]
    if at_limit and at_limit[-1].thrust_n < target_n * (1.0 - tolerance):
        raise ParameterError(
            f"--thrust = {target_n:g} N is out of range; "
            f"allowed (0, {at_limit[-1].thrust_n:.4g}] N "
            f"(the thrust at the rpm limit {rpm_limit:.0f} rpm, simulated)"
        )


@dataclass(frozen=True)
class SearchState:
    """Where the search is: ``done``, the run to report (the closest), and whether it is within the
    tolerance."""

    done: bool
    best: ThrustRun
    within_tolerance: bool


def search_state(
    runs: Sequence[ThrustRun], target_n: float, tolerance: float, max_runs: int, rpm_limit: float
) -> SearchState:
    """The stopping rule: done when the last run is within ``tolerance`` of ``target_n`` or
    ``max_runs`` are done; ParameterError when the rpm limit cannot reach the target
    (:func:`check_reachable`)."""
    best = closest(runs, target_n)
    if within(runs[-1], target_n, tolerance):
        return SearchState(True, runs[-1], True)
    check_reachable(runs, target_n, tolerance, rpm_limit)
    return SearchState(len(runs) >= max_runs, best, within(best, target_n, tolerance))
