"""The lifting-surface vortex lattice (torus_cad.vortex) against closed forms and symmetries: a
planar elliptic wing's lift slope, a rotor's thrust scaling with the square of its speed, the mirror
image, and no force without motion. Inviscid: the section polars are not in these."""

from __future__ import annotations

import math

import numpy as np
import pytest

from torus_cad.geometry.analysis.camber_surface import cosine_fractions
from torus_cad.parameters import PropellerParameters
from torus_cad.vortex.lattice import WakeShape
from torus_cad.vortex.rotor import Discretisation, rotor_blade
from torus_cad.vortex.solver import solve_inviscid

APC = "examples/apc_10x7sf.toml"
SMALL = Discretisation(chordwise=6, spanwise=20)


def _elliptic_wing(
    aspect_ratio: float, alpha_rad: float, spanwise: int = 40, chordwise: int = 6
) -> np.ndarray:
    """A flat elliptic wing of span 1 m in the flow along -z: its span along x, its chord along -z
    turned by ``alpha_rad`` about x (leading edge at the top). ``(K, C + 1, 3)``."""
    theta = np.linspace(0.0, math.pi, spanwise + 1)
    x = -0.5 * np.cos(theta)  # cosine spacing: finer at the tips
    root_chord = 4.0 / (math.pi * aspect_ratio)  # area pi b c0 / 4 = b^2 / AR
    chord = root_chord * np.sqrt(np.clip(1.0 - (2.0 * x) ** 2, 0.0, None)) + 1e-6
    fractions = cosine_fractions(chordwise)
    along = (fractions[None, :] - 0.25) * chord[:, None]  # quarter chord straight
    grid = np.zeros((spanwise + 1, chordwise + 1, 3))
    grid[..., 0] = x[:, None]
    grid[..., 1] = along * math.sin(alpha_rad)
    grid[..., 2] = -along * math.cos(alpha_rad)
    return grid


def _lifting_line(aspect_ratio: float) -> float:
    return 2.0 * math.pi * aspect_ratio / (aspect_ratio + 2.0)


def _helmbold(aspect_ratio: float) -> float:
    """Helmbold's lift slope of a low-aspect-ratio wing (the lifting line's with the chord's own
    effect)."""
    return 2.0 * math.pi * aspect_ratio / (2.0 + math.sqrt(aspect_ratio**2 + 4.0))


@pytest.mark.parametrize(
    ("aspect_ratio", "closed_form"), [(8.0, _lifting_line), (12.0, _lifting_line), (4.0, _helmbold)]
)
def test_a_planar_elliptic_wing_has_the_lifting_line_lift_slope(
    aspect_ratio: float, closed_form
) -> None:
    alpha = math.radians(2.0)
    result = solve_inviscid(
        _elliptic_wing(aspect_ratio, alpha),
        1,
        1.0,
        0.0,
        10.0,
        1.225,
        0.5,
        WakeShape(length_diameters=20.0),
        momentum_wake=False,
    )
    lift = -float(result.force_n[..., 1].sum())  # the flow runs along -z, the wing lifts toward -y
    slope = lift / (0.5 * 1.225 * 10.0**2 * (1.0 / aspect_ratio)) / alpha
    assert slope == pytest.approx(closed_form(aspect_ratio), rel=0.03)


def _naca_mean_line(
    fractions: np.ndarray, camber: float = 0.04, position: float = 0.4
) -> np.ndarray:
    """The NACA four-digit mean line's height (a fraction of the chord) at the chord
    ``fractions``."""
    front = camber / position**2 * (2.0 * position * fractions - fractions**2)
    back = (
        camber
        / (1.0 - position) ** 2
        * ((1.0 - 2.0 * position) + 2.0 * position * fractions - fractions**2)
    )
    return np.where(fractions < position, front, back)


@pytest.mark.parametrize("chordwise", [6, 8, 12])
def test_a_cambered_elliptic_wing_lifts_at_zero_incidence_as_thin_airfoil_theory_says(
    chordwise: int,
) -> None:
    """A NACA 4412 mean line on an elliptic wing of aspect ratio 8 at zero incidence: the lifting
    line's slope times the mean line's zero-lift angle of thin-airfoil theory (-4.15 deg), within 3
    %."""
    aspect_ratio, spanwise = 8.0, 40
    grid = _elliptic_wing(aspect_ratio, 0.0, spanwise, chordwise)
    theta = np.linspace(0.0, math.pi, spanwise + 1)
    chord = (
        4.0 / (math.pi * aspect_ratio) * np.sqrt(np.clip(1.0 - np.cos(theta) ** 2, 0.0, None))
        + 1e-6
    )
    # toward the lift
    grid[..., 1] -= _naca_mean_line(cosine_fractions(chordwise))[None, :] * chord[:, None]
    result = solve_inviscid(
        grid, 1, 1.0, 0.0, 10.0, 1.225, 0.5, WakeShape(length_diameters=20.0), momentum_wake=False
    )
    lift_coefficient = -float(result.force_n[..., 1].sum()) / (0.5 * 1.225 * 10.0**2 / aspect_ratio)
    assert lift_coefficient == pytest.approx(
        _lifting_line(aspect_ratio) * math.radians(4.15), rel=0.03
    )


