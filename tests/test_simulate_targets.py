"""``simulate --thrust`` (the rpm search), ``simulate --step`` (a user's STEP propeller) and the
grid convergence index of the convergence study.

The search's arithmetic, the GCI and the refusals run without OpenFOAM; the runs need it (and
the thrust search and the STEP-against-design comparison are in the long tier).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from cli_exit import exit_code
from hypothesis import given
from hypothesis import strategies as st
from openfoam_marks import needs_openfoam

from torus_cad.cli import main
from torus_cad.errors import ParameterError
from torus_cad.simulate.coefficients import (
    GCI_SAFETY_FACTOR,
    SPREAD_SAFETY_FACTOR,
    UncertaintyMethod,
    richardson,
)
from torus_cad.simulate.thrust_target import (
    ThrustRun,
    check_target,
    first_rpm,
    next_rpm,
    rpm_for,
    search_state,
    thrust_at,
)

RATIO = 2.0 ** (1.0 / 3.0)


# -- grid convergence index
# -------------------------------------------------------------------------


def test_gci_of_a_manufactured_second_order_sequence():
    # f(h) = f0 + C h^2 on h = r^2, r, 1 (coarse, medium, fine): p = 2 and the limit f0 exactly
    f0, c = 0.05, 0.004
    coarse, medium, fine = (f0 + c * RATIO ** (2 * k) for k in (2, 1, 0))
    result = richardson(coarse, medium, fine, RATIO)
    assert result.order == pytest.approx(2.0, abs=1e-9)
    assert result.extrapolated == pytest.approx(f0, rel=1e-9)
    # GCI_fine = Fs |(f_m - f_f) / f_f| / (r^2 - 1) = Fs C / f_f; GCI_medium = Fs C r^2 / f_m
    assert result.gci_fine == pytest.approx(1.25 * c / fine, rel=1e-9)
    assert result.gci_medium == pytest.approx(1.25 * c * RATIO**2 / medium, rel=1e-9)
    # asymptotic check: GCI_medium / (r^p GCI_fine) = f_f / f_m
    assert result.asymptotic_ratio == pytest.approx(fine / medium, rel=1e-9)


def test_gci_by_hand_on_three_numbers():
    # f = 1.00, 0.90, 0.86 (coarse, medium, fine), r = 2: p = ln(0.10 / 0.04) / ln 2 = 1.3219
    result = richardson(1.00, 0.90, 0.86, 2.0)
    assert result.order == pytest.approx(1.321928, rel=1e-6)
    growth = 2.0**result.order - 1.0  # 1.5
    assert growth == pytest.approx(1.5)
    assert result.extrapolated == pytest.approx(0.86 - 0.04 / 1.5)
    assert result.gci_fine == pytest.approx(GCI_SAFETY_FACTOR * (0.04 / 0.86) / 1.5)  # 3.876 %
    assert result.gci_fine == pytest.approx(0.038760, rel=1e-4)
    assert result.gci_medium == pytest.approx(1.25 * (0.10 / 0.90) / 1.5)  # 9.259 %
    assert result.asymptotic_ratio == pytest.approx(result.gci_medium / (2.5 * result.gci_fine))


def test_no_order_and_no_gci_when_the_levels_do_not_converge_monotonically():
    for values in ((0.0401, 0.0437, 0.0495), (1.0, 2.0, 1.5), (1.0, 1.0, 1.0)):
        result = richardson(*values, RATIO)
        assert not result.converges_monotonically
        assert (
            result.order,
            result.extrapolated,
            result.gci_fine,
            result.gci_medium,
            result.asymptotic_ratio,
        ) == (None,) * 5


def test_levels_that_do_not_converge_still_get_an_uncertainty_from_their_spread():
    # the default design's torque without layers: +5.0 %, then +4.9 % (no order, no GCI)
    result = richardson(0.9862, 1.036, 1.087, RATIO)
    assert (
        not result.converges_monotonically and result.uncertainty_method is UncertaintyMethod.SPREAD
    )
    assert result.spread == pytest.approx((1.087 - 0.9862) / 1.087)
    # 27.8 %
    assert result.uncertainty_fine == pytest.approx(SPREAD_SAFETY_FACTOR * (1.087 - 0.9862) / 1.087)
    entry = result.report()
    assert (entry["uncertainty_method"], entry["gci_fine"]) == ("spread", None)
    assert json.loads(json.dumps(entry)) == entry  # the study's JSON holds it as it is


def test_levels_that_converge_take_their_gci_as_the_uncertainty():
    result = richardson(1.00, 0.90, 0.86, 2.0)
    assert (
        result.uncertainty_method is UncertaintyMethod.GCI
        and result.uncertainty_fine == result.gci_fine
    )
    assert result.spread == pytest.approx(0.14 / 0.86)
    # GCI_medium / (r^p GCI_fine) = 0.956, within 0.1 of 1
    assert result.report()["in_asymptotic_range"] is True


@given(
    st.lists(
        st.floats(min_value=-1e3, max_value=1e3, allow_nan=False).filter(
            lambda value: abs(value) > 1e-6
        ),
        min_size=3,
        max_size=3,
    )
)
def test_the_uncertainty_band_of_levels_without_a_gci_holds_every_level(values):
    result = richardson(*values, RATIO)
    if result.converges_monotonically:
        return
    fine = values[2]
    band = result.uncertainty_fine * abs(fine)
    assert all(abs(value - fine) <= band * (1.0 + 1e-12) for value in values)


# -- the thrust search's arithmetic
# ------------------------------------------------------------------


def _propeller(ct: float, offset: float = 0.0):
    """Thrust of a propeller whose CT drifts with rpm (``offset`` per 10,000 rpm): not exactly
    rpm^2."""
    return lambda rpm: thrust_at(ct * (1.0 + offset * rpm / 10000.0), rpm, 0.0451, 1.225)


@pytest.mark.parametrize("ct, offset", [(0.25, 0.0), (0.29, 0.0), (0.29, 0.15), (0.12, -0.05)])
def test_the_secant_on_sqrt_thrust_reaches_one_percent_in_few_runs(ct, offset):
    thrust, target, limit = _propeller(ct, offset), 0.05, 86465.0
    runs = [ThrustRun(first_rpm(target, limit, 0.0451, 1.225), 0.0)]
    runs[0] = ThrustRun(runs[0].rpm, thrust(runs[0].rpm))
    while not (state := search_state(runs, target, 0.01, 5, limit)).done:
        rpm = next_rpm(runs, target, limit)
        runs.append(ThrustRun(rpm, thrust(rpm)))
    assert state.within_tolerance and abs(state.best.thrust_n / target - 1.0) <= 0.01
    assert len(runs) <= (1 if (ct, offset) == (0.25, 0.0) else 4)


def test_exact_rpm_squared_thrust_is_found_by_the_second_run():
    thrust = _propeller(0.29)
    runs = [ThrustRun(9000.0, thrust(9000.0))]
    rpm = next_rpm(runs, 0.05, 86465.0)
    assert rpm == pytest.approx(rpm_for(0.29, 0.05, 0.0451, 1.225))


def test_the_search_stops_after_max_runs_with_the_closest_run():
    runs = [ThrustRun(10000.0, 0.040), ThrustRun(11000.0, 0.046), ThrustRun(11500.0, 0.0483)]
    state = search_state(runs, 0.05, 0.01, 3, 86465.0)
    assert state.done and not state.within_tolerance and state.best == runs[-1]
    assert not search_state(runs, 0.05, 0.01, 4, 86465.0).done


def test_a_target_beyond_the_rpm_limit_is_refused_once_a_run_at_the_limit_falls_short():
    limit = 20000.0
    runs = [ThrustRun(15000.0, 0.10)]
    assert next_rpm(runs, 1.0, limit) == limit  # clipped
    runs.append(ThrustRun(limit, 0.18))
    with pytest.raises(
        ParameterError, match=r"--thrust = 1 N is out of range; allowed \(0, 0.18\] N"
    ):
        search_state(runs, 1.0, 0.01, 5, limit)


def test_no_positive_thrust_cannot_be_scaled():
    with pytest.raises(
        ParameterError, match=re.escape("--thrust: the propeller gives -0.01 N at 10000 rpm")
    ):
        next_rpm([ThrustRun(10000.0, -0.01)], 0.05, 86465.0)


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf, 11.0])
def test_check_target_refuses_naming_the_option_value_and_range(value):
    with pytest.raises(
        ParameterError, match=r"--thrust = .* N is out of range; allowed \(0, 10.5\d\] N"
    ):
        check_target(value, 86465.0, 0.0451, 1.225)


@pytest.mark.parametrize(
    "arguments, fragment",
    [
        (["--thrust", "0"], "--thrust = 0 N is out of range; allowed (0, "),
        (["--thrust", "-0.5"], "--thrust = -0.5 N is out of range"),
        (["--thrust", "1e6"], "--thrust = 1e+06 N is out of range"),
        (
            ["--thrust", "0.05", "--thrust-tolerance", "0.5"],
            "--thrust-tolerance = 0.5 is out of range; allowed [0.001, 0.2]",
        ),
        (
            ["--thrust", "0.05", "--thrust-runs", "11"],
            "--thrust-runs = 11 is out of range; allowed [1, 10]",
        ),
        (["--thrust", "0.05", "--case-only"], "--thrust meshes once"),
        (["--rpm", "1000", "--turning", "ccw"], "--axis and --turning describe a --step file"),
    ],
)
def test_bad_thrust_options_exit_2_with_one_line_and_write_nothing(
    tmp_path, capsys, arguments, fragment
):
    out = tmp_path / "out"
    # out of an option's range: while parsing
    assert exit_code(["simulate", *arguments, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize(
    "arguments, fragment",
    [
        (
            ["--thrust", "0.05", "--rpm", "1000"],
            "argument --rpm: not allowed with argument --thrust",
        ),
        ([], "one of the arguments --rpm --thrust is required"),
    ],
)
def test_thrust_and_rpm_exclude_each_other_exit_2(tmp_path, capsys, arguments, fragment):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as raised:
        main(["simulate", *arguments, "--out", str(out)])
    assert raised.value.code == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


# -- --step
# ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def design_step(tmp_path_factory):
    """The default design's STEP (``torus-cad build``) and its report."""
    out = tmp_path_factory.mktemp("build")
    assert main(["build", "--out", str(out), "--no-stl", "-q"]) == 0
    return out / "torus_propeller.step", json.loads((out / "torus_propeller.json").read_text())


