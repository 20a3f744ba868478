"""Airfoils from coordinate files: layouts, normalisation, accuracy, malformed files."""

from itertools import pairwise
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

from torus_cad.errors import ParameterError
from torus_cad.geometry.section.airfoil import NacaAirfoil
from torus_cad.geometry.section.airfoil_file import (
    INTERPOLATION_ERROR_LIMIT,
    parse_airfoil_text,
    read_airfoil_file,
    write_lednicer_file,
    write_selig_file,
)
from torus_cad.geometry.section.arc_length import equal_arc_length_section
from torus_cad.geometry.section.section import (
    Section,
    closed_points,
    has_base,
    trailing_edge_vector,
)

AIRFOILS = Path(__file__).resolve().parent.parent / "examples" / "airfoils"
U = np.linspace(0.0, 1.0, 2001)


def naca_points(airfoil: NacaAirfoil, stations: int = 81) -> tuple[np.ndarray, np.ndarray]:
    chord = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, stations)))
    return airfoil.surfaces(chord)


def selig_loop(upper: np.ndarray, lower: np.ndarray) -> np.ndarray:
    return np.concatenate([upper[::-1], lower[1:]])


def distance_to_curve(points: np.ndarray, curve: np.ndarray) -> np.ndarray:
    """Distance of each point to a dense polyline ``curve`` (nearest vertex, then its two
    segments)."""
    _, nearest = cKDTree(curve).query(points)
    best = np.full(len(points), np.inf)
    for offset in (-1, 0):
        start = np.clip(nearest + offset, 0, len(curve) - 2)
        a, b = curve[start], curve[start + 1]
        along = np.clip(
            np.sum((points - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0.0, 1.0
        )
        best = np.minimum(best, np.linalg.norm(a + along[:, None] * (b - a) - points, axis=1))
    return best


def test_shipped_selig_and_lednicer_files_give_the_same_section():
    selig = read_airfoil_file(AIRFOILS / "naca2412.dat")
    lednicer = read_airfoil_file(AIRFOILS / "naca2412_lednicer.dat")
    for upper in (True, False):
        np.testing.assert_allclose(
            selig.points_on_half(U, upper), lednicer.points_on_half(U, upper), atol=1e-6
        )


@pytest.mark.parametrize("designation", ["2412", "0012", "4415"])
def test_selig_and_lednicer_layouts_of_the_same_points_agree(tmp_path, designation):
    upper, lower = naca_points(NacaAirfoil.from_designation(designation), 61)
    selig = read_airfoil_file(
        write_selig_file(tmp_path / "s.dat", designation, selig_loop(upper, lower))
    )
    lednicer = read_airfoil_file(write_lednicer_file(tmp_path / "l.dat", designation, upper, lower))
    for side in (True, False):
        np.testing.assert_allclose(
            selig.points_on_half(U, side), lednicer.points_on_half(U, side), atol=1e-6
        )


@pytest.mark.parametrize("designation", ["2412", "0012", "4412", "2415"])
def test_a_file_written_from_the_naca_formulas_reproduces_the_naca_section(designation):
    """81 cosine-spaced stations per surface (the density of the database's files): within the
    stated error."""
    airfoil = NacaAirfoil.from_designation(designation)
    upper, lower = naca_points(airfoil, 81)
    text = "\n".join([designation] + [f"{x:.9f} {y:.9f}" for x, y in selig_loop(upper, lower)])
    section = parse_airfoil_text(text, designation)
    dense = np.linspace(0.0, 1.0, 200001) ** 2  # chord positions, dense at the leading edge
    exact_upper, exact_lower = airfoil.surfaces(dense)
    error = max(
        distance_to_curve(section.points_on_half(U, True), exact_upper).max(),
        distance_to_curve(section.points_on_half(U, False), exact_lower).max(),
    )
    assert error < INTERPOLATION_ERROR_LIMIT
    assert section.points_on_half([0.0], True) == pytest.approx(np.zeros((1, 2)), abs=1e-12)
    assert section.points_on_half([1.0], True) == pytest.approx(np.array([[1.0, 0.0]]), abs=1e-9)


def test_any_placement_of_a_file_is_normalised_to_unit_chord_at_the_origin(tmp_path):
    upper, lower = naca_points(NacaAirfoil.from_designation("0012"), 61)
    loop = selig_loop(upper, lower)
    angle = np.radians(10.0)
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    moved = 200.0 * loop @ turn.T + np.array([31.0, -7.0])
    reference = parse_airfoil_text("\n".join(f"{x:.12f} {y:.12f}" for x, y in loop), "unit")
    section = parse_airfoil_text("\n".join(f"{x:.12f} {y:.12f}" for x, y in moved), "moved")
    for side in (True, False):
        np.testing.assert_allclose(
            section.points_on_half(U, side), reference.points_on_half(U, side), atol=1e-8
        )


def test_a_loop_stored_lower_surface_first_is_the_same_section():
    upper, lower = naca_points(NacaAirfoil.from_designation("2412"), 61)
    loop = selig_loop(upper, lower)
    forward = parse_airfoil_text("\n".join(f"{x:.9f} {y:.9f}" for x, y in loop), "forward")
    backward = parse_airfoil_text("\n".join(f"{x:.9f} {y:.9f}" for x, y in loop[::-1]), "backward")
    for side in (True, False):
        np.testing.assert_allclose(
            forward.points_on_half(U, side), backward.points_on_half(U, side), atol=1e-12
        )


def test_clark_y_from_its_published_table():
    section = read_airfoil_file(AIRFOILS / "clarky.dat")
    assert isinstance(section, Section)
    upper, lower = section.points_on_half(U, True), section.points_on_half(U, False)
    assert upper[0] == pytest.approx([0.0, 0.0], abs=1e-12)
    assert 0.5 * (upper[-1] + lower[-1]) == pytest.approx([1.0, 0.0], abs=1e-12)
    thickness = np.interp(U, upper[:, 0], upper[:, 1]) - np.interp(U, lower[:, 0], lower[:, 1])
    assert thickness.max() == pytest.approx(0.117, abs=1e-3)  # the Clark Y is 11.7 % thick
    assert has_base(section)  # its published trailing edge is 0.12 % open
    assert np.linalg.norm(trailing_edge_vector(section)) == pytest.approx(0.0012, rel=2e-2)


def test_file_sections_are_resampled_at_equal_arc_length():
    section = read_airfoil_file(AIRFOILS / "naca2412.dat")
    sampling = equal_arc_length_section(section, 120)
    te = sampling.trailing_edge_index
    closed = np.append(sampling.t, 2.0)
    gaps = np.array(
        [
            np.linalg.norm(
                np.diff(closed_points(section, np.linspace(a, b, 200)), axis=0), axis=1
            ).sum()
            for a, b in pairwise(closed)
        ]
    )  # arc length between neighbours
    for side in (gaps[:te], gaps[te:]):
        assert np.abs(side / side.mean() - 1).max() < 2e-3


def test_blunt_edge_of_a_file_section_has_the_requested_gap():
    section = read_airfoil_file(AIRFOILS / "clarky.dat").with_trailing_edge_gap(0.02)
    assert trailing_edge_vector(section)[1] == pytest.approx(0.02, abs=1e-12)
    near_leading_edge = section.points_on_half(np.linspace(0, 0.3, 50), True)
    original = read_airfoil_file(AIRFOILS / "clarky.dat").points_on_half(
        np.linspace(0, 0.3, 50), True
    )
    # the change is confined to the trailing edge
    assert np.abs(near_leading_edge - original).max() < 1e-6


# -- malformed files: ParameterError naming the file and the line
# -----------------------------------

MALFORMED = {
    "no_numbers": ("just a name\nand some words\n", 2, "expected two numbers"),
    "empty": ("\n\n", 1, "no coordinates"),
    "name_only": ("NACA 2412\n", 1, "no coordinates"),
    "text_in_data": ("foil\n1.0 0.0\n0.5 0.05\nhello world\n0.0 0.0\n", 4, "expected two numbers"),
    "three_columns": ("foil\n1.0 0.0 3\n", 2, "expected two numbers"),
    "one_surface_selig": (
        "foil\n1.0 0.0\n0.8 0.03\n0.6 0.05\n0.4 0.06\n0.2 0.05\n0.1 0.03\n0.0 0.0\n",
        8,
        "only one surface",
    ),
    "one_surface_lednicer": (
        "foil\n5. 5.\n\n0.0 0.0\n0.25 0.05\n0.5 0.06\n0.75 0.04\n1.0 0.0\n",
        8,
        "only one surface",
    ),
    "crossing": (
        (
            "foil\n1.0 0.0\n0.75 -0.04\n0.5 0.06\n0.25 "
            "0.05\n0.0 0.0\n0.25 -0.05\n0.5 -0.06\n0.75 0.04\n"
            "1.0 0.0\n"
        ),
        3,
        "cross",
    ),
    "zero_chord": ("foil\n" + "0.5 0.5\n" * 9, 2, "chord is zero"),
    "not_finite": ("foil\n1.0 nan\n", 2, "finite"),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_files_are_refused_naming_file_and_line(tmp_path, case):
    text, line, reason = MALFORMED[case]
    path = tmp_path / f"{case}.dat"
    path.write_text(text)
    with pytest.raises(ParameterError) as error:
        read_airfoil_file(path)
    message = str(error.value)
    assert str(path) in message and f"line {line}:" in message and reason in message
    assert "\n" not in message


def test_binary_and_missing_files_are_refused(tmp_path):
    binary = tmp_path / "binary.dat"
    binary.write_bytes(b"\x00\x01\x02\xff" * 10)
    with pytest.raises(ParameterError, match=r"binary\.dat"):
        read_airfoil_file(binary)
    with pytest.raises(ParameterError, match=r"missing\.dat"):
        read_airfoil_file(tmp_path / "missing.dat")


# -- the crossing checks refuse crossings, not round-off (issue 33)
# ----------------------------------------


def ellipse_text(points: int, thickness: float) -> str:
    """A Selig file of a closed ellipse of chord 1: ``points`` points from (1, 0) round and back to
    (1, 0)."""
    angle = np.linspace(0.0, 2.0 * np.pi, points)
    loop = np.stack([0.5 + 0.5 * np.cos(angle), 0.5 * thickness * np.sin(angle)], axis=1)
    return "ellipse\n" + "\n".join(f"{x:.7f} {y:.7f}" for x, y in loop) + "\n"


def test_a_closed_ellipse_is_a_section_at_every_point_count():
    """A closed smooth loop's two spline ends meet only to round-off (~1e-19 chord); the crossing
    check took that for a crossing and refused 206 of 1448 closed ellipses of 20-200 points (80
    points, thickness 0.12 among them: 'line 2: the surfaces cross')."""
    for points in range(20, 201):
        for thickness in (0.08, 0.12):
            section = parse_airfoil_text(ellipse_text(points, thickness), "ellipse.dat")
            upper, lower = section.points_on_half(U, True), section.points_on_half(U, False)
            assert np.abs(upper[:, 1] + lower[:, 1]).max() < 1e-6  # symmetric about the chord
            # the halves never meet between
            assert np.all(upper[1:-1, 1] > 0.0) and np.all(lower[1:-1, 1] < 0.0)
            assert upper[:, 1].max() == pytest.approx(0.5 * thickness, rel=1e-2)  # 20 points: 3e-3


def test_a_smooth_curve_that_runs_into_the_other_surface_is_still_refused():
    """The points do not cross, but the spline's overshoot next to a spike on the upper surface
    does."""
    upper = [
        (1, 0),
        (0.8, 0.002),
        (0.62, 0.002),
        (0.56, 0.08),
        (0.5, 0.002),
        (0.3, 0.002),
        (0.1, 0.002),
        (0, 0),
    ]
    lower = [(0.1, -0.002), (0.3, -0.002), (0.5, -0.002), (0.7, -0.002), (0.9, -0.002), (1, 0)]
    text = "spike\n" + "\n".join(f"{x} {y}" for x, y in upper + lower) + "\n"
    with pytest.raises(
        ParameterError, match=r"spike\.dat' line 3: the surfaces cross \(the smooth curve"
    ):
        parse_airfoil_text(text, "spike.dat")
