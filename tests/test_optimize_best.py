"""A study's best design is what its trial wrote: every trial writes the files its best set would
hold (the STL included), the best set is the trial's own files copied and ``torus-cad verify``
accepts it, and a best trial whose files are gone gives way to the next best with one line and exit
0."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip(
    "optuna",
    reason="the optimize extra is not installed: pip install -c constraints.txt -e '.[optimize]'",
)

ROOT = Path(__file__).resolve().parent.parent
BASE = ROOT / "examples" / "optimize" / "light_prop.toml"
TRIALS = 3


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        env=env,
        text=True,
        capture_output=True,
        timeout=900,
        check=False,
    )


def _run_study(
    folder: Path, trials: int, workers: int
) -> tuple[Path, Path, subprocess.CompletedProcess[str]]:
    """The issue's study, few trials: minimise mass_g over airfoil.thickness 0.2-0.6 and hub.radius
    8-12 with the thinnest wall >= 0.8 mm."""
    shutil.copy(BASE, folder / "light_prop.toml")
    (folder / "study.toml").write_text(
        '[study]\nname = "light"\nbase = "light_prop.toml"\ntrials '
        f'= {trials}\nsampler = "random"\nseed = 3\n\n'
        '[vary]\n"airfoil.thickness" = [0.2, 0.6]\n"hub.radius" = [8.0, 12.0]\n\n'
        '[[objective]]\nmetric = "mass_g"\ndirection = "minimize"\n\n'
        '[constraints]\n"printability.thinnest_wall_mm" = { min = 0.8 }\n'
    )
    out = folder / "out"
    run = _cli("optimize", str(folder / "study.toml"), "--out", str(out), "--workers", str(workers))
    return folder / "study.toml", out, run


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> tuple[Path, Path, subprocess.CompletedProcess[str]]:
    """The issue's study with TRIALS trials on 2 workers."""
    return _run_study(tmp_path_factory.mktemp("study"), TRIALS, 2)


def _summary(out: Path) -> dict:
    return json.loads((out / "light_study.json").read_text())


def _assert_best_set_is_the_trials_files(out: Path, run: subprocess.CompletedProcess[str]) -> None:
    assert run.returncode == 0, run.stderr
    best = _summary(out)["best"]
    assert len(best) == 1, run.stdout
    number = best[0]["number"]
    trial_dir = out / "trials" / str(number)
    assert {path.suffix for path in trial_dir.glob(f"trial_{number}.*")} >= {
        ".step",
        ".stl",
        ".json",
        ".toml",
    }
    verify = _cli("verify", str(out / "best"))
    assert verify.returncode == 0, verify.stderr
    for suffix in (".step", ".stl"):  # the very bytes the trial wrote and was judged on
        assert (out / "best" / f"light_best{suffix}").read_bytes() == (
            trial_dir / f"trial_{number}{suffix}"
        ).read_bytes()
    report = json.loads((out / "best" / "light_best.json").read_text())
    assert report["study_trial"]["number"] == number and report["mass_g"] == pytest.approx(
        best[0]["values"][0]
    )
    assert report["stl_mesh"]["self_intersecting_pairs"] == 0


@pytest.mark.long
def test_a_one_trial_study_publishes_its_trials_files_as_the_best_set(tmp_path):
    """The fast variant: one trial on one worker."""
    _, out, run = _run_study(tmp_path, 1, 1)
    _assert_best_set_is_the_trials_files(out, run)


@pytest.mark.long
def test_the_best_set_is_the_best_trials_own_files_and_verify_accepts_it(study):
    _assert_best_set_is_the_trials_files(*study[1:])


@pytest.mark.long
def test_a_best_trial_whose_files_are_gone_gives_way_to_the_next_best_with_one_line(study):
    study_file, out, run = study
    assert run.returncode == 0, run.stderr
    summary = _summary(out)
    number = summary["best"][0]["number"]
    with open(out / "results.csv", newline="") as handle:
        feasible = [row for row in csv.DictReader(handle) if row["feasible"] == "True"]
    if len(feasible) < 2:
        pytest.skip(
            f"the {TRIALS} trials hold {len(feasible)} feasible "
            "design(s): no next best to fall back to"
        )
    (out / "trials" / str(number) / f"trial_{number}.stl").unlink()
    shutil.rmtree(out / "best")
    # the study is full: results only
    again = _cli("optimize", str(study_file), "--out", str(out), "--workers", "1")
    assert again.returncode == 0, again.stderr
    lines = [
        line for line in again.stdout.splitlines() if f"trial {number} is not published" in line
    ]
    assert len(lines) == 1 and "trial_" + str(number) in lines[0], again.stdout
    after = _summary(out)
    assert after["best"][0]["number"] != number and after["not_published"] == [number]
    assert "next best trial" in again.stdout
    verify = _cli("verify", str(out / "best"))
    assert verify.returncode == 0, verify.stderr