def _two_solids(path):
    import cadquery as cq

    from torus_cad.kernel.writers.step import write_step

    boxes = cq.Compound.makeCompound(
        [cq.Solid.makeBox(1, 1, 1), cq.Solid.makeBox(1, 1, 1, cq.Vector(3, 0, 0))]
    )
    return write_step(boxes, path, "two", check_readback=False)


def _open_box(path):
    """A box with one face missing, made a solid: its STEP reads back as a shell, no solid."""
    import cadquery as cq
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.TopoDS import TopoDS

    from torus_cad.kernel.writers.step import write_step

    sewing = BRepBuilderAPI_Sewing()
    for face in cq.Solid.makeBox(1, 1, 1).Faces()[:5]:
        sewing.Add(face.wrapped)
    sewing.Perform()
    return write_step(
        cq.Solid(BRepBuilderAPI_MakeSolid(TopoDS.Shell_s(sewing.SewedShape())).Solid()),
        path,
        "open",
        check_readback=False,
    )


@pytest.mark.parametrize(
    "kind, fragment",
    [
        ("two_solids", "holds 2 solids; it must hold exactly one"),
        ("open_box", "holds 0 solids; it must hold exactly one"),
        ("empty", "is not a STEP file"),
        ("text", "is not a STEP file"),
        ("broken", "does not read as STEP"),
        ("no_data", "holds no shape"),
        ("folder", "is not a regular file (a folder)"),
        ("missing", "cannot read STEP file"),
    ],
)
def test_a_bad_step_file_exits_2_with_one_line_naming_it_and_writes_nothing(
    tmp_path, capsys, kind, fragment
):
    path = tmp_path / f"{kind}.step"
    if kind == "two_solids":
        _two_solids(path)
    elif kind == "open_box":
        _open_box(path)
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "text":
        path.write_text("solid secret_content\nendsolid\n")
    elif kind == "broken":
        path.write_text("ISO-10303-21;\nHEADER;\nsecret_content garbage\n")
    elif kind == "no_data":  # a whole file whose DATA section is empty
        path.write_text(
            "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('secret_content'),'2;1');\n"
            "FILE_NAME('x','2026-01-01',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\n"
            "ENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n"
        )
    elif kind == "folder":
        path.mkdir()
    capsys.readouterr()
    out = tmp_path / "out"
    assert (
        main(["simulate", "--step", str(path), "--rpm", "1000", "--case-only", "--out", str(out)])
        == 2
    )
    captured = capsys.readouterr()
    assert (
        fragment in captured.err
        and repr(str(path)) in captured.err
        and captured.err.count("\n") == 1
    )
    assert "secret_content" not in captured.err + captured.out
    assert not out.exists()


