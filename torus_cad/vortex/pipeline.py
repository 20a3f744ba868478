"""``simulate --solver vortex``: a design's operating point (or the rpm for a thrust) in the vortex
solver, published as the OpenFOAM route publishes a run (torus_cad.simulate.pipeline):
``<name>_performance.json`` with the same keys (thrust, torque, power, CT, CP, efficiency or figure
of merit, J, converged, rpm, noise), the loading along the blade as CSV and picture, a picture of
the wake and the tonal noise, written as one set (all or none); and with ``--convergence`` three
lattices, each finer than the last by :data:`REFINEMENT_RATIO` in every count, and
``<name>_convergence.json`` in the OpenFOAM study's schema (Richardson, GCI, or the spread where the
lattices do not converge monotonically).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.acoustics.fwh import Medium
from torus_cad.acoustics.noise_report import (
    Noise,
    evaluate_noise,
    write_noise_csv,
    write_noise_plot,
)
from torus_cad.acoustics.observers import DEFAULT_OBSERVERS, Observer, check_observers
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.errors import ParameterError
from torus_cad.outputs.output_set import OutputSet
from torus_cad.parameters.design import PropellerParameters
from torus_cad.simulate.coefficients import convergence_report
from torus_cad.simulate.settings import (
    OperatingPoint,
    check_count,
    check_operating_point,
    rpm_limit,
)
from torus_cad.simulate.thrust_target import (
    DEFAULT_MAX_RUNS,
    DEFAULT_TOLERANCE,
    ThrustRun,
    check_target,
    first_rpm,
    next_rpm,
    search_state,
)
from torus_cad.tolerances import VORTEX_CHORDWISE_RANGE, VORTEX_SPANWISE_RANGE
from torus_cad.vortex.loading_files import write_loading_csv, write_loading_plot, write_wake_plot
from torus_cad.vortex.noise_surface import rotor_surface
from torus_cad.vortex.polars import LOW_CONFIDENCE
from torus_cad.vortex.rotor import Discretisation
from torus_cad.vortex.vortex_performance import LIFT_RATIO_BOUNDS, VortexResult, vortex_performance

#: Rings across the chord, and strips along the blade, a run may ask for (--chordwise, --spanwise).
CHORDWISE_RANGE = VORTEX_CHORDWISE_RANGE
SPANWISE_RANGE = VORTEX_SPANWISE_RANGE
#: ``--convergence``: each lattice's rings across the chord, strips and wake steps a turn are the
#: last's times this, rounded (scripts/vortex_convergence.py's default; OpenFOAM's levels divide
#: their element sizes by 2^(1/3), torus_cad.simulate.settings.REFINEMENT_RATIO).
REFINEMENT_RATIO = math.sqrt(2.0)
#: The study's lattices, coarsest first: the request's own, then two finer.
STUDY_LEVELS = ("coarse", "medium", "fine")


@dataclass(frozen=True)
class VortexRequest:
    """One vortex run: the design, the operating point, the lattice, the noise's observers, and
    whether the section polars correct the lattice (``viscous``)."""

    params: PropellerParameters
    point: OperatingPoint
    discretisation: Discretisation = field(default_factory=Discretisation)
    observers: tuple[Observer, ...] = DEFAULT_OBSERVERS
    viscous: bool = True
    # : False: the report and CSVs only (an optimiser's trial), no PNG nor directivity sweep
    pictures: bool = True


@dataclass
class VortexRun:
    """What a run published: paths by kind, and the report."""

    paths: dict[str, Path]
    report: dict[str, Any]


def tip_diameter_m(params: PropellerParameters) -> float:
    """The tip diameter of ``params`` with its design targets applied, m: the one the rpm's range is
    set by."""
    from torus_cad.cfd_domain.sizes import tip_radius

    return 2.0 * tip_radius(resolve_design_targets(params).parameters) / 1000.0


def check_vortex_request(request: VortexRequest) -> float:
    """ParameterError (exit 2) naming the option, the value and the range; the design's tip
    diameter, m."""
    check_count("--chordwise", request.discretisation.chordwise, *CHORDWISE_RANGE)
    check_count("--spanwise", request.discretisation.spanwise, *SPANWISE_RANGE)
    diameter_m = tip_diameter_m(request.params)
    check_operating_point(request.point, diameter_m, request.params)
    check_observers(request.observers, diameter_m / 2.0)
    return diameter_m


def simulate_vortex(
    request: VortexRequest,
    out_dir: str | Path,
    stage: Callable[[str], None] | None = None,
    search: dict[str, Any] | None = None,
) -> VortexRun:
    """Solve ``request`` and publish its set into ``out_dir`` (module doc); ``search``: a thrust
    search's record, kept in the report."""
    request = _with_targets_met(request)
    check_vortex_request(request)
    start = time.perf_counter()
    return _published(request, _solved(request, stage), Path(out_dir), start, stage, search)


