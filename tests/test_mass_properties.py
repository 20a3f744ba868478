"""Mass properties: analytic checks, the fast route over the blade faces
against OpenCascade's adaptive integration at 1e-9, the fallback, the JSON report, --density,
--verbose."""

from __future__ import annotations

import json
import math

import cadquery as cq
import numpy as np
import pytest

from torus_cad.cli import EXIT_BAD_INPUT, EXIT_OK, main
from torus_cad.kernel.blade_integrals import hub_with_blade_integrals
from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.kernel.hub import hub_solid
from torus_cad.kernel.mass_properties import mass_properties, occt_mass_properties, precise_volume
from torus_cad.kernel.step_readback import read_step
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, propeller_objects
from torus_cad.tolerances import READ_BACK_RELATIVE_TOLERANCE

FAST = ["--set", "resolution.sections=16", "--set", "resolution.points=40"]

#: The reference: BRepGProp's adaptive integration at this relative precision (and BRepBndLib's
#: box).
REFERENCE_PRECISION = 1e-9

#: What the reported figures must agree with the reference to: relative for volume, area and
#: inertia; times the box diagonal for centroid and box (mm).
AGREEMENT = 1e-6


@pytest.fixture(scope="module")
def objects():
    return propeller_objects(
        overrides={"resolution.sections": 16, "resolution.points": 40, "name": "mass_fast"}
    )


@pytest.fixture(scope="module")
def cli_build(tmp_path_factory):
    """``torus-cad build`` with the same design and --density 7.85 (steel); returns (out_dir,
    report)."""
    out = tmp_path_factory.mktemp("cli_mass")
    code = main(
        [
            "build",
            *FAST,
            "--set",
            "name=mass_fast",
            "--density",
            "7.85",
            "--no-stl",
            "-q",
            "--out",
            str(out),
        ]
    )
    assert code == EXIT_OK
    return out, json.loads((out / "mass_fast.json").read_text())


@pytest.mark.parametrize(
    ("radius", "length", "density"),
    [(10.0, 20.0, 1.24), (7.5, 13.0, 7.85), (0.5, 2.5, 1.0), (250.0, 40.0, 2.7)],
)
def test_hub_inertia_matches_the_analytic_cylinder(radius, length, density):
    properties = mass_properties(hub_solid(radius, length), density)
    inertia_mm5 = math.pi * radius**4 * length / 2.0  # integral of r^2 dV about the axis
    assert properties.spin_axis_inertia_mm5 == pytest.approx(inertia_mm5, rel=1e-6)
    assert properties.spin_axis_inertia_g_mm2 == pytest.approx(
        inertia_mm5 * density * 1e-3, rel=1e-6
    )
    volume = math.pi * radius**2 * length
    assert properties.volume_mm3 == pytest.approx(volume, rel=1e-6)
    assert properties.mass_g == pytest.approx(volume * density * 1e-3, rel=1e-6)
    assert properties.surface_area_mm2 == pytest.approx(
        2 * math.pi * radius * (radius + length), rel=1e-6
    )
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
            density * 1e-3 * properties.spin_axis_inertia_mm5, rel=1e-12
        )


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
    (xmin, _, zmin), (xmax, _, zmax) = properties.bounding_box_mm
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
    assert report["spin_axis_inertia_mm5"] == pytest.approx(
        expected.spin_axis_inertia_mm5, rel=1e-6
    )
    assert report["spin_axis_inertia_g_mm2"] == pytest.approx(
        expected.spin_axis_inertia_g_mm2, rel=1e-6
    )


def test_default_density_is_pla(tmp_path):
    assert main(["build", *FAST, "--no-stl", "-q", "--out", str(tmp_path)]) == EXIT_OK
    report = json.loads((tmp_path / f"{PropellerParameters().name}.json").read_text())
    assert report["density_g_cm3"] == 1.24
    assert report["mass_g"] == pytest.approx(1.24e-3 * report["volume_mm3"], rel=1e-12)


def test_verbose_prints_mass_properties_and_stays_quiet_on_stderr(tmp_path, capsys):
    assert (
        main(["build", *FAST, "--no-stl", "-v", "--density", "2.7", "--out", str(tmp_path)])
        == EXIT_OK
    )
    captured = capsys.readouterr()
    for words in (
        "volume",
        "mm^3",
        "area",
        "mm^2",
        "mass",
        "g at 2.7 g/cm^3",
        "centroid",
        "spin-axis inertia",
        "g mm^2",
    ):
        assert words in captured.out
    # progress only on a terminal (capsys is not one): stderr holds the warnings alone (the
    # default's sharp trailing edge is not printable), one line each
    assert all(line.startswith("warning: ") for line in captured.err.splitlines()), captured.err


@pytest.mark.parametrize("density", ["0", "-1", "abc", "30"])
def test_bad_density_is_refused(tmp_path, density, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["build", "--density", density, "--out", str(tmp_path)])
    assert stop.value.code == EXIT_BAD_INPUT
    assert "--density" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


# -- the fast route: blade faces alone, against BRepGProp at 1e-9 ----------------------------------


def _assert_agrees_with_the_reference(solid: cq.Solid) -> None:
    fast = mass_properties(solid, 1.0)
    reference = occt_mass_properties(solid, 1.0, REFERENCE_PRECISION)
    size = float(np.linalg.norm(np.subtract(*reference.bounding_box_mm)))
    assert fast.volume_mm3 == pytest.approx(reference.volume_mm3, rel=AGREEMENT)
    assert fast.surface_area_mm2 == pytest.approx(reference.surface_area_mm2, rel=AGREEMENT)
    assert fast.spin_axis_inertia_mm5 == pytest.approx(
        reference.spin_axis_inertia_mm5, rel=AGREEMENT
    )
    assert fast.centroid_mm == pytest.approx(reference.centroid_mm, abs=AGREEMENT * size)
    assert np.allclose(
        fast.bounding_box_mm, reference.bounding_box_mm, rtol=0.0, atol=AGREEMENT * size
    )


