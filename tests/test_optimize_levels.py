"""Studies that find better propellers: a target thrust, noise at an observer and mass as objectives
and constraints, checked when the study file is read; multi-fidelity studies whose cheap level
screens and whose good designs climb to a finer one, a pruned trial recorded as pruned and never
simulated at the finer level.

The fast tests run the study loop with a stand-in for the build and ``torus-cad simulate``
(:func:`stand_in_without_build`: a performance report made up from the design) so that the loop's
bookkeeping costs seconds; the long ones run OpenFOAM."""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

optuna = pytest.importorskip(
    "optuna",
    reason="the optimize extra is not installed: pip install -c constraints.txt -e '.[optimize]'",
)

from optuna.trial import TrialState  # noqa: E402

from torus_cad.batch.outcome import DesignResult, Outcome  # noqa: E402
from torus_cad.errors import ParameterError  # noqa: E402
from torus_cad.optimize import parse_study, read_study_file, run_study  # noqa: E402
from torus_cad.optimize.metrics import metric_value  # noqa: E402
from torus_cad.optimize.storage import open_storage  # noqa: E402
from torus_cad.optimize.study import dominated_at_level  # noqa: E402
from torus_cad.optimize.study_file import Direction, Objective  # noqa: E402
from torus_cad.optimize.trial_job import TrialTask  # noqa: E402
from torus_cad.optimize.trial_simulation import simulate_unavailable  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
BASE = ROOT / "examples" / "optimize" / "light_prop.toml"
QUIET = ROOT / "examples" / "optimize_quiet.toml"

#: The stand-in's power grows with the airfoil's thickness, and is 10 % higher on the finer level.
LEVEL_FACTOR = {"coarse": 1.0, "medium": 1.1, "fine": 1.2}


def stand_in_without_build(task: TrialTask) -> DesignResult:
    """A worker's job for the fast tests, in place of the build and OpenFOAM: stage 0 writes a build
    report holding only ``mass_g`` (the loop's bookkeeping in a second per trial; the trials have no
    output set to publish), and every stage :func:`_stand_in_report` at its level."""
    folder = Path(str(task.folder))
    if task.stage == 0:
        (folder / f"{task.design_id}.json").write_text(json.dumps({"mass_g": 1.0}))
    _stand_in_report(task)
    return DesignResult(task.design_id, Outcome.VALID)


def _stand_in_report(task: TrialTask) -> None:
    """A performance report at the stage's level, made up from the design: power 1 + 10 t W (t the
    airfoil thickness) times the level's factor, the target thrust met at 5000 / t rpm, 30 + 5 t
    dB(A) at 1 m, 90 deg."""
    settings = task.simulate or {}
    folder = Path(str(task.folder)) / task.simulate_dir
    folder.mkdir(parents=True, exist_ok=True)
    thickness = float(task.parameters["airfoil"]["thickness"])
    report = {
        "thrust_n": settings.get("thrust", 1.0),
        "rpm": 5000.0 / thickness,
        "power_w": (1.0 + 10.0 * thickness) * LEVEL_FACTOR[settings["level"]],
        "level": settings["level"],
        "noise": {
            "observers": [
                {
                    "distance_m": 1.0,
                    "angle_deg": 90.0,
                    "oaspl_db": 40.0 + thickness,
                    "oaspl_dba": 30.0 + 5.0 * thickness,
                }
            ]
        },
    }
    (folder / f"{task.design_id}_performance.json").write_text(json.dumps(report))


def _data(**tables) -> dict:
    data = {
        "study": {"trials": 4},
        "vary": {"airfoil.thickness": [0.2, 0.6]},
        "objective": [{"metric": "performance.power_w"}],
        "simulate": {"thrust": 1.0},
    }
    data.update(tables)
    return data


# -- the study file
# ----------------------------------------------------------------------------------