def _induced_share(result: VortexResult, rpm: float) -> float | None:
    """``result``'s (at ``rpm``) wake inflow as a share of its tip speed: where the next run of a
    thrust search starts its wake iteration (the share hardly moves with the rpm); None for a rotor
    at rest."""
    tip_speed = rpm * math.pi / 30.0 * result.blade.tip_radius_m
    return result.inviscid.induced_m_s / tip_speed if tip_speed > 0.0 else None


def _with_targets_met(request: VortexRequest) -> VortexRequest:
    """``request`` with its design's targets (diameter, pitch, airfoil.naca) applied once, not at
    every run of a thrust search (the refit takes about a second)."""
    return dataclasses.replace(request, params=resolve_design_targets(request.params).parameters)


def _published(
    request: VortexRequest,
    result: VortexResult,
    out: Path,
    start: float,
    stage: Callable[[str], None] | None,
    search: dict[str, Any] | None,
) -> VortexRun:
    """``result`` (of ``request``) with its noise, published into ``out``."""
    return _publish(request, result, _noise(request, result, stage), out, start, search)


def vortex_thrust_search(
    request: VortexRequest,
    thrust_n: float,
    out_dir: str | Path,
    stage: Callable[[str], None] | None = None,
    tolerance: float = DEFAULT_TOLERANCE,
    max_runs: int = DEFAULT_MAX_RUNS,
) -> VortexRun:
    """The rpm at which ``request``'s design gives ``thrust_n`` N within ``tolerance`` of it, found
    by the OpenFOAM route's search (torus_cad.simulate.thrust_target: the first rpm from a plausible
    CT, then secant steps on sqrt(thrust)), published as :func:`simulate_vortex` publishes one run,
    the search in its report."""
    request = _with_targets_met(request)
    diameter_m = check_vortex_request(request)
    density = request.point.fluid.density_kg_m3
    limit = rpm_limit(diameter_m, request.point.airspeed_m_s, request.point.fluid)
    check_target(thrust_n, limit, diameter_m, density)
    start = time.perf_counter()
    rpm = first_rpm(thrust_n, limit, diameter_m, density)
    runs: list[ThrustRun] = []
    results: list[VortexResult] = []
    while True:
        results.append(
            vortex_performance(
                request.params,
                rpm,
                request.point.airspeed_m_s,
                request.discretisation,
                request.viscous,
                _induced_share(results[-1], runs[-1].rpm) if results else None,
            )
        )
        runs.append(ThrustRun(rpm, float(results[-1].report["thrust_n"])))
        if stage:
            stage(f"run {len(runs)}: {rpm:.0f} rpm, thrust {runs[-1].thrust_n:.4g} N")
        state = search_state(runs, thrust_n, tolerance, max_runs, limit)
        if state.done:
            break
        rpm = next_rpm(runs, thrust_n, limit)
    chosen = runs.index(state.best)
    search = {
        "target_thrust_n": thrust_n,
        "tolerance": tolerance,
        "max_runs": max_runs,
        "rpm": state.best.rpm,
        "thrust_n": state.best.thrust_n,
        "within_tolerance": state.within_tolerance,
        "rpm_limit": limit,
        "chosen_run": chosen,
        "runs": [
            {
                "rpm": run.rpm,
                "thrust_n": run.thrust_n,
                **{
                    key: result.report[key]
                    for key in ("torque_nm", "power_w", "figure_of_merit", "efficiency")
                },
                "converged": True,
            }
            for run, result in zip(runs, results, strict=True)
        ],
        "method": "secant on sqrt(thrust) over rpm; the first rpm from CT = the OpenFOAM route's",
    }
    best_point = OperatingPoint(state.best.rpm, request.point.airspeed_m_s, request.point.fluid)
    return _published(
        dataclasses.replace(request, point=best_point),
        results[chosen],
        Path(out_dir),
        start,
        stage,
        search,
    )


