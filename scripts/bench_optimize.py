"""Benchmark of ``torus-cad optimize``: trials per minute against ``torus-cad sweep`` on the same designs.

Runs the shipped geometric study (examples/optimize_light.toml) with ``--workers`` local workers,
then builds exactly the designs its trials asked for through the sweep's runner (same pool, same
job, STEP + JSON, no STL, as the trials), and prints both rates, the optimiser's overhead (the
target is at most 5 %) and the best feasible objective against the number of trials::

    python scripts/bench_optimize.py --trials 30 --workers 2 --repeat 3
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "optimize_light.toml"


def _sweep_rate(spec, parameter_sets, out: Path, workers: int) -> tuple[float, float]:
    """Designs per minute and seconds of the sweep's runner on these designs."""
    from torus_cad.batch.designs import Design
    from torus_cad.batch.job import DesignTask
    from torus_cad.batch.sweep import _run
    from torus_cad.batch.sweep_file import SweepSpec
    from torus_cad.runtime.progress import BatchProgress

    sweep = SweepSpec(name="bench", base=spec.base)
    designs = [Design(index, parameters["name"], {}, parameters) for index, parameters in enumerate(parameter_sets)]
    pending = [DesignTask(d.design_id, d.parameters, str(out / "designs" / d.design_id), stl=False) for d in designs]
    result = _run(sweep, out, designs, pending, False, workers=workers, scheduler=None, client=None,
                  time_limit_s=300.0, bar=BatchProgress(len(designs), 0, enabled=False), job=None)
    return result.designs_per_minute(), result.seconds


def _one_pair(spec, folder: Path, trials: int, workers: int) -> tuple[Any, float, float, float, list[Any]]:
    """One study run, then the sweep's runner on the designs its trials asked for: the study's result,
    its main-process CPU s, the sweep's designs/min and s, and the trials."""
    import optuna

    from torus_cad.optimize import run_study

    cpu_start = time.process_time()
    result = run_study(spec, folder / "study", trials=trials, workers=workers, write_results=False)
    main_cpu_s = time.process_time() - cpu_start  # the sampler, the storage, the loop: this process only
    study = optuna.load_study(study_name=spec.name, storage=f"sqlite:///{folder / 'study' / f'{spec.name}.db'}")
    trials_done = sorted(study.get_trials(), key=lambda trial: trial.number)
    parameter_sets = [spec.parameters(trial.params, f"design_{trial.number}") for trial in trials_done]
    sweep_per_min, sweep_s = _sweep_rate(spec, parameter_sets, folder / "sweep", workers)
    return result, main_cpu_s, sweep_per_min, sweep_s, trials_done


def _print_best(spec, trials: list[Any], count_asked: int) -> None:
    from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, build_propeller

    base_g = build_propeller(spec.base).mass_properties(DEFAULT_DENSITY_G_CM3).mass_g
    best, marks = math.inf, {5, 10, 20, 30, 50, 100, count_asked}
    print(f"best feasible mass_g against trials (the base design: {base_g:.4f} g):")
    for count, trial in enumerate(trials, start=1):
        constraint = trial.user_attrs.get("constraint", [math.inf])
        if trial.state.name == "COMPLETE" and max(constraint) <= 0.0:
            best = min(best, trial.value)
        if count in marks:
            print(f"  {count:4d} trials: {best:.4f} g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3,
                        help="study/sweep pairs, run one after the other; the overhead is their median")
    args = parser.parse_args()

    from torus_cad.optimize import load_study

    spec = load_study(EXAMPLE)
    overheads, cpu_per_trial_ms, cpu_shares = [], [], []
    with tempfile.TemporaryDirectory(prefix="bench_optimize_") as scratch:
        start = time.perf_counter()
        _sweep_rate(spec, [spec.parameters({"airfoil.thickness": 0.4, "transforms.scale_x[4]": 5.0}, f"warm_{i}")
                           for i in range(args.workers)], Path(scratch) / "warm", args.workers)
        print(f"warm-up (pool start, kernel import in the fork server): {time.perf_counter() - start:.1f} s")
        for repeat in range(args.repeat):
            result, main_cpu_s, sweep_per_min, sweep_s, trials = _one_pair(
                spec, Path(scratch) / f"pair_{repeat}", args.trials, args.workers)
            optimize_per_min = result.trials_per_minute()
            overheads.append(100.0 * (sweep_per_min / optimize_per_min - 1.0))
            cpu_per_trial_ms.append(1000.0 * main_cpu_s / max(1, result.ran))
            cpu_shares.append(100.0 * main_cpu_s / (args.workers * result.seconds))  # of the cores the trials use
            print(f"pair {repeat + 1}: optimize {result.ran} trials in {result.seconds:.1f} s = "
                  f"{optimize_per_min:.1f} trials/min ({result.backend}); sweep of the same designs "
                  f"{len(trials)} in {sweep_s:.1f} s = {sweep_per_min:.1f} designs/min; overhead "
                  f"{overheads[-1]:+.1f} %; optimiser's own CPU {cpu_per_trial_ms[-1]:.0f} ms per trial")
    print(f"optimiser's own CPU in this process (sampler, storage, loop), median: "
          f"{statistics.median(cpu_per_trial_ms):.0f} ms per trial, {statistics.median(cpu_shares):.1f} % of "
          f"the {args.workers} workers' core time (the overhead it costs the trials; unlike the rates, "
          "not moved by the machine's speed from one run to the next)")
    print(f"optimiser overhead, median of {args.repeat}: {statistics.median(overheads):+.1f} % "
          f"(range {min(overheads):+.1f} to {max(overheads):+.1f} %; target <= 5 %)")
    _print_best(spec, trials, args.trials)


if __name__ == "__main__":
    main()
