"""Designing with diameter, pitch and airfoils, measured on the built B-rep."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from torus_cad.cli import main
from torus_cad.cli.design_input import load_parameters
from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.geometry.analysis.diameter import DIAMETER_TOLERANCE_MM
from torus_cad.geometry.blade.blade_surface import blade_frames
from torus_cad.kernel.measure import (
    contour_through,
    max_radius_mm,
    plane_section_edges,
    straight_edges,
    vertex_radius_mm,
)
from torus_cad.outputs.measured_targets import pitch_on_solid, radius_crossings
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
MULTIROTOR = EXAMPLES / "multirotor_5in_3blade.toml"
EXIT_BAD_INPUT = 2
LIGHT = {"resolution.sections": 16, "resolution.points": 48}


@pytest.fixture(scope="module")
def multirotor():
    """The 5-inch example: diameter 127 mm, pitch 114 mm."""
    return build_propeller(MULTIROTOR)


def test_the_solid_has_the_requested_tip_diameter(multirotor):
    measured = 2.0 * max_radius_mm(multirotor.solid)  # BRepExtrema against a coaxial cylinder
    assert measured == pytest.approx(127.0, abs=DIAMETER_TOLERANCE_MM)
    # the extremum bounds every vertex
    assert 2.0 * vertex_radius_mm(multirotor.solid) <= measured + 1e-6
    assert multirotor.design_targets.tip_diameter_mm == pytest.approx(127.0, abs=1e-3)


@pytest.fixture(scope="module")
def multirotor_ccw():
    """The 5-inch example's mirror image (handedness ccw)."""
    return build_propeller(EXAMPLES / "multirotor_5in_3blade_ccw.toml")


@pytest.mark.parametrize("handed", ["multirotor", "multirotor_ccw"])
def test_the_solid_has_the_requested_pitch_at_75_percent_radius(handed, request):
    multirotor = request.getfixturevalue(handed)
    fit = multirotor.design_targets.pitch_fit
    radius = 0.75 * multirotor.design_targets.tip_diameter_mm / 2.0
    crossings = radius_crossings(multirotor.parameters, radius)
    assert len(crossings) == 2 == len(fit.pitch_at_75_mm)  # a loop passes 75 % of the radius twice
    for (s, model_pitch), reported in zip(crossings, fit.pitch_at_75_mm):
        measured = pitch_on_solid(multirotor, s)
        assert measured == pytest.approx(reported, rel=0.01)  # the report tells what the solid has
        # and that is the target, to the quartic's fit
        assert measured == pytest.approx(114.0, rel=0.03)
        assert model_pitch == pytest.approx(reported, rel=1e-3)


def test_resolved_parameters_build_the_same_design_without_targets():
    params = PropellerParameters.from_toml(MULTIROTOR)
    targets = resolve_design_targets(params)
    resolved = targets.parameters
    assert resolved.diameter == 0.0 and resolved.pitch == 0.0 and resolved.airfoil.naca == ""
    assert resolved.airfoil.thickness == 0.09 and resolved.airfoil.max_camber == 0.0
    assert resolved.centerline.p2[2] == pytest.approx(50.0 * targets.radial_scale)
    again = resolve_design_targets(resolved)  # nothing left to solve: the same parameters
    assert again.parameters == resolved and not again.requested


def test_defaults_resolved_prints_the_spec_parameters(capsys, tmp_path):
    assert main(["defaults", "--resolved", str(MULTIROTOR)]) == 0
    text = capsys.readouterr().out
    assert "diameter = 0.0" in text and "tip diameter 127.000 mm" in text
    path = tmp_path / "resolved.toml"
    path.write_text(text)
    resolved = PropellerParameters.from_toml(path)
    assert resolved == resolve_design_targets(PropellerParameters.from_toml(MULTIROTOR)).parameters


def test_an_unreachable_diameter_is_refused_with_the_reachable_range(tmp_path, capsys):
    code = main(
        [
            "build",
            "--set",
            "diameter=5000",
            *[f"--set={k}={v}" for k, v in LIGHT.items()],
            "--out",
            str(tmp_path / "out"),
        ]
    )
    error = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT
    assert "diameter = 5000 mm is out of reach" in error and "gives tip diameters" in error
    assert error.count("\n") == 1 and not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "overrides, words",
    [
        (
            {"airfoil.naca": "2412", "airfoil.max_camber": 0.04},
            "airfoil.naca = '2412' conflicts with airfoil.max_camber",
        ),
        (
            {"airfoil.naca": "2412", "airfoil.file": str(EXAMPLES / "airfoils" / "clarky.dat")},
            "conflicts with airfoil.file",
        ),
        (
            {"airfoil.file": str(EXAMPLES / "airfoils" / "clarky.dat"), "airfoil.thickness": 0.12},
            "conflicts with airfoil.thickness",
        ),
        ({"airfoil.naca": "9x12"}, "airfoil.naca = '9x12'"),
    ],
)
def test_conflicting_airfoil_inputs_exit_2(tmp_path, capsys, overrides, words):
    arguments = [f"--set={key}={json.dumps(value)}" for key, value in overrides.items()]
    assert main(["build", *arguments, "--out", str(tmp_path / "out")]) == EXIT_BAD_INPUT
    assert words in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_malformed_airfoil_file_exits_2_naming_file_and_line(tmp_path, capsys):
    (tmp_path / "crossed.dat").write_text(
        "crossed\n1 0\n0.5 -0.05\n0 0\n0.5 0.05\n0.25 -0.04\n0.75 0.04\n1 0\n"
    )
    # relative to the design file
    (tmp_path / "design.toml").write_text('[airfoil]\nfile = "crossed.dat"\n')
    assert (
        main(["build", str(tmp_path / "design.toml"), "--out", str(tmp_path / "out")])
        == EXIT_BAD_INPUT
    )
    error = capsys.readouterr().err
    assert "airfoil.file" in error and str(tmp_path / "crossed.dat") in error and "line " in error
    assert not (tmp_path / "out").exists()


