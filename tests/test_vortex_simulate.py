"""``simulate --solver vortex``: the vortex solver behind the same command, report and study levels
as OpenFOAM.

Run as a user runs it (a fresh ``python -m torus_cad`` process), the files read back by readers we
did not write (json, csv, Pillow), a small lattice (4 x 12) where the test is about the plumbing,
not the numbers."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip(
    "neuralfoil",
    reason="the simulate extra is not installed: pip install -c constraints.txt -e '.[simulate]'",
)

from PIL import Image

from torus_cad.optimize.metrics import NOISE_METRICS, PERFORMANCE_METRICS
from torus_cad.vortex.loading_files import LOADING_COLUMNS

SMALL = ["--chordwise", "4", "--spanwise", "12"]


def _simulate(out: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", "simulate", *args, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


@pytest.fixture(scope="module")
def vortex_run(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[Path, subprocess.CompletedProcess[str]]:
    out = tmp_path_factory.mktemp("vortex") / "out"
    return out, _simulate(out, "--solver", "vortex", "--rpm", "10000", *SMALL)


def test_the_vortex_run_writes_the_openfoam_routes_numbers_the_loading_the_wake_and_the_noise(
    vortex_run,
):
    out, done = vortex_run
    assert done.returncode == 0, done.stderr
    report = json.loads((out / "torus_propeller_performance.json").read_text())
    assert report["solver"] == "vortex" and report["rpm"] == 10000.0
    assert all(
        isinstance(report[key], (int, float)) for key in PERFORMANCE_METRICS if key != "efficiency"
    )
    # still air: a figure of merit
    assert report["efficiency"] is None and 0.0 < report["figure_of_merit"] < 1.0
    assert report["thrust_n"] > 0.0 and report["power_w"] > 0.0
    for observer in report["noise"]["observers"]:
        assert set(NOISE_METRICS) <= set(observer)
    with (out / "torus_propeller_loading.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert tuple(rows[0]) == LOADING_COLUMNS and len(rows) == 12  # one row a strip
    named = {entry["file"] for entry in report["files"].values()}
    assert {
        f"torus_propeller_{kind}"
        for kind in ("loading.csv", "loading.png", "wake.png", "noise.png", "noise.csv")
    } <= named
    for picture in ("loading", "wake", "noise"):
        with Image.open(out / f"torus_propeller_{picture}.png") as image:
            assert image.size[0] > 300 and image.size[1] > 300
    assert "thrust" in done.stdout and "vortex lattice 4 x 12" in done.stdout
    verify = subprocess.run(
        [sys.executable, "-m", "torus_cad", "verify", str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    # a whole set, every file as the report seals it
    assert verify.returncode == 0, verify.stdout + verify.stderr


def test_both_solvers_answer_a_study_through_the_same_report_keys(vortex_run):
    """The seam: every performance metric a study may name reads from the vortex report as from
    OpenFOAM's."""
    from torus_cad.optimize.metrics import metric_value

    out, _ = vortex_run
    report = json.loads((out / "torus_propeller_performance.json").read_text())
    for key in PERFORMANCE_METRICS:
        if key != "efficiency":  # None in still air, on both routes
            assert metric_value(f"performance.{key}", {}, report) == pytest.approx(
                float(report[key])
            )
    assert metric_value("performance.noise[1:90].oaspl_dba", {}, report) < 120.0


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["--solver", "vortex", "--rpm", "10000", "--level", "fine"], "--level"),
        (["--solver", "vortex", "--rpm", "10000", "--chordwise", "40"], "--chordwise = 40"),
        (["--solver", "vortex", "--rpm", "-5"], "--rpm"),
        (["--rpm", "10000", "--spanwise", "20"], "--spanwise"),
        (
            ["--solver", "vortex", "--rpm", "10000", "--convergence", "--spanwise", "61"],
            "--spanwise = 61 is out of range with --convergence, whose finest lattice has 2 times "
            "as many; allowed [6, 60]",
        ),
    ],
)
def test_bad_vortex_options_exit_2_naming_the_option_and_write_nothing(tmp_path, args, named):
    done = _simulate(tmp_path / "out", *args)
    assert done.returncode == 2 and named in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_the_vortex_convergence_study_runs_three_finer_lattices_and_bounds_the_fine_value(
    tmp_path,
):
    """--solver vortex --convergence: the given lattice and two each sqrt 2 finer in every count,
    each run a whole set of its own, and the OpenFOAM study's report, whose uncertainty of the fine
    value covers Richardson's extrapolation, or every level where there is none."""
    out = tmp_path / "out"
    done = _simulate(out, "--solver", "vortex", "--rpm", "10000", "--convergence", *SMALL)
    assert done.returncode == 0, done.stderr
    study = json.loads((out / "torus_propeller_convergence.json").read_text())
    lattices = []
    for level in ("coarse", "medium", "fine"):
        run = json.loads((out / level / "torus_propeller_performance.json").read_text())
        lattice = run["lattice"]
        lattices.append((lattice["chordwise"], lattice["spanwise"], lattice["wake_steps_per_turn"]))
        assert study["levels"][level]["thrust_n"] == run["thrust_n"]
        assert study["levels"][level]["torque_nm"] == run["torque_nm"]
    assert lattices == [(4, 12, 24), (6, 17, 34), (8, 24, 48)]
    for key in ("thrust_n", "torque_nm"):
        entry, fine = study[key], study["levels"]["fine"][key]
        if entry["converges_monotonically"]:
            covered = [entry["extrapolated"]]
        else:
            covered = [values[key] for values in study["levels"].values()]
        for value in covered:
            assert abs(value - fine) <= entry["uncertainty_fine"] * abs(fine) * (1 + 1e-9)
    assert "thrust: coarse" in done.stdout and "torque: coarse" in done.stdout


