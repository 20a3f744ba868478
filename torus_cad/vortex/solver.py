"""The steady lifting-surface solve of a rotor in the blade's frame (SI units).

For a prescribed wake (:mod:`.lattice`): the rings' circulations that let no flow through any
control point, (V_kinematic + v_induced) . n = 0, with V_kinematic = -V_inf z + spin Omega z x r
(the air's velocity seen from the turning blade); then the Kutta-Joukowski force rho Gamma V x dl on
every bound segment (where two rings share a side, both carry their circulation there), at the
velocity the whole lattice induces at its midpoint. The wake's induced velocity comes from the
thrust by momentum theory, v = -V/2 + sqrt((V/2)^2 + T / (2 rho A)), A the tip circle's area; wake
and solve are iterated until that velocity changes by less than :data:`INDUCED_TOLERANCE` of the tip
speed, each wake's thrust the full Kutta-Joukowski sum: the induced velocity is the root of one
smooth function (momentum theory's answer on a wake less the wake's own), found by secant steps
until two wakes bracket it, then by the Illinois method (:class:`_InflowBracket`). (A cheaper
thrust, the force at the kinematic velocity alone scaled by the full sum's ratio to it, left the
wake iteration swinging on loops whose return leg sits in the front leg's wake, where that ratio
changes sign from one wake to the next.)

Where a strip's chord stands across the flow (a toroidal loop's apex, where the sections turn from
meeting the flow with their leading edge to meeting it with their trailing edge), no lifting
surface applies: the flow separates from a plate held square to it. There the ring's row of the
system is blended, by the strip's lifting share (:func:`lifting_share`), with one that holds its
circulation at zero; the two legs either side then shed the loop's circulation as two tips would,
and the share the lattice does not hold is a plate's drag (:mod:`.vortex_performance`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import KernelError
from torus_cad.vortex.biot_savart import induced_velocity, normal_influence
from torus_cad.vortex.lattice import (
    Lattice,
    StripFrame,
    WakeShape,
    rotor_lattice,
    strip_edges,
    wake_lines,
)

#: The wake iteration stops when its induced velocity changes by less than this fraction of the tip
#: speed (plus the airspeed).
INDUCED_TOLERANCE = 1e-5
#: Wake iterations at most; a solve that has not converged then raises.
MAX_WAKE_ITERATIONS = 20
#: Under-relaxation of the wake's induced velocity between iterations.
WAKE_RELAXATION = 1.0
#: A secant step of the wake iteration goes at most this many plain steps: where momentum theory's
#: answers creep toward the root from one side (a toroidal loop whose return leg sits in its
#: front leg's wake: 0.64 of the way a step, measured), the secant reaches it in a few.
SECANT_REACH = 4.0
#: The blade's own segments get a vortex core of this many mean chords where the force on a bound
#: segment is evaluated: where a loop's flow turns round, two strips' rings meet on one section line
#: at different nodes, and a segment's midpoint lies a hair from its neighbour's segment.
BOUND_CORE_CHORDS = 0.02
#: The relaxed wake: each sweep moves its first turn this share of the way to the streamlines ...
WAKE_SWEEP_RELAXATION = 0.3
#: ... halved, down to this, after a sweep whose change grew (the wake swinging round its shape) ...
WAKE_SWEEP_RELAXATION_MIN = 0.05
#: ... until the thrust changes by less than this fraction of itself between sweeps (scaled to a
#: full step) ...
RELAXED_THRUST_TOLERANCE = 5e-3
#: ... in this many sweeps at most (each a solve after the prescribed wake's).
RELAXATION_SWEEPS_MAX = 30
#: Where a strip's chord stands across the flow (a toroidal loop's apex, where the flow meets the
#: sections broadside): below the first cosine between chord and flow (84 deg) a strip carries no
#: circulation, above the second (73 deg) it is the lattice's, a smooth step between
#: (:func:`lifting_share`); the share it does not carry is a plate in cross flow
#: (:mod:`.vortex_performance`). A lifting surface at such incidences has a near-singular boundary
#: condition: measured, the apex's one strip moved the default design's thrust by 17 % from 8 to 16
#: rings across the chord.
CROSS_FLOW_COSINES = (0.1, 0.3)
#: The first guess of the induced velocity in still air, as a fraction of the tip speed.
STATIC_INDUCED_GUESS = 0.05


@dataclass(frozen=True)
class Inviscid:
    """The inviscid solution on one blade (all blades carry the same).

    Attributes:
        circulation: ``(K - 1, C)`` m^2/s, each ring's.
        force_n: ``(K - 1, C, 3)`` N, the force on each ring's bound segments (blade 0).
        moment_nm: ``(K - 1, C, 3)`` N m, their moment about the origin.
        thrust_n / torque_nm: the rotor's (all blades): thrust along +z, torque resisting the
            rotation.
        induced_m_s: the wake's induced velocity at the disk (momentum theory).
        lifting_share: ``(K - 1,)`` the share of each strip the lattice holds to its boundary
            condition (:func:`lifting_share`).
        iterations: wake iterations and relaxation sweeps; change: the last change the iteration
            measured.
    """

    circulation: NDArray[np.float64]
    force_n: NDArray[np.float64]
    moment_nm: NDArray[np.float64]
    thrust_n: float
    torque_nm: float
    induced_m_s: float
    iterations: int
    change: float
    lifting_share: NDArray[np.float64]
    lattice: Lattice = field(repr=False)


def kinematic_velocity(
    points: NDArray[np.float64], omega_rad_s: float, spin: float, airspeed_m_s: float
) -> NDArray[np.float64]:
    """``(P, 3)`` the air's velocity at ``points`` seen from the turning blade (module doc)."""
    velocity = np.zeros_like(points)
    velocity[:, 0] = -spin * omega_rad_s * points[:, 1]
    velocity[:, 1] = spin * omega_rad_s * points[:, 0]
    velocity[:, 2] = -airspeed_m_s
    return velocity