def _refined_count(count: int, steps: int, ratio: float = REFINEMENT_RATIO) -> int:
    """``count`` refined ``steps`` times by ``ratio``: times ``ratio ** steps``, rounded, at least
    2."""
    return max(2, round(count * ratio**steps))


def refined_lattice(
    discretisation: Discretisation, steps: int, ratio: float = REFINEMENT_RATIO
) -> Discretisation:
    """``discretisation`` refined ``steps`` times by ``ratio``: its rings across the chord, strips
    and wake steps a turn each :func:`_refined_count`."""
    wake = dataclasses.replace(
        discretisation.wake,
        steps_per_turn=_refined_count(discretisation.wake.steps_per_turn, steps, ratio),
    )
    return Discretisation(
        _refined_count(discretisation.chordwise, steps, ratio),
        _refined_count(discretisation.spanwise, steps, ratio),
        wake,
    )


def check_study_lattice(discretisation: Discretisation) -> None:
    """ParameterError (exit 2) where the study's finest lattice would leave the counts' ranges:
    names the option, its value and the range that keeps the finest lattice within them."""
    finest = len(STUDY_LEVELS) - 1
    for option, value, (low, high) in (
        ("--chordwise", discretisation.chordwise, CHORDWISE_RANGE),
        ("--spanwise", discretisation.spanwise, SPANWISE_RANGE),
    ):
        largest = max(
            count for count in range(low, high + 1) if _refined_count(count, finest) <= high
        )
        if not low <= value <= largest:
            raise ParameterError(
                f"{option} = {value} is out of range with --convergence, whose finest lattice "
                f"has {REFINEMENT_RATIO**finest:.0f} times as many; allowed [{low}, {largest}]"
            )


def vortex_convergence_study(
    request: VortexRequest, out_dir: str | Path, stage: Callable[[str], None] | None = None
) -> VortexRun:
    """``request`` on three lattices (its own and two finer: :func:`refined_lattice`), each run
    published whole into ``OUT/<level>/`` (:data:`STUDY_LEVELS`), and ``<name>_convergence.json``:
    each lattice's forces, and for thrust and torque Richardson's extrapolation, the observed order
    and Roache's GCI, or the spread where the lattices do not converge monotonically
    (:func:`torus_cad.simulate.coefficients.convergence_report`, as the OpenFOAM study reports)."""
    check_study_lattice(request.discretisation)
    request = _with_targets_met(request)
    check_vortex_request(request)
    out = Path(out_dir)
    levels: dict[str, dict[str, Any]] = {}
    for steps, level in enumerate(STUDY_LEVELS):
        lattice = refined_lattice(request.discretisation, steps)
        if stage:
            stage(f"{level} lattice, {lattice.chordwise} x {lattice.spanwise}")
        run = simulate_vortex(
            dataclasses.replace(request, discretisation=lattice), out / level, stage
        )
        levels[level] = {
            "lattice": run.report["lattice"],
            **{
                key: run.report[key]
                for key in ("thrust_n", "torque_nm", "ct", "cp", "converged", "wall_seconds")
            },
        }
    report = convergence_report(request.params.name, request.point, REFINEMENT_RATIO, levels)
    with OutputSet(out, f"{request.params.name}_convergence") as output:
        paths = output.publish(report)
        return VortexRun(paths, output.sealed_report)


