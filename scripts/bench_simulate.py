#!/usr/bin/env python3
"""Benchmark `torus-cad simulate` on the default design: each level, then the convergence study.

    python scripts/bench_simulate.py
        # coarse, medium, fine at 10000 rpm in still air
    python scripts/bench_simulate.py --levels coarse      # one level
    python scripts/bench_simulate.py --iterations 100 --processes 2
    python scripts/bench_simulate.py --design examples/apc_10x7sf_pe0.toml --rpm 5000

Never part of the test suite. Each level is a fresh `torus-cad simulate` process timed from
outside: cells, wall time, peak memory (the largest sum of resident memory over the process and
every program it starts, snappyHexMesh and the MPI solvers included, sampled by psutil every
0.2 s), thrust, torque, CT, CP, convergence and the stage times from its report. With all three
levels, the Richardson-extrapolated thrust and torque and the observed order
(torus_cad.simulate.coefficients.richardson, refinement ratio 2^(1/3) in element size).

Results go to ``bench_out/bench_simulate.json`` and a table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
LEVELS = ("coarse", "medium", "fine")


def run_with_peak_memory(
    command: list[str], env: dict[str, str]
) -> tuple[subprocess.CompletedProcess[str], int]:
    """Run ``command``; its result and the peak of its process tree's summed resident memory, bytes
    (sampled: psutil has no tree-wide high-water mark, and getrusage keeps only the largest single
    child)."""
    import psutil

    with tempfile.TemporaryFile("w+") as stdout, tempfile.TemporaryFile("w+") as stderr:
        process = psutil.Popen(command, env=env, stdout=stdout, stderr=stderr, text=True)
        peak = 0
        while process.poll() is None:
            try:
                tree = [process, *process.children(recursive=True)]
                peak = max(peak, sum(_rss(member) for member in tree))
            except psutil.NoSuchProcess:
                pass
            time.sleep(0.2)
        stdout.seek(0)
        stderr.seek(0)
        return subprocess.CompletedProcess(
            command, process.returncode, stdout.read(), stderr.read()
        ), peak


def _rss(process: Any) -> int:
    """Resident bytes of one process, 0 when it has just ended."""
    import psutil

    try:
        return int(process.memory_info().rss)
    except psutil.NoSuchProcess:
        return 0


def run_level(level: str, args: argparse.Namespace, out: Path) -> dict[str, Any]:
    command = [
        sys.executable,
        "-m",
        "torus_cad",
        "simulate",
        *([args.design] if args.design else []),
        "--rpm",
        f"{args.rpm:g}",
        "--airspeed",
        f"{args.airspeed:g}",
        "--level",
        level,
        "--processes",
        str(args.processes),
        "--out",
        str(out),
        "-q",
    ]
    if args.iterations:
        command += ["--iterations", str(args.iterations)]
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    start = time.perf_counter()
    completed, peak_bytes = run_with_peak_memory(command, env)
    wall = time.perf_counter() - start
    if completed.returncode != 0:
        return {
            "level": level,
            "exit_code": completed.returncode,
            "error": completed.stderr.strip()[-500:],
            "wall_seconds": wall,
        }
    report = json.loads(next(out.glob("*_performance.json")).read_text())
    keys = (
        "cells",
        "mesher",
        "y_plus",
        "iterations",
        "thrust_n",
        "torque_nm",
        "power_w",
        "ct",
        "cp",
        "figure_of_merit",
        "efficiency",
        "converged",
        "force_variation_last_10_percent",
        "momentum_balance",
        "stage_seconds",
    )
    return {
        "level": level,
        "exit_code": 0,
        "wall_seconds": wall,
        "peak_memory_gb": peak_bytes / 1e9,
        **{key: report[key] for key in keys},
    }


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--design", help="design file (default: the default toroidal design)")
    parser.add_argument("--rpm", type=float, default=10000.0)
    parser.add_argument("--airspeed", type=float, default=0.0)
    parser.add_argument("--levels", nargs="+", choices=LEVELS, default=list(LEVELS))
    parser.add_argument("--iterations", type=int, default=0, help="0: each level's default")
    parser.add_argument("--processes", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="bench_out")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from torus_cad.simulate.coefficients import richardson
    from torus_cad.simulate.settings import REFINEMENT_RATIO

    results = []
    with tempfile.TemporaryDirectory(prefix="bench_simulate_") as scratch:
        for level in args.levels:
            result = run_level(level, args, Path(scratch) / level)
            results.append(result)
            print(json.dumps(result), flush=True)
    summary: dict[str, Any] = {
        "design": args.design or "default",
        "rpm": args.rpm,
        "airspeed_m_s": args.airspeed,
        "processes": args.processes,
        "load_average": os.getloadavg(),
        "levels": results,
    }
    done = {result["level"]: result for result in results if result["exit_code"] == 0}
    if all(level in done for level in LEVELS):
        for key in ("thrust_n", "torque_nm"):
            summary[key] = richardson(
                *(float(done[level][key]) for level in LEVELS), REFINEMENT_RATIO
            ).report()
    print(
        f"{'level':<8}{'cells':>9}{'wall s':>9}{'peak GB':>9}"
        f"{'thrust N':>11}{'torque N m':>12}{'CT':>9}{'CP':>9}  converged"
    )
    for result in results:
        if result["exit_code"]:
            print(f"{result['level']:<8} failed: {result['error']}")
            continue
        print(
            f"{result['level']:<8}{result['cells']:>9,}{result['wall_seconds']:>9.0f}"
            f"{result['peak_memory_gb']:>9.2f}{result['thrust_n']:>11.4g}"
            f"{result['torque_nm']:>12.4g}{result['ct']:>9.4f}"
            f"{result['cp']:>9.4f}  {result['converged']}"
        )
    for key in ("thrust_n", "torque_nm"):
        if key in summary:
            entry = summary[key]
            print(
                f"{key}: Richardson {entry['extrapolated']}, "
                f"observed order {entry['observed_order']}, "
                "uncertainty of the fine level "
                f"{entry['uncertainty_fine']} ({entry['uncertainty_method']})"
            )
    out = Path(args.out)
    out.mkdir(exist_ok=True)
    (out / "bench_simulate.json").write_text(json.dumps(summary, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