def solve_inviscid(
    camber_m: NDArray[np.float64],
    blades: int,
    spin: float,
    omega_rad_s: float,
    airspeed_m_s: float,
    density: float,
    tip_radius_m: float,
    wake: WakeShape,
    momentum_wake: bool = True,
    induced_guess: float | None = None,
) -> Inviscid:
    """Circulations and forces of the rotor whose blade 0 has the camber grid ``camber_m`` (module
    doc).

    Args:
        camber_m: ``(K, C + 1, 3)`` blade 0's camber surface, m (sections along the blade, leading
            to trailing edge across it).
        blades: blade count; spin: +1 where the blade turns clockwise seen from +z, -1 otherwise.
        omega_rad_s: rotation rate (>= 0); airspeed_m_s: axial inflow (>= 0), toward -z.
        density: kg/m^3; tip_radius_m: the disk's radius (momentum theory, the wake's length).
        wake: the wake's layout.
        momentum_wake: iterate the wake's induced velocity (a rotor); False leaves it at 0 (a wing).
        induced_guess: the induced velocity to start that iteration from, as a fraction of the tip
            speed ``omega_rad_s * tip_radius_m`` (default STATIC_INDUCED_GUESS in still air, else
            0): a thrust search passes its last run's, which the next rpm's is close to (the same
            answer, fewer iterations).

    Raises:
        KernelError: the wake iteration did not converge (naming the change reached).
    """
    area = np.pi * tip_radius_m**2
    frame = StripFrame.of(camber_m)
    chord = frame.chord
    meeting = kinematic_velocity(frame.middle, omega_rad_s, spin, airspeed_m_s)
    downstream_first = np.einsum("jk,jk->j", frame.across_span(meeting), chord) < 0.0
    strips = strip_edges(camber_m, downstream_first)
    share = lifting_share(frame, meeting)
    lifting = np.repeat(share, camber_m.shape[1] - 1)
    guess = STATIC_INDUCED_GUESS if airspeed_m_s == 0.0 else 0.0
    induced = (
        (guess if induced_guess is None else induced_guess) * omega_rad_s * tip_radius_m
        if momentum_wake
        else 0.0
    )
    scale = airspeed_m_s + omega_rad_s * tip_radius_m
    mean_chord = float(np.linalg.norm(chord, axis=1).mean()) / 2.0
    change, blade_part, bound_core = np.inf, BladePart(), BOUND_CORE_CHORDS * mean_chord
    bracket = _InflowBracket()
    for iteration in range(1, MAX_WAKE_ITERATIONS + 1):  # noqa: B007 (the count is reported)
        edges = strips[:, :, -1].reshape(-1, 3)
        lines = wake_lines(edges, omega_rad_s, spin, airspeed_m_s, induced, tip_radius_m, wake)
        lattice = rotor_lattice(
            strips,
            blades,
            lines.reshape(len(strips), 2, *lines.shape[1:]),
            wake.core_chords * mean_chord,
            mean_chord,
        )
        circulation = _circulation(lattice, spin, omega_rad_s, airspeed_m_s, blade_part, lifting)
        force, moment = _forces(
            lattice, circulation, spin, omega_rad_s, airspeed_m_s, density, bound_core
        )
        thrust = blades * float(force[..., 2].sum())
        if scale == 0.0 or not momentum_wake:
            break
        momentum = momentum_inflow_m_s(thrust, airspeed_m_s, density, area)
        change = abs(momentum - induced) / scale
        if change < INDUCED_TOLERANCE:
            break
        induced = bracket.next(induced, momentum)
    else:
        raise KernelError(
            f"the vortex solve did not converge: the wake's induced velocity still changed by "
            f"{change:.2g} of the tip speed after {MAX_WAKE_ITERATIONS} wake iterations "
            f"(tolerance {INDUCED_TOLERANCE:g})"
        )
    if momentum_wake and omega_rad_s > 0.0 and wake.free_turns:
        relaxed = _relaxed(
            strips,
            lines.reshape(len(strips), 2, *lines.shape[1:]),
            (lattice, circulation, blade_part, lifting),
            blades,
            spin,
            omega_rad_s,
            airspeed_m_s,
            wake,
            mean_chord,
        )
        circulation, lattice, change, sweeps = relaxed
        force, moment = _forces(
            lattice, circulation, spin, omega_rad_s, airspeed_m_s, density, bound_core
        )
        iteration += sweeps
        thrust = blades * float(force[..., 2].sum())
    torque = spin * blades * float(moment[..., 2].sum())
    return Inviscid(
        circulation, force, moment, thrust, torque, induced, iteration, change, share, lattice
    )


