"""torus-cad optimize: study files checked like designs, studies that improve on their base, survive
a SIGKILL, share one storage (SQLite between processes, a real PostgreSQL server), run on Dask, and
give best designs that ``torus-cad build`` rebuilds with the same numbers."""

from __future__ import annotations

import csv
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

optuna = pytest.importorskip(
    "optuna",
    reason="the optimize extra is not installed: pip install -c constraints.txt -e '.[optimize]'",
)

from optuna.trial import TrialState  # noqa: E402

from torus_cad.errors import ParameterError  # noqa: E402
from torus_cad.optimize import parse_study, read_study_file, run_study  # noqa: E402
from torus_cad.optimize.metrics import REPORT_METRICS, metric_value  # noqa: E402
from torus_cad.optimize.storage import RETRY_OF, open_storage, owner_record, retry_stale_trials  # noqa: E402
from torus_cad.optimize.trial_simulation import simulate_unavailable  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "optimize_light.toml"
BASE = ROOT / "examples" / "optimize" / "light_prop.toml"


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


def _cli(*args: str, **kwargs) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "torus_cad", *args],
        env=_env(),
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        **kwargs,
    )


def _study_file(
    folder: Path, trials: int = 6, extra: str = "", objectives: str = "", sampler: str = "tpe"
) -> Path:
    """A small copy of the shipped example in ``folder`` (its base design beside it)."""
    shutil.copy(BASE, folder / "light_prop.toml")
    objectives = objectives or '[[objective]]\nmetric = "mass_g"\ndirection = "minimize"\n'
    text = (
        '[study]\nname = "light"\nbase = "light_prop.toml"\ntrials '
        f'= {trials}\nsampler = "{sampler}"\n'
        f'seed = 0\n{extra}\n[vary]\n"airfoil.thickness" = '
        '[0.2, 0.6]\n"transforms.scale_x[4]" = [4.0, 6.5]\n\n'
        f'{objectives}\n[constraints]\n"printability.thinnest_wall_mm" = {{ min = 0.8 }}\n'
    )
    path = folder / "study.toml"
    path.write_text(text)
    return path


def _stopped(trial) -> bool:
    """Failed because its run stopped (not for a reason of the design)."""
    return trial.state is TrialState.FAIL and (
        "result" not in trial.user_attrs or "stopped" in trial.user_attrs
    )


def _finished(trials) -> list:
    """Trials that count towards --trials: complete, or failed for a reason of the design."""
    return [
        t
        for t in trials
        if t.state is TrialState.COMPLETE or (t.state is TrialState.FAIL and not _stopped(t))
    ]


def _check_whole(trials, total: int) -> None:
    """Exactly ``total`` finished trials, nothing left running, every interrupted trial asked again
    once."""
    assert len(_finished(trials)) == total
    assert not [t.number for t in trials if t.state in (TrialState.RUNNING, TrialState.WAITING)]
    interrupted = [t for t in trials if _stopped(t)]
    for trial in interrupted:
        retries = [t for t in trials if t.user_attrs.get(RETRY_OF) == trial.number]
        # the same parameters; a trial killed before it had any is asked again with the sampler's
        # new ones
        assert len(retries) == 1 and (retries[0].params == trial.params or not trial.params)
    assert len({t.number for t in trials}) == len(trials)


def _load(url: str, name: str = "light"):
    return optuna.load_study(study_name=name, storage=open_storage(url))


# -- the study file
# ----------------------------------------------------------------------------------