def _ideally_twisted_rotor(tip_pitch_deg: float, radius_m: float = 0.15) -> np.ndarray:
    """Blade 0 of a hovering rotor twisted for uniform inflow (blade-element momentum theory: a
    constant-chord blade's pitch theta(r) = theta_tip R / r): flat, 20 mm chord, from 0.2 R to the
    tip along +x, the air meeting it from -y, ``(K, C + 1, 3)``."""
    radius = radius_m * (0.2 + 0.8 * np.sin(np.linspace(0.0, math.pi / 2.0, 31)))  # tip clustered
    pitch = math.radians(tip_pitch_deg) * radius_m / radius
    fractions = cosine_fractions(8)
    grid = np.zeros((len(radius), len(fractions), 3))
    grid[..., 0] = radius[:, None]
    grid[..., 1] = (fractions[None, :] - 0.5) * 0.02 * np.cos(pitch)[:, None]
    grid[..., 2] = (0.5 - fractions[None, :]) * 0.02 * np.sin(pitch)[:, None]
    return grid


@pytest.mark.parametrize(("blades", "tip_pitch_deg"), [(2, 4.0), (2, 8.0), (3, 8.0)])
def test_a_rotor_twisted_for_uniform_inflow_needs_at_least_the_ideal_induced_power_and_near_it(
    blades: int, tip_pitch_deg: float
) -> None:
    omega, radius = 5000.0 * math.pi / 30.0, 0.15
    result = solve_inviscid(
        _ideally_twisted_rotor(tip_pitch_deg, radius),
        blades,
        1.0,
        omega,
        0.0,
        1.225,
        radius,
        WakeShape(),
    )
    # momentum theory's ideal: T^1.5 / sqrt(2 rho A); a real wake needs more (tip loss, the
    # loading's own spread), a figure of merit above 1 would be a wake that induces too little
    ideal_w = result.thrust_n**1.5 / math.sqrt(2.0 * 1.225 * math.pi * radius**2)
    assert result.thrust_n > 0.0
    assert 1.0 <= result.torque_nm * omega / ideal_w <= 1.15


@pytest.fixture(scope="module")
def apc_blade():
    return rotor_blade(PropellerParameters.from_toml(APC), SMALL)


def _solve(blade, rpm: float, airspeed: float = 0.0):
    return solve_inviscid(
        blade.camber_m,
        blade.blades,
        blade.spin,
        rpm * math.pi / 30.0,
        airspeed,
        1.225,
        blade.tip_radius_m,
        WakeShape(),
    )


def test_zero_rpm_in_still_air_gives_exactly_no_force(apc_blade) -> None:
    result = _solve(apc_blade, 0.0)
    assert result.thrust_n == 0.0 and result.torque_nm == 0.0 and not result.circulation.any()


def test_inviscid_thrust_and_torque_scale_with_the_square_of_the_speed_at_fixed_advance_ratio(
    apc_blade,
) -> None:
    slow, fast = _solve(apc_blade, 4000.0, 4.0), _solve(apc_blade, 8000.0, 8.0)
    assert fast.thrust_n == pytest.approx(4.0 * slow.thrust_n, rel=0.01)
    assert fast.torque_nm == pytest.approx(4.0 * slow.torque_nm, rel=0.01)


def test_the_mirror_image_turning_the_other_way_gives_the_same_thrust_and_torque(apc_blade) -> None:
    params = PropellerParameters.from_toml(APC).with_values({"handedness": "ccw"})
    mirror = rotor_blade(params, SMALL)
    assert mirror.spin == -1.0 and np.allclose(mirror.camber_m[..., 1], -apc_blade.camber_m[..., 1])
    cw, ccw = _solve(apc_blade, 5000.0), _solve(mirror, 5000.0)
    assert ccw.thrust_n == pytest.approx(cw.thrust_n, rel=0.005) and cw.thrust_n > 0.0
    assert ccw.torque_nm == pytest.approx(cw.torque_nm, rel=0.005) and cw.torque_nm > 0.0


def test_the_section_polars_take_thrust_and_add_power_at_every_strips_own_reynolds_number() -> None:
    pytest.importorskip("neuralfoil", reason="the simulate extra is not installed")
    from torus_cad.vortex.vortex_performance import vortex_performance

    result = vortex_performance(PropellerParameters.from_toml(APC), 5000.0, 0.0, SMALL)
    report = result.report
    assert 0.0 < report["thrust_n"] < report["inviscid_thrust_n"]
    assert report["power_w"] > report["inviscid_power_w"] > 0.0
    assert report["figure_of_merit"] is not None and 0.0 < report["figure_of_merit"] < 1.0
    strips = result.strips
    assert (strips.cd > 0.0).all() and (np.diff(strips.radius_m) > 0.0).all()  # root to tip
    # the Reynolds number of a strip is its own: V c / nu with the strip's flow (tens of thousands
    # here)
    assert 5e3 < np.median(strips.reynolds) < 2e5


