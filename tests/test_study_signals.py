"""``torus-cad optimize`` and ``torus-cad sweep`` against signals at any moment, a full disk and a
failing storage, and the staging folders of stopped workers (issue 34, items 2, 3 and 5).

Each attacked run is checked through readers we did not write (tests/study_attacks.py): the exit
code, stderr, the files beside the SQLite database, ``torus-cad verify`` on ``best/`` and on the
study folder, and optuna opening a copy of the storage (nothing RUNNING, no trial counted twice or
asked again twice).
"""

from __future__ import annotations

import os
import random
import shlex
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip(
    "optuna",
    reason="the optimize extra is not installed: pip install -c constraints.txt -e '.[optimize]'",
)

from study_attacks import NAME, attack, env, study_file

from torus_cad.runtime.processes import host_tag


def _torus_cad(*args: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        env=env(),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _dead_pid() -> int:
    """The pid of a process that has exited (and been reaped)."""
    process = subprocess.Popen([sys.executable, "-c", ""])
    process.wait()
    return process.pid


def _assert_clean(outcome) -> None:
    assert not outcome.problems, (
        outcome.moment,
        outcome.delay_s,
        outcome.returncode,
        outcome.stderr,
    )


def _assert_no_staging_left(out: Path) -> None:
    left = [str(path.relative_to(out)) for path in out.rglob("*") if ".staging-" in path.name]
    assert not left, left


# -- signals (item 2)
# ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("moment", "delay_s", "trials"),
    [
        ("storage", 0.3, 1),  # the pool is starting (forkserver, its workers)
        # a first trial is written, the other one running
        pytest.param("trials", 0.0, 2, marks=pytest.mark.long),
        # the table is written; the picture, best/ and
        pytest.param("finish", 0.0, 1, marks=pytest.mark.long),
        # the summary are being written (34 s: the long tier; the random-moments test there covers
        # it 7 times)
    ],
)
def test_a_sigterm_while_the_pool_starts_trials_run_or_the_results_are_written_is_one_line_and_leaves_all_whole(  # noqa: E501 (the test name is its sentence)
    tmp_path, moment, delay_s, trials
):
    outcome = attack("optimize", moment, delay_s, tmp_path, trials=trials)
    _assert_clean(outcome)
    if outcome.returncode == 143:
        assert "interrupted by SIGTERM" in outcome.stderr
    if (tmp_path / "out" / "trials").is_dir():
        assert _torus_cad("verify", str(tmp_path / "out")).returncode == 0
        _assert_no_staging_left(tmp_path / "out")


def test_a_sigterm_to_the_whole_process_group_is_an_interruption_not_a_crash(tmp_path):
    # the workers die of the signal too; their trials are asked again, none is recorded as a crash
    outcome = attack("optimize", "trials", 0.0, tmp_path, trials=2, group=True)
    _assert_clean(outcome)
    if outcome.returncode == 143:
        assert "interrupted by SIGTERM" in outcome.stderr


@pytest.mark.long
def test_sigterm_at_random_moments_of_optimize_and_sweep_always_ends_cleanly(tmp_path):
    """27 SIGTERMs at random moments: 21 for optimize (7 over the start-up and the pool's start, 7
    while trials run, 7 while the results are written), 6 for sweep. Each run is checked on its
    own."""
    seed = int(os.environ.get("ATTACK_SEED", random.randrange(1 << 16)))
    generator = random.Random(seed)
    plan = (
        [("optimize", "startup", generator.uniform(0.5, 6.0)) for _ in range(7)]
        + [("optimize", "trials", generator.uniform(0.0, 3.0)) for _ in range(7)]
        + [("optimize", "finish", generator.uniform(0.0, 3.0)) for _ in range(7)]
        + [("sweep", "storage", generator.uniform(0.0, 3.0)) for _ in range(3)]
        + [("sweep", "trials", generator.uniform(0.0, 2.0)) for _ in range(3)]
    )
    failures = []
    for index, (command, moment, delay_s) in enumerate(plan):
        folder = tmp_path / str(index)
        folder.mkdir()
        outcome = attack(command, moment, delay_s, folder)
        if outcome.problems:
            failures.append(
                (
                    command,
                    moment,
                    round(delay_s, 2),
                    outcome.returncode,
                    outcome.problems,
                    outcome.stderr[-400:],
                )
            )
        elif (folder / "out" / "trials").is_dir() or (folder / "out" / "designs").is_dir():
            verified = _torus_cad("verify", str(folder / "out"))
            if verified.returncode != 0:
                failures.append((command, moment, round(delay_s, 2), "verify", verified.stderr))
        shutil.rmtree(folder)
    assert not failures, f"seed {seed}: {failures}"


