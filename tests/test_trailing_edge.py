"""Blunt trailing edge: absolute thickness on every section, closed sections, sampling;
flat and round (a cap tangent to both surfaces; on the solid: tests/test_round_trailing_edge.py)."""

import itertools
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.geometry.analysis.printability import printability
from torus_cad.geometry.blade.blade_surface import sections_along
from torus_cad.geometry.blade.trailing_edge import (
    blunt_sections,
    section_matrices,
    trailing_edge_thickness_mm,
)
from torus_cad.geometry.blade.transforms import transform_sections
from torus_cad.geometry.section.airfoil import NacaAirfoil
from torus_cad.geometry.section.airfoil_file import read_airfoil_file
from torus_cad.geometry.section.arc_length import ROUND_CAP_MINIMUM_POINTS, equal_arc_length_section
from torus_cad.geometry.section.section import (
    ROUND_CAP_HANDLE_FRACTION,
    RoundTrailingEdge,
    cap_points,
    closed_points,
    end_tangents,
    half_ends,
    has_base,
)
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import TrailingEdgeShape

AIRFOILS = Path(__file__).resolve().parent.parent / "examples" / "airfoils"
EXAMPLES = AIRFOILS.parent


@settings(max_examples=40, deadline=None)
@given(
    thickness_mm=st.floats(0.05, 2.0),
    angle=st.floats(-180.0, 180.0),
    scale_x=st.floats(2.0, 60.0),
    scale_y=st.floats(0.5, 60.0),
    camber_normal=st.booleans(),
)
def test_every_transformed_section_gets_the_absolute_thickness(
    thickness_mm, angle, scale_x, scale_y, camber_normal
):
    airfoil = NacaAirfoil(0.04, 0.4, 0.12, camber_normal)
    sections = blunt_sections(airfoil, thickness_mm, [angle, 0.0], [scale_x, 10.0], [scale_y, 3.0])
    measured = trailing_edge_thickness_mm(sections, [angle, 0.0], [scale_x, 10.0], [scale_y, 3.0])
    np.testing.assert_allclose(measured, thickness_mm, rtol=1e-10)
    # The same, measured on the transformed corner points themselves (spec §2.3 applied to the
    # section).
    corners = closed_points(sections[0], [1.0, 2.0])
    placed = transform_sections(corners, [angle], [scale_x], [scale_y])[0]
    assert np.linalg.norm(placed[0] - placed[1]) == pytest.approx(thickness_mm, rel=1e-10)


def test_a_file_airfoil_gets_the_absolute_thickness_too():
    clark = read_airfoil_file(AIRFOILS / "clarky.dat")
    s = np.linspace(0.0, 1.0, 7)
    angle, scale_x, scale_y = 20.0 + 30.0 * s, 8.0 + 4.0 * s, 2.0 + s
    sections = blunt_sections(clark, 0.6, angle, scale_x, scale_y)
    np.testing.assert_allclose(
        trailing_edge_thickness_mm(sections, angle, scale_x, scale_y), 0.6, rtol=1e-10
    )


def test_the_sampling_covers_the_base_and_keeps_both_corners():
    airfoil = NacaAirfoil(0.02, 0.4, 0.12).with_trailing_edge_gap(0.05)
    sampling = equal_arc_length_section(airfoil, 120)
    assert sampling.base and has_base(airfoil)
    upper_corner, lower_corner = closed_points(airfoil, [1.0, 2.0])
    np.testing.assert_allclose(
        sampling.points[sampling.trailing_edge_index], upper_corner, atol=1e-14
    )
    np.testing.assert_allclose(
        sampling.points[sampling.lower_corner_index], lower_corner, atol=1e-14
    )
    base = sampling.points[sampling.trailing_edge_index : sampling.lower_corner_index + 1]
    assert len(base) >= 3  # the base has points of its own, equally spaced on the straight edge
    steps = np.linalg.norm(np.diff(base, axis=0), axis=1)
    np.testing.assert_allclose(steps, steps.mean(), rtol=1e-12)
    # Spacing around the closed section: equal within 1 / count (the base's share is rounded).
    gaps = np.linalg.norm(
        np.diff(np.vstack([sampling.points, sampling.points[:1]]), axis=0), axis=1
    )
    assert np.abs(gaps / np.median(gaps) - 1).max() < 0.25


