"""Mass properties by OpenCascade (issue 6): analytic checks, the JSON report, --density, --verbose."""

from __future__ import annotations

import json
import math

import pytest

from torus_cad.propeller import propeller_objects
from torus_cad.cli import EXIT_BAD_INPUT, EXIT_OK, main
from torus_cad.parameters import PropellerParameters
from torus_cad.kernel.checks import is_valid_closed_solid, mass_properties, precise_volume
from torus_cad.kernel.export import read_step
from torus_cad.kernel.hub import hub_solid
from torus_cad.propeller import DEFAULT_DENSITY_G_CM3
from torus_cad.tolerances import READ_BACK_RELATIVE_TOLERANCE

FAST = ["--set", "resolution.sections=16", "--set", "resolution.points=40"]


@pytest.fixture(scope="module")
def objects():
    return propeller_objects(overrides={"resolution.sections": 16, "resolution.points": 40, "name": "mass_fast"})


@pytest.fixture(scope="module")
def cli_build(tmp_path_factory):
    """``torus-cad build`` with the same design and --density 7.85 (steel); returns (out_dir, report)."""
    out = tmp_path_factory.mktemp("cli_mass")
    code = main(["build", *FAST, "--set", "name=mass_fast", "--density", "7.85", "--no-stl", "-q", "--out", str(out)])
    assert code == EXIT_OK
    return out, json.loads((out / "mass_fast.json").read_text())


@pytest.mark.parametrize(("radius", "length", "density"), [(10.0, 20.0, 1.24), (7.5, 13.0, 7.85), (0.5, 2.5, 1.0),
                                                            (250.0, 40.0, 2.7)])
def test_hub_inertia_matches_the_analytic_cylinder(radius, length, density):
    properties = mass_properties(hub_solid(radius, length), density)
    inertia_mm5 = math.pi * radius**4 * length / 2.0  # integral of r^2 dV about the axis
    assert properties.spin_axis_inertia_mm5 == pytest.approx(inertia_mm5, rel=1e-6)
    assert properties.spin_axis_inertia_g_mm2 == pytest.approx(inertia_mm5 * density * 1e-3, rel=1e-6)
    volume = math.pi * radius**2 * length
    assert properties.volume_mm3 == pytest.approx(volume, rel=1e-6)
    assert properties.mass_g == pytest.approx(volume * density * 1e-3, rel=1e-6)
    assert properties.surface_area_mm2 == pytest.approx(2 * math.pi * radius * (radius + length), rel=1e-6)
    assert properties.centroid_mm == pytest.approx((0.0, 0.0, 0.0), abs=1e-9 * max(radius, length))


def test_api_hub_inertia_matches_the_analytic_cylinder(objects):
    hub = objects.parameters.hub
    properties = mass_properties(objects.hub, DEFAULT_DENSITY_G_CM3)
    expected = math.pi * hub.radius**4 * hub.length / 2.0 * DEFAULT_DENSITY_G_CM3 * 1e-3
    assert properties.spin_axis_inertia_g_mm2 == pytest.approx(expected, rel=1e-6)


def test_mass_is_density_times_volume(objects):
    for density in (1.24, 19.3):
        properties = objects.mass_properties(density)
        assert properties.density_g_cm3 == density
        assert properties.mass_g == pytest.approx(density * 1e-3 * properties.volume_mm3, rel=1e-12)
        assert properties.spin_axis_inertia_g_mm2 == pytest.approx(
            density * 1e-3 * properties.spin_axis_inertia_mm5, rel=1e-12)


def test_propeller_mass_properties_are_physically_sound(objects):
    properties = objects.mass_properties()
    hub = objects.parameters.hub
    hub_properties = mass_properties(objects.hub, DEFAULT_DENSITY_G_CM3)
    assert properties.density_g_cm3 == DEFAULT_DENSITY_G_CM3 == 1.24  # PLA by default
    # n equal blades spaced evenly around z: the centroid lies on the spin axis.
    cx, cy, cz = properties.centroid_mm
    assert math.hypot(cx, cy) < 1e-6 * hub.radius
    assert abs(cz) < hub.length / 2
    # Blades add material (mass, inertia and area) outside the hub.
    assert properties.mass_g > hub_properties.mass_g
    assert properties.spin_axis_inertia_mm5 > hub_properties.spin_axis_inertia_mm5
    assert properties.surface_area_mm2 > hub_properties.surface_area_mm2
    (xmin, ymin, zmin), (xmax, ymax, zmax) = properties.bounding_box_mm
    assert xmax - xmin > 2 * hub.radius and zmax - zmin >= hub.length - 1e-6


def test_api_solid_volume_equals_the_cli_step_volume(objects, cli_build):
    out, report = cli_build
    shape = read_step(out / "mass_fast.step")
    assert is_valid_closed_solid(shape)
    api_volume = precise_volume(objects.solid)
    assert precise_volume(shape) == pytest.approx(api_volume, rel=READ_BACK_RELATIVE_TOLERANCE)
    assert report["volume_mm3"] == pytest.approx(api_volume, rel=READ_BACK_RELATIVE_TOLERANCE)


def test_json_report_holds_every_mass_property(objects, cli_build):
    _, report = cli_build
    expected = objects.mass_properties(7.85)
    assert report["density_g_cm3"] == 7.85
    assert report["mass_g"] == pytest.approx(7.85e-3 * report["volume_mm3"], rel=1e-12)
    assert report["surface_area_mm2"] == pytest.approx(expected.surface_area_mm2, rel=1e-6)
    assert report["centroid_mm"] == pytest.approx(list(expected.centroid_mm), abs=1e-6)
    assert report["spin_axis_inertia_mm5"] == pytest.approx(expected.spin_axis_inertia_mm5, rel=1e-6)
    assert report["spin_axis_inertia_g_mm2"] == pytest.approx(expected.spin_axis_inertia_g_mm2, rel=1e-6)


def test_default_density_is_pla(tmp_path):
    assert main(["build", *FAST, "--no-stl", "-q", "--out", str(tmp_path)]) == EXIT_OK
    report = json.loads((tmp_path / f"{PropellerParameters().name}.json").read_text())
    assert report["density_g_cm3"] == 1.24
    assert report["mass_g"] == pytest.approx(1.24e-3 * report["volume_mm3"], rel=1e-12)


def test_verbose_prints_mass_properties_and_stays_quiet_on_stderr(tmp_path, capsys):
    assert main(["build", *FAST, "--no-stl", "-v", "--density", "2.7", "--out", str(tmp_path)]) == EXIT_OK
    captured = capsys.readouterr()
    for words in ("volume", "mm^3", "area", "mm^2", "mass", "g at 2.7 g/cm^3", "centroid", "spin-axis inertia",
                  "g mm^2"):
        assert words in captured.out
    assert captured.err == ""  # progress only on a terminal; capsys is not one


@pytest.mark.parametrize("density", ["0", "-1", "abc", "30"])
def test_bad_density_is_refused(tmp_path, density, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["build", "--density", density, "--out", str(tmp_path)])
    assert stop.value.code == EXIT_BAD_INPUT
    assert "--density" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