def test_the_shipped_example_reads_and_names_real_report_numbers():
    spec = read_study_file(EXAMPLE)
    assert spec.name == "light_prop" and spec.trials == 30 and spec.base.diameter == 100.0
    assert [axis.key for axis in spec.axes] == ["airfoil.thickness", "transforms.scale_x[4]"]
    assert spec.metrics == ("mass_g", "printability.thinnest_wall_mm")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"study": {"trials": 0}}, "study.trials = 0 is out of range; allowed [1, 100000]"),
        ({"study": {"trials": "4"}}, "study.trials must be a whole number"),
        ({"study": {"sampler": "annealing"}}, "study.sampler = 'annealing' is not allowed"),
        ({"study": {"trails": 4}}, "unknown key 'study.trails'; did you mean 'study.trials'?"),
        (
            {"vary": {"airfoil.thickness": [0.2, 1.5]}},
            "airfoil.thickness = 1.5 is out of range; allowed (0, 1]",
        ),
        (
            {"vary": {"airfoil.thicknes": [0.2, 0.5]}},
            "unknown key 'airfoil.thicknes'; did you mean 'airfoil.thickness'?",
        ),
        ({"vary": {"blades": [2.5, 4]}}, "vary.'blades' low must be a whole number"),
        ({"vary": {"airfoil.thickness": [0.2, 0.3, 0.4]}}, "must be [low, high], two numbers"),
        (
            {"vary": {"handedness": ["cw", "left"]}},
            "vary.'handedness' item 1 = 'left' is not allowed; choose one of cw, ccw",
        ),
        (
            {"vary": {"centerline.p2[3]": [1.0, 2.0]}},
            "index 3 is out of range; centerline.p2 has 3 elements",
        ),
        (
            {"objective": [{"metric": "mass"}]},
            "objective[0].metric = 'mass' is not a number of the build report",
        ),
        (
            {"objective": [{"metric": "mass_g", "direction": "down"}]},
            "objective[0].direction: Input should be 'minimize' or 'maximize' (got string 'down')",
        ),
        (
            {"constraints": {"printability.thinnest_wall_mm": {"least": 0.8}}},
            "constraints.'printability.thinnest_wall_mm' has keys ['least']; give min, max or both",
        ),
        (
            {"constraints": {"printability.thinnest_wall_mm": {"min": 2.0, "max": 1.0}}},
            "must not be above max",
        ),
        ({"objective": [{"metric": "performance.thrust_n"}]}, "give [simulate] rpm"),
        ({"simulate": {"rpm": 8000.0}}, "[simulate] applies only when"),
        ({"study": {"sampler": "cmaes"}}, "'cmaes' takes no [constraints]"),
        ({"study": {"name": "a/b"}}, "study.name = 'a/b' must be"),
    ],
)
def test_bad_study_files_are_one_line_naming_the_key(change, message):
    data = {
        "study": {"trials": 4},
        "vary": {"airfoil.thickness": [0.2, 0.6]},
        "objective": [{"metric": "mass_g"}],
        "constraints": {"printability.thinnest_wall_mm": {"min": 0.8}},
    }
    for table, value in change.items():
        data[table] = (
            {**data[table], **value}
            if isinstance(value, dict) and table in ("study", "vary")
            else value
        )
    with pytest.raises(ParameterError) as raised:
        parse_study(data, source="study")
    text = str(raised.value)
    assert message in text and "\n" not in text


def test_the_cli_refuses_a_bad_study_with_exit_2_and_writes_nothing(tmp_path):
    study = _study_file(tmp_path)
    study.write_text(study.read_text().replace("[0.2, 0.6]", "[0.2, 1.6]"))
    out = tmp_path / "out"
    done = _cli("optimize", str(study), "--out", str(out))
    _, stderr = done.communicate(timeout=300)
    assert done.returncode == 2, stderr
    assert stderr.count("\n") == 1 and "airfoil.thickness = 1.6 is out of range" in stderr
    assert not out.exists()


def test_every_number_of_a_real_build_report_is_a_metric():
    from torus_cad.outputs.build_report import build_report
    from torus_cad.propeller import build_propeller

    report = build_report(build_propeller(BASE), 1.24)
    leaves = set()

    def walk(data, prefix=""):
        for key, value in data.items():
            if key in (
                "parameters",
                "stage_seconds",
                "design_targets",
                "files",
                "valid",
                "solids",
                "checks",
            ):
                # inputs, timings, present only when asked, what every report says (valid, 1 solid,
                # checks passed)
                continue
            if isinstance(value, dict):
                walk(value, f"{prefix}{key}.")
            elif isinstance(value, (int, float)) and value is not None:
                leaves.add(prefix + key)

    walk(report)
    assert leaves == set(REPORT_METRICS)
    assert all(math.isfinite(metric_value(metric, report, None)) for metric in REPORT_METRICS)
    assert metric_value("mass_g", report, None) == report["mass_g"]