def test_a_blunt_section_stays_closed_and_simple():
    airfoil = NacaAirfoil(0.02, 0.4, 0.12).with_trailing_edge_gap(0.03)
    t = np.linspace(0.0, 3.0, 3001)
    points = closed_points(airfoil, t)
    assert np.linalg.norm(points[0] - points[-1]) < 1e-14  # closed at the leading edge
    # no jump: the base joins the corners
    assert np.max(np.linalg.norm(np.diff(points, axis=0), axis=1)) < 0.01
    upper, lower = airfoil.surfaces(np.linspace(0.0, 1.0, 1001))
    assert np.all(upper[1:, 1] - lower[1:, 1] > 0.0)  # the surfaces never cross


def test_a_trailing_edge_thicker_than_the_sections_is_refused(tmp_path, capsys):
    from torus_cad.cli import main

    # The default's sections are 1.0-1.6 mm thick (Sy 2-3 mm x thickness 0.5).
    code = main(
        ["build", "--set", "airfoil.trailing_edge_thickness=1.2", "--out", str(tmp_path / "out")]
    )
    error = capsys.readouterr().err
    assert code == 2 and "airfoil.trailing_edge_thickness = 1.2 mm is too thick" in error
    assert not (tmp_path / "out").exists()


ANGLE, SCALE_X, SCALE_Y = [20.0, 35.0], [12.0, 6.0], [4.0, 2.0]


def _round_sections(thickness_mm=0.4):
    airfoil = propeller_geometry(PropellerParameters()).blade.airfoil
    return blunt_sections(airfoil, thickness_mm, ANGLE, SCALE_X, SCALE_Y, round_cap=True)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def test_round_cap_leaves_each_surface_along_its_tangent():
    for section in _round_sections():
        assert isinstance(section, RoundTrailingEdge)
        poles = section.cap_poles()
        tangents = end_tangents(section)
        leaving, arriving = poles[1] - poles[0], poles[3] - poles[2]
        # the cap starts in the upper surface's direction and arrives along the lower one's reversed
        assert abs(_cross(leaving / np.linalg.norm(leaving), tangents[0])) < 1e-12
        assert leaving @ tangents[0] > 0.0
        assert abs(_cross(arriving / np.linalg.norm(arriving), -tangents[1])) < 1e-12
        # closed_points runs through the cap between t = 1 and 2, from U to L
        np.testing.assert_allclose(
            closed_points(section, [1.0, 2.0]), half_ends(section), atol=1e-14
        )


def test_round_cap_keeps_the_thickness_and_is_a_near_half_circle_in_mm():
    sections = _round_sections(0.4)
    np.testing.assert_allclose(
        trailing_edge_thickness_mm(sections, ANGLE, SCALE_X, SCALE_Y), 0.4, rtol=1e-10
    )
    matrices = section_matrices(ANGLE, SCALE_X, SCALE_Y)
    for matrix, section in zip(matrices, sections):
        poles_mm = section.cap_poles() @ matrix.T
        handles_mm = np.linalg.norm(poles_mm[[1, 2]] - poles_mm[[0, 3]], axis=1)
        np.testing.assert_allclose(handles_mm, ROUND_CAP_HANDLE_FRACTION * 0.4, rtol=1e-9)
        cap_mm = cap_points(section, np.linspace(0.0, 1.0, 201)) @ matrix.T
        # it reaches aft of its ends by about a radius (a half circle: 0.2 mm; less where the
        # surfaces converge)
        across = (poles_mm[0] - poles_mm[3]) / 0.4
        aft = np.array([across[1], -across[0]])
        reach = np.max(np.abs((cap_mm - 0.5 * (poles_mm[0] + poles_mm[3])) @ aft))
        assert 0.1 < reach < 0.25


def test_equal_arc_length_sampling_covers_the_cap():
    section = _round_sections()[0]
    sampling = equal_arc_length_section(section, 200)
    te, lower = sampling.trailing_edge_index, sampling.lower_corner_index
    assert lower - te >= ROUND_CAP_MINIMUM_POINTS
    cap = sampling.points[te : lower + 1]
    np.testing.assert_allclose(cap[[0, -1]], half_ends(section), atol=1e-14)
    # the points lie on the cap and are equally spaced in its arc length
    np.testing.assert_allclose(closed_points(section, sampling.t[te : lower + 1]), cap, atol=1e-14)
    cap_t = sampling.t[te : lower + 1] - 1.0
    arcs = [
        np.linalg.norm(np.diff(cap_points(section, np.linspace(a, b, 2001)), axis=0), axis=1).sum()
        for a, b in itertools.pairwise(cap_t)
    ]
    assert max(arcs) / min(arcs) < 1.001


def test_sharp_default_is_the_same_whatever_the_shape():
    round_surface = sampled_blade_surface(PropellerParameters())
    flat_surface = sampled_blade_surface(
        PropellerParameters().with_values({"airfoil.trailing_edge_shape": "flat"})
    )
    assert np.array_equal(round_surface.points, flat_surface.points)
    assert round_surface.lower_corner_index is None and not round_surface.round_trailing_edge


