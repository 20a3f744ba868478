"""Benchmark of ``torus-cad optimize``: trials per minute against ``torus-cad sweep`` on the same designs.

Runs the shipped geometric study (examples/optimize_light.toml) with ``--workers`` local workers,
then builds exactly the designs its trials asked for through the sweep's runner (same pool, same
job, STEP + JSON, no STL, as the trials), and prints both rates, the optimiser's overhead (the
target is at most 5 %) and the best feasible objective against the number of trials::

    python scripts/bench_optimize.py --trials 30 --workers 2
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "optimize_light.toml"


def _sweep_rate(spec, parameter_sets, out: Path, workers: int) -> tuple[float, float]:
    """Designs per minute and seconds of the sweep's runner on these designs."""
    from torus_cad.batch.designs import Design
    from torus_cad.batch.job import DesignTask
    from torus_cad.batch.sweep import _run
    from torus_cad.batch.sweep_file import SweepSpec
    from torus_cad.progress import BatchProgress

    sweep = SweepSpec(name="bench", base=spec.base)
    designs = [Design(index, parameters["name"], {}, parameters) for index, parameters in enumerate(parameter_sets)]
    pending = [DesignTask(d.design_id, d.parameters, str(out / "designs" / d.design_id), stl=False) for d in designs]
    result = _run(sweep, out, designs, pending, False, workers=workers, scheduler=None, client=None,
                  time_limit_s=300.0, bar=BatchProgress(len(designs), 0, enabled=False), job=None)
    return result.designs_per_minute(), result.seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()

    import optuna

    from torus_cad.optimize import load_study, run_study

    spec = load_study(EXAMPLE)
    with tempfile.TemporaryDirectory(prefix="bench_optimize_") as scratch:
        folder = Path(scratch)
        start = time.perf_counter()
        _sweep_rate(spec, [spec.parameters({"airfoil.thickness": 0.4, "transforms.scale_x[4]": 5.0}, f"warm_{i}")
                           for i in range(args.workers)], folder / "warm", args.workers)
        print(f"warm-up (pool start, kernel import in the fork server): {time.perf_counter() - start:.1f} s")
        cpu_start = time.process_time()
        result = run_study(spec, folder / "study", trials=args.trials, workers=args.workers, write_results=False)
        main_cpu_s = time.process_time() - cpu_start  # the sampler, the storage, the loop: this process only
        study = optuna.load_study(study_name=spec.name, storage=f"sqlite:///{folder / 'study' / f'{spec.name}.db'}")
        trials = sorted(study.get_trials(), key=lambda trial: trial.number)
        parameter_sets = [spec.parameters(trial.params, f"design_{trial.number}") for trial in trials]
        sweep_per_min, sweep_s = _sweep_rate(spec, parameter_sets, folder / "sweep", args.workers)
    optimize_per_min = result.trials_per_minute()
    print(f"optimize: {result.ran} trials in {result.seconds:.1f} s = {optimize_per_min:.1f} trials/min "
          f"({result.backend})")
    print(f"sweep:    {len(parameter_sets)} designs in {sweep_s:.1f} s = {sweep_per_min:.1f} designs/min "
          "(the same designs, the sweep's runner)")
    print(f"optimiser's own CPU in this process: {main_cpu_s:.2f} s = {1000.0 * main_cpu_s / max(1, result.ran):.0f} ms "
          "per trial (sampler, storage, loop)")
    print(f"optimiser overhead: {100.0 * (sweep_per_min / optimize_per_min - 1.0):+.1f} % (target <= 5 %)")
    from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, build_propeller

    base_g = build_propeller(spec.base).mass_properties(DEFAULT_DENSITY_G_CM3).mass_g
    best, marks = math.inf, {5, 10, 20, 30, 50, 100, args.trials}
    print(f"best feasible mass_g against trials (the base design: {base_g:.4f} g):")
    for count, trial in enumerate(trials, start=1):
        constraint = trial.user_attrs.get("constraint", [math.inf])
        if trial.state.name == "COMPLETE" and max(constraint) <= 0.0:
            best = min(best, trial.value)
        if count in marks:
            print(f"  {count:4d} trials: {best:.4f} g")


if __name__ == "__main__":
    main()
