"""Benchmark of a ``torus-cad optimize`` study with ``performance.*`` metrics: its cost by mesh
level, and the time of each noise evaluation against the solver's.

Reads a study's output folder (``OUT/trials/<n>/simulate[/<level>]/trial_<n>_performance.json`` and
the study's storage) and prints, by mesh level: the trials that ran it, the pruned ones, the worker
seconds (the first level's include the build), and the mean of each simulation's stages (mesh,
conversion, solver, noise) with the solver runs of a thrust search; then the noise's share of a
simulation::

    python scripts/bench_study_levels.py OUT
    python scripts/bench_study_levels.py OUT --study STUDY.toml --trials 3
        # run (or continue) the study first

A study run here uses one local worker (one CFD at a time on a shared machine); run it under
``nice``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path
from typing import Any


def _reports(out: Path) -> dict[str, list[dict[str, Any]]]:
    """The performance reports of the study's trials, by mesh level."""
    found: dict[str, list[dict[str, Any]]] = {}
    for path in sorted((out / "trials").glob("*/simulate/**/trial_*_performance.json")):
        report = json.loads(path.read_text())
        found.setdefault(str(report.get("level", "?")), []).append(report)
    return found


def _mean(values: list[float]) -> str:
    return f"{statistics.fmean(values):7.1f}" if values else "      -"


def summarise(out: Path) -> list[str]:
    """The benchmark's lines for the study in ``out``."""
    summary_files = sorted(out.glob("*_study.json"))
    summary = json.loads(summary_files[0].read_text()) if summary_files else {}
    spent = summary.get("level_seconds", {})
    pruned = summary.get("pruned", {})
    lines = [
        f"study {summary.get('name', out.name)}: {summary.get('trials', '?')} trials, states "
        f"{summary.get('states', {})}",
        "level   trials pruned  worker s | per simulation, "
        "mean s: mesh  convert   solve   (runs)   noise   wall",
    ]
    noise_share = []
    for level, reports in _reports(out).items():
        stages = [report.get("stage_seconds", {}) for report in reports]
        runs = [
            len(report["thrust_search"]["runs"])
            for report in reports
            if report.get("thrust_search")
        ]
        noise = [float(report["noise"]["seconds"]) for report in reports if report.get("noise")]
        walls = [float(report.get("wall_seconds", 0.0)) for report in reports]
        solve = [float(stage.get("solve", 0.0)) for stage in stages]
        entry = spent.get(level, {"trials": len(reports), "seconds": sum(walls)})
        lines.append(
            f"{level:8s}{entry['trials']:6.0f}{pruned.get(level, 0):7d}{entry['seconds']:10.0f} | "
            f"{_mean([float(s.get('mesh', 0.0)) for s in stages])}"
            f"{_mean([float(s.get('convert', 0.0)) for s in stages])}"
            f"{_mean(solve)}   ({statistics.fmean(runs) if runs else 1:.1f}"
            f"){_mean(noise)}{_mean(walls)}"
        )
        noise_share += [n / w for n, w in zip(noise, walls) if w > 0]
    if noise_share:
        lines.append(
            f"noise: {100 * statistics.fmean(noise_share):.1f} % "
            "of a simulation's wall time on average"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the study's output folder")
    parser.add_argument(
        "--study", type=Path, help="run (or continue) this study file into OUT first"
    )
    parser.add_argument("--trials", type=int, help="trials in all (default: the study file's)")
    args = parser.parse_args()
    if args.study is not None:
        from torus_cad.optimize import read_study_file, run_study

        start = time.perf_counter()
        result = run_study(read_study_file(args.study), args.out, trials=args.trials, workers=1)
        print(result.summary())
        print(f"study wall time {time.perf_counter() - start:.0f} s")
    print("\n".join(summarise(args.out)))


if __name__ == "__main__":
    main()
