"""The rotor's vortex lattice: rings on blade 0's camber surface, their images on the other blades,
and the helical wake shed from the whole trailing edge (SI units: m, s).

Rings (Katz and Plotkin, ch. 12): the camber surface's panels, each ring's leading segment a quarter
of its panel behind the panel's leading edge (the last ring ends on the trailing edge), its
collocation point at three quarters of the panel, where the flow may not cross the surface. A
strip's last ring and its wake form a horseshoe: the trailing-edge segment cancels against the
wake's first one in a steady wake of constant strength, so each strip sheds two helical lines from
its trailing-edge nodes. Both ends of a toroidal blade sit in the hub: their rings shed into the
wake like any other; no image of the hub is modelled.

A strip sheds from the edge its flow leaves by: the trailing edge, or the leading edge where the air
meets the trailing edge first (a toroidal loop's return leg turns its trailing edge into the
rotation); each strip sheds its own two lines.

The wake is prescribed: in the blade's frame its lines turn against the rotation at the rotor's rate
and travel downstream at the free stream plus momentum theory's induced velocity at the disk, V + v:
a rigid helix (Goldstein's and XROTOR's wake), neither speeding up nor contracting. v comes from the
thrust by momentum theory (:mod:`.solver` iterates); in still air behind a rotor that pushes the air
up (a negative thrust) it is negative and the wake leaves toward +z. The alternative,
``WakeShape.slipstream``, moves the lines as the axis of a uniformly loaded actuator disk's
slipstream, V + v (1 + z / sqrt(z^2 + R^2)) (2 v far downstream), contracting as its mass flow
requires: every line then travels at the slipstream's core speed, while the vorticity it stands for,
rolled up at the slipstream's edge, moves at the mean of the speeds either side (V + v far
downstream), so the wake leaves too fast and induces too little at the blade; measured, its induced
power fell 12 % below momentum theory's ideal (docs/explanation/simulation-accuracy.md).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.sparse import csr_matrix

#: Ring segments: corners (first, second) of each of a ring's four sides, as (section, chord)
#: offsets.
_SIDES = (((0, 0), (1, 0)), ((1, 0), (1, 1)), ((1, 1), (0, 1)), ((0, 1), (0, 0)))


@dataclass(frozen=True)
class WakeShape:
    """How the wake is laid out.

    Attributes:
        length_diameters: how far downstream it reaches, in tip diameters.
        steps_per_turn: segments per turn of each helical line in its first turn, reached ...
        first_step_fraction: ... from a first segment this fraction of that step long ...
        near_growth: ... each next one this much longer: the lattice's answer hangs most on the
            near wake's straight segments (the first turns the wake's line away from the
            trailing edge's), so they start about a chord panel long (a relaxed first turn,
            ``free_turns``, is traced in even steps); then ...
        growth: ... after which each segment is this much longer than the one before ...
        longest_step_deg: ... up to this turn a segment.
        max_turns: turns at most (a still-air wake of small pitch would need very many).
        core_chords: the wake lines' vortex core radius, in mean chords, reached one mean chord
            behind the blade: a line that passes a blade downstream (a toroidal loop's return leg)
            induces a finite velocity there.
        slipstream: the lines speed up downstream and contract as an actuator disk's slipstream
            (module doc); False (the default) keeps the rigid helix.
        free_turns: the wake's first turn follows the flow (relaxed, :mod:`.solver`); False (the
            default) keeps the whole wake prescribed, its pitch from the momentum-theory inflow:
            measured, the relaxed turn does not settle on every design (a 4-blade toroidal one) and
            ranks the toroidal designs and the APC 10x7 SF's static thrust worse
            (docs/explanation/simulation-accuracy.md).
    """

    length_diameters: float = 4.0
    steps_per_turn: int = 24
    first_step_fraction: float = 0.1
    near_growth: float = 1.3
    growth: float = 1.1
    longest_step_deg: float = 60.0
    max_turns: float = 40.0
    core_chords: float = 0.1
    slipstream: bool = False
    free_turns: bool = False


@dataclass(frozen=True)
class Lattice:
    """Blade 0's rings and every segment of the rotor (all blades, the wake) with its unknown.

    Attributes:
        grid: ``(K - 1, 2, C + 1, 3)`` m, the rings' corners of each strip on blade 0 (C rings a
            strip).
        collocation / normals: ``(1, (K - 1) C, 3)`` the rings' control points and unit normals.
        starts / ends: ``(S, 3)`` m, every segment of the rotor and its wake.
        incidence: ``(S, rings)`` sparse: the circulation each segment carries is incidence @ the
            rings' (a wake line carries its strip's last ring's).
        bound_segments: the first this many segments are blade 0's bound ones, one ring's each.
        core_m: ``(S,)`` each segment's vortex core radius (0 on the blades, the wake's core on the
            wake).
        on_blades: ``(S,)`` whether each segment is a blade's (bound) rather than the wake's.
    """

    grid: NDArray[np.float64]
    collocation: NDArray[np.float64]
    normals: NDArray[np.float64]
    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    incidence: csr_matrix
    bound_segments: int
    core_m: NDArray[np.float64]
    on_blades: NDArray[np.bool_]

    @property
    def rings(self) -> int:
        """Number of unknowns: rings of blade 0."""
        return int(self.collocation.shape[1])


@dataclass(frozen=True)
class StripFrame:
    """Each strip's place and axes on a camber grid ``(K, C + 1, 3)`` (one strip between two
    sections): what the solve, the apex's lifting share and the polars' step all measure from.

    Attributes:
        middle: ``(K - 1, 3)`` the mean of the strip's two section lines.
        chord: ``(K - 1, 3)`` the sum of its two sections' leading-to-trailing-edge vectors.
        span: ``(K - 1, 3)`` from its first section line's mean to its second's.
    """

    middle: NDArray[np.float64]
    chord: NDArray[np.float64]
    span: NDArray[np.float64]

    @classmethod
    def of(cls, camber_m: NDArray[np.float64]) -> StripFrame:
        """The strips of the camber grid ``camber_m`` ``(K, C + 1, 3)``."""
        return cls(
            0.5 * (camber_m[:-1] + camber_m[1:]).mean(axis=1),
            camber_m[:-1, -1] + camber_m[1:, -1] - camber_m[:-1, 0] - camber_m[1:, 0],
            camber_m[1:].mean(axis=1) - camber_m[:-1].mean(axis=1),
        )

    @property
    def width(self) -> NDArray[np.float64]:
        """``(K - 1,)`` each strip's width along the span."""
        return np.asarray(np.linalg.norm(self.span, axis=1))

    def across_span(self, vectors: NDArray[np.float64]) -> NDArray[np.float64]:
        """``vectors`` ``(K - 1, 3)``, one a strip, less their parts along the strip's span."""
        along = self.span / self.width[:, None]
        return vectors - np.einsum("jk,jk->j", vectors, along)[:, None] * along