def test_the_shipped_quiet_study_reads_with_its_target_thrust_noise_objective_and_levels():
    spec = read_study_file(QUIET)
    assert [o.metric for o in spec.objectives] == [
        "performance.power_w",
        "performance.noise[1:90].oaspl_dba",
    ]
    assert (
        spec.simulate is not None
        and spec.simulate["thrust"] == 1.0
        and spec.simulate["observers"] == ["1:90"]
    )
    assert (
        spec.levels == ("coarse", "medium")
        and spec.pruner is not None
        and spec.pruner.kind.value == "dominated"
    )
    assert spec.base.diameter == 127.0 and spec.base.blades == 3
    # the target thrust is a constraint within the tolerance, and the rpm found is recorded with
    # every trial
    thrust = [c for c in spec.constraints if c.metric == "performance.thrust_n"]
    assert thrust and thrust[0].low == pytest.approx(0.98) and thrust[0].high == pytest.approx(1.02)
    assert "performance.rpm" in spec.metrics
    # the how-to shows the file as it is shipped
    text = QUIET.read_text()
    assert text[text.index("[study]") :] in (ROOT / "docs" / "how-to" / "optimize.md").read_text()


@pytest.mark.parametrize(
    ("tables", "message"),
    [
        (
            {"simulate": {"thrust": 1.0, "rpm": 8000.0}},
            "simulate.rpm = 8000 and simulate.thrust = 1 N: give one",
        ),
        (
            {"simulate": {"thrust": -1.0}},
            "simulate.thrust = -1 is out of range; allowed [0, 1e+06] N",
        ),
        # simulate's own limits, before the first trial: the airspeed named (not the thrust), the
        # tip-Mach rpm
        (
            {"simulate": {"thrust": 1.0, "airspeed": 500.0}},
            "simulate.airspeed = 500 is out of range; allowed [0, 100] m/s",
        ),
        (
            {"simulate": {"rpm": 90000.0}},
            "simulate.rpm = 90000 is out of range; allowed (0, 86481] rpm",
        ),
        ({"simulate": {}}, "give [simulate] rpm = ... (> 0) or thrust = ..."),
        (
            {"simulate": {"thrust": 1.0, "thrust_tolerance": 0.5}},
            "simulate.thrust_tolerance = 0.5 is out of range; allowed [0.001, 0.2]",
        ),
        (
            {"simulate": {"rpm": 8000.0, "thrust_runs": 3}},
            "simulate.thrust_runs applies only with simulate.thrust",
        ),
        (
            {"simulate": {"thrust": 1.0, "levels": ["medium", "coarse"]}},
            "simulate.levels = ['medium', 'coarse'] must "
            "name levels from the cheapest to the finest",
        ),
        (
            {"simulate": {"thrust": 1.0, "levels": ["coarse", "huge"]}},
            "simulate.levels[1]: Input should be 'vortex', 'coarse', 'medium' or 'fine'",
        ),
        (
            {"simulate": {"thrust": 1.0, "level": "coarse", "levels": ["coarse", "medium"]}},
            "simulate.level and simulate.levels: give one",
        ),
        (
            {"simulate": {"thrust": 1.0, "iterations": -1}},
            "simulate.iterations = -1 is out of range",
        ),
        (
            {"pruner": {"kind": "median"}},
            "[pruner] applies only with [simulate] levels of two or more",
        ),
        (
            {
                "simulate": {"thrust": 1.0, "levels": ["coarse", "medium"]},
                "pruner": {"kind": "halfing"},
            },
            "pruner.kind: Input should be 'median', 'halving', 'dominated' or 'none'",
        ),
        (
            {
                "simulate": {"thrust": 1.0, "levels": ["coarse", "medium"]},
                "pruner": {"kind": "median"},
                "objective": [{"metric": "performance.power_w"}, {"metric": "mass_g"}],
            },
            "pruner.kind = 'median' judges one objective (optuna's "
            "pruners take one value); with 2 objectives use 'dominated'",
        ),
        (
            {"objective": [{"metric": "performance.noise[1:190].oaspl_dba"}]},
            "objective[0].metric = 'performance.noise[1:190].oaspl_dba': "
            "the observer '1:190' is out of range",
        ),
        (
            {"objective": [{"metric": "performance.noise[1:90].dba"}]},
            "'dba' is not a number of an observer's noise; did you mean 'oaspl_dba'?",
        ),
        (
            {"objective": [{"metric": "performance.noise.dba"}]},
            "is not a noise number; name the observer as simulate --observer does",
        ),
        (
            {"study": {"trials": 4, "sampler": "cmaes"}},
            "study.sampler = 'cmaes' cannot take [simulate] thrust",
        ),
        # a range's NaN or infinite end: the parameter's own range named, not the type the schema
        # tried
        (
            {"vary": {"hub.length": [math.nan, 140.0]}},
            "vary.'hub.length' low must be a finite number in (2, 2000] mm, got nan",
        ),
        (
            {"vary": {"blades": [2, math.inf]}},
            "vary.'blades' high must be a whole number in [1, 12], got inf",
        ),
    ],
)
def test_bad_new_keys_are_one_line_naming_the_field(tables, message):
    with pytest.raises(ParameterError) as raised:
        parse_study(_data(**tables), source="study")
    assert message in str(raised.value) and "\n" not in str(raised.value)