def test_a_dead_processs_running_trial_is_failed_and_asked_again(tmp_path):
    url = f"sqlite:///{tmp_path / 'x.db'}"
    rdb = open_storage(url)
    study = optuna.create_study(storage=rdb, study_name="x")
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    from torus_cad.runtime.processes import host_tag

    alive = study.ask({"a": optuna.distributions.FloatDistribution(0.0, 1.0)})
    alive.set_user_attr("owner", owner_record())
    trial = study.ask({"a": optuna.distributions.FloatDistribution(0.0, 1.0)})
    trial.set_user_attr("owner", {"host": host_tag(), "pid": int(dead.stdout), "start": "gone"})
    assert retry_stale_trials(study, rdb) == [trial.number]
    trials = study.get_trials()
    assert trials[trial.number].state is TrialState.FAIL
    retry = trials[-1]
    assert retry.state is TrialState.WAITING and retry.params == trial.params
    assert retry.user_attrs == {RETRY_OF: trial.number}  # not the dead run's owner or records
    assert (
        optuna.storages.RetryHeartbeatStaleTrialCallback.retried_trial_number(retry) == trial.number
    )
    assert trials[alive.number].state is TrialState.RUNNING  # its owner (this process) lives
    assert retry_stale_trials(study, rdb) == []  # once only
    asked = study.ask({"a": optuna.distributions.FloatDistribution(0.0, 1.0)})
    # the retry is asked first, as it was
    assert (asked.number, asked.params) == (retry.number, trial.params)


def test_a_trial_of_another_host_whose_heartbeat_stopped_is_failed_and_asked_again(
    tmp_path, monkeypatch
):
    """Owners on other hosts are judged by optuna's heartbeat (fail_stale_trials) once it is GRACE_S
    old."""
    from torus_cad.optimize import storage

    monkeypatch.setattr(storage, "GRACE_S", 1)
    monkeypatch.setattr(storage, "HEARTBEAT_S", 1)
    rdb = open_storage(f"sqlite:///{tmp_path / 'x.db'}")
    study = optuna.create_study(storage=rdb, study_name="x")
    trial = study.ask({"a": optuna.distributions.FloatDistribution(0.0, 1.0)})
    trial.set_user_attr("owner", {"host": "another-host", "pid": os.getpid(), "start": "elsewhere"})
    with storage.Heartbeat(rdb, study) as heartbeat:
        heartbeat.add(trial)
        assert retry_stale_trials(study, rdb) == []  # beating: alive, wherever its pid is
        heartbeat.discard(trial)
    time.sleep(2.5)
    assert retry_stale_trials(study, rdb) == [trial.number]
    trials = study.get_trials()
    assert trials[trial.number].state is TrialState.FAIL
    assert trials[-1].state is TrialState.WAITING and trials[-1].user_attrs == {
        RETRY_OF: trial.number
    }
    assert trials[-1].params == trial.params


def test_a_trial_left_without_an_owner_by_a_process_killed_while_claiming_it_is_asked_again(
    tmp_path,
):
    """Trials are asked for and given their owner under the claim lock: one seen there without an
    owner belongs to a process killed between the two, and is failed and asked again (not counted
    forever)."""
    url = f"sqlite:///{tmp_path / 'x.db'}"
    rdb = open_storage(url)
    study = optuna.create_study(storage=rdb, study_name="x")
    orphan = study.ask({"a": optuna.distributions.FloatDistribution(0.0, 1.0)})
    assert retry_stale_trials(study, rdb) == [orphan.number]
    assert study.get_trials()[orphan.number].state is TrialState.FAIL
    assert study.get_trials()[-1].state is TrialState.WAITING


def test_a_study_made_from_another_file_is_refused(tmp_path):
    study = _study_file(tmp_path, trials=1)
    spec = read_study_file(study)
    from torus_cad.optimize.study import _load_study

    _load_study(spec, open_storage(f"sqlite:///{tmp_path / 'light.db'}"))
    study.write_text(study.read_text().replace("[4.0, 6.5]", "[4.0, 6.0]"))
    with pytest.raises(ParameterError, match="was made from another base"):
        _load_study(read_study_file(study), open_storage(f"sqlite:///{tmp_path / 'light.db'}"))


# -- studies
# -------------------------------------------------------------------------------------------


