"""`torus-cad simulate`: the OpenFOAM case reads back through foamlib with the right rotation; the
physics checks on the coarse level (mirror pair, rpm scaling, still propeller, momentum balance);
bad input, a missing OpenFOAM and a diverging run are one clear line with the right exit code."""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from cli_exit import exit_code
from openfoam_marks import needs_openfoam

from torus_cad.cli import main

foamlib = pytest.importorskip("foamlib")
pytest.importorskip("gmsh")

from torus_cad.parameters import PropellerParameters  # noqa: E402
from torus_cad.parameters.design import Handedness  # noqa: E402
from torus_cad.simulate.coefficients import force_variation, performance, richardson  # noqa: E402
from torus_cad.simulate.history import History  # noqa: E402
from torus_cad.simulate.pipeline import Request, simulate  # noqa: E402
from torus_cad.simulate.run import divergence  # noqa: E402
from torus_cad.simulate.settings import Level, Mesher, OperatingPoint, TurbulenceModel  # noqa: E402

RPM = 10000.0
#: Iterations of the physics runs: thrust settles within ~2 % by 120 on the coarse mesh.
ITERATIONS = 150
PROCESSES = 2 if len(os.sched_getaffinity(0)) > 1 else 1


# -- numbers without OpenFOAM ---------------------------------------------------------------------


def test_richardson_recovers_the_order_and_limit_of_an_exact_power_series():
    ratio, order, limit = 2.0 ** (1.0 / 3.0), 1.7, 0.25
    coarse, medium, fine = (limit + 0.04 * (ratio**power) ** order for power in (2, 1, 0))
    result = richardson(coarse, medium, fine, ratio)
    assert (
        result.converges_monotonically
        and result.order == pytest.approx(order)
        and result.extrapolated == pytest.approx(limit)
    )
    assert richardson(1.0, 2.0, 1.5, ratio).extrapolated is None  # oscillating: no extrapolation


def test_coefficients_follow_the_propeller_convention():
    point = OperatingPoint(rpm=6000.0, airspeed_m_s=5.0)
    result = performance(thrust_n=1.0, torque_nm=0.02, point=point, diameter_m=0.1)
    n = 100.0
    assert result.power_w == pytest.approx(0.02 * 2 * math.pi * n)
    assert result.ct == pytest.approx(1.0 / (1.225 * n**2 * 0.1**4))
    assert result.cp == pytest.approx(result.power_w / (1.225 * n**3 * 0.1**5))
    assert result.advance_ratio == pytest.approx(0.5)
    assert (
        result.efficiency == pytest.approx(0.5 * result.ct / result.cp)
        and result.figure_of_merit is None
    )
    hover = performance(1.0, 0.02, OperatingPoint(6000.0), 0.1)
    # the figure of merit is momentum theory's ideal power T^1.5 / sqrt(2 rho A) over the power, A
    # the tip circle
    ideal_w = 1.0**1.5 / math.sqrt(2.0 * 1.225 * math.pi * 0.1**2 / 4.0)
    assert hover.efficiency is None and hover.figure_of_merit == pytest.approx(
        ideal_w / hover.power_w
    )


def test_omega_is_negative_about_z_for_cw_and_positive_for_its_mirror_image():
    point = OperatingPoint(rpm=600.0)
    assert point.omega_rad_s(Handedness.CW) == pytest.approx(-20 * math.pi)
    assert point.omega_rad_s(Handedness.CCW) == pytest.approx(20 * math.pi)


def test_divergence_names_the_iteration_and_the_residual():
    history = History(
        iterations=np.arange(1, 4),
        force_n=np.ones((3, 3)),
        moment_nm=np.ones((3, 3)),
        residual_iterations=np.arange(1, 4),
        residuals={"p": np.array([1.0, 0.5, 4e5])},
    )
    assert divergence(history) == "iteration 3: p residual 4e+05 (limit 1000)"
    history.residuals["p"][2] = 0.1
    history.force_n[1, 2] = math.nan
    assert divergence(history) == "iteration 2: the propeller's force is not finite"
    assert force_variation(np.r_[np.zeros(90), np.full(5, 2.0), np.full(5, 2.02)]) == pytest.approx(
        0.02 / 2.01
    )


