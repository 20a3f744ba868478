"""SIGTERM (or another signal) at a chosen moment of ``torus-cad optimize`` / ``torus-cad sweep``,
and what the run left behind, checked through readers we did not write (optuna's own storage reader,
the ``torus-cad verify`` command, the file system).

Used by tests/test_study_signals.py, and as a script for the attack table::

    python3 tests/study_attacks.py optimize startup 2.0 4.5 8
        # 8 SIGTERMs, 2.0-4.5 s after the start
    python3 tests/study_attacks.py optimize finish 0.0 3.0 8
        # 0-3 s after the results table appears
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BASE = ROOT / "examples" / "optimize" / "light_prop.toml"
NAME = "light"


def env() -> dict[str, str]:
    environment = dict(os.environ)
    environment["PYTHONPATH"] = os.pathsep.join([str(ROOT), environment.get("PYTHONPATH", "")])
    return environment


def study_file(folder: Path, trials: int) -> Path:
    """A small study (the shipped example's base design at its coarse resolution)."""
    shutil.copy(BASE, folder / "light_prop.toml")
    path = folder / "study.toml"
    path.write_text(
        f'[study]\nname = "{NAME}"\nbase = "light_prop.toml"\ntrials = {trials}\nsampler = "tpe"\n'
        'seed = 0\n\n[vary]\n"airfoil.thickness" = [0.2, '
        '0.6]\n"transforms.scale_x[4]" = [4.0, 6.5]\n\n'
        '[[objective]]\nmetric = "mass_g"\ndirection = "minimize"\n\n'
        '[constraints]\n"printability.thinnest_wall_mm" = { min = 0.8 }\n'
    )
    return path


def sweep_file(folder: Path) -> Path:
    path = folder / "sweep.toml"
    path.write_text(
        "[base.resolution]\nsections = 10\npoints = 32\n[sweep]\nstl = false\n"
        '[vary]\nblades = [2, 3]\n"airfoil.max_camber" = [0.0, 0.02]\n'
    )
    return path


@dataclass
class Outcome:
    """What one attacked run gave, and what is wrong with it (``problems``, empty when all is
    well)."""

    command: str
    moment: str
    delay_s: float
    returncode: int | None = None
    stderr: str = ""
    problems: list[str] = field(default_factory=list)


def _moment_reached(moment: str, out: Path, trials: int) -> Callable[[], bool]:
    """When the clock for the delay starts: the process start, the storage made, a first trial
    written, or the results table."""
    if moment == "startup":
        return lambda: True
    if moment == "storage":  # the storage is made: the pool starts next
        return lambda: (out / f"{NAME}.db").is_file() or (out / "sweep.json").is_file()
    if moment == "trials":  # a first trial or design is written: the others are running
        return lambda: (
            any((out / "trials").glob("*/trial_*.json")) or any((out / "designs").glob("*/*.json"))
        )
    if moment == "finish":
        return lambda: (out / "results.csv").is_file()
    raise ValueError(moment)


def attack(
    command: str,
    moment: str,
    delay_s: float,
    folder: Path,
    trials: int = 2,
    signum: int = signal.SIGTERM,
    timeout_s: float = 600.0,
    group: bool = False,
) -> Outcome:
    """Run ``command`` in ``folder``, send ``signum`` ``delay_s`` after ``moment``, check what it
    left; with ``group`` the run is started in a session of its own and the signal goes to its whole
    process group (the workers too, as ``timeout`` and job schedulers send it)."""
    out = folder / "out"
    source = study_file(folder, trials) if command == "optimize" else sweep_file(folder)
    argv = [
        sys.executable,
        "-m",
        "torus_cad",
        command,
        str(source),
        "--out",
        str(out),
        "--workers",
        "2",
        "-q",
    ]
    outcome = Outcome(command, moment, delay_s)
    reached = _moment_reached(moment, out, trials)
    process = subprocess.Popen(
        argv,
        env=env(),
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=group,
    )
    try:
        deadline = time.monotonic() + timeout_s
        while process.poll() is None and not reached() and time.monotonic() < deadline:
            time.sleep(0.02)
        time.sleep(delay_s)
        if process.poll() is None:
            if group:
                os.killpg(process.pid, signum)
            else:
                process.send_signal(signum)
        _, outcome.stderr = process.communicate(timeout=timeout_s)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    outcome.returncode = process.returncode
    outcome.problems = check(command, out, process.returncode, outcome.stderr, signum, trials)
    return outcome


def check(
    command: str, out: Path, returncode: int | None, stderr: str, signum: int, trials: int
) -> list[str]:
    """Everything wrong with what the run left in ``out`` (empty: all is well)."""
    problems = []
    if returncode not in (0, 128 + signum):
        problems.append(f"exit code {returncode}")
    for bad in ("Traceback", "Exception ignored", "internal error", "Error:", "Warning"):
        if bad in stderr:
            problems.append(f"stderr has {bad!r}")
    if returncode == 128 + signum and len(stderr.strip().splitlines()) != 1:
        problems.append(f"{len(stderr.strip().splitlines())} lines on stderr")
    if not out.exists():
        return problems
    debris = [
        str(path.relative_to(out))
        for path in out.rglob("*")
        if path.name.endswith(("-wal", "-shm", "-journal"))
    ]
    if debris:
        problems.append(f"left {debris}")
    for folder in [out / "best"] if (out / "best").is_dir() else []:
        verified = subprocess.run(
            [sys.executable, "-m", "torus_cad", "verify", str(folder)],
            env=env(),
            capture_output=True,
            text=True,
        )
        if verified.returncode != 0 and "no output set" not in verified.stderr:
            problems.append(f"verify best/: {verified.stderr.strip()}")
    if command == "optimize" and (out / f"{NAME}.db").is_file():
        problems += _check_storage(out / f"{NAME}.db", trials)
    return problems


def _check_storage(database: Path, total: int) -> list[str]:
    """The storage opens with optuna; nothing left RUNNING, no trial counted twice, none retried
    twice."""
    import optuna
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.ERROR)
    # a copy: opening the file here must not checkpoint or tidy up what the run left
    with tempfile.TemporaryDirectory() as scratch:
        for path in database.parent.glob(database.name + "*"):
            shutil.copy(path, Path(scratch) / path.name)
        try:
            storage = optuna.storages.RDBStorage(f"sqlite:///{Path(scratch) / database.name}")
            summaries = optuna.get_all_study_summaries(storage)
            if not summaries:
                return []  # stopped before the study was created
            trials = optuna.load_study(study_name=NAME, storage=storage).get_trials(deepcopy=False)
            storage.engine.dispose()
        except Exception as error:  # any failure to read it is the finding
            return [f"the storage does not open with optuna: {type(error).__name__}: {error}"]
    problems = [
        f"trial {t.number} recorded as a crash"
        for t in trials
        if "crash" in str(t.user_attrs.get("result", ""))
        or "crash" in str(t.user_attrs.get("outcome", ""))
    ]
    stopped = [
        t
        for t in trials
        if t.state is TrialState.FAIL
        and ("result" not in t.user_attrs or "stopped" in t.user_attrs)
    ]
    finished = [
        t
        for t in trials
        if t.state is TrialState.COMPLETE or (t.state is TrialState.FAIL and t not in stopped)
    ]
    if len(finished) > total:
        problems.append(f"{len(finished)} trials counted for --trials {total}")
    if [t for t in trials if t.state is TrialState.RUNNING]:
        problems.append("a trial left RUNNING")
    for trial in stopped:
        retries = [t for t in trials if t.user_attrs.get("retry_of") == trial.number]
        if len(retries) > 1:
            problems.append(f"trial {trial.number} asked again {len(retries)} times")
    return problems


def main() -> int:
    command, moment, low, high, count = (
        sys.argv[1],
        sys.argv[2],
        float(sys.argv[3]),
        float(sys.argv[4]),
        int(sys.argv[5]),
    )
    seed = int(os.environ.get("ATTACK_SEED", "0"))
    generator = random.Random(seed)
    bad = 0
    for _ in range(count):
        with tempfile.TemporaryDirectory() as scratch:
            outcome = attack(command, moment, generator.uniform(low, high), Path(scratch))
        bad += bool(outcome.problems)
        print(json.dumps({**asdict(outcome), "stderr": outcome.stderr[-600:]}), flush=True)
    print(f"{bad} of {count} runs with a problem")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