def test_the_geometric_study_improves_on_its_base_and_its_best_design_rebuilds(tmp_path):
    """The shipped example: a lighter 100 mm propeller whose thinnest wall stays >= 0.8 mm within 30
    trials."""
    from matplotlib.image import imread

    from torus_cad.outputs.build_report import build_report
    from torus_cad.propeller import build_propeller

    base = build_report(build_propeller(BASE), 1.24)
    # the base is feasible: the study must beat it
    assert base["printability"]["thinnest_wall_mm"] >= 0.8
    out = tmp_path / "out"
    result = run_study(read_study_file(EXAMPLE), out, workers=2)
    study = _load(f"sqlite:///{out / 'light_prop.db'}", "light_prop")
    trials = study.get_trials()
    _check_whole(trials, 30)
    best = study.best_trial
    metrics = best.user_attrs["result"]["metrics"]
    assert metrics["printability.thinnest_wall_mm"] >= 0.8
    assert best.value < base["mass_g"] * 0.95, (best.value, base["mass_g"])
    assert result.ran == 30

    design = out / "best" / "light_prop_best.toml"
    rebuilt = tmp_path / "rebuilt"
    done = _cli("build", str(design), "--out", str(rebuilt), "--no-stl", "-q")
    _, stderr = done.communicate(timeout=600)
    assert done.returncode == 0, stderr
    report = json.loads((rebuilt / "light_prop_best.json").read_text())
    assert report["mass_g"] == pytest.approx(best.value, rel=1e-9)
    assert report["printability"]["thinnest_wall_mm"] == pytest.approx(
        metrics["printability.thinnest_wall_mm"], rel=1e-9
    )
    assert {p.suffix for p in (out / "best").iterdir()} >= {".toml", ".step", ".stl", ".json"}

    import pyarrow.parquet

    table = pyarrow.parquet.read_table(out / "results.parquet").to_pylist()
    assert len(table) == len(trials) and {row["number"] for row in table} == {
        t.number for t in trials
    }
    assert min(row["mass_g"] for row in table if row["feasible"]) == pytest.approx(best.value)
    assert (
        (out / "results.csv")
        .read_text()
        .splitlines()[0]
        .startswith("number,state,outcome,feasible,reason")
    )
    picture = imread(out / "light_prop_history.png")
    assert picture.shape[0] > 100 and picture.shape[1] > 100


def test_a_study_killed_with_sigkill_resumes_to_its_trial_count_with_no_duplicate_or_lost_trial(
    tmp_path,
):
    study_path = _study_file(tmp_path, trials=6)
    out = tmp_path / "out"
    first = _cli("optimize", str(study_path), "--out", str(out), "--workers", "2", "-q")
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline and first.poll() is None:
        if (
            len(list(out.glob("trials/*/trial_*.json")) + list(out.glob("trials/*/refusal.json")))
            >= 2
        ):
            break
        time.sleep(0.2)
    assert first.poll() is None, first.communicate()
    first.send_signal(signal.SIGKILL)
    first.wait(timeout=60)
    url = f"sqlite:///{out / 'light.db'}"
    running = [t.number for t in _load(url).get_trials() if t.state is TrialState.RUNNING]
    assert running, "the kill came when no trial was running: nothing to resume"

    again = _cli("optimize", str(study_path), "--out", str(out), "--workers", "2")
    stdout, stderr = again.communicate(timeout=900)
    assert again.returncode == 0, stderr
    trials = _load(url).get_trials()
    _check_whole(trials, 6)
    assert {t.user_attrs.get(RETRY_OF) for t in trials} >= set(running)
    assert "of a stopped run were asked again" in stdout


def test_sigterm_stops_the_study_with_one_line_and_exit_143_and_asks_its_running_trials_again(
    tmp_path,
):
    study_path = _study_file(tmp_path, trials=6)
    out = tmp_path / "out"
    run = _cli("optimize", str(study_path), "--out", str(out), "--workers", "2")
    deadline = time.monotonic() + 600
    while (
        time.monotonic() < deadline
        and run.poll() is None
        and not list(out.glob("trials/*/trial_*.json"))
    ):
        time.sleep(0.2)
    run.send_signal(signal.SIGTERM)
    _, stderr = run.communicate(timeout=300)
    assert run.returncode == 143, stderr
    assert stderr.count("\n") == 1 and "interrupted by SIGTERM" in stderr
    trials = _load(f"sqlite:///{out / 'light.db'}").get_trials()
    assert not [t for t in trials if t.state is TrialState.RUNNING]
    stopped = [t.number for t in trials if _stopped(t)]
    assert (
        stopped
        and sorted(t.user_attrs[RETRY_OF] for t in trials if t.state is TrialState.WAITING)
        == stopped
    )
    assert (out / "results.csv").read_text().count("\n") == 1 + len(trials)