def test_a_step_over_the_size_limit_is_refused(tmp_path, capsys, monkeypatch):
    import torus_cad.cfd_domain.step_body as step_body

    monkeypatch.setattr(step_body, "STEP_FILE_MAX_BYTES", 100)
    path = tmp_path / "big.step"
    path.write_bytes(b"ISO-10303-21;\n" + b" " * 200)
    with pytest.raises(ParameterError, match="is 214 bytes, over the limit of 100 bytes"):
        step_body.read_step_solid(path)


def test_step_names_are_sanitised():
    from torus_cad.cfd_domain.step_body import step_name

    assert step_name("dir/My prop (v2).step") == "My_prop__v2_"
    assert step_name("/x/..step") == "step_propeller"
    assert len(step_name("a" * 100 + ".stp")) == 64
    # a stem starting with what a name may not start with is cleaned, not refused as a bad name
    assert step_name("x/-dash.step") == "dash" and step_name("x/_under.step") == "under"
    from torus_cad.parameters import PropellerParameters

    for stem in ("-dash", "_under", "._-x"):
        PropellerParameters.from_dict({"name": step_name(f"{stem}.step")})  # a valid name


@pytest.mark.parametrize("axis", ["+z", "-z", "+x", "-x", "+y", "-y"])
def test_each_axis_is_turned_onto_plus_z(axis):
    import cadquery as cq

    from torus_cad.cfd_domain.step_body import Axis, place_on_z

    # a cylinder of radius 5 and length 2 along ``axis``, moved off the origin
    sign = -1.0 if axis[0] == "-" else 1.0
    direction = {"x": (sign, 0, 0), "y": (0, sign, 0), "z": (0, 0, sign)}[axis[1]]
    solid = cq.Solid.makeCylinder(5.0, 2.0, cq.Vector(3.0, -2.0, 1.0), cq.Vector(*direction))
    placed, centroid = place_on_z(solid, Axis(axis))
    box = placed.BoundingBox()
    assert (
        box.zlen == pytest.approx(2.0)
        and box.xlen == pytest.approx(10.0)
        and box.ylen == pytest.approx(10.0)
    )
    assert placed.Center().x == pytest.approx(0.0, abs=1e-9) and placed.Center().y == pytest.approx(
        0.0, abs=1e-9
    )
    assert centroid == pytest.approx(
        tuple(base + d for base, d in zip((3.0, -2.0, 1.0), direction))
    )


