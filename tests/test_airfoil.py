"""NACA 4-digit section (spec §1) against its analytic properties."""

import numpy as np
import pytest

from torus_cad.errors import ParameterError
from torus_cad.geometry.section.airfoil import NacaAirfoil, airfoil_points, naca_section

CHORD = np.linspace(0.0, 1.0, 20001)


def test_symmetric_section_is_symmetric():
    upper, lower = NacaAirfoil(max_camber=0.0, camber_position=0.0, thickness=0.12).surfaces(CHORD)
    np.testing.assert_allclose(upper[:, 0], lower[:, 0], atol=1e-15)
    np.testing.assert_allclose(upper[:, 1], -lower[:, 1], atol=1e-15)


@pytest.mark.parametrize("thickness", [0.06, 0.12, 0.5])
def test_maximum_thickness_is_the_parameter_near_30_percent_chord(thickness):
    airfoil = NacaAirfoil(max_camber=0.0, camber_position=0.0, thickness=thickness)
    full_thickness = 2 * airfoil.half_thickness(CHORD)
    at = CHORD[np.argmax(full_thickness)]
    assert full_thickness.max() == pytest.approx(thickness, rel=2e-4)
    assert 0.28 < at < 0.32


@pytest.mark.parametrize("m, p", [(0.02, 0.4), (0.06, 0.25), (0.04, 0.7)])
def test_camber_peaks_at_m_at_p(m, p):
    camber = NacaAirfoil(max_camber=m, camber_position=p).camber(CHORD)
    assert camber.max() == pytest.approx(m, abs=1e-12)
    assert CHORD[np.argmax(camber)] == pytest.approx(p, abs=1e-4)
    assert camber[0] == 0.0 and camber[-1] == pytest.approx(0.0, abs=1e-15)


def test_camber_slope_is_the_derivative_of_the_camber():
    airfoil = NacaAirfoil(max_camber=0.05, camber_position=0.35)
    numeric = np.gradient(airfoil.camber(CHORD), CHORD)
    # the slope is continuous at p but the curvature jumps there
    smooth = np.abs(CHORD - 0.35) > 1e-3
    np.testing.assert_allclose(
        airfoil.camber_slope(CHORD)[smooth][1:-1], numeric[smooth][1:-1], atol=1e-6
    )


@pytest.mark.parametrize("camber_normal", [True, False])
def test_closed_parametrisation_runs_upper_then_lower(camber_normal):
    airfoil = NacaAirfoil(camber_normal=camber_normal)
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    points = airfoil_points(airfoil, t)
    np.testing.assert_allclose(points[0], points[-1], atol=1e-15)  # closed at the leading edge
    assert points[2, 0] == pytest.approx(1.0) and points[2, 1] == pytest.approx(0.0, abs=1e-12)
    assert points[1, 1] > points[3, 1]  # upper surface first


def test_thickness_normal_to_camber_differs_only_when_cambered():
    with_normal = NacaAirfoil(max_camber=0.06, camber_normal=True).surfaces(CHORD)[0]
    along_y = NacaAirfoil(max_camber=0.06, camber_normal=False).surfaces(CHORD)[0]
    assert np.abs(with_normal - along_y).max() > 1e-3
    flat = [
        NacaAirfoil(max_camber=0.0, camber_normal=flag).surfaces(CHORD)[0] for flag in (True, False)
    ]
    np.testing.assert_allclose(flat[0], flat[1], atol=1e-15)
    # With the normal offset, the distance from the camber line is y_t everywhere.
    airfoil = NacaAirfoil(max_camber=0.06, camber_normal=True)
    camber_points = np.stack([CHORD, airfoil.camber(CHORD)], axis=-1)
    np.testing.assert_allclose(
        np.linalg.norm(with_normal - camber_points, axis=1),
        airfoil.half_thickness(CHORD),
        atol=1e-12,
    )


# -- designations -------------------------------------------------------------


@pytest.mark.parametrize(
    "designation, m, p, thickness",
    [
        ("2412", 0.02, 0.4, 0.12),
        ("0012", 0.0, 0.0, 0.12),
        ("4415", 0.04, 0.4, 0.15),
        ("6409", 0.06, 0.4, 0.09),
    ],
)
def test_naca_designation_gives_the_section_of_its_numbers(designation, m, p, thickness):
    from_name = NacaAirfoil.from_designation(designation)
    from_numbers = NacaAirfoil(max_camber=m, camber_position=p, thickness=thickness)
    u = np.linspace(0.0, 1.0, 501)
    for upper in (True, False):
        np.testing.assert_array_equal(
            from_name.points_on_half(u, upper), from_numbers.points_on_half(u, upper)
        )


def test_naca_5_digit_230_series_camber_peaks_at_15_percent():
    # NACA 23012: design lift coefficient 0.3, maximum camber 1.84 % at 15 % chord (Abbott & von
    # Doenhoff).
    airfoil = naca_section("23012")
    camber = airfoil.camber(CHORD)
    assert camber.max() == pytest.approx(0.0184, abs=1e-4)
    assert CHORD[np.argmax(camber)] == pytest.approx(0.15, abs=2e-3)
    assert camber[0] == 0.0 and camber[-1] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(
        airfoil.camber_slope(CHORD)[1:-1], np.gradient(camber, CHORD)[1:-1], atol=1e-4
    )
    assert 2 * airfoil.half_thickness(CHORD).max() == pytest.approx(0.12, rel=2e-4)


def test_reflexed_5_digit_mean_line_returns_to_zero_with_reflex():
    camber = naca_section("23112").camber(CHORD)
    assert camber[-1] == pytest.approx(0.0, abs=1e-12)
    assert CHORD[np.argmax(camber)] == pytest.approx(0.15, abs=5e-3)


@pytest.mark.parametrize(
    "bad", ["241", "24123x", "abcd", "2400", "2012", "24000", "23712", "03012", ""]
)
def test_malformed_designations_are_parameter_errors(bad):
    with pytest.raises(ParameterError, match=r"airfoil\.naca"):
        naca_section(bad)


def test_blunt_trailing_edge_changes_only_the_t4_coefficient():
    sharp = NacaAirfoil(0.02, 0.4, 0.12)
    blunt = sharp.with_trailing_edge_gap(0.01)
    # -0.1036 -> -0.1036 + g / (10 thickness): the classical open-edge coefficient for g = 0.0021 x
    # 10 thickness.
    open_edge = (
        5
        * 0.12
        * (
            0.2969 * np.sqrt(CHORD)
            - 0.1260 * CHORD
            - 0.3516 * CHORD**2
            + 0.2843 * CHORD**3
            - (0.1036 - 0.01 / (10 * 0.12)) * CHORD**4
        )
    )
    np.testing.assert_allclose(blunt.half_thickness(CHORD), open_edge, atol=1e-15)
    upper, lower = blunt.surfaces(np.array([1.0]))
    assert np.linalg.norm(upper - lower) == pytest.approx(0.01, rel=1e-12)
    assert blunt.points_on_half([0.0], True) == pytest.approx(sharp.points_on_half([0.0], True))