def _solved(request: VortexRequest, stage: Callable[[str], None] | None) -> VortexResult:
    if stage:
        stage("vortex lattice")
    return vortex_performance(
        request.params,
        request.point.rpm,
        request.point.airspeed_m_s,
        request.discretisation,
        request.viscous,
    )


def _noise(
    request: VortexRequest, result: VortexResult, stage: Callable[[str], None] | None
) -> Noise | None:
    """The tonal noise at the request's observers (None when the rotor does not turn)."""
    if request.point.rpm == 0.0:
        return None
    if stage:
        stage("noise")
    fluid = request.point.fluid
    surface = rotor_surface(result.blade, result.inviscid.lattice, result.ring_force_n)
    # FW-H: positive counter-clockwise from +z
    omega = -result.blade.spin * request.point.rpm * math.pi / 30.0
    noise = evaluate_noise(
        surface,
        omega,
        result.blade.blades,
        Medium(fluid.density_kg_m3, fluid.speed_of_sound_m_s),
        request.observers,
        directivity=request.pictures,
    )
    noise.report["harmonics_of"] = "the blade-passing frequency"
    noise.report["source"] = (
        "the vortex lattice's pressure jump (loading) and the blade's surface (thickness); "
        "profile drag and leading-edge suction left out"
    )
    return noise


def _publish(
    request: VortexRequest,
    result: VortexResult,
    noise: Noise | None,
    out: Path,
    start: float,
    search: dict[str, Any] | None,
) -> VortexRun:
    name = request.params.name
    title = (
        f"{name}: {request.point.rpm:.0f} rpm, {request.point.airspeed_m_s:g} m/s, vortex lattice"
    )
    with OutputSet(out, f"{name}_performance") as output:
        output.write_files(
            lambda folder: _files(result, noise, folder, name, title if request.pictures else None)
        )
        report = {
            **_report(request, result, start),
            "noise": noise.report if noise is not None else None,
            **({"thrust_search": search} if search is not None else {}),
        }
        paths = output.publish(report)
        return VortexRun(paths, output.sealed_report)


def _files(
    result: VortexResult, noise: Noise | None, folder: Path, name: str, title: str | None
) -> dict[str, Path]:
    """The loading and noise CSVs, and with a ``title`` the pictures (loading, wake, noise)."""
    paths = {"loading_csv": write_loading_csv(result.strips, folder / f"{name}_loading.csv")}
    if noise is not None:
        paths["noise_csv"] = write_noise_csv(noise, folder / f"{name}_noise.csv")
    if title is None:
        return paths
    paths["loading_png"] = write_loading_plot(
        result.strips, folder / f"{name}_loading.png", f"loading, {title}"
    )
    paths["wake_png"] = write_wake_plot(
        result.blade, result.inviscid.lattice, folder / f"{name}_wake.png", f"wake, {title}"
    )
    if noise is not None:
        paths["noise_png"] = write_noise_plot(
            noise, folder / f"{name}_noise.png", f"tonal noise, {title}"
        )
    return paths