def test_the_vortex_thrust_search_finds_the_rpm_for_the_thrust(tmp_path):
    done = _simulate(tmp_path / "out", "--solver", "vortex", "--thrust", "0.03", *SMALL)
    assert done.returncode == 0, done.stderr
    report = json.loads((tmp_path / "out" / "torus_propeller_performance.json").read_text())
    search = report["thrust_search"]
    assert search["within_tolerance"] and report["rpm"] == pytest.approx(search["rpm"])
    assert report["thrust_n"] == pytest.approx(0.03, rel=0.01)


def test_a_study_level_vortex_runs_simulate_with_the_vortex_solver_and_levels_go_cheapest_first(
    tmp_path,
):
    from torus_cad.errors import ParameterError
    from torus_cad.optimize import parse_study
    from torus_cad.optimize.trial_simulation import _command

    command = _command(
        Path("d.toml"), {"rpm": 8000.0, "level": "vortex", "iterations": 50}, tmp_path, None
    )
    assert command[command.index("--solver") + 1] == "vortex" and "--level" not in command
    assert "--iterations" not in command  # OpenFOAM's
    data = {
        "study": {"trials": 4},
        "vary": {"airfoil.thickness": [0.2, 0.6]},
        "objective": [{"metric": "performance.power_w"}],
    }
    spec = parse_study({**data, "simulate": {"rpm": 8000.0, "levels": ["vortex", "medium"]}})
    assert spec.levels == ("vortex", "medium")
    with pytest.raises(ParameterError, match="cheapest to the finest"):
        parse_study({**data, "simulate": {"rpm": 8000.0, "levels": ["coarse", "vortex"]}})


def test_the_shipped_quiet_study_on_the_vortex_solver_runs_every_trial_on_it():
    from torus_cad.optimize import read_study_file

    spec = read_study_file(
        Path(__file__).resolve().parent.parent / "examples" / "optimize_quiet_vortex.toml"
    )
    assert spec.levels == ("vortex",) and spec.trials >= 300
    assert spec.simulate["thrust"] == 1.0 and spec.simulate["observers"] == ["1:90"]