def test_the_design_step_measures_its_diameter_and_hub(design_step):
    from torus_cad.cfd_domain.step_body import load_step_propeller

    path, _ = design_step
    step = load_step_propeller(path)
    diameter = 2.0 * 22.5498  # the design's analytic tip radius (cfd.sizes.tip_radius), mm
    assert step.body.tip_diameter_mm == pytest.approx(diameter, rel=0.005)
    assert step.hub_radius_mm == pytest.approx(10.0, abs=0.1)  # hub.radius
    assert step.hub_length_mm == pytest.approx(20.0, abs=0.5)  # hub length, less its chamfers


def test_case_only_from_the_design_step_has_a_propeller_patch_and_its_diameter(
    design_step, tmp_path
):
    from torus_cad.cfd_domain.sizes import tip_radius
    from torus_cad.parameters import PropellerParameters

    path, _ = design_step
    out = tmp_path / "out"
    assert (
        main(
            [
                "simulate",
                "--step",
                str(path),
                "--rpm",
                "10000",
                "--case-only",
                "--processes",
                "1",
                "--mesher",
                "tet",
                "--out",
                str(out),
                "-q",
            ]
        )
        == 0
    )
    case = out / "torus_propeller_case"
    msh = (case / "cfd" / "torus_propeller_cfd_v2.msh").read_text()
    names = msh[msh.index("$PhysicalNames") : msh.index("$EndPhysicalNames")]
    assert '"propeller"' in names and '"rotating_zone"' in names
    cfd = json.loads((case / "cfd" / "torus_propeller_cfd.json").read_text())
    design = 2.0 * tip_radius(PropellerParameters())
    assert cfd["domain_mm"]["tip_diameter"] == pytest.approx(design, rel=0.005)
    assert (case / "Allrun").is_file()


