"""A design's thrust, torque and coefficients from the vortex lattice with its sections' viscous
polars.

The lattice (:mod:`.solver`) gives each strip its circulation and force. At each strip's flow (the
mean of the velocity at its control points, less its part along the span) the polar (:mod:`.polars`)
at the strip's Reynolds number takes over where potential flow stops: the strip's effective angle of
attack is the one at which the polar's linear part gives the lattice's lift coefficient cl (the
polar's zero-lift angle plus cl over its own lift slope); past the polar's stall angle the strip's
force is scaled toward the polar's lift over the lattice's there, fully STALL_BLEND_DEG past it
(before it the lattice's lift stands: the lift is corrected beyond the linear range only), and its
profile drag, 1/2 rho V^2 c ds cd along the flow, adds to the torque and takes from the thrust.

The coefficients follow UIUC's convention (n in rev/s, D the tip diameter): CT = T / (rho n^2 D^4),
CP = P / (rho n^3 D^5), J = V / (n D), efficiency J CT / CP, and at J = 0 the figure of merit
(momentum theory's ideal power over the power), as :mod:`torus_cad.simulate.coefficients` reports
them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.parameters.design import PropellerParameters
from torus_cad.simulate.coefficients import performance
from torus_cad.simulate.settings import OperatingPoint
from torus_cad.vortex.biot_savart import induced_velocity
from torus_cad.vortex.lattice import StripFrame
from torus_cad.vortex.polars import LOW_CONFIDENCE, strip_polars
from torus_cad.vortex.rotor import Discretisation, RotorBlade, rotor_blade
from torus_cad.vortex.solver import Inviscid, kinematic_velocity, solve_inviscid

#: The drag coefficient of a flat plate square to the flow (two-dimensional; Hoerner,
#: Fluid-Dynamic Drag, 3-16): the share of a strip standing across the flow that the lattice does
#: not hold.
CROSS_FLOW_PLATE_DRAG = 1.98
#: Past the polar's stall angle its lift takes over from the lattice's over this many degrees of
#: effective angle of attack: at once, a strip crossing stall as the lattice is refined jumped in
#: force, and the APC 10x7 SF's thrust with its polars changed non-monotonically (measured; with
#: the blend its three-lattice GCI_fine is 0.05 %).
STALL_BLEND_DEG = 2.0
#: The lattice's lift over the polar's is taken within these bounds (a stalled strip keeps some
#: lift).
LIFT_RATIO_BOUNDS = (0.0, 1.5)


@dataclass(frozen=True)
class StripLoads:
    """Blade 0's loading along the blade, one entry a strip (``(K - 1,)`` arrays).

    Attributes:
        s: centerline parameter; radius_m: radius of the strip's middle.
        circulation_m2_s: the strip's bound circulation.
        thrust_n_per_m / torque_nm_per_m: thrust and torque per unit length of the blade (viscous).
        reynolds, cl, cd, confidence: the strip's Reynolds number, lift and drag coefficients and
            NeuralFoil's
            confidence.
    """

    s: NDArray[np.float64]
    radius_m: NDArray[np.float64]
    circulation_m2_s: NDArray[np.float64]
    thrust_n_per_m: NDArray[np.float64]
    torque_nm_per_m: NDArray[np.float64]
    reynolds: NDArray[np.float64]
    cl: NDArray[np.float64]
    cd: NDArray[np.float64]
    confidence: NDArray[np.float64]


@dataclass(frozen=True)
class VortexResult:
    """The vortex solver's answer at one operating point.

    Attributes:
        report: thrust_n, torque_nm, power_w, advance_ratio, ct, cp, efficiency, figure_of_merit
            (the simulate report's keys), and inviscid_thrust_n / inviscid_power_w,
            low_confidence_strips.
        strips: the loading along the blade.
        blade: blade 0 as solved; inviscid: the lattice's solution.
        ring_force_n: ``(K - 1, C, 3)`` N, the force on each of blade 0's rings with its strip's
            loss of lift and its share of the strip's drag (they add up to the thrust and torque).
    """

    report: dict[str, Any]
    strips: StripLoads = field(repr=False)
    blade: RotorBlade = field(repr=False)
    inviscid: Inviscid = field(repr=False)
    ring_force_n: NDArray[np.float64] = field(repr=False)


def vortex_performance(
    params: PropellerParameters,
    rpm: float,
    airspeed_m_s: float = 0.0,
    discretisation: Discretisation | None = None,
    viscous: bool = True,
    induced_guess: float | None = None,
) -> VortexResult:
    """The performance of ``params`` at ``rpm`` and axial ``airspeed_m_s`` (module doc);
    ``induced_guess``: where the wake's iteration starts
    (:func:`~torus_cad.vortex.solver.solve_inviscid`)."""
    point = OperatingPoint(rpm=rpm, airspeed_m_s=airspeed_m_s)
    discretisation = discretisation or Discretisation()
    blade = rotor_blade(params, discretisation)
    density = point.fluid.density_kg_m3
    omega = rpm * np.pi / 30.0
    inviscid = solve_inviscid(
        blade.camber_m,
        blade.blades,
        blade.spin,
        omega,
        airspeed_m_s,
        density,
        blade.tip_radius_m,
        discretisation.wake,
        induced_guess=induced_guess,
    )
    force, moment, strips, ratio = _strip_forces(
        blade, inviscid, omega, airspeed_m_s, point, viscous
    )
    thrust = blade.blades * float(force[:, 2].sum())
    torque = blade.spin * blade.blades * float(moment[:, 2].sum())
    coefficients = performance(thrust, torque, point, 2.0 * blade.tip_radius_m)
    report = {
        "thrust_n": thrust,
        "torque_nm": torque,
        "power_w": coefficients.power_w,
        "advance_ratio": coefficients.advance_ratio,
        "ct": coefficients.ct,
        "cp": coefficients.cp,
        "efficiency": coefficients.efficiency,
        "figure_of_merit": coefficients.figure_of_merit,
        "inviscid_thrust_n": inviscid.thrust_n,
        "inviscid_power_w": inviscid.torque_nm * omega,
        "low_confidence_strips": int((strips.confidence < LOW_CONFIDENCE).sum()),
    }
    return VortexResult(report, strips, blade, inviscid, _ring_forces(inviscid, force, ratio))


def _ring_forces(
    inviscid: Inviscid, strip_force_n: NDArray[np.float64], ratio: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(K - 1, C, 3)`` N: each ring's lattice force scaled by its strip's loss of lift, and the
    strip's drag (its profile drag and, across the flow, its plate's) shared equally among its
    rings: the rings' forces add up to the strips' ``strip_force_n`` ``(K - 1, 3)``, so the loading
    noise sees every force the thrust and torque count."""
    lifting = inviscid.force_n * ratio[:, None, None]
    drag = strip_force_n - lifting.sum(axis=1)
    return lifting + drag[:, None, :] / inviscid.force_n.shape[1]


def _strip_forces(
    blade: RotorBlade,
    inviscid: Inviscid,
    omega: float,
    airspeed: float,
    point: OperatingPoint,
    viscous: bool,
) -> tuple[NDArray[np.float64], NDArray[np.float64], StripLoads, NDArray[np.float64]]:
    """Each strip's force and moment ``(K - 1, 3)`` on blade 0 with the polars' corrections, its
    loading, and its lift's ratio to the lattice's ``(K - 1,)``."""
    lattice = inviscid.lattice
    strips = inviscid.circulation.shape[0]
    force = inviscid.force_n.sum(axis=1)
    moment = inviscid.moment_nm.sum(axis=1)
    frame = StripFrame.of(blade.camber_m)
    middle, width = frame.middle, frame.width
    chord = 0.5 * (blade.chord_m[:-1] + blade.chord_m[1:])
    points = lattice.collocation.reshape(-1, 3)
    velocity = kinematic_velocity(points, omega, blade.spin, airspeed)
    if inviscid.circulation.any():
        velocity = velocity + induced_velocity(
            points,
            lattice.starts,
            lattice.ends,
            lattice.incidence @ inviscid.circulation.ravel(),
            lattice.core_m,
        )
    flow = frame.across_span(velocity.reshape(strips, -1, 3).mean(axis=1))
    speed = np.linalg.norm(flow, axis=1)
    density, viscosity = point.fluid.density_kg_m3, point.fluid.viscosity_m2_s
    reynolds = speed * chord / viscosity
    dynamic = 0.5 * density * speed**2 * chord * width
    lift = _lift(force, flow, speed)
    cl = np.where(dynamic > 0.0, lift / np.maximum(dynamic, 1e-300), 0.0)
    cd = np.zeros(strips)
    confidence = np.ones(strips)
    ratios = np.ones(strips)
    if viscous and speed.any():
        turned = np.einsum("jk,jk->j", flow, frame.chord) < 0.0
        for j, polar in enumerate(strip_polars(blade.sections, reynolds, turned)):
            alpha = polar.zero_lift_deg + cl[j] / polar.lift_slope_per_deg
            # before stall the lattice's lift stands (module doc)
            # the polar's lift takes over past stall, over STALL_BLEND_DEG (module doc)
            past = float(np.clip((alpha - polar.stall_deg) / STALL_BLEND_DEG, 0.0, 1.0))
            viscous_cl = cl[j] + past * (float(np.interp(alpha, polar.alpha_deg, polar.cl)) - cl[j])
            cd[j] = float(np.interp(alpha, polar.alpha_deg, polar.cd))
            confidence[j] = float(np.interp(alpha, polar.alpha_deg, polar.confidence))
            ratio = float(np.clip(viscous_cl / cl[j], *LIFT_RATIO_BOUNDS)) if cl[j] > 0.0 else 1.0
            ratios[j] = ratio
            drag = dynamic[j] * cd[j] * flow[j] / max(speed[j], 1e-300)
            drag = drag + (1.0 - inviscid.lifting_share[j]) * _plate_force(
                flow[j], frame.chord[j], chord[j] * width[j], density
            )
            force[j] = ratio * force[j] + drag
            moment[j] = ratio * moment[j] + np.cross(middle[j], drag)
            cl[j] = cl[j] * ratio
    loads = StripLoads(
        0.5 * (blade.s[:-1] + blade.s[1:]),
        np.hypot(middle[:, 0], middle[:, 1]),
        inviscid.circulation[:, -1],
        force[:, 2] / width,
        blade.spin * moment[:, 2] / width,
        reynolds,
        cl,
        cd,
        confidence,
    )
    return force, moment, loads, ratios


def _plate_force(
    flow: NDArray[np.float64], chord: NDArray[np.float64], area_m2: float, density: float
) -> NDArray[np.float64]:
    """``(3,)`` N: the drag of a flat plate of ``area_m2`` in the part of ``flow`` ``(3,)`` square
    to its ``chord`` ``(3,)`` (the cross-flow principle), along that part: a strip the lattice does
    not hold (:func:`torus_cad.vortex.solver.lifting_share`) stands across the flow like one."""
    along = chord / max(float(np.linalg.norm(chord)), 1e-300)
    across = flow - float(flow @ along) * along
    return 0.5 * density * CROSS_FLOW_PLATE_DRAG * area_m2 * float(np.linalg.norm(across)) * across


def _lift(
    force: NDArray[np.float64], flow: NDArray[np.float64], speed: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The part of each strip's force ``(K - 1, 3)`` across its flow, N."""
    unit = flow / np.maximum(speed, 1e-300)[:, None]
    return np.linalg.norm(force - np.einsum("jk,jk->j", force, unit)[:, None] * unit, axis=1)