class _InflowBracket:
    """The wake iteration's next induced velocity: momentum theory's answer on the last wake (or a
    secant step toward its root), or, once two wakes have given answers on either side of their own
    induced velocities, the Illinois method's step inside that bracket (the plain update swings
    between two wakes where the thrust falls steeply with the induced velocity, as on a blade set
    near its zero-lift angle). Hand-written: scipy's root finders need the bracket before the first
    step, and this iteration has to find it."""

    def __init__(self) -> None:
        self.low: tuple[float, float] | None = None  # (induced, momentum - induced) below the root
        self.high: tuple[float, float] | None = None  # ... above it
        self.last: tuple[float, float] | None = None
        self.side = 0  # which end the last step moved: -1 low, +1 high

    def next(self, induced: float, momentum: float) -> float:
        """The induced velocity (m/s) to try next after ``induced`` gave ``momentum``."""
        residual = momentum - induced
        last, self.last = self.last, (induced, residual)
        if residual > 0.0:
            self.low, moved = (induced, residual), -1
        else:
            self.high, moved = (induced, residual), 1
        if self.low is None or self.high is None:
            return self._unbracketed(induced, residual, last)
        (x_low, r_low), (x_high, r_high) = self.low, self.high
        if moved == self.side:  # the same end moved twice: halve the other's residual (Illinois)
            if moved < 0:
                r_high *= 0.5
                self.high = (x_high, r_high)
            else:
                r_low *= 0.5
                self.low = (x_low, r_low)
        self.side = moved
        return x_low - r_low * (x_high - x_low) / (r_high - r_low)

    @staticmethod
    def _unbracketed(induced: float, residual: float, last: tuple[float, float] | None) -> float:
        """Momentum theory's answer, or, where the answers creep toward the root from one side, the
        secant step through the last two residuals, at most SECANT_REACH plain steps long."""
        plain = WAKE_RELAXATION * residual
        if last is None or last[1] == residual or last[0] == induced:
            return induced + plain
        step = -residual * (induced - last[0]) / (residual - last[1])
        if step * plain <= 0.0:  # the secant points away from the root: the plain step
            return induced + plain
        return induced + float(np.clip(step, -SECANT_REACH * abs(plain), SECANT_REACH * abs(plain)))