def test_the_loops_apex_across_the_flow_carries_no_circulation_at_any_chordwise_count() -> None:
    # the default toroidal design: at the loop's apex the sections meet the flow broadside, where
    # a lifting surface's boundary condition is near-singular (one strip moved the thrust by 17 %
    # from 8 to 16 rings across the chord before such strips were held at zero circulation)
    params = PropellerParameters()
    solves = []
    for chordwise in (8, 16):
        blade = rotor_blade(params, Discretisation(chordwise=chordwise, spanwise=16))
        solves.append(_solve(blade, 10000.0))
    share = solves[0].lifting_share
    assert share.min() == 0.0 and share[0] == 1.0 and share[-1] == 1.0
    assert not solves[0].circulation[share == 0.0].any()
    assert solves[1].thrust_n == pytest.approx(solves[0].thrust_n, rel=0.02)


@pytest.mark.parametrize(
    ("design", "rpm"),
    [("examples/cooling_fan_7blade.toml", 6366.0), ("examples/marine_3blade_loop.toml", 4780.0)],
)
def test_a_loop_whose_return_leg_sits_in_its_front_legs_wake_is_solved(
    design: str, rpm: float
) -> None:
    from torus_cad.vortex.solver import momentum_inflow_m_s

    # the shipped fan and marine loops: the ratio of the full thrust to the kinematic one changes
    # sign from one wake to the next there, and an iteration on that ratio never settled; the wake's
    # inflow is momentum theory's for the full thrust it gives
    blade = rotor_blade(PropellerParameters.from_toml(design), Discretisation(4, 16))
    solve = _solve(blade, rpm)
    area = math.pi * blade.tip_radius_m**2
    assert solve.thrust_n > 0.0
    assert solve.induced_m_s == pytest.approx(
        momentum_inflow_m_s(solve.thrust_n, 0.0, 1.225, area), rel=1e-3
    )


def test_a_blade_pitched_the_other_way_pushes_the_air_up_with_the_same_thrust_and_power() -> None:
    from torus_cad.vortex.vortex_performance import vortex_performance

    # a symmetric section at every beta negated: the mirror image of the flow, whose wake leaves
    # upward (before, momentum theory gave it no inflow and the iteration never settled)
    base = PropellerParameters.from_toml(
        "examples/compare/conventional_127mm_3blade.toml"
    ).with_values({"airfoil.naca": "0012"})
    solves = []
    for sign in (1.0, -1.0):
        params = base.with_values({"conventional.beta": [sign * b for b in base.conventional.beta]})
        solves.append(vortex_performance(params, 6000.0, 0.0, SMALL, viscous=False))
    up, down = solves[1], solves[0]
    assert down.report["thrust_n"] > 0.0 > up.report["thrust_n"]
    assert up.inviscid.induced_m_s < 0.0
    assert -up.report["thrust_n"] == pytest.approx(down.report["thrust_n"], rel=1e-3)
    assert up.report["power_w"] == pytest.approx(down.report["power_w"], rel=1e-3)


def test_the_loading_noise_sees_every_force_the_thrust_counts_the_apex_plate_s_too() -> None:
    pytest.importorskip("neuralfoil", reason="the simulate extra is not installed")
    from torus_cad.vortex.vortex_performance import vortex_performance

    # the default toroidal design: its apex strips stand across the flow as plates, whose drag
    # counts in the thrust; the rings' forces, which the FW-H loading noise takes, hold it too
    result = vortex_performance(PropellerParameters(), 10000.0, 0.0, SMALL)
    assert (result.inviscid.lifting_share < 1.0).any()
    rings_thrust = result.blade.blades * result.ring_force_n[..., 2].sum()
    assert rings_thrust == pytest.approx(result.report["thrust_n"], rel=1e-9)
    assert rings_thrust != pytest.approx(result.report["inviscid_thrust_n"], rel=0.01)


def test_the_apc_10x7sf_static_point_at_5000_rpm_is_within_ten_percent_of_the_wind_tunnel() -> None:
    pytest.importorskip("neuralfoil", reason="the simulate extra is not installed")
    from studies.wind_tunnel import read_wind_tunnel
    from torus_cad.vortex.vortex_performance import vortex_performance

    # APC's own station table, the blade the OpenFOAM validation runs on (docs: simulation accuracy)
    params = PropellerParameters.from_toml("examples/apc_10x7sf_pe0.toml")
    measured = read_wind_tunnel().static_point(5000.0)
    report = vortex_performance(params, 5000.0).report
    assert report["ct"] == pytest.approx(measured.ct, rel=0.10)
    assert report["cp"] == pytest.approx(measured.cp, rel=0.10)


def test_the_vortex_blade_is_the_built_blade_when_the_design_asks_for_a_diameter_and_pitch() -> (
    None
):
    # examples/optimize/quiet_prop.toml asks for a 127 mm, 114 mm-pitch propeller: the build scales
    # and re-twists the loop to meet both, and the vortex solver must solve that blade, not the
    # unscaled one
    params = PropellerParameters.from_toml("examples/optimize/quiet_prop.toml")
    blade = rotor_blade(params, SMALL)
    assert 2000.0 * blade.tip_radius_m == pytest.approx(127.0, rel=0.01)