def _report(request: VortexRequest, result: VortexResult, start: float) -> dict[str, Any]:
    params, point, fluid = request.params, request.point, request.point.fluid
    strips = result.strips
    doubtful = np.flatnonzero(strips.confidence < LOW_CONFIDENCE)
    return {
        "name": params.name,
        "handedness": params.handedness.value,
        "solver": "vortex",
        "rpm": point.rpm,
        "airspeed_m_s": point.airspeed_m_s,
        "omega_rad_s": point.omega_rad_s(params.handedness),
        "tip_diameter_m": 2.0 * result.blade.tip_radius_m,
        **{
            key: result.report[key]
            for key in (
                "thrust_n",
                "torque_nm",
                "power_w",
                "advance_ratio",
                "ct",
                "cp",
                "efficiency",
                "figure_of_merit",
            )
        },
        "converged": True,
        "inviscid": {
            "thrust_n": result.report["inviscid_thrust_n"],
            "power_w": result.report["inviscid_power_w"],
        },
        "lattice": {
            "chordwise": request.discretisation.chordwise,
            "spanwise": request.discretisation.spanwise,
            "wake_diameters": request.discretisation.wake.length_diameters,
            "wake_steps_per_turn": request.discretisation.wake.steps_per_turn,
            "relaxed_first_turn": request.discretisation.wake.free_turns,
            "iterations": result.inviscid.iterations,
        },
        "polars": {
            "viscous": request.viscous,
            "source": "NeuralFoil (large) at each strip's Reynolds number",
            "lift_ratio_bounds": list(LIFT_RATIO_BOUNDS),
            "low_confidence_below": LOW_CONFIDENCE,
            "low_confidence_strips": [float(strips.s[j]) for j in doubtful],
            "reynolds_range": [float(strips.reynolds.min()), float(strips.reynolds.max())],
        },
        "fluid": {
            "name": fluid.name,
            "density_kg_m3": fluid.density_kg_m3,
            "viscosity_m2_s": fluid.viscosity_m2_s,
        },
        "wall_seconds": time.perf_counter() - start,
        "conventions": "thrust > 0 pushes the air toward -z "
        "(the design's way); torque > 0 resists the design's "
        "rotation; CT = T/(rho n^2 D^4), CP = P/(rho n^3 D^5), n in rev/s, D the tip diameter; "
        "polars.low_confidence_strips: the centerline "
        "parameters s of strips whose polar NeuralFoil "
        "trusts less than low_confidence_below (stall, very low Reynolds number)",
    }


def vortex_summary_lines(run: VortexRun) -> list[str]:
    """The paths written and the designer's numbers, as the OpenFOAM route prints them; a warning
    line where the polars are out of their confident range."""
    from torus_cad.simulate.cli_output import noise_line, thrust_search_lines

    report = run.report
    lines = [f"wrote {path}" for path in run.paths.values()]
    if "thrust_search" in report:
        lines += thrust_search_lines(report["thrust_search"])
    merit = (
        f"efficiency {report['efficiency']:.3f}"
        if report["efficiency"] is not None
        else f"figure of merit {report['figure_of_merit']:.3f}"
        if report["figure_of_merit"] is not None
        else ""
    )
    lines.append(
        f"thrust {report['thrust_n']:.4g} N, torque {report['torque_nm'] * 1000.0:.4g} N mm, power "
        f"{report['power_w']:.4g} W at {report['rpm']:g} rpm, {report['airspeed_m_s']:g} m/s: CT "
        f"{report['ct']:.4g}, CP {report['cp']:.4g}, {merit}"
    )
    lattice = report["lattice"]
    lines.append(
        f"vortex lattice {lattice['chordwise']} x {lattice['spanwise']} a blade, wake "
        f"{lattice['wake_diameters']:g} D, {report['wall_seconds']:.1f} s; inviscid thrust "
        f"{report['inviscid']['thrust_n']:.4g} N, power {report['inviscid']['power_w']:.4g} W"
    )
    doubtful = report["polars"]["low_confidence_strips"]
    if doubtful:
        lines.append(
            f"warning: NeuralFoil's polars are not confident on {len(doubtful)} strip(s), at s = "
            f"{', '.join(f'{s:.2f}' for s in doubtful[:8])}"
            f"{' ...' if len(doubtful) > 8 else ''} (stall or "
            "very low Reynolds number): the numbers there are rough"
        )
    if report.get("noise"):
        lines.append(noise_line(report["noise"]))
    return lines
