"""NACA 4-digit section (spec §1) against its analytic properties."""

import numpy as np
import pytest

from torus_cad.geometry.airfoil import NacaAirfoil, airfoil_points

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
    smooth = np.abs(CHORD - 0.35) > 1e-3  # the slope is continuous at p but the curvature jumps there
    np.testing.assert_allclose(airfoil.camber_slope(CHORD)[smooth][1:-1], numeric[smooth][1:-1], atol=1e-6)


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
    flat = [NacaAirfoil(max_camber=0.0, camber_normal=flag).surfaces(CHORD)[0] for flag in (True, False)]
    np.testing.assert_allclose(flat[0], flat[1], atol=1e-15)
    # With the normal offset, the distance from the camber line is y_t everywhere.
    airfoil = NacaAirfoil(max_camber=0.06, camber_normal=True)
    camber_points = np.stack([CHORD, airfoil.camber(CHORD)], axis=-1)
    np.testing.assert_allclose(np.linalg.norm(with_normal - camber_points, axis=1), airfoil.half_thickness(CHORD),
                               atol=1e-12)