def test_two_processes_share_one_sqlite_study(tmp_path):
    study_path = _study_file(tmp_path, trials=8)
    out = tmp_path / "out"
    runs = [
        _cli("optimize", str(study_path), "--out", str(out), "--workers", "1", "-q")
        for _ in range(2)
    ]
    for run in runs:
        _, stderr = run.communicate(timeout=900)
        assert run.returncode == 0, stderr
    trials = _load(f"sqlite:///{out / 'light.db'}").get_trials()
    _check_whole(trials, 8)
    owners = {t.user_attrs["owner"]["pid"] for t in _finished(trials)}
    assert owners == {run.pid for run in runs}  # both ran trials of the one study


@pytest.fixture(scope="module")
def postgres_url():
    """A PostgreSQL 15 server of its own on a unix socket in a temporary folder, stopped
    afterwards."""
    bindir = Path("/usr/lib/postgresql/15/bin")
    if not (bindir / "initdb").is_file():
        pytest.skip(
            "PostgreSQL 15 is not installed (apt-get install postgresql; .ci/run installs it)"
        )
    folder = Path(tempfile.mkdtemp(prefix="torus_pg_"))
    as_user: list[str] = []
    if os.geteuid() == 0:  # postgres refuses to run as root
        shutil.chown(folder, "postgres")
        as_user = ["runuser", "-u", "postgres", "--"]
    data = folder / "data"
    try:
        subprocess.run(
            as_user
            + [
                str(bindir / "initdb"),
                "-D",
                str(data),
                "-A",
                "trust",
                "-U",
                "postgres",
                "--no-sync",
            ],
            check=True,
            capture_output=True,
        )
        subprocess.run(
            as_user
            + [
                str(bindir / "pg_ctl"),
                "-D",
                str(data),
                "-l",
                str(folder / "log"),
                "-w",
                "-o",
                f"-k {folder} -c listen_addresses=''",
                "start",
            ],
            check=True,
            capture_output=True,
        )
        yield f"postgresql://postgres@/postgres?host={folder}"
    finally:
        subprocess.run(
            as_user + [str(bindir / "pg_ctl"), "-D", str(data), "-m", "immediate", "stop"],
            capture_output=True,
        )
        shutil.rmtree(folder, ignore_errors=True)


def test_a_study_on_a_postgresql_server_continues_on_a_second_run(tmp_path, postgres_url):
    spec = read_study_file(_study_file(tmp_path, trials=3))
    out = tmp_path / "out"
    run_study(spec, out, workers=2, storage=postgres_url)
    result = run_study(spec, out, trials=5, workers=2, storage=postgres_url)
    assert result.ran == 2 and result.storage == postgres_url
    _check_whole(_load(postgres_url).get_trials(), 5)
    assert not (out / "light.db").exists()  # the server holds the study
    assert (out / "results.csv").read_text().count("\n") == 1 + 5


def test_a_two_objective_study_on_a_dask_local_cluster_gives_its_pareto_front(tmp_path):
    objectives = (
        '[[objective]]\nmetric = "mass_g"\ndirection = "minimize"\n\n'
        '[[objective]]\nmetric = "printability.thinnest_wall_mm"\ndirection = "maximize"\n'
    )
    spec = read_study_file(_study_file(tmp_path, trials=5, objectives=objectives, sampler="nsga2"))
    out = tmp_path / "out"
    result = run_study(spec, out, workers=2, scheduler="local")
    assert result.backend.startswith("dask")
    study = _load(f"sqlite:///{out / 'light.db'}")
    trials = study.get_trials()
    _check_whole(trials, 5)
    front = study.best_trials
    assert front
    feasible = [
        t
        for t in trials
        if t.state is TrialState.COMPLETE and max(t.user_attrs["result"]["constraint"]) <= 0
    ]
    for trial in front:  # no feasible trial dominates a member of the front
        assert not any(
            o.values[0] <= trial.values[0]
            and o.values[1] >= trial.values[1]
            and o.values != trial.values
            for o in feasible
        )
        assert (out / "best" / f"light_pareto_{trial.number}.toml").is_file()
    assert (out / "light_pareto.png").stat().st_size > 1000