def test_case_only_from_the_design_step_on_the_layered_route_meshes_the_step_s_own_surface(
    design_step, tmp_path
):
    import trimesh

    from torus_cad.cfd_domain.sizes import tip_radius
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.snappy import SURFACE_MM

    path, _ = design_step
    out = tmp_path / "out"
    assert (
        main(
            [
                "simulate",
                "--step",
                str(path),
                "--rpm",
                "10000",
                "--case-only",
                "--processes",
                "1",
                "--out",
                str(out),
                "-q",
            ]
        )
        == 0
    )
    case = out / "torus_propeller_case"
    surface = trimesh.load(case / SURFACE_MM)  # read by another library than the one that wrote it
    assert surface.is_watertight
    radius = np.hypot(surface.vertices[:, 0], surface.vertices[:, 1]).max()
    assert 2.0 * radius == pytest.approx(2.0 * tip_radius(PropellerParameters()), rel=0.005)
    assert "propeller" in (case / "system" / "snappyHexMeshDict").read_text()
    assert (case / "Allrun").is_file()


def _scaled_step(source, factor, path):
    """The STEP ``source`` scaled by ``factor`` about the origin, written to ``path``."""
    import cadquery as cq
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Pnt, gp_Trsf

    from torus_cad.cfd_domain.step_body import read_step_solid
    from torus_cad.kernel.writers.step import write_step

    scale = gp_Trsf()
    scale.SetScale(gp_Pnt(0.0, 0.0, 0.0), factor)
    solid = cq.Solid(BRepBuilderAPI_Transform(read_step_solid(source).wrapped, scale, True).Shape())
    # 1 km: edge tolerances read back too coarse
    return write_step(solid, path, path.stem, check_readback=False)


@pytest.mark.parametrize("diameter_mm", [1.0e6, 0.1])
def test_a_step_part_of_a_size_the_mesher_cannot_serve_is_refused_before_any_work(
    design_step, tmp_path, capsys, diameter_mm
):
    path = _scaled_step(design_step[0], diameter_mm / 45.1004, tmp_path / "scaled.step")
    out = tmp_path / "out"
    capsys.readouterr()
    assert (
        main(["simulate", "--step", str(path), "--rpm", "1", "--case-only", "--out", str(out)]) == 2
    )
    error = capsys.readouterr().err
    shown = re.search(r": tip diameter ([\d,.]+) mm is out of range; allowed \[5, 2000\] mm", error)
    assert (
        error.count("\n") == 1
        and shown
        and float(shown.group(1).replace(",", "")) == pytest.approx(diameter_mm, rel=1e-3)
    )
    assert repr(str(path)) in error and not out.exists()