def lifting_share(frame: StripFrame, meeting: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(K - 1,)``: how much of each strip of ``frame`` the lattice holds to its boundary
    condition, from the cosine between its chord and the flow ``meeting`` it ``(K - 1, 3)`` (the
    turning blade's kinematic flow, less its part along the span): 1 down to
    CROSS_FLOW_COSINES[1], 0 below CROSS_FLOW_COSINES[0], a smooth step between (module doc). 1
    where there is no flow."""
    low, high = CROSS_FLOW_COSINES
    flow = frame.across_span(meeting)
    scale = np.linalg.norm(flow, axis=1) * np.linalg.norm(frame.chord, axis=1)
    cosine = np.abs(np.einsum("jk,jk->j", flow, frame.chord)) / np.maximum(scale, 1e-300)
    step = np.clip((cosine - low) / (high - low), 0.0, 1.0)
    return np.where(scale > 0.0, step * step * (3.0 - 2.0 * step), 1.0)


def momentum_inflow_m_s(
    thrust_n: float, airspeed_m_s: float, density: float, area_m2: float
) -> float:
    """Momentum theory's induced velocity at the disk (m/s, toward -z) for ``thrust_n`` on
    ``area_m2`` in axial ``airspeed_m_s``.

    In still air a negative thrust (a rotor that pushes the air toward +z: turned the other way
    round, or its blades set so) drives the air up as a positive one drives it down: the same
    speed, negative. In axial inflow a negative thrust gives none (its wake leaves at the airspeed).
    """
    if airspeed_m_s == 0.0 and thrust_n < 0.0:
        return -float(np.sqrt(-thrust_n / (2.0 * density * area_m2)))
    return float(
        -airspeed_m_s / 2.0
        + np.sqrt((airspeed_m_s / 2.0) ** 2 + max(thrust_n, 0.0) / (2.0 * density * area_m2))
    )


def _relaxed(
    strips: NDArray[np.float64],
    lines: NDArray[np.float64],
    prescribed: tuple[Any, ...],
    blades: int,
    spin: float,
    omega: float,
    airspeed: float,
    wake: WakeShape,
    mean_chord: float,
) -> tuple[Any, ...]:
    """The solve on a wake whose first turn follows the flow (module doc), from the solve on the
    prescribed ``lines`` (``prescribed``: its lattice, circulations, the blades' part of the
    influence matrix and the rings' lifting shares): each sweep retraces the first turn as
    streamlines of the blade frame's velocity (kinematic plus induced, the wake's core on every
    segment), moves the rest with its end, blends by WAKE_SWEEP_RELAXATION and solves for the
    circulations again, until the thrust (:func:`_kinematic_thrust`, which needs no Biot-Savart
    sum) changes by less than RELAXED_THRUST_TOLERANCE of itself; KernelError naming the change
    after RELAXATION_SWEEPS_MAX sweeps. Returns the circulations, the lattice, the last change and
    the sweeps."""
    free = wake.steps_per_turn  # the first turn's even steps
    step_s = 2.0 * np.pi / wake.steps_per_turn / omega
    core = wake.core_chords * mean_chord
    lattice, circulation, blade_part, lifting = prescribed
    thrust = _kinematic_thrust(lattice, circulation, blades, spin, omega, airspeed)
    change, blend = np.inf, WAKE_SWEEP_RELAXATION
    for sweep in range(1, RELAXATION_SWEEPS_MAX + 1):
        nodes = lines[:, :, : free + 1].reshape(-1, 3)
        velocity = kinematic_velocity(nodes, omega, spin, airspeed) + induced_velocity(
            nodes,
            lattice.starts,
            lattice.ends,
            lattice.incidence @ circulation.ravel(),
            np.maximum(lattice.core_m, core),
        )
        velocity = velocity.reshape(*lines.shape[:2], free + 1, 3)
        traced = lines.copy()
        for node in range(free):
            traced[:, :, node + 1] = traced[:, :, node] + step_s * 0.5 * (
                velocity[:, :, node] + velocity[:, :, node + 1]
            )
        traced[:, :, free + 1 :] += (traced[:, :, free] - lines[:, :, free])[:, :, None, :]
        lines = (1.0 - blend) * lines + blend * traced
        lattice = rotor_lattice(strips, blades, lines, core, mean_chord)
        circulation = _circulation(lattice, spin, omega, airspeed, blade_part, lifting)
        new_thrust = _kinematic_thrust(lattice, circulation, blades, spin, omega, airspeed)
        previous = change
        # the change a full WAKE_SWEEP_RELAXATION step would make: a smaller blend moves the wake
        # less
        change = (
            abs(new_thrust - thrust) / max(abs(new_thrust), 1e-300) * WAKE_SWEEP_RELAXATION / blend
        )
        thrust = new_thrust
        # the sweeps overshoot (the wake swings round its shape): smaller steps
        if change > previous:
            blend = max(0.5 * blend, WAKE_SWEEP_RELAXATION_MIN)
        if change < RELAXED_THRUST_TOLERANCE:
            return circulation, lattice, change, sweep
    raise KernelError(
        "the vortex solve did not converge: with its "
        "first wake turn following the flow the thrust "
        f"still changed by {change:.2g} of itself after {RELAXATION_SWEEPS_MAX} sweeps "
        f"(tolerance {RELAXED_THRUST_TOLERANCE:g})"
    )


class BladePart:
    """The part of the influence matrix that the blades' own segments make: the same for every wake
    of one solve (only the wake moves), so it is computed once (the rings' rows, ``(P, rings)``)."""

    def __init__(self) -> None:
        self.matrix: NDArray[np.float64] | None = None


def _circulation(
    lattice: Lattice,
    spin: float,
    omega: float,
    airspeed: float,
    blade_part: BladePart,
    lifting: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The rings' circulations ``(K - 1, C)`` that let no flow through the control points, each
    ring's row blended by its ``lifting`` share ``(rings,)`` with one that holds its circulation at
    zero (:func:`lifting_share`)."""
    points = lattice.collocation.reshape(-1, 3)
    normals = lattice.normals.reshape(-1, 3)
    on_blades = lattice.on_blades
    if blade_part.matrix is None:
        influence = normal_influence(
            points,
            normals,
            lattice.starts[on_blades],
            lattice.ends[on_blades],
            lattice.core_m[on_blades],
        )
        blade_part.matrix = np.asarray(influence @ lattice.incidence[on_blades])
    wake = ~on_blades
    influence = normal_influence(
        points, normals, lattice.starts[wake], lattice.ends[wake], lattice.core_m[wake]
    )
    matrix = blade_part.matrix + np.asarray(influence @ lattice.incidence[wake])
    rhs = -np.einsum("pk,pk->p", kinematic_velocity(points, omega, spin, airspeed), normals)
    diagonal = np.diag(matrix).copy()
    matrix = lifting[:, None] * matrix
    matrix[np.diag_indices_from(matrix)] += (1.0 - lifting) * diagonal
    rhs = lifting * rhs
    circulation = np.linalg.solve(matrix, rhs) if rhs.any() else np.zeros(lattice.rings)
    return circulation.reshape(-1, lattice.grid.shape[2] - 1)


def _forces(
    lattice: Lattice,
    circulation: NDArray[np.float64],
    spin: float,
    omega: float,
    airspeed: float,
    density: float,
    bound_core_m: float,
    induced: bool = True,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The Kutta-Joukowski force on each ring's bound segments and its moment about the origin
    ``(K - 1, C, 3)`` (blade 0), at the velocity the whole lattice induces at each segment's middle
    (the kinematic velocity alone without ``induced``: no Biot-Savart sum)."""
    shape = circulation.shape
    bound = lattice.bound_segments
    starts, ends = lattice.starts[:bound], lattice.ends[:bound]
    middle = 0.5 * (starts + ends)
    strengths = lattice.incidence @ circulation.ravel()
    velocity = kinematic_velocity(middle, omega, spin, airspeed)
    if induced and circulation.any():
        cores = lattice.core_m.copy()
        # neighbours' segments on a shared section line (module doc)
        cores[cores == 0.0] = bound_core_m
        velocity = velocity + induced_velocity(
            middle, lattice.starts, lattice.ends, strengths, cores
        )
    force = density * strengths[:bound, None] * np.cross(velocity, ends - starts)
    ring = lattice.incidence[:bound].indices  # each bound segment carries one ring's circulation
    per_ring = np.zeros((lattice.rings, 3))
    moment = np.zeros((lattice.rings, 3))
    np.add.at(per_ring, ring, force)
    np.add.at(moment, ring, np.cross(middle, force))
    return per_ring.reshape(*shape, 3), moment.reshape(*shape, 3)


def _kinematic_thrust(
    lattice: Lattice,
    circulation: NDArray[np.float64],
    blades: int,
    spin: float,
    omega: float,
    airspeed: float,
) -> float:
    """The rotor's thrust (per unit density) from the Kutta-Joukowski force at the kinematic
    velocity alone: no Biot-Savart sum, so it is cheap; the wake iterations and the relaxed wake's
    sweeps watch it settle."""
    force, _ = _forces(lattice, circulation, spin, omega, airspeed, 1.0, 0.0, induced=False)
    return blades * float(force[..., 2].sum())