@pytest.mark.parametrize(
    "arguments, fragment",
    [
        (["--rpm", "-1"], "--rpm = -1 is out of range; allowed [0, "),
        (["--rpm", "1e6"], "--rpm = 1e+06 is out of range"),
        (["--rpm", "nan"], "--rpm = nan is out of range"),
        (
            ["--rpm", "1000", "--airspeed", "500"],
            "--airspeed = 500 m/s is out of range; allowed [0, 100] m/s",
        ),
        (
            ["--rpm", "1000", "--iterations", "0"],
            "--iterations = 0 is out of range; allowed [1, 20000]",
        ),
        (["--rpm", "1000", "--processes", "999"], "--processes = 999 is out of range"),
        (["--rpm", "1000", "--time-limit", "0"], "--time-limit = 0 s is out of range"),
        (
            ["--rpm", "1000", "--airspeed", "5", "--set", "cfd.inlet_side='-z'"],
            "cfd.inlet_side = '-z'",
        ),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, arguments, fragment):
    out = tmp_path / "out"
    assert exit_code(["simulate", *arguments, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


def test_without_openfoam_one_line_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # no simpleFoam on it
    out = tmp_path / "out"
    assert main(["simulate", "--rpm", "1000", "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "apt-get install --no-install-recommends openfoam" in error
    assert not out.exists()


# -- the case
# ---------------------------------------------------------------------------------------


def test_case_only_writes_a_case_foamlib_reads_back_with_the_mirror_rotation(tmp_path):
    params = PropellerParameters(handedness=Handedness.CCW)
    result = simulate(
        Request(
            params, OperatingPoint(RPM), Level.COARSE, iterations=50, processes=2, case_only=True
        ),
        tmp_path,
    )
    case = foamlib.FoamCase(result.paths["case"])
    mrf = case.file("constant/MRFProperties")["MRF1"]
    assert mrf["cellZone"] == "rotating_zone" and mrf["omega"] == pytest.approx(RPM * math.pi / 30)
    assert list(mrf["axis"]) == [0, 0, 1]
    assert case.control_dict["endTime"] == 50
    assert case.file("system/decomposeParDict")["numberOfSubdomains"] == 2
    assert case.turbulence_properties["RAS"]["RASModel"] == "kOmegaSST"
    assert case[0]["nut"].boundary_field["propeller"]["type"] == "nutkWallFunction"
    assert case.control_dict["functions"]["yPlus"]["type"] == "yPlus"
    allrun = (result.paths["case"] / "Allrun").read_text()
    assert "snappyHexMesh -overwrite" in allrun and "mpiexec -n 2 simpleFoam -parallel" in allrun
    assert "gmshToFoam" not in allrun and "grep -q 'Mesh OK' log.checkMesh" in allrun
    assert (result.paths["case"] / "constant" / "triSurface" / "propeller_mm.stl").is_file()
    layers = case.file("system/snappyHexMeshDict")["addLayersControls"]
    assert 0.0 < layers["firstLayerThickness"] < 1e-4  # m: y+ 1 on a 45 mm propeller at 10,000 rpm
    assert sorted(path.name for path in tmp_path.iterdir()) == ["torus_propeller_case"]
    assert not (result.paths["case"] / "constant" / "polyMesh").exists()  # Allrun makes it


def test_the_transition_model_case_carries_its_two_fields_from_the_inflow_turbulence(tmp_path):
    result = simulate(
        Request(
            PropellerParameters(),
            OperatingPoint(RPM),
            Level.COARSE,
            iterations=50,
            processes=1,
            case_only=True,
            turbulence=TurbulenceModel.K_OMEGA_SST_LM,
        ),
        tmp_path,
    )
    case = foamlib.FoamCase(result.paths["case"])
    assert case.turbulence_properties["RAS"]["RASModel"] == "kOmegaSSTLM"
    re_theta, gamma = case[0]["ReThetat"], case[0]["gammaInt"]
    # Langtry and Menter's onset correlation at 1 % inflow turbulence: Re_theta_t = 1173.51 -
    # 589.428 + 0.2196
    assert (
        re_theta.internal_field == pytest.approx(584.30, abs=0.01) and gamma.internal_field == 1.0
    )
    assert (
        re_theta.boundary_field["propeller"]["type"]
        == gamma.boundary_field["propeller"]["type"]
        == "zeroGradient"
    )
    schemes, solution = case.fv_schemes, case.fv_solution
    assert {"div(phi,ReThetat)", "div(phi,gammaInt)"} <= set(schemes["divSchemes"])
    assert "ReThetat" in case.control_dict["functions"]["residuals"]["fields"]
    assert any("ReThetat" in key for key in solution["solvers"])


def test_the_tet_mesher_stays_reachable(tmp_path):
    result = simulate(
        Request(
            PropellerParameters(),
            OperatingPoint(RPM),
            Level.COARSE,
            iterations=50,
            processes=1,
            case_only=True,
            mesher=Mesher.TET,
        ),
        tmp_path,
    )
    allrun = (result.paths["case"] / "Allrun").read_text()
    assert "gmshToFoam cfd/torus_propeller_cfd_v2.msh" in allrun and "snappyHexMesh" not in allrun
    assert 0 < result.report["cells"] <= 60_000


# -- physics on the coarse level
# --------------------------------------------------------------------


def _run(out, params, rpm, mesh_from=None, iterations=ITERATIONS):
    request = Request(
        params, OperatingPoint(rpm), Level.COARSE, iterations, PROCESSES, mesh_from=mesh_from
    )
    return simulate(request, out).report


@pytest.fixture(scope="module")
def cw(tmp_path_factory):
    out = tmp_path_factory.mktemp("cw")
    assert (
        main(
            [
                "simulate",
                "--rpm",
                f"{RPM:g}",
                "--iterations",
                str(ITERATIONS),
                "--processes",
                str(PROCESSES),
                "--out",
                str(out),
                "-q",
            ]
        )
        == 0
    )
    return out, json.loads((out / "torus_propeller_performance.json").read_text())


@needs_openfoam
def test_the_published_set_verifies_and_thrust_is_positive_for_the_design_rotation(cw):
    out, report = cw
    assert main(["verify", str(out), "torus_propeller_performance", "-q"]) == 0
    assert report["thrust_n"] > 0.0 and report["torque_nm"] > 0.0 and report["power_w"] > 0.0
    assert report["cells"] <= 60_000 and report["level"] == "coarse"
    assert (
        report["fluid"]["density_kg_m3"] == 1.225 and report["fluid"]["viscosity_m2_s"] == 1.46e-5
    )
    assert report["efficiency"] is None and report["figure_of_merit"] > 0.0
    assert (out / "torus_propeller_case" / "Allrun").is_file()


@needs_openfoam
def test_the_default_mesh_has_prism_layers_checkmesh_accepts_and_y_plus_is_reported(cw):
    _, report = cw
    mesh = report["mesh"]
    assert report["mesher"] == "snappy" and mesh["mesh_ok"] and mesh["cells"] == report["cells"]
    assert mesh["cell_types"]["prisms"] > 0 and sum(mesh["cell_types"].values()) == report["cells"]
    assert mesh["layers"]["mean_layers"] > 1.0
    y_plus = report["y_plus"]
    assert all(math.isfinite(y_plus[key]) for key in ("min", "mean", "max"))
    assert 0.0 <= y_plus["min"] <= y_plus["mean"] <= y_plus["max"]
    # the first layer is sized for y+ 1 where layers were added; the mean stays in the viscous
    # sublayer
    assert y_plus["mean"] < 5.0


@needs_openfoam
def test_the_wall_shear_part_is_reported_and_the_rest_is_the_blade_surfaces_pressure_thrust(cw):
    """The report's viscous part: the shear resists the rotation and is a minor share of the torque
    on a lifting blade; thrust less its viscous part equals the pressure integrated over the blade
    surface the case wrote (the noise model's own reading of the VTK surface, not the forces
    function object)."""
    _, report = cw
    viscous = report["viscous"]
    assert 0.0 < viscous["torque_share"] < 0.5 and abs(viscous["thrust_share"]) < 0.2
    assert viscous["torque_nm"] == pytest.approx(viscous["torque_share"] * report["torque_nm"])
    pressure_thrust = report["thrust_n"] - viscous["thrust_n"]
    assert report["noise"]["surface_pressure_thrust_n"] == pytest.approx(pressure_thrust, rel=1e-3)


@needs_openfoam
def test_the_report_gives_finite_tonal_noise_at_the_default_observers_and_the_set_holds_its_signals(
    cw,
):
    """The noise entry (torus_cad.acoustics, from the blade surface pressure the case wrote): finite
    levels at 1 m, 0 / 30 / 60 / 90 degrees, no tone on the axis, the loudest in the rotor's plane;
    the surface's pressure thrust is the forces function object's thrust less its small viscous
    part; the signals CSV (read by numpy) covers one revolution."""
    out, report = cw
    noise = report["noise"]
    assert [(entry["distance_m"], entry["angle_deg"]) for entry in noise["observers"]] == [
        (1.0, 0.0),
        (1.0, 30.0),
        (1.0, 60.0),
        (1.0, 90.0),
    ]
    assert noise["blades"] == 3 and noise["blade_passing_frequency_hz"] == pytest.approx(
        3 * RPM / 60.0
    )
    off_axis = noise["observers"][1:]
    for entry in off_axis:
        assert math.isfinite(entry["oaspl_db"]) and math.isfinite(entry["oaspl_dba"])
        assert len(entry["harmonics"]) == 10 and all(
            math.isfinite(row["spl_db"]) for row in entry["harmonics"][:3]
        )
        assert entry["oaspl_dba"] < entry["oaspl_db"]  # the blade-passing tones lie below 1 kHz
    # a steady rotor's tones cancel there: silent, not a round-off level
    on_axis = noise["observers"][0]
    assert on_axis["silent"] and on_axis["oaspl_db"] is None and on_axis["oaspl_dba"] is None
    assert not any(entry["silent"] for entry in off_axis)
    assert off_axis[0]["oaspl_db"] < off_axis[1]["oaspl_db"] < off_axis[2]["oaspl_db"]
    assert noise["surface_pressure_thrust_n"] == pytest.approx(report["thrust_n"], rel=0.1)
    signals = np.loadtxt(out / "torus_propeller_noise.csv", delimiter=",", skiprows=1)
    assert signals.shape == (noise["samples_per_revolution"], 5)
    assert signals[-1, 0] == pytest.approx(60.0 / RPM * (1.0 - 1.0 / len(signals)))
    assert set(report["files"]) >= {"png", "noise_png", "noise_csv"}


@needs_openfoam
def test_thrust_from_the_surface_agrees_with_the_momentum_balance(cw):
    _, report = cw
    balance = report["momentum_balance"]
    assert abs(balance["relative_difference"]) < 0.10, (report["thrust_n"], balance)


@needs_openfoam
def test_mirror_image_at_the_same_rpm_gives_the_same_thrust_and_torque(cw, tmp_path):
    _, report = cw
    mirror = _run(tmp_path, PropellerParameters(handedness=Handedness.CCW), RPM)
    assert mirror["omega_rad_s"] == pytest.approx(-report["omega_rad_s"])
    # The mirror gets its own mesh, not the mirror of cw's: the two differ by their discretisation
    # (docs/how-to/simulate.md), not by a sign or an axis.
    assert mirror["thrust_n"] == pytest.approx(report["thrust_n"], rel=0.05)
    assert mirror["torque_nm"] == pytest.approx(report["torque_nm"], rel=0.05)


@needs_openfoam
def test_doubling_the_rpm_in_still_air_scales_thrust_by_4(cw, tmp_path):
    out, report = cw
    doubled = _run(tmp_path, PropellerParameters(), 2 * RPM, mesh_from=out / "torus_propeller_case")
    assert doubled["cells"] == report["cells"]  # the same mesh
    assert doubled["thrust_n"] / report["thrust_n"] == pytest.approx(4.0, rel=0.15)


@needs_openfoam
def test_a_still_propeller_in_still_air_gives_no_thrust(cw, tmp_path):
    out, report = cw
    still = _run(
        tmp_path, PropellerParameters(), 0.0, mesh_from=out / "torus_propeller_case", iterations=20
    )
    assert abs(still["thrust_n"]) < 0.01 * report["thrust_n"]
    assert still["ct"] is None and still["advance_ratio"] is None


# -- faults
# -------------------------------------------------------------------------------------------


def _again(out, *arguments):
    return [
        "simulate",
        "--rpm",
        f"{RPM:g}",
        "--processes",
        "1",
        "--mesh-from",
        str(out / "torus_propeller_case"),
        *arguments,
    ]


@needs_openfoam
def test_a_diverging_run_exits_1_naming_the_iteration_and_residual_and_keeps_the_case(
    cw, tmp_path, capsys, monkeypatch
):
    out, _ = cw
    # every residual above 1e-12 counts as divergence: the watcher stops the solver at its first
    # iteration
    monkeypatch.setattr("torus_cad.simulate.run.SIMULATE_DIVERGENCE_RESIDUAL", 1e-12)
    target = tmp_path / "diverged"
    assert main(_again(out, "--iterations", "50", "--out", str(target))) == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and re.search(
        r"simpleFoam diverged at iteration \d+: \w+ residual \S+ \(limit 1e-12\)", error
    ), error
    assert f"the case is kept in {target / 'torus_propeller_case_failed'}" in error
    assert (target / "torus_propeller_case_failed" / "log.simpleFoam").is_file()
    assert [path.name for path in target.iterdir()] == ["torus_propeller_case_failed"]


@needs_openfoam
def test_a_run_over_its_time_budget_is_refused_before_the_solver_starts(cw, tmp_path, capsys):
    out, _ = cw
    target = tmp_path / "refused"
    assert (
        main(_again(out, "--iterations", "20000", "--time-limit", "10", "--out", str(target))) == 2
    )
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and "the solver would take about" in error
        and "--time-limit = 10 s" in error
    )
    assert not target.exists() or not list(target.iterdir())


@needs_openfoam
def test_sigterm_stops_the_solver_and_publishes_nothing(cw, tmp_path):
    psutil = pytest.importorskip("psutil")
    out, _ = cw
    target = tmp_path / "stopped"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(
            [str(Path(__file__).resolve().parent.parent), os.environ.get("PYTHONPATH", "")]
        ),
    }
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "torus_cad",
            *_again(out, "--iterations", "2000", "--out", str(target)),
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 180
    while not list(
        target.glob(".*staging*/torus_propeller_case/postProcessing/residuals/0/solverInfo.dat")
    ):
        assert process.poll() is None and time.monotonic() < deadline, (
            process.stderr.read() if process.stderr else ""
        )
        time.sleep(0.5)
    solvers = psutil.Process(process.pid).children(recursive=True)
    assert any(child.name() == "simpleFoam" for child in solvers)
    process.send_signal(signal.SIGTERM)
    _, error = process.communicate(timeout=60)
    assert process.returncode == 143 and "interrupted by SIGTERM" in error
    _, alive = psutil.wait_procs(solvers, timeout=10)
    assert not alive
    assert not target.exists()  # nothing published, and the --out folder it made is removed again