def test_a_step_mesh_estimated_over_the_cell_limit_is_refused_with_the_estimate_and_the_limit(
    design_step, tmp_path, capsys
):
    out = tmp_path / "out"
    capsys.readouterr()
    assert (
        main(
            [
                "simulate",
                "--step",
                str(design_step[0]),
                "--rpm",
                "10000",
                "--case-only",
                "--level",
                "fine",
                "--surface-refinement",
                "4",
                "--out",
                str(out),
            ]
        )
        == 2
    )
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and not out.exists()
    assert re.search(
        r"the layered mesh would have about [\d,]+ cells and need about [\d.]+ GB of memory \(fine "
        r"level, --surface-refinement 4, a surface of "
        r"1.61 D\^2\), over the limit of 2,000,000 cells; "
        r"lower --surface-refinement or --level",
        error,
    )


def test_the_layered_estimate_errs_high_but_within_two_and_a_half_times_on_the_measured_meshes():
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.settings import Level, with_level
    from torus_cad.simulate.validity import estimate_layered_cells

    cfd = with_level(PropellerParameters(), Level.COARSE).cfd
    fine = with_level(PropellerParameters(), Level.FINE).cfd
    # the default design (area 3280 mm^2, 20 mm long, D 45.1 mm) and the APC 10x7 SF E63 (12,616
    # mm^2, 15.9 mm, 254 mm): their measured cells (docs/explanation/simulation-accuracy.md)
    for area, length, diameter, level, refinement, settings, measured in (
        (3280.0, 20.0, 45.1, Level.COARSE, 0, cfd, 51_822),
        (3280.0, 20.0, 45.1, Level.FINE, 0, fine, 131_098),
        (3280.0, 20.0, 45.1, Level.COARSE, 2, cfd, 628_012),
        (12_616.0, 15.9, 254.0, Level.COARSE, 0, cfd, 20_006),
        (12_616.0, 15.9, 254.0, Level.COARSE, 3, cfd, 289_804),
        (12_616.0, 15.9, 254.0, Level.COARSE, 4, cfd, 966_950),
    ):
        estimate = estimate_layered_cells(area, length, diameter, level, refinement, settings)
        assert 1.0 <= estimate / measured <= 2.5, (level, refinement, estimate, measured)
        # the same part at any size has the same cells
        assert estimate_layered_cells(
            area * 100.0, length * 10.0, diameter * 10.0, level, refinement, settings
        ) == pytest.approx(estimate, rel=1e-9)


def test_validity_flags_a_tiny_part_s_first_layer_and_leaves_the_default_design_alone():
    from torus_cad.simulate.settings import OperatingPoint
    from torus_cad.simulate.snappy import first_cell_height_m
    from torus_cad.simulate.validity import validity_flags

    point = OperatingPoint(10_000.0)
    # the default design at 10,000 rpm: first layer 13.4 um, y+ min 0.001, mean 1.13, max 17.8
    # measured
    default = first_cell_height_m(0.0451, 10_000.0, 0.0)
    assert default == pytest.approx(13.4e-6, rel=0.02)
    assert validity_flags(0.0451, point, default, {"min": 0.001, "mean": 1.13, "max": 17.8}) == []
    assert validity_flags(0.0451, point, default, None) == []
    # the 0.1 mm part at 1 rpm: a 4.8 mm first layer, y+ max 1.7e-5
    tiny = first_cell_height_m(1e-4, 1.0, 0.0)
    flags = validity_flags(
        1e-4, OperatingPoint(1.0), tiny, {"min": 1e-7, "mean": 5e-6, "max": 1.7e-5}
    )
    assert len(flags) == 3
    assert (
        flags[0].startswith(f"the first prism layer, {tiny * 1e3:.3g} mm, is ")
        and "over 0.01" in flags[0]
    )
    assert "Reynolds number at 0.75 R is" in flags[1] and "[1e+03, 1e+07]" in flags[1]
    assert "mean y+ on the propeller is 5e-06, outside [0.1, 30]" in flags[2]
    # a 2 m part at its tip Mach limit: still inside the model's range; a mean y+ of 40 is not
    assert validity_flags(
        2.0, OperatingPoint(1900.0), 1e-5, {"min": 1.0, "mean": 40.0, "max": 300.0}
    ) == [
        "the mean y+ on the propeller is 40, outside [0.1, 30] "
        "around the first layer's target 1: the wall is not "
        "resolved as sized"
    ]


