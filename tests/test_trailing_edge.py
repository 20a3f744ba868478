"""Blunt trailing edge (issue 13 part 3): absolute thickness on every section, closed sections, sampling."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from torus_cad.geometry.airfoil import NacaAirfoil
from torus_cad.geometry.airfoil_file import read_airfoil_file
from torus_cad.geometry.arc_length import equal_arc_length_section
from torus_cad.geometry.section import closed_points, has_base
from torus_cad.geometry.trailing_edge import blunt_sections, trailing_edge_thickness_mm
from torus_cad.geometry.transforms import transform_sections

AIRFOILS = Path(__file__).resolve().parent.parent / "examples" / "airfoils"


@settings(max_examples=40, deadline=None)
@given(thickness_mm=st.floats(0.05, 2.0), angle=st.floats(-180.0, 180.0), scale_x=st.floats(2.0, 60.0),
       scale_y=st.floats(0.5, 60.0), camber_normal=st.booleans())
def test_every_transformed_section_gets_the_absolute_thickness(thickness_mm, angle, scale_x, scale_y, camber_normal):
    airfoil = NacaAirfoil(0.04, 0.4, 0.12, camber_normal)
    sections = blunt_sections(airfoil, thickness_mm, [angle, 0.0], [scale_x, 10.0], [scale_y, 3.0])
    measured = trailing_edge_thickness_mm(sections, [angle, 0.0], [scale_x, 10.0], [scale_y, 3.0])
    np.testing.assert_allclose(measured, thickness_mm, rtol=1e-10)
    # The same, measured on the transformed corner points themselves (spec §2.3 applied to the section).
    corners = closed_points(sections[0], [1.0, 2.0])
    placed = transform_sections(corners, [angle], [scale_x], [scale_y])[0]
    assert np.linalg.norm(placed[0] - placed[1]) == pytest.approx(thickness_mm, rel=1e-10)


def test_a_file_airfoil_gets_the_absolute_thickness_too():
    clark = read_airfoil_file(AIRFOILS / "clarky.dat")
    s = np.linspace(0.0, 1.0, 7)
    angle, scale_x, scale_y = 20.0 + 30.0 * s, 8.0 + 4.0 * s, 2.0 + s
    sections = blunt_sections(clark, 0.6, angle, scale_x, scale_y)
    np.testing.assert_allclose(trailing_edge_thickness_mm(sections, angle, scale_x, scale_y), 0.6, rtol=1e-10)


def test_the_sampling_covers_the_base_and_keeps_both_corners():
    airfoil = NacaAirfoil(0.02, 0.4, 0.12).with_trailing_edge_gap(0.05)
    sampling = equal_arc_length_section(airfoil, 120)
    assert sampling.base and has_base(airfoil)
    upper_corner, lower_corner = closed_points(airfoil, [1.0, 2.0])
    np.testing.assert_allclose(sampling.points[sampling.trailing_edge_index], upper_corner, atol=1e-14)
    np.testing.assert_allclose(sampling.points[sampling.lower_corner_index], lower_corner, atol=1e-14)
    base = sampling.points[sampling.trailing_edge_index:sampling.lower_corner_index + 1]
    assert len(base) >= 3  # the base has points of its own, equally spaced on the straight edge
    steps = np.linalg.norm(np.diff(base, axis=0), axis=1)
    np.testing.assert_allclose(steps, steps.mean(), rtol=1e-12)
    # Spacing around the closed section: equal within 1 / count (the base's share is rounded).
    gaps = np.linalg.norm(np.diff(np.vstack([sampling.points, sampling.points[:1]]), axis=0), axis=1)
    assert np.abs(gaps / np.median(gaps) - 1).max() < 0.25


def test_a_blunt_section_stays_closed_and_simple():
    airfoil = NacaAirfoil(0.02, 0.4, 0.12).with_trailing_edge_gap(0.03)
    t = np.linspace(0.0, 3.0, 3001)
    points = closed_points(airfoil, t)
    assert np.linalg.norm(points[0] - points[-1]) < 1e-14  # closed at the leading edge
    assert np.max(np.linalg.norm(np.diff(points, axis=0), axis=1)) < 0.01  # no jump: the base joins the corners
    upper, lower = airfoil.surfaces(np.linspace(0.0, 1.0, 1001))
    assert np.all(upper[1:, 1] - lower[1:, 1] > 0.0)  # the surfaces never cross


def test_a_trailing_edge_thicker_than_the_sections_is_refused(tmp_path, capsys):
    from torus_cad.cli import main

    # The default's sections are 1.0-1.6 mm thick (Sy 2-3 mm x thickness 0.5).
    code = main(["build", "--set", "airfoil.trailing_edge_thickness=1.2", "--out", str(tmp_path / "out")])
    error = capsys.readouterr().err
    assert code == 2 and "airfoil.trailing_edge_thickness = 1.2 mm is too thick" in error
    assert not (tmp_path / "out").exists()