def test_the_default_takes_the_fast_route_and_agrees_with_the_reference(default_propeller):
    assert hub_with_blade_integrals(default_propeller.solid.wrapped) is not None
    _assert_agrees_with_the_reference(default_propeller.solid)


def test_the_fast_route_agrees_with_the_reference_on_random_designs():
    from studies.fuzz import random_design
    from torus_cad.errors import GeometryError, ParameterError
    from torus_cad.propeller import build_propeller

    built, seed = 0, 0
    while built < 8:  # 8 designs of 1-8 blades; each reference integration costs seconds
        seed += 1
        try:
            propeller = build_propeller(random_design(seed))
        except (ParameterError, GeometryError):
            continue  # refused before the kernel: nothing to integrate
        built += 1
        assert hub_with_blade_integrals(propeller.solid.wrapped) is not None, (
            f"seed {seed} fell back"
        )
        _assert_agrees_with_the_reference(propeller.solid)


@pytest.mark.parametrize(
    "shape",
    [
        pytest.param(lambda: cq.Solid.makeBox(3.0, 4.0, 5.0), id="box"),
        pytest.param(lambda: hub_solid(10.0, 20.0), id="hub without blades"),
        pytest.param(
            lambda: hub_solid(10.0, 20.0).fuse(
                cq.Solid.makeBox(4.0, 4.0, 30.0, cq.Vector(-2, -2, -15))
            ),
            id="end faces with holes",
        ),
    ],
)
def test_other_shapes_fall_back_to_opencascade(shape):
    solid = shape()
    assert hub_with_blade_integrals(solid.wrapped) is None
    assert mass_properties(solid, 2.0) == occt_mass_properties(solid, 2.0)


@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_the_local_b_spline_basis_is_scipys(degree):
    from scipy.interpolate import BSpline

    from torus_cad.kernel.blade_integrals.bspline import local_basis

    rng = np.random.default_rng(degree)
    knots = np.r_[[0.0] * (degree + 1), np.sort(rng.random(9)), [2.0] * (degree + 1)]
    x = np.r_[2.0 * rng.random(300), 0.0, 2.0, knots[degree + 4]]  # ends and an inner knot included
    columns, values = local_basis(x, knots, degree)
    dense = np.zeros((len(x), len(knots) - degree - 1))
    np.put_along_axis(dense, columns, values, axis=1)
    assert np.allclose(
        dense, BSpline.design_matrix(x, knots, degree).toarray(), rtol=0.0, atol=1e-14
    )


def test_a_bored_hub_takes_the_fast_route_and_agrees(light_params):
    """A plain through-bore (the multirotor example's kind): the hub is a tube, integrated in closed
    form."""
    from torus_cad.propeller import build_propeller

    bored = build_propeller(light_params.with_values({"hub.bore_diameter": 5.0}))
    assert (
        hub_with_blade_integrals(bored.solid.wrapped).volume_mm3
        < hub_with_blade_integrals(build_propeller(light_params).solid.wrapped).volume_mm3
    )  # the bore is taken out
    _assert_agrees_with_the_reference(bored.solid)
    flatted = build_propeller(
        light_params.with_values({"hub.bore_diameter": 5.0, "hub.bore_flat_depth": 0.5})
    )
    # a D-flat: OpenCascade's integration
    assert hub_with_blade_integrals(flatted.solid.wrapped) is None


def test_a_mirrored_propeller_takes_the_fast_route_and_agrees(light_params):
    from torus_cad.propeller import build_propeller

    mirrored = build_propeller(light_params.with_values({"handedness": "ccw"}))
    assert hub_with_blade_integrals(mirrored.solid.wrapped) is not None
    _assert_agrees_with_the_reference(mirrored.solid)


@pytest.mark.parametrize(
    "overrides", [{"blades": 1}, {"blades": 2, "phase_deg": 17.0}, {}], ids=["1", "2", "3"]
)
def test_the_balance_from_the_blade_faces_agrees_with_the_reference(light_params, overrides):
    from torus_cad.kernel.mass_properties import balance, balance_of, volume_properties
    from torus_cad.propeller import build_propeller

    solid = build_propeller(light_params.with_values(overrides)).solid
    assert hub_with_blade_integrals(solid.wrapped) is not None
    fast = balance(solid, 1.0)
    reference = balance_of(volume_properties(solid, REFERENCE_PRECISION), 1.0)
    # the scale of the products
    spin_inertia_g_mm2 = mass_properties(solid, 1.0).spin_axis_inertia_g_mm2
    mass_g = mass_properties(solid, 1.0).mass_g
    size = float(np.linalg.norm(np.subtract(*reference_box(solid))))
    assert fast.centroid_offset_mm == pytest.approx(
        reference.centroid_offset_mm, abs=AGREEMENT * size
    )
    assert fast.static_imbalance_g_mm == pytest.approx(
        reference.static_imbalance_g_mm, abs=AGREEMENT * mass_g * size
    )
    for name, value in reference.products_of_inertia_g_mm2.items():
        assert fast.products_of_inertia_g_mm2[name] == pytest.approx(
            value, abs=AGREEMENT * spin_inertia_g_mm2
        )
    if overrides.get("blades", 3) >= 3:  # 3-fold symmetry or more: no imbalance, no products
        assert (
            fast.static_imbalance_g_mm < 1e-6
            and max(map(abs, fast.products_of_inertia_g_mm2.values())) < 1e-3
        )


def reference_box(solid: cq.Solid) -> tuple:
    return occt_mass_properties(solid, 1.0).bounding_box_mm
