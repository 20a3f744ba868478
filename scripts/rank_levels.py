#!/usr/bin/env python3
"""Does the coarse level rank designs as the fine one does? Spearman's rho over toroidal designs.

    python scripts/rank_levels.py                 # 8 designs, coarse and fine, 10000 rpm, still air
    python scripts/rank_levels.py --levels coarse medium --processes 2 --out rank_out
    python scripts/rank_levels.py --designs default pitch_low two_blades   # a subset

Never part of the test suite (16 simulations). A run whose report is already in OUT is read, not
repeated, so an interrupted study resumes where it stopped. The designs are the default toroidal
propeller and variations of its pitch (the angle-of-attack law's constant term), chord (the scale_x
law's constant term) and blade count, each a ``--set`` on the default; every design runs at each
level as a fresh ``torus-cad simulate`` process. Prints, for thrust and for figure of merit, the
value per design and level and Spearman's rank correlation between the two levels
(scipy.stats.spearmanr); writes ``OUT/rank_levels.json`` with each run's cells, wall seconds and
peak memory (bench_simulate.run_with_peak_memory).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from bench_simulate import run_with_peak_memory

ROOT = Path(__file__).resolve().parent.parent

#: name -> --set overrides on the default design: pitch (alpha's constant term, deg), chord
#: (scale_x's constant term, mm) and blade count apart.
DESIGNS: dict[str, list[str]] = {
    "default": [],
    "pitch_low": ["transforms.angle_of_attack=[0,0,0,0,14]"],
    "pitch_high": ["transforms.angle_of_attack=[0,0,0,0,26]"],
    "chord_narrow": ["transforms.scale_x=[0,0,-16,16,4.5]"],
    "chord_wide": ["transforms.scale_x=[0,0,-16,16,6.8]"],
    "two_blades": ["blades=2"],
    "four_blades": ["blades=4"],
    "chord_very_narrow": ["transforms.scale_x=[0,0,-16,16,3.5]"],
}


def run(name: str, overrides: list[str], level: str, args: argparse.Namespace) -> dict[str, Any]:
    """One design at one level: its performance report and the process's wall seconds."""
    out = args.out / f"{name}_{level}"
    done, cost = out / f"{name}_performance.json", args.out / f"{name}_{level}_cost.json"
    # the sealed report is left as simulate wrote it; the process's cost sits beside it
    if done.is_file():
        measured = json.loads(cost.read_text(encoding="utf-8")) if cost.is_file() else {}
        return {**json.loads(done.read_text(encoding="utf-8")), **measured}
    command = [
        sys.executable,
        "-m",
        "torus_cad",
        "simulate",
        "--rpm",
        f"{args.rpm:g}",
        "--level",
        level,
        "--processes",
        str(args.processes),
        "--out",
        str(out),
        "-q",
        "--set",
        f"name={name}",
    ]
    for override in overrides:
        command += ["--set", override]
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    start = time.perf_counter()
    completed, peak_bytes = run_with_peak_memory(command, env)
    if completed.returncode != 0:
        raise SystemExit(
            f"{name} at {level} failed (exit {completed.returncode}): "
            f"{completed.stderr.strip()[-400:]}"
        )
    measured = {
        "process_wall_seconds": time.perf_counter() - start,
        "peak_memory_gb": peak_bytes / 1e9,
    }
    cost.write_text(json.dumps(measured), encoding="utf-8")
    return {**json.loads(done.read_text(encoding="utf-8")), **measured}


def main() -> int:
    from scipy.stats import spearmanr

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--levels", nargs=2, default=["coarse", "fine"], metavar=("CHEAP", "REFERENCE")
    )
    parser.add_argument("--rpm", type=float, default=10000.0)
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "rank_out")
    parser.add_argument("--designs", nargs="+", choices=sorted(DESIGNS), default=list(DESIGNS))
    args = parser.parse_args()
    designs = {name: DESIGNS[name] for name in args.designs}
    results: dict[str, dict[str, dict[str, Any]]] = {}
    for name, overrides in designs.items():
        results[name] = {level: run(name, overrides, level, args) for level in args.levels}
        print(
            name,
            {
                level: (round(report["thrust_n"], 5), report["figure_of_merit"])
                for level, report in results[name].items()
            },
            flush=True,
        )
    summary: dict[str, Any] = {
        "levels": args.levels,
        "rpm": args.rpm,
        "designs": designs,
        "rho": {},
    }
    for key in ("thrust_n", "figure_of_merit"):
        cheap, reference = (
            [results[name][level][key] for name in designs] for level in args.levels
        )
        rho = float(spearmanr(cheap, reference).statistic)
        summary["rho"][key] = rho
        print(f"Spearman rho of {key}, {args.levels[0]} against {args.levels[1]}: {rho:.3f}")
    summary["results"] = {
        name: {
            level: {
                key: report[key]
                for key in (
                    "thrust_n",
                    "torque_nm",
                    "figure_of_merit",
                    "cells",
                    "wall_seconds",
                    "process_wall_seconds",
                    "peak_memory_gb",
                )
                if key in report
            }
            for level, report in levels.items()
        }
        for name, levels in results.items()
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "rank_levels.json").write_text(
        json.dumps(summary, indent=2) + "\n", encoding="utf-8"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