def test_the_validity_flags_are_printed_as_warnings():
    from torus_cad.simulate.cli_output import summary_lines
    from torus_cad.simulate.pipeline import Result

    report = {"cells": None, "level": "coarse", "validity": ["the first prism layer is thick"]}
    assert summary_lines(Result({}, report))[-1] == "warning: the first prism layer is thick"
    assert not any(
        line.startswith("warning") for line in summary_lines(Result({}, {**report, "validity": []}))
    )


# -- runs (OpenFOAM)
# --------------------------------------------------------------------------------------

#: Iterations of the runs here: the coarse mesh's thrust settles within ~2 % by 120.
ITERATIONS = 120


@needs_openfoam
@pytest.mark.long
def test_thrust_search_finds_the_rpm_within_one_percent_on_one_mesh(tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(
            [
                "simulate",
                "--thrust",
                "0.05",
                "--iterations",
                str(ITERATIONS),
                "--processes",
                "1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    report = json.loads((out / "torus_propeller_performance.json").read_text())
    search = report["thrust_search"]
    assert search["within_tolerance"] and abs(report["thrust_n"] / 0.05 - 1.0) <= 0.01
    assert 1 <= len(search["runs"]) <= 5 and report["rpm"] == search["rpm"]
    assert report["figure_of_merit"] > 0.0 and report["power_w"] > 0.0
    assert f"rpm for 0.05 N: {search['rpm']:.0f} rpm" in printed and "N mm" in printed
    assert main(["verify", str(out), "torus_propeller_performance", "-q"]) == 0
    assert sorted(path.name for path in out.iterdir()) == [
        "torus_propeller_case",
        "torus_propeller_noise.csv",
        "torus_propeller_noise.png",
        "torus_propeller_performance.json",
        "torus_propeller_performance.png",
    ]
    # the chosen run's tones, in the rotor's plane
    assert report["noise"]["observers"][-1]["oaspl_db"] > 0.0


@needs_openfoam
@pytest.mark.long
def test_the_design_s_step_gives_the_design_s_thrust(design_step, tmp_path):
    path, _ = design_step
    arguments = ["--rpm", "10000", "--iterations", str(ITERATIONS), "--processes", "1", "-q"]
    assert main(["simulate", "--step", str(path), *arguments, "--out", str(tmp_path / "step")]) == 0
    assert main(["simulate", *arguments, "--out", str(tmp_path / "design")]) == 0
    step, design = (
        json.loads((tmp_path / kind / "torus_propeller_performance.json").read_text())
        for kind in ("step", "design")
    )
    assert step["step"]["tip_diameter_mm"] == pytest.approx(
        design["tip_diameter_m"] * 1000.0, rel=0.005
    )
    assert step["omega_rad_s"] == design["omega_rad_s"]
    # the default design is within the physics' range
    assert step["validity"] == [] and design["validity"] == []
    # the two meshes differ (the STEP has no trailing-edge size field: docs/how-to/simulate.md)
    assert step["thrust_n"] == pytest.approx(design["thrust_n"], rel=0.05)
    assert step["torque_nm"] == pytest.approx(design["torque_nm"], rel=0.05)


# -- what the terminal shows
# ----------------------------------------------------------------------------


def _level(thrust, torque):
    return {
        "cells": 1,
        "thrust_n": thrust,
        "torque_nm": torque,
        "ct": 0.3,
        "cp": 0.8,
        "converged": True,
    }


def test_the_convergence_study_prints_torque_in_n_mm_and_the_gci_in_percent():
    from torus_cad.simulate.cli_output import summary_lines
    from torus_cad.simulate.pipeline import Result

    thrust = richardson(0.0400, 0.0440, 0.0456, RATIO)
    report = {
        "levels": {
            "coarse": _level(0.0400, 0.00080),
            "medium": _level(0.0440, 0.00085),
            "fine": _level(0.0456, 0.00086),
        },
        "thrust_n": {
            "extrapolated": thrust.extrapolated,
            "observed_order": thrust.order,
            "converges_monotonically": True,
            "gci_fine": thrust.gci_fine,
            "gci_medium": thrust.gci_medium,
            "gci_asymptotic_ratio": thrust.asymptotic_ratio,
            "in_asymptotic_range": False,
        },
        "torque_nm": {"converges_monotonically": False},
    }
    thrust_line, torque_line = summary_lines(Result({}, report), convergence=True)
    assert thrust_line.startswith("thrust: coarse 0.04, medium 0.044, fine 0.0456 N; Richardson ")
    assert (
        f"GCI fine {100 * thrust.gci_fine:.2g} %" in thrust_line
        and "NOT in the asymptotic range" in thrust_line
    )
    assert torque_line.startswith(
        "torque: coarse 0.8, medium 0.85, fine 0.86 N mm; no Richardson extrapolation and "
        "no grid convergence index"
    )
    torque = richardson(0.00080, 0.00086, 0.00085, RATIO).report()
    _, torque_line = summary_lines(Result({}, {**report, "torque_nm": torque}), convergence=True)
    assert torque_line.endswith(
        f"uncertainty of the fine value {100 * 3 * 0.06 / 0.85:.2g} % (the levels spread over "
        f"{100 * 0.06 / 0.85:.2g} % of it; 3 times that bounds the error without an "
        "observed order)"
    )


def test_a_run_prints_torque_in_n_mm_and_variations_in_percent():
    from torus_cad.simulate.cli_output import summary_lines
    from torus_cad.simulate.pipeline import Result

    report = {
        "thrust_n": 0.05,
        "torque_nm": 0.000989,
        "power_w": 1.13,
        "rpm": 10932.0,
        "airspeed_m_s": 0.0,
        "advance_ratio": 0.0,
        "ct": 0.297,
        "cp": 0.819,
        "efficiency": None,
        "figure_of_merit": 0.139,
        "converged": True,
        "force_variation_last_10_percent": {"thrust": 0.014, "torque": 0.0041},
        "iterations": 120,
        "cells": 54844,
        "level": "coarse",
        "wall_seconds": 129.0,
        "fluid": {"name": "air"},
        "thrust_search": {
            "target_thrust_n": 0.05,
            "tolerance": 0.01,
            "rpm": 10932.0,
            "thrust_n": 0.0499,
            "within_tolerance": True,
            "runs": [{"rpm": 11919.0, "thrust_n": 0.0594}, {"rpm": 10932.0, "thrust_n": 0.0499}],
        },
    }
    lines = summary_lines(Result({}, report))
    assert lines[0] == "thrust search, 2 runs on one mesh: 11919 rpm 0.0594 N; 10932 rpm 0.0499 N"
    assert lines[1] == "rpm for 0.05 N: 10932 rpm (0.0499 N, within 1 %)"
    assert "torque 0.989 N mm" in lines[2] and "figure of merit 0.139" in lines[2]
    assert lines[3].startswith("converged: thrust varies 1.4 %, torque 0.41 % over the last 10 %")
    # a report without the wall shear's part (written before it was reported)
    assert len(lines) == 4
    report["viscous"] = {
        "thrust_n": -0.0001,
        "torque_nm": 0.0000189,
        "thrust_share": -0.002,
        "torque_share": 0.0191,
    }
    assert (
        summary_lines(Result({}, report))[4]
        == "wall shear: 1.9 % of the torque, -0.2 % of the thrust (the rest is pressure)"
    )


@pytest.mark.parametrize("axis", ["-x", "-y", "-z", "+x"])
def test_the_axis_is_taken_with_or_without_an_equals_sign(axis):
    from torus_cad.cli import _joined_signed_values, build_parser

    for argv in (
        ["simulate", "--step", "p.step", "--rpm", "1000", "--axis", axis],
        ["simulate", "--step", "p.step", "--rpm", "1000", f"--axis={axis}"],
    ):
        assert build_parser().parse_args(_joined_signed_values(argv)).axis == axis