_STOP_AS_WORKERS_START = textwrap.dedent("""
    import sys
    from torus_cad.batch.runner import LocalPool

    def job(value):
        return value

    if __name__ == "__main__":
        for _ in range(5):
            pool = LocalPool(2)
            pool.submit(job, 1)  # starts the workers (from the fork server)
            pool.shutdown(wait=False)  # at once, as after a signal: they may still be reading their start-up data
""")  # noqa: E501 (code or text written out verbatim)


def test_a_pool_stopped_while_its_workers_start_leaves_no_traceback(tmp_path):
    """pebble removes a pool's semaphores before it stops the workers; a worker still starting then
    failed with a fork-server traceback (FileNotFoundError in SemLock._rebuild) on the command's
    stderr."""
    script = tmp_path / "stop_as_workers_start.py"
    script.write_text(_STOP_AS_WORKERS_START)
    run = subprocess.run(
        [sys.executable, str(script)], env=env(), capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0 and run.stderr == "", run.stderr[-3000:]


# -- storage and disk failures (item 3)
# --------------------------------------------------------------------

_FILL_STORAGE = textwrap.dedent("""
    import resource, signal, sys
    import optuna
    from torus_cad.optimize.storage import open_storage, storage_failures_named
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead
    url = "sqlite:///" + sys.argv[1]
    storage = open_storage(url)
    study = optuna.create_study(storage=storage, study_name="s")
    resource.setrlimit(resource.RLIMIT_FSIZE, (256 * 1024, 256 * 1024))  # the file may grow no further
    with storage_failures_named(url):
        for index in range(100000):
            study.set_user_attr(f"k{index}", "x" * 20000)
""")  # noqa: E501 (code or text written out verbatim)


def test_a_storage_that_cannot_grow_is_a_storage_error_naming_the_file_and_the_cause(tmp_path):
    database = tmp_path / "full.db"
    run = subprocess.run(
        [sys.executable, "-c", _FILL_STORAGE, str(database)],
        env=env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("torus_cad.optimize.storage.StorageError: "), run.stderr[-2000:]
    assert str(database) in last and ("disk" in last or "full" in last), last


def _in_small_disk(size: str, script: str, *args: str) -> subprocess.CompletedProcess[str]:
    """Run ``script`` with a tmpfs of ``size`` at its first argument, in a mount namespace of its
    own."""
    return subprocess.run(
        [
            "unshare",
            "--map-root-user",
            "--mount",
            "sh",
            "-c",
            f'mount -t tmpfs -o size={size} tmpfs {shlex.quote(args[0])} && exec "$@"',
            "sh",
            sys.executable,
            "-c",
            script,
            *args,
        ],
        env=env(),
        capture_output=True,
        text=True,
        timeout=900,
    )


_FULL_DISK_STUDY = textwrap.dedent("""
    import json, os, subprocess, sys, time
    from pathlib import Path
    disk, study = Path(sys.argv[1]), sys.argv[2]
    out = disk / "out"
    run = subprocess.Popen([sys.executable, "-m", "torus_cad", "optimize", study, "--out", str(out),
                            "--workers", "1", "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    while run.poll() is None and not list(out.glob("trials/*/trial_*.json")):
        time.sleep(0.05)
    try:  # fill the disk: everything written from now on fails
        with open(disk / "filler", "wb") as handle:
            while True:
                handle.write(b"x" * 65536)
                handle.flush()
    except OSError:
        pass
    stdout, stderr = run.communicate(timeout=600)
    (disk / "filler").unlink()
    verify = subprocess.run([sys.executable, "-m", "torus_cad", "verify", str(out)], capture_output=True,
                            text=True)
    left = [str(p) for p in out.rglob("*") if ".staging-" in p.name or ".tmp-" in p.name]
    print(json.dumps({"code": run.returncode, "stderr": stderr, "verify": verify.returncode,
                      "verify_stderr": verify.stderr, "left": left}))
""")  # noqa: E501 (code or text written out verbatim)


@pytest.mark.long
@pytest.mark.skipif(
    shutil.which("unshare") is None, reason="needs unshare (util-linux) for a small tmpfs"
)
def test_a_disk_that_fills_up_during_a_study_is_one_line_naming_the_file_and_the_cause(tmp_path):
    import json

    study = study_file(tmp_path, trials=4)
    disk = tmp_path / "disk"
    disk.mkdir()
    run = _in_small_disk("16m", _FULL_DISK_STUDY, str(disk), str(study))
    if run.returncode != 0 and "mount" in run.stderr:
        pytest.skip(f"cannot mount a tmpfs here: {run.stderr.strip()}")
    result = json.loads(run.stdout.strip().splitlines()[-1])
    stderr = result["stderr"]
    assert result["code"] == 1, stderr
    assert (
        len(stderr.strip().splitlines()) == 1
        and "internal error" not in stderr
        and "Traceback" not in stderr
    )
    assert ("no space left" in stderr or "database or disk is full" in stderr) and str(
        disk
    ) in stderr, stderr
    # every set published is whole, no staging left
    assert result["verify"] == 0, result["verify_stderr"]
    assert not result["left"], result["left"]


# -- staging folders of stopped workers (item 5)
# ---------------------------------------------------------


@pytest.mark.long
def test_verify_names_a_staging_folder_left_in_a_study_and_the_next_run_removes_it(tmp_path):
    study = study_file(tmp_path, trials=1)
    out = tmp_path / "out"

    def left_by_a_killed_worker(number: int) -> Path:
        """What a worker killed mid-write leaves (its trial is asked again under a new number, in a
        new folder)."""
        debris = (
            out
            / "trials"
            / str(number)
            / f".trial_{number}.staging-{host_tag()}-{_dead_pid()}-0a1b2c3d"
        )
        debris.mkdir(parents=True)
        (debris / f"trial_{number}.step").write_text("partial")
        return debris

    earlier = left_by_a_killed_worker(7)  # by an earlier run of the study
    # the study continues
    run = _torus_cad("optimize", str(study), "--out", str(out), "--workers", "1", "-q")
    assert run.returncode == 0, run.stderr
    assert not earlier.exists()
    verified = _torus_cad("verify", str(out))
    assert verified.returncode == 0 and "no staging folder left" in verified.stdout, verified.stderr
    assert (out / f"{NAME}.db").is_file() and not list(out.glob(f"{NAME}.db-*"))
    left = left_by_a_killed_worker(0)
    verified = _torus_cad("verify", str(out))
    assert verified.returncode == 1 and "trials/0/.trial_0.staging-" in verified.stderr, (
        verified.stderr
    )
    assert len(verified.stderr.strip().splitlines()) == 1
    assert left.exists()  # verify only reads


def test_a_staging_folder_of_a_running_process_is_not_reported_as_left(tmp_path):
    """A study folder being written: the staging folder of a live worker is work in progress, not
    debris."""
    folder = tmp_path / "study" / "trials" / "3"
    folder.mkdir(parents=True)
    (folder / f".trial_3.staging-{host_tag()}-{os.getpid()}-0a1b2c3d").mkdir()
    verified = _torus_cad("verify", str(tmp_path / "study"))
    assert (
        verified.returncode == 0 and "1 staging folder of running processes" in verified.stdout
    ), verified.stderr