def ring_grid(camber_m: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(K, C + 1, 3)``: the ring corners of a camber grid ``(K, C + 1, 3)``: each panel's quarter
    line, and the trailing edge."""
    grid = camber_m.copy()
    grid[:, :-1] = camber_m[:, :-1] + 0.25 * (camber_m[:, 1:] - camber_m[:, :-1])
    return grid


def control_points(
    camber_m: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Each panel's three-quarter point (mean of its two section lines) and unit normal there:
    ``(K - 1, C, 3)`` each. The normal is square to the span and to the camber line's tangent at the
    point (the derivative of the parabola through the panel's and a neighbour's nodes), not to the
    panel's chord: on a curved camber line the chord's slope is the slope half way along the panel,
    and a lattice of chord normals misses a tenth of the camber's lift at 8 panels (a NACA 4412 mean
    line on an elliptic wing; tested)."""
    three_quarter = camber_m[:, :-1] + 0.75 * (camber_m[:, 1:] - camber_m[:, :-1])
    points = 0.5 * (three_quarter[:-1] + three_quarter[1:])
    diagonal_normals = np.cross(
        camber_m[1:, 1:] - camber_m[:-1, :-1], camber_m[:-1, 1:] - camber_m[1:, :-1]
    )
    tangents = _camber_tangents(0.5 * (camber_m[:-1] + camber_m[1:]))
    normals = np.cross(tangents, three_quarter[1:] - three_quarter[:-1])
    # the same side as before
    normals *= np.sign(np.einsum("jik,jik->ji", normals, diagonal_normals))[..., None]
    return points, normals / np.linalg.norm(normals, axis=2, keepdims=True)


def _camber_tangents(line: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(K - 1, C, 3)``: the tangent of each strip's mean camber line ``(K - 1, C + 1, 3)`` at
    three quarters of each panel, from the parabola through three neighbouring nodes (parameter: the
    distance along the line)."""
    chordwise = line.shape[1] - 1
    if chordwise < 2:
        return np.diff(line, axis=1)
    steps = np.linalg.norm(np.diff(line, axis=1), axis=2)
    t = np.concatenate([np.zeros((len(line), 1)), np.cumsum(steps, axis=1)], axis=1)
    # the parabola's first node, each panel
    first = np.clip(np.arange(chordwise) - 1, 0, chordwise - 2)
    nodes = first[:, None] + np.arange(3)[None, :]  # (C, 3)
    where = t[:, :-1] + 0.75 * steps  # (K - 1, C)
    tn = t[:, nodes]  # (K - 1, C, 3)
    weights = np.empty_like(tn)
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        weights[..., a] = ((where - tn[..., b]) + (where - tn[..., c])) / (
            (tn[..., a] - tn[..., b]) * (tn[..., a] - tn[..., c])
        )
    return np.einsum("jca,jcak->jck", weights, line[:, nodes])


def wake_lines(
    trailing_edge_m: NDArray[np.float64],
    omega_rad_s: float,
    spin: float,
    inflow_m_s: float,
    induced_m_s: float,
    radius_m: float,
    shape: WakeShape,
) -> NDArray[np.float64]:
    """``(N, M + 1, 3)``: the helical lines shed from the trailing-edge nodes ``(N, 3)`` (module
    doc), in the blade's frame; ``spin`` +1 where the air seems to turn the +theta way past the
    blade (cw)."""
    length = shape.length_diameters * 2.0 * radius_m
    # negative in still air behind a rotor that pushes the air up: its wake leaves toward +z
    base = inflow_m_s + induced_m_s
    speed = max(abs(base), 1e-9 * max(omega_rad_s * radius_m, 1.0))
    if omega_rad_s == 0.0:
        times = np.linspace(0.0, length / speed, shape.steps_per_turn * 4 + 1)
    else:
        turns = min(shape.max_turns, length * omega_rad_s / (2.0 * np.pi * speed))
        times = _wake_angles(turns, shape) / omega_rad_s
    travelled, contraction = np.copysign(speed, base) * times, np.ones_like(times)
    if shape.slipstream and base > 0.0:
        travelled = _travelled(times, inflow_m_s, induced_m_s, radius_m)
        far = inflow_m_s + induced_m_s * (1.0 + travelled / np.hypot(travelled, radius_m))
        contraction = np.sqrt(max(base, 1e-12) / np.maximum(far, 1e-12))
    angle = spin * omega_rad_s * times
    x, y, z = trailing_edge_m[:, 0:1], trailing_edge_m[:, 1:2], trailing_edge_m[:, 2:3]
    cos, sin = np.cos(angle)[None, :], np.sin(angle)[None, :]
    scale = contraction[None, :]
    return np.stack(
        [(x * cos - y * sin) * scale, (x * sin + y * cos) * scale, z - travelled[None, :]], axis=2
    )


def _wake_angles(turns: float, shape: WakeShape) -> NDArray[np.float64]:
    """Angles (rad) of a line's nodes over ``turns`` turns: from a step
    ``shape.first_step_fraction`` of the first turn's even step (the even step itself if the turn
    is relaxed), each ``shape.near_growth`` times the last up to the even step, then, past the
    first turn, each ``shape.growth`` times the last up to ``shape.longest_step_deg``."""
    even = 2.0 * np.pi / shape.steps_per_turn
    angles, step = [0.0], even * (1.0 if shape.free_turns else shape.first_step_fraction)
    end = turns * 2.0 * np.pi
    while angles[-1] < end:
        angles.append(min(angles[-1] + step, end))
        if step < even:
            step = min(step * shape.near_growth, even)
        elif angles[-1] >= 2.0 * np.pi - 1e-12:
            step = min(step * shape.growth, np.radians(shape.longest_step_deg))
    return np.array(angles)


def _travelled(
    times: NDArray[np.float64], inflow: float, induced: float, radius: float
) -> NDArray[np.float64]:
    """Distance downstream at ``times`` of a point leaving the disk (explicit midpoint steps)."""
    travelled = np.zeros_like(times)
    for step in range(1, len(times)):
        dt = times[step] - times[step - 1]

        def speed(distance: float) -> float:
            return inflow + induced * (1.0 + distance / np.hypot(distance, radius))

        half = travelled[step - 1] + 0.5 * dt * speed(travelled[step - 1])
        travelled[step] = travelled[step - 1] + dt * speed(half)
    return travelled


def strip_edges(
    camber_m: NDArray[np.float64], downstream_first: NDArray[np.bool_]
) -> NDArray[np.float64]:
    """``(K - 1, 2, C + 1, 3)``: each strip's two section lines ordered from the edge the flow meets
    first to the edge it leaves (the trailing edge, or the leading edge where ``downstream_first``
    says the flow runs from the trailing edge to the leading edge there: a loop's return leg)."""
    pairs = np.stack([camber_m[:-1], camber_m[1:]], axis=1)
    return np.where(downstream_first[:, None, None, None], pairs[:, :, ::-1], pairs)


def rotor_lattice(
    strips_m: NDArray[np.float64],
    blades: int,
    wake: NDArray[np.float64],
    core_m: float,
    core_growth_m: float,
) -> Lattice:
    """The lattice of ``blades`` blades whose blade 0 has the strips ``strips_m`` ``(K - 1, 2, C +
    1, 3)`` (:func:`strip_edges`) and whose strips shed the lines ``wake`` ``(K - 1, 2, M + 1, 3)``
    from the last nodes of their two lines (blade 0's; the others are blade 0's turned by 360 /
    blades degrees about +z), the wake's lines with a vortex core growing from nothing at the blade
    to ``core_m`` at ``core_growth_m`` along the line (the near wake stays a sheet at the trailing
    edge)."""
    strips, chordwise = strips_m.shape[0], strips_m.shape[2] - 1
    grid = np.stack([ring_grid(pair) for pair in strips_m])  # (K - 1, 2, C + 1, 3)
    controls = [control_points(pair) for pair in strips_m]
    points = np.concatenate([point for point, _ in controls]).reshape(-1, 3)
    normals = np.concatenate([normal for _, normal in controls]).reshape(-1, 3)
    starts: list[NDArray[np.float64]] = []
    ends: list[NDArray[np.float64]] = []
    rows: list[int] = []
    columns: list[int] = []
    signs: list[float] = []

    def add(start: NDArray[np.float64], end: NDArray[np.float64], ring: int, sign: float) -> None:
        rows.append(len(starts))
        columns.append(ring)
        signs.append(sign)
        starts.append(start)
        ends.append(end)

    for j in range(strips):
        for i in range(chordwise):
            for side, ((dk0, di0), (dk1, di1)) in enumerate(_SIDES):
                if side == 2 and i == chordwise - 1:
                    continue  # the trailing-edge segment: cancelled by the wake's first one
                add(grid[j, dk0, i + di0], grid[j, dk1, i + di1], j * chordwise + i, 1.0)
    bound = len(starts)
    cores: list[float] = [0.0] * bound
    shed: dict[tuple[float, ...], int] = {}  # a line's first node -> its first segment's row
    # the horseshoe's two legs: out of the second line's node, into the first's
    for j in range(strips):
        last = j * chordwise + chordwise - 1
        for line, sign in ((wake[j, 1], 1.0), (wake[j, 0], -1.0)):
            key = tuple(line[0].tolist())
            # a neighbour's leg from the same node: the same line, both circulations on it
            if key in shed:
                first = shed[key]
                for step in range(len(line) - 1):
                    rows.append(first + step)
                    columns.append(last)
                    signs.append(sign)
                continue
            shed[key] = len(starts)
            steps = np.linalg.norm(np.diff(line, axis=0), axis=1)
            along = np.cumsum(steps) - 0.5 * steps  # each segment's middle, from the blade
            cores.extend(core_m * np.minimum(1.0, along / core_growth_m))
            for start, end in itertools.pairwise(line):
                add(start, end, last, sign)
    one_start, one_end = np.array(starts), np.array(ends)
    count = len(starts)
    all_starts = np.concatenate(
        [_turned(one_start, 2.0 * np.pi * b / blades) for b in range(blades)]
    )
    all_ends = np.concatenate([_turned(one_end, 2.0 * np.pi * b / blades) for b in range(blades)])
    incidence = csr_matrix(
        (
            np.tile(signs, blades),
            (
                np.concatenate([np.array(rows) + b * count for b in range(blades)]),
                np.tile(columns, blades),
            ),
        ),
        shape=(count * blades, strips * chordwise),
    )
    return Lattice(
        grid,
        points[None],
        normals[None],
        all_starts,
        all_ends,
        incidence,
        bound,
        np.tile(np.array(cores), blades),
        np.tile(np.arange(count) < bound, blades),
    )


def _turned(points: NDArray[np.float64], angle_rad: float) -> NDArray[np.float64]:
    cos, sin = np.cos(angle_rad), np.sin(angle_rad)
    return np.stack(
        [
            cos * points[:, 0] - sin * points[:, 1],
            sin * points[:, 0] + cos * points[:, 1],
            points[:, 2],
        ],
        axis=1,
    )