def test_a_performance_study_runs_torus_cad_simulate_for_each_trial(tmp_path):
    reason = simulate_unavailable()
    if reason:
        pytest.skip(reason)
    objectives = '[[objective]]\nmetric = "performance.thrust_n"\ndirection = "maximize"\n'
    extra = ""
    study_path = _study_file(
        tmp_path, trials=2, objectives=objectives, sampler="random", extra=extra
    )
    study_path.write_text(
        study_path.read_text() + '\n[simulate]\nrpm = 10000.0\nlevel = "coarse"\n'
    )
    out = tmp_path / "out"
    run_study(read_study_file(study_path), out, workers=2)
    trials = _load(f"sqlite:///{out / 'light.db'}").get_trials()
    _check_whole(trials, 2)
    for trial in trials:
        if trial.state is TrialState.COMPLETE:
            assert math.isfinite(trial.user_attrs["result"]["metrics"]["performance.thrust_n"])
            assert (
                out
                / "trials"
                / str(trial.number)
                / "simulate"
                / f"trial_{trial.number}_performance.json"
            ).is_file()
        else:
            assert trial.user_attrs["result"]["reason"]  # a refused or failed design says why
    assert any(t.state is TrialState.COMPLETE for t in trials), [
        t.user_attrs.get("result") for t in trials
    ]


def test_optuna_dashboard_shows_the_study(tmp_path):
    """The README's `optuna-dashboard sqlite:///OUT/<name>.db` line serves the study."""
    pytest.importorskip(
        "optuna_dashboard", reason="optuna-dashboard is not installed (the optimize extra has it)"
    )
    import socket
    import urllib.request

    from torus_cad.optimize.study import _load_study

    url = f"sqlite:///{tmp_path / 'light.db'}"
    _load_study(read_study_file(_study_file(tmp_path, trials=1)), open_storage(url))
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    command = (
        "import sys; from optuna_dashboard._cli import "
        "main; sys.argv[0] = 'optuna-dashboard'; main()"
    )
    server = subprocess.Popen(
        [sys.executable, "-c", command, url, "--host", "127.0.0.1", "--port", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline, body = time.monotonic() + 120, ""
        while time.monotonic() < deadline and not body:
            try:
                with urllib.request.urlopen(
                    f"http://127.0.0.1:{port}/api/studies", timeout=5
                ) as response:
                    body = response.read().decode()
            except OSError:
                time.sleep(0.5)
        summaries = json.loads(body)["study_summaries"]
        assert [summary["study_name"] for summary in summaries] == ["light"]
    finally:
        server.terminate()
        server.wait(timeout=30)


def test_a_trial_repeating_an_earlier_ones_parameters_takes_its_values_and_files_without_a_build(
    tmp_path,
):
    """A genetic sampler's offspring can repeat a parent: the study answers it from the complete
    trial it repeats (the same parameters give the same design), so a worker never builds or
    simulates that design again."""
    shutil.copy(BASE, tmp_path / "light_prop.toml")
    study_path = tmp_path / "study.toml"
    study_path.write_text(
        '[study]\nname = "twins"\nbase = "light_prop.toml"\ntrials = 6\nsampler = "random"\n'
        'seed = 0\n\n[vary]\n"blades" = [2, 3]\n\n[[objective]]\nmetric = "mass_g"\n'
        'direction = "minimize"\n\n[[objective]]\nmetric = "spin_axis_inertia_g_mm2"\n'
        'direction = "maximize"\n'
    )
    out = tmp_path / "out"
    result = run_study(read_study_file(study_path), out, workers=1)
    trials = {
        trial.number: trial
        for trial in _load(f"sqlite:///{out / 'twins.db'}", "twins").get_trials()
    }
    _check_whole(list(trials.values()), 6)
    assert result.ran == 6 and all(trial.state is TrialState.COMPLETE for trial in trials.values())
    with (out / "results.csv").open(newline="") as handle:
        rows = {int(row["number"]): row for row in csv.DictReader(handle)}
    twins = [number for number, row in rows.items() if row["same_as"]]
    assert twins, rows  # two designs, six trials: the later ones repeat a complete one
    for number in twins:
        original = trials[int(rows[number]["same_as"])]
        assert (
            "same_as" not in original.user_attrs["result"]
            and original.params == trials[number].params
        )
        assert trials[number].values == original.values
        assert (
            rows[number]["folder"] == f"trials/{original.number}"
            and (out / rows[number]["folder"]).is_dir()
        )
        assert not (out / "trials" / str(number)).exists()  # nothing was built for it
    # the lighter design has less inertia: both designs are on the front, published from the trials
    # that ran
    published = sorted(path.name for path in (out / "best").glob("*.toml"))
    ran = sorted(int(path.name) for path in (out / "trials").iterdir())
    assert published == sorted(f"twins_pareto_{number}.toml" for number in ran), published
