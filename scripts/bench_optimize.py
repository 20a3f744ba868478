"""Benchmark of ``torus-cad optimize``: trials per minute against ``torus-cad sweep`` on the same
designs.

Runs the shipped geometric study (examples/optimize_light.toml) with ``--workers`` local workers,
then builds exactly the designs its trials asked for through the sweep's runner (same pool, same
job, STEP + JSON, no STL, as the trials), and prints both rates, the optimiser's overhead (the
target is at most 5 %) and the best feasible objective against the number of trials.

The wall-clock ratio of two runs carries the machine's drift: the first pair also runs the sweep
a second time on the same designs, and that sweep-to-sweep difference is printed as the noise
floor. The overhead is also printed from what the optimiser does inside one run, which the
drift does not move: the extra CPU its process takes from the workers' cores and the extra time
the workers sit idle (their busy share, from each design's own seconds), both against the sweep::

    python scripts/bench_optimize.py --trials 30 --workers 2 --repeat 3
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "optimize_light.toml"


@dataclass
class Run:
    """One run on the pool: its wall s, its designs' summed worker s and its main process's CPU
    s."""

    designs: int
    wall_s: float
    worker_s: float
    main_cpu_s: float
    workers: int

    def per_minute(self) -> float:
        return 60.0 * self.designs / self.wall_s

    def busy(self) -> float:
        """The workers' busy share of their wall time."""
        return self.worker_s / (self.workers * self.wall_s)

    def cpu_share(self) -> float:
        """The main process's CPU as a share of the workers' core time."""
        return self.main_cpu_s / (self.workers * self.wall_s)


def _sweep(spec, parameter_sets, out: Path, workers: int) -> Run:
    """The sweep's runner on these designs."""
    from torus_cad.batch.designs import Design
    from torus_cad.batch.job import DesignTask
    from torus_cad.batch.sweep_file import SweepSpec
    from torus_cad.batch.sweep_run import run_pending
    from torus_cad.runtime.progress import BatchProgress

    sweep = SweepSpec(name="bench", base=spec.base)
    designs = [
        Design(index, parameters["name"], {}, parameters)
        for index, parameters in enumerate(parameter_sets)
    ]
    pending = [
        DesignTask(d.design_id, d.parameters, str(out / "designs" / d.design_id), stl=spec.stl)
        for d in designs
    ]  # the files the trials write
    cpu_start = time.process_time()  # the sweep's own loop, its table included
    result = run_pending(
        sweep,
        out,
        designs,
        pending,
        False,
        workers=workers,
        scheduler=None,
        client=None,
        time_limit_s=300.0,
        bar=BatchProgress(len(designs), 0, enabled=False),
        job=None,
    )
    worker_s = sum(row.get("time_total_s") or 0.0 for row in result.rows)
    return Run(len(designs), result.seconds, worker_s, time.process_time() - cpu_start, workers)


def _study(spec, folder: Path, trials: int, workers: int) -> tuple[Run, list[Any]]:
    """One study run: the run and its trials by number."""
    import optuna

    from torus_cad.optimize import run_study
    from torus_cad.optimize.storage import SECONDS, trial_result

    result = run_study(spec, folder, trials=trials, workers=workers, write_results=False)
    study = optuna.load_study(
        study_name=spec.name, storage=f"sqlite:///{folder / f'{spec.name}.db'}"
    )
    done = sorted(study.get_trials(), key=lambda trial: trial.number)
    worker_s = sum(trial_result(trial).get(SECONDS) or 0.0 for trial in done)
    return Run(result.ran, result.seconds, worker_s, result.cpu_seconds, workers), done


def _print_best(spec, trials: list[Any], count_asked: int) -> None:
    from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, build_propeller

    base_g = build_propeller(spec.base).mass_properties(DEFAULT_DENSITY_G_CM3).mass_g
    best, marks = math.inf, {5, 10, 20, 30, 50, 100, count_asked}
    print(f"best feasible mass_g against trials (the base design: {base_g:.4f} g):")
    for count, trial in enumerate(trials, start=1):
        constraint = trial.user_attrs.get("result", {}).get("constraint", [math.inf])
        if trial.state.name == "COMPLETE" and max(constraint) <= 0.0:
            best = min(best, trial.value)
        if count in marks:
            print(f"  {count:4d} trials: {best:.4f} g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="study/sweep pairs, run one after the other; the overhead is their median",
    )
    args = parser.parse_args()

    from torus_cad.optimize import read_study_file

    spec = read_study_file(EXAMPLE)
    wall, inside, cpu_ms = [], [], []
    with tempfile.TemporaryDirectory(prefix="bench_optimize_") as scratch:
        start = time.perf_counter()
        _sweep(
            spec,
            [
                spec.parameters(
                    {"airfoil.thickness": 0.4, "transforms.scale_x[4]": 5.0}, f"warm_{i}"
                )
                for i in range(args.workers)
            ],
            Path(scratch) / "warm",
            args.workers,
        )
        print(
            "warm-up (pool start, kernel import in the fork "
            f"server): {time.perf_counter() - start:.1f} s"
        )
        for repeat in range(args.repeat):
            folder = Path(scratch) / f"pair_{repeat}"
            study, trials = _study(spec, folder / "study", args.trials, args.workers)
            designs = [spec.parameters(trial.params, f"design_{trial.number}") for trial in trials]
            sweep = _sweep(spec, designs, folder / "sweep", args.workers)
            wall.append(100.0 * (sweep.per_minute() / study.per_minute() - 1.0))
            inside.append(
                100.0 * (study.cpu_share() - sweep.cpu_share() + sweep.busy() - study.busy())
            )
            cpu_ms.append(1000.0 * study.main_cpu_s / max(1, study.designs))
            print(
                f"pair {repeat + 1}: optimize {study.designs} trials in {study.wall_s:.1f} s = "
                f"{study.per_minute():.1f}/min, workers busy {100 * study.busy():.1f} %, main CPU "
                f"{100 * study.cpu_share():.1f} % of their "
                f"cores ({cpu_ms[-1]:.0f} ms/trial); sweep "
                f"{sweep.per_minute():.1f}/min, busy {100 * sweep.busy():.1f} %, main CPU "
                f"{100 * sweep.cpu_share():.1f} %; overhead by wall clock {wall[-1]:+.1f} %, "
                f"from inside the run {inside[-1]:+.1f} %",
                flush=True,
            )
            if repeat == 0:
                again = _sweep(spec, designs, folder / "sweep_again", args.workers)
                print(
                    f"noise floor: the same sweep again {again.per_minute():.1f}/min, "
                    f"{100.0 * (sweep.per_minute() / again.per_minute() - 1.0):+.1f} % "
                    "against the first",
                    flush=True,
                )
    print(
        "optimiser's own CPU (sampler, storage, loop), "
        f"median: {statistics.median(cpu_ms):.0f} ms per trial"
    )
    print(
        f"optimiser overhead from inside the runs (extra main CPU + extra worker idle), median of "
        f"{args.repeat}: {statistics.median(inside):+.1f} % "
        f"(range {min(inside):+.1f} to {max(inside):+.1f} %; "
        "target <= 5 %)"
    )
    print(
        "optimiser overhead by wall clock, median of "
        f"{args.repeat}: {statistics.median(wall):+.1f} % "
        f"(range {min(wall):+.1f} to {max(wall):+.1f} %)"
    )
    _print_best(spec, trials, args.trials)


if __name__ == "__main__":
    main()