def test_shape_choice_is_validated():
    params = PropellerParameters().with_values({"airfoil.trailing_edge_shape": "flat"})
    assert params.airfoil.trailing_edge_shape == TrailingEdgeShape.FLAT
    assert PropellerParameters().airfoil.trailing_edge_shape == TrailingEdgeShape.ROUND
    with pytest.raises(Exception, match="trailing_edge_shape"):
        PropellerParameters().with_values({"airfoil.trailing_edge_shape": "pointy"})


def test_coordinate_file_with_an_open_edge_gets_a_round_cap(tmp_path):
    published = (AIRFOILS / "clarky.dat").read_text()
    assert " 1.00000  0.00120\n" in published
    (tmp_path / "open.dat").write_text(
        published.replace(" 1.00000  0.00120\n", " 1.00000  0.02000\n")
    )
    params = PropellerParameters.from_toml(EXAMPLES / "prop_10x5_2blade.toml").with_values(
        # the file's own edge
        {"airfoil.trailing_edge_thickness": 0.0, "airfoil.file": str(tmp_path / "open.dat")}
    )
    # over 0.05 mm thick everywhere: kept
    assert propeller_geometry(params).blade.closed_file_edge_mm is None
    blade = propeller_geometry(params).blade
    sections = sections_along(blade, [0.2, 0.5])
    assert all(isinstance(section, RoundTrailingEdge) for section in sections)
    # the cap closes the file's own gap: the surfaces are the file's
    np.testing.assert_allclose(half_ends(sections[0]), half_ends(blade.airfoil), atol=1e-12)
    assert sampled_blade_surface(params).round_trailing_edge


def test_printability_reports_the_round_edge_thickness():
    geometry = propeller_geometry(
        PropellerParameters().with_values({"airfoil.trailing_edge_thickness": 0.9})
    )
    assert geometry.blade.round_trailing_edge
    result = printability(geometry, 0.8)
    assert result.trailing_edge_thickness_mm == pytest.approx(0.9, rel=1e-6)


def test_a_sharpened_file_section_meets_at_the_trailing_edge_and_keeps_its_surfaces():
    clark = read_airfoil_file(AIRFOILS / "clarky.dat")
    sharp = clark.sharpened()
    assert has_base(clark) and not has_base(sharp)
    u = np.linspace(0.0, 1.0, 201)
    for upper in (True, False):
        change = np.linalg.norm(
            sharp.points_on_half(u, upper) - clark.points_on_half(u, upper), axis=1
        )
        assert change.max() < 0.002  # at most half the published 0.0012 gap, plus the chord's tilt
        assert np.all(change[u < 0.5] < 1e-5)  # the u^8 law leaves the front half as published


def test_a_blunt_trailing_edge_thinner_than_meshable_is_refused(tmp_path, capsys):
    from torus_cad.cli import main

    code = main(
        ["build", "--set", "airfoil.trailing_edge_thickness=0.02", "--out", str(tmp_path / "out")]
    )
    error = capsys.readouterr().err
    assert code == 2 and "airfoil.trailing_edge_thickness = 0.02 mm is too thin" in error
    assert "allowed 0 (sharp) or 0.05 to 50 mm" in error and not (tmp_path / "out").exists()


def test_a_files_hair_thin_open_edge_is_closed_and_the_build_says_so(tmp_path, capsys):
    """Clark Y's published 0.0012-chord gap is a few micrometres on this blade: its faces' triangles
    would cross, so the build makes the edge sharp, warns, and its STL (read by meshlib) is
    clean."""
    import json

    from torus_cad.cli import main
    from torus_cad.kernel.mesh_check import intersecting_pairs_in_file

    (tmp_path / "clarky.dat").write_bytes((AIRFOILS / "clarky.dat").read_bytes())
    (tmp_path / "clark.toml").write_text('blades = 3\n[airfoil]\nfile = "clarky.dat"\n')
    assert main(["build", str(tmp_path / "clark.toml"), "--out", str(tmp_path / "out")]) == 0
    assert "warning: airfoil.file's open trailing edge is only" in capsys.readouterr().err
    report = json.loads((tmp_path / "out" / "torus_propeller.json").read_text())
    thinnest, thickest = report["closed_file_trailing_edge_mm"]
    assert 0.0 < thinnest <= thickest < 0.05
    assert report["printability"]["trailing_edge_thickness_mm"] == 0.0
    assert intersecting_pairs_in_file(tmp_path / "out" / "torus_propeller.stl")[0] == 0