def test_a_naca_designation_builds_the_numbers_solid():
    by_name = PropellerParameters().with_values({"airfoil.naca": "2450", **LIGHT})
    by_numbers = PropellerParameters().with_values(
        {
            "airfoil.max_camber": 0.02,
            "airfoil.camber_position": 0.4,
            "airfoil.thickness": 0.5,
            **LIGHT,
        }
    )
    resolved = resolve_design_targets(by_name).parameters
    np.testing.assert_array_equal(
        sampled_blade_surface(resolved).points, sampled_blade_surface(by_numbers).points
    )


@pytest.mark.parametrize(
    "airfoil",
    [
        {"airfoil.file": str(EXAMPLES / "airfoils" / "clarky.dat")},
        {"airfoil.file": str(EXAMPLES / "airfoils" / "naca2412_lednicer.dat")},
        {"airfoil.naca": "23012"},
    ],
)
def test_other_airfoils_build_one_valid_solid(airfoil):
    params = PropellerParameters().with_values(
        {**airfoil, **LIGHT, "transforms.scale_y": [0, 0, -16, 16, 6]}
    )
    propeller = build_propeller(params)
    assert propeller.solid.isValid() and len(propeller.solid.Solids()) == 1


def test_blunt_trailing_edge_measured_on_the_solid():
    """A 0.4 mm flat base on every section: the straight edge where a section plane cuts the solid
    (the round cap: tests/test_round_trailing_edge.py)."""
    params = PropellerParameters().with_values(
        {"airfoil.trailing_edge_thickness": 0.4, "airfoil.trailing_edge_shape": "flat", **LIGHT}
    )
    propeller = build_propeller(params)
    assert propeller.solid.isValid() and len(propeller.solid.Solids()) == 1
    sharp_faces = len(build_propeller(PropellerParameters().with_values(LIGHT)).solid.Faces())
    # each blade's side is two faces either way: the sharp edge's lower and upper, the blunt one's
    # base and airfoil
    assert len(propeller.solid.Faces()) == sharp_faces
    geometry = propeller_geometry(params)
    s_values = [0.5, 0.5 + 0.5 / 15.0]  # on a section, and half-way between two sections
    frames = blade_frames(geometry.blade, geometry.centerline(0), s_values)
    for origin, tangent in zip(frames.origin, frames.tangent):
        edges = contour_through(plane_section_edges(propeller.solid, origin, tangent, 15.0), origin)
        bases = straight_edges(edges)
        assert len(bases) == 1
        assert bases[0].Length() == pytest.approx(0.4, rel=0.01)


def test_sections_table_is_written_beside_the_step(tmp_path):
    code = main(
        [
            "build",
            *[f"--set={k}={v}" for k, v in LIGHT.items()],
            "--set",
            "airfoil.trailing_edge_thickness=0.3",
            "--no-stl",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    with open(tmp_path / "torus_propeller_sections.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 16
    assert list(rows[0]) == [
        "s",
        "r_mm",
        "axial_mm",
        "chord_mm",
        "max_thickness_mm",
        "thickness_to_chord",
        "beta_deg",
        "geometric_pitch_mm",
        "position_angle_deg",
        "radial_fraction",
        "trailing_edge_mm",
    ]
    for row in rows:
        assert float(row["trailing_edge_mm"]) == pytest.approx(0.3, rel=1e-4)
        assert float(row["thickness_to_chord"]) == pytest.approx(
            float(row["max_thickness_mm"]) / float(row["chord_mm"]), rel=1e-4
        )
    assert (tmp_path / "torus_propeller_sections.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_targets_are_fitted_on_geometry_objects_with_few_validations(monkeypatch):
    """A diameter + pitch design validates its document at most 3 times while its targets are
    fitted, and builds its geometry a few times, not once per step of the fits."""
    from torus_cad.design import design_targets
    from torus_cad.parameters import PropellerParameters

    params = load_parameters(str(EXAMPLES / "cooling_fan_7blade.toml"))
    calls = {"with_values": 0, "geometry": 0}
    with_values, geometry = PropellerParameters.with_values, design_targets.propeller_geometry

    def counted_with_values(self, *args, **kwargs):
        calls["with_values"] += 1
        return with_values(self, *args, **kwargs)

    def counted_geometry(*args, **kwargs):
        calls["geometry"] += 1
        return geometry(*args, **kwargs)

    monkeypatch.setattr(PropellerParameters, "with_values", counted_with_values)
    monkeypatch.setattr(design_targets, "propeller_geometry", counted_geometry)
    resolved = design_targets.resolve_design_targets(params)
    assert resolved.tip_diameter_mm == pytest.approx(120.0, abs=1e-6)
    assert calls["with_values"] <= 3
    assert calls["geometry"] <= 3