def test_a_thrust_no_propeller_of_the_bases_diameter_reaches_and_an_observer_inside_the_rotor_are_refused(  # noqa: E501 (the test name is its sentence)
    tmp_path,
):
    shutil.copy(BASE, tmp_path / "light_prop.toml")  # D = 100 mm
    with pytest.raises(
        ParameterError,
        match=r"simulate.thrust = 900000 N is out of range; allowed \(0, [0-9.]+\] N",
    ):
        parse_study(
            _data(study={"base": "light_prop.toml"}, simulate={"thrust": 9e5}), base_dir=tmp_path
        )
    with pytest.raises(
        ParameterError, match=r"performance.noise\[0.04:90\]: the observer is inside the rotor"
    ):
        parse_study(
            _data(
                study={"base": "light_prop.toml"},
                objective=[{"metric": "performance.noise[0.04:90].oaspl_db"}],
            ),
            base_dir=tmp_path,
        )


def test_the_cli_refuses_a_bad_new_key_with_exit_2_one_line_and_writes_nothing(tmp_path):
    study = tmp_path / "quiet.toml"
    shutil.copytree(ROOT / "examples" / "optimize", tmp_path / "optimize")
    study.write_text(
        QUIET.read_text().replace('levels = ["coarse", "medium"]', 'levels = ["coarse", "coarse"]')
    )
    out = tmp_path / "out"
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    done = subprocess.run(
        [sys.executable, "-m", "torus_cad", "optimize", str(study), "--out", str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 2, done.stderr
    assert (
        done.stderr.count("\n") == 1
        and "simulate.levels = ['coarse', 'coarse'] must name levels" in done.stderr
    )
    assert not out.exists()


def test_noise_metrics_read_the_observer_of_that_distance_and_angle():
    performance = {
        "noise": {
            "observers": [
                {"distance_m": 1.0, "angle_deg": 60.0, "oaspl_dba": 9.5},
                {"distance_m": 1.0, "angle_deg": 90.0, "oaspl_dba": 13.4, "oaspl_db": 16.6},
            ]
        }
    }
    assert metric_value("performance.noise[1:90].oaspl_dba", {}, performance) == 13.4
    assert metric_value("performance.noise[1.0:60].oaspl_dba", {}, performance) == 9.5
    with pytest.raises(KeyError, match="no noise at the observer 2:90"):
        metric_value("performance.noise[2:90].oaspl_dba", {}, performance)


# -- pruning
# -----------------------------------------------------------------------------------------


def _level_trial(values: list[float], level: str = "coarse", feasible: bool = True):
    metrics = {"performance.power_w": values[0], "performance.noise[1:90].oaspl_dba": values[1]}
    return optuna.trial.create_trial(
        state=TrialState.RUNNING,
        user_attrs={"levels": {level: {"metrics": metrics, "feasible": feasible}}},
    )


def test_a_multi_objective_trial_stops_when_another_trials_values_at_that_level_dominate_its_own():
    objectives = [
        Objective("performance.power_w", Direction.MINIMIZE),
        Objective("performance.noise[1:90].oaspl_dba", Direction.MINIMIZE),
    ]
    others = [
        _level_trial([2.0, 30.0]),
        _level_trial([3.0, 20.0]),
        _level_trial([1.0, 10.0], feasible=False),
    ]
    # by the first
    assert dominated_at_level([2.5, 31.0], objectives, "coarse", others, startup_trials=2)
    # on the front
    assert not dominated_at_level([2.5, 25.0], objectives, "coarse", others, startup_trials=2)
    # equal: not dominated
    assert not dominated_at_level([2.0, 30.0], objectives, "coarse", others, startup_trials=2)
    # too few seen yet
    assert not dominated_at_level([2.5, 31.0], objectives, "coarse", others, startup_trials=3)
    # other level
    assert not dominated_at_level([2.5, 31.0], objectives, "medium", others, startup_trials=0)
    maximize = [objectives[0], Objective("performance.noise[1:90].oaspl_dba", Direction.MAXIMIZE)]
    assert not dominated_at_level([2.5, 31.0], maximize, "coarse", others, startup_trials=2)


def _levels_study(
    folder: Path,
    pruner: str,
    trials: int,
    objectives: str = "",
    thickness: str = "[0.5, 0.6]",
    seed: int = 1,
) -> Path:
    """A study of the light example's base over the airfoil thickness (from 0.5, thick enough for
    its 0.8 mm trailing edge), solved to 1 N, coarse then medium."""
    shutil.copy(BASE, folder / "light_prop.toml")
    objectives = (
        objectives or '[[objective]]\nmetric = "performance.power_w"\ndirection = "minimize"\n'
    )
    path = folder / "study.toml"
    path.write_text(
        '[study]\nname = "levels"\nbase = '
        f'"light_prop.toml"\ntrials = {trials}\nsampler = "random"\n'
        f'seed = {seed}\nstl = false\n\n[vary]\n"airfoil.thickness" = {thickness}\n\n'
        f"{objectives}\n[simulate]\nthrust = 1.0\nlevels "
        f'= ["coarse", "medium"]\n\n[pruner]\n{pruner}\n'
    )
    return path


def test_a_pruned_trial_is_recorded_as_pruned_and_never_reaches_the_finer_level(tmp_path):
    spec = read_study_file(
        _levels_study(
            tmp_path,
            'kind = "median"\nstartup_trials = 1',
            trials=6,
            # seed 3: some trials pruned, some not
            thickness="[0.5, 0.9]",
            seed=3,
        )
    )
    out = tmp_path / "out"
    result = run_study(spec, out, workers=1, trial_job=stand_in_without_build)
    trials = optuna.load_study(
        study_name="levels", storage=open_storage(f"sqlite:///{out / 'levels.db'}")
    ).get_trials()
    states = [trial.state for trial in trials]
    assert len(trials) == 6 and TrialState.PRUNED in states and TrialState.COMPLETE in states, (
        states
    )
    with (out / "results.csv").open(newline="") as handle:
        rows = {int(row["number"]): row for row in csv.DictReader(handle)}
    for trial in trials:
        folder = out / "trials" / str(trial.number) / "simulate"
        row = rows[trial.number]
        assert (folder / "coarse" / f"trial_{trial.number}_performance.json").is_file()
        thickness = trial.params["airfoil.thickness"]
        # its value is the screening level's; the finer level never ran
        if trial.state is TrialState.PRUNED:
            assert not (folder / "medium").exists()
            assert (
                row["state"] == "pruned"
                and row["level"] == "coarse"
                and "pruned at the coarse level" in row["reason"]
            )
            assert float(row["performance.power_w"]) == pytest.approx(1.0 + 10.0 * thickness)
        else:
            assert trial.state is TrialState.COMPLETE
            assert (folder / "medium" / f"trial_{trial.number}_performance.json").is_file()
            # the finer level's value
            assert trial.values[0] == pytest.approx((1.0 + 10.0 * thickness) * 1.1)
            assert row["state"] == "complete" and row["level"] == "medium"
            # the coarse one
            assert trial.intermediate_values == {0: pytest.approx(1.0 + 10.0 * thickness)}
        assert float(row["performance.rpm"]) == pytest.approx(5000.0 / thickness)
    # the median pruner stops a trial worse than the median of the complete ones (all of them, here:
    # one)
    complete = [t for t in trials if t.state is TrialState.COMPLETE]
    for trial in trials:
        if trial.state is TrialState.PRUNED:
            earlier = [t.intermediate_values[0] for t in complete if t.number < trial.number]
            assert earlier and trial.intermediate_values[0] > min(earlier)
    pruned = states.count(TrialState.PRUNED)
    summary = json.loads((out / "levels_study.json").read_text())
    assert summary["pruned"] == {"coarse": pruned} and summary["states"]["pruned"] == pruned
    assert (
        summary["level_seconds"]["coarse"]["trials"] == 6
        and summary["level_seconds"]["medium"]["trials"] == 6 - pruned
    )
    assert f"({pruned} pruned at a screening level)" in result.summary()
    assert (
        "coarse: 6 trials" in result.summary()
        and f"({pruned} pruned); medium: {6 - pruned} trials" in result.summary()
    )


def test_a_two_objective_study_of_two_levels_prunes_the_trials_another_dominates_and_pictures_its_front(  # noqa: E501 (the test name is its sentence)
    tmp_path,
):
    objectives = (
        '[[objective]]\nmetric = "performance.power_w"\ndirection = "minimize"\n\n'
        '[[objective]]\nmetric = "performance.noise[1:90].oaspl_dba"\ndirection = "minimize"\n'
    )
    spec = read_study_file(
        _levels_study(
            tmp_path, "startup_trials = 1", trials=5, objectives=objectives, thickness="[0.5, 0.9]"
        )
    )
    assert spec.pruner is not None and spec.pruner.kind.value == "dominated"
    out = tmp_path / "out"
    run_study(spec, out, workers=1, trial_job=stand_in_without_build)
    trials = optuna.load_study(
        study_name="levels", storage=open_storage(f"sqlite:///{out / 'levels.db'}")
    ).get_trials()
    assert len(trials) == 5
    # power and dB(A) both grow with the thickness: a trial thicker than one screened before it is
    # dominated there (one worker: the trials reach the coarse level in order) and stops; the others
    # climb
    thickness = [t.params["airfoil.thickness"] for t in trials]
    for trial in trials:
        dominated = any(earlier < thickness[trial.number] for earlier in thickness[: trial.number])
        assert trial.state is (TrialState.PRUNED if dominated else TrialState.COMPLETE), (
            trial.number,
            thickness,
        )
        medium = out / "trials" / str(trial.number) / "simulate" / "medium"
        assert medium.exists() == (not dominated)
        if not dominated:
            t = thickness[trial.number]
            assert trial.values == pytest.approx([(1.0 + 10.0 * t) * 1.1, 30.0 + 5.0 * t])
    assert any(t.state is TrialState.PRUNED for t in trials)
    assert (out / "levels_pareto.png").stat().st_size > 1000


@pytest.mark.long
def test_a_study_of_two_levels_climbs_and_prunes_on_a_dask_local_cluster(tmp_path):
    pytest.importorskip(
        "distributed", reason="Dask's distributed is not installed (the optimize extra has it)"
    )
    spec = read_study_file(
        _levels_study(
            tmp_path,
            'kind = "median"\nstartup_trials = 1',
            trials=6,
            thickness="[0.5, 0.9]",
            seed=3,
        )
    )
    out = tmp_path / "out"
    result = run_study(spec, out, workers=2, scheduler="local", trial_job=stand_in_without_build)
    assert result.backend.startswith("dask")
    trials = optuna.load_study(
        study_name="levels", storage=open_storage(f"sqlite:///{out / 'levels.db'}")
    ).get_trials()
    assert len(trials) == 6 and {t.state for t in trials} == {
        TrialState.COMPLETE,
        TrialState.PRUNED,
    }
    for trial in trials:
        medium = out / "trials" / str(trial.number) / "simulate" / "medium"
        assert medium.exists() == (trial.state is TrialState.COMPLETE)


# -- with OpenFOAM
# -----------------------------------------------------------------------------------


def _needs_simulate() -> None:
    reason = simulate_unavailable()
    if reason:
        pytest.skip(reason)


@pytest.mark.long
def test_a_target_thrust_trial_carries_the_rpm_found_and_the_thrust_within_tolerance(tmp_path):
    """One trial of the default design solved to 0.05 N (coarse level, 60 iterations per run, one
    process)."""
    _needs_simulate()
    path = tmp_path / "thrust.toml"
    path.write_text(
        '[study]\nname = "thrust"\ntrials = 1\nsampler = "random"\nstl = false\n\n'
        '[vary]\n"airfoil.thickness" = [0.14, 0.16]\n\n'
        '[[objective]]\nmetric = "performance.power_w"\ndirection = "minimize"\n\n'
        '[[objective]]\nmetric = "performance.noise[1:90].oaspl_dba"\ndirection = "minimize"\n\n'
        "[simulate]\nthrust = 0.05\nthrust_tolerance = "
        "0.05\nthrust_runs = 5\niterations = 60\nprocesses = 1\n"
    )
    out = tmp_path / "out"
    run_study(read_study_file(path), out, workers=1)
    (trial,) = optuna.load_study(
        study_name="thrust", storage=open_storage(f"sqlite:///{out / 'thrust.db'}")
    ).get_trials()
    record = trial.user_attrs["result"]
    assert trial.state is TrialState.COMPLETE, record
    metrics = record["metrics"]
    report = json.loads(
        (out / "trials" / "0" / "simulate" / "trial_0_performance.json").read_text()
    )
    search = report["thrust_search"]
    assert metrics["performance.rpm"] == pytest.approx(search["rpm"]) and search["within_tolerance"]
    assert abs(metrics["performance.thrust_n"] - 0.05) <= 0.05 * 0.05
    assert metrics["performance.power_w"] == pytest.approx(report["power_w"])  # at the rpm found
    (observer,) = report["noise"]["observers"]  # only the observer the study names was computed
    assert (observer["distance_m"], observer["angle_deg"]) == (1.0, 90.0)
    assert trial.values[1] == pytest.approx(observer["oaspl_dba"]) and math.isfinite(
        trial.values[1]
    )
    assert max(record["constraint"]) <= 0.0  # within the tolerance: feasible


@pytest.mark.long
def test_with_openfoam_a_pruned_trial_never_reaches_the_medium_level(tmp_path):
    """Three trials of the default design at 10,000 rpm, coarse then medium (40 iterations, one
    process): the median pruner after one complete trial."""
    _needs_simulate()
    path = tmp_path / "levels.toml"
    path.write_text(
        '[study]\nname = "levels"\ntrials = 3\nsampler = "random"\nseed = 2\nstl = false\n\n'
        '[vary]\n"airfoil.thickness" = [0.08, 0.2]\n\n'
        '[[objective]]\nmetric = "performance.thrust_n"\ndirection = "maximize"\n\n'
        '[simulate]\nrpm = 10000.0\nlevels = ["coarse", '
        '"medium"]\niterations = 40\nprocesses = 1\n\n'
        '[pruner]\nkind = "median"\nstartup_trials = 1\n'
    )
    out = tmp_path / "out"
    run_study(read_study_file(path), out, workers=1)
    trials = optuna.load_study(
        study_name="levels", storage=open_storage(f"sqlite:///{out / 'levels.db'}")
    ).get_trials()
    assert len(trials) == 3 and all(
        t.state in (TrialState.COMPLETE, TrialState.PRUNED) for t in trials
    ), [t.user_attrs.get("result") for t in trials]
    for trial in trials:
        medium = (
            out
            / "trials"
            / str(trial.number)
            / "simulate"
            / "medium"
            / f"trial_{trial.number}_performance.json"
        )
        assert medium.is_file() == (trial.state is TrialState.COMPLETE)
        if trial.state is TrialState.COMPLETE:
            assert json.loads(medium.read_text())["level"] == "medium"
            assert trial.values[0] == pytest.approx(json.loads(medium.read_text())["thrust_n"])


def test_a_study_on_a_terminal_shows_its_trials_and_each_better_one(tmp_path, capsys):
    """Issue 47: optimize is not silent for minutes: a bar of the trials (finished of all, by state)
    and a line each time a one-objective study finds a better trial, on stderr (drawn on a terminal;
    forced on here)."""
    spec = read_study_file(
        _levels_study(tmp_path, 'kind = "none"', trials=4, thickness="[0.5, 0.9]", seed=3)
    )
    run_study(spec, tmp_path / "out", workers=1, trial_job=stand_in_without_build, progress=True)
    error = capsys.readouterr().err
    assert "trials" in error and "4/4" in error and "complete 4" in error
    best = [line for line in error.splitlines() if "best so far, performance.power_w = " in line]
    # the first complete trial, then each better one
    assert best and all(line.startswith("trial ") for line in best)
    values = [float(line.rsplit("= ", 1)[1]) for line in best]
    # power is minimised: each line lower than the last
    assert values == sorted(values, reverse=True)
    run_study(spec, tmp_path / "quiet", workers=1, trial_job=stand_in_without_build, progress=False)
    assert capsys.readouterr().err == ""
