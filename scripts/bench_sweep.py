"""Benchmark (not a test): designs per minute of a sweep with 1 and 2 local workers and a 2-worker
Dask LocalCluster.

    python scripts/bench_sweep.py        # the built-in 12-design sweep, full resolution, STEP + STL
    python scripts/bench_sweep.py --sweep examples/sweep_example.toml

Each configuration runs the whole sweep from scratch into its own folder under bench_out/sweep/
and is timed from the call to the last table write. One-off start-up is timed apart: the local
pool's fork server importing cadquery (once per process, warmed by a one-design sweep) and the
LocalCluster starting and importing cadquery in its workers. Each line also gives
how many CPUs the whole machine kept busy meanwhile: above the sweep's worker count, other
programs were competing. The figures go to bench_out/sweep_bench.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import time
from pathlib import Path
from typing import Any

from torus_cad.batch import Outcome, load_sweep, run_sweep

# 12 designs at the default resolution (25 sections x 80 points): 3 blade counts x 4 cambers.
BENCH_SWEEP = """\
# written by scripts/bench_sweep.py
[sweep]
mode = "grid"
stl = true

[vary]
blades = [2, 3, 4]
"airfoil.max_camber" = [0.0, 0.02, 0.03, 0.04]
"""


def run_configuration(label: str, sweep_path: Path, out: Path, **kwargs: Any) -> dict[str, Any]:
    """Run the sweep from scratch with ``kwargs`` for :func:`run_sweep`; return its figures."""
    shutil.rmtree(out, ignore_errors=True)
    spec = load_sweep(sweep_path)
    cpu_before = _cpu_seconds()
    start = time.perf_counter()
    result = run_sweep(spec, out, progress=False, **kwargs)
    seconds = time.perf_counter() - start
    busy = (_cpu_seconds() - cpu_before) / seconds  # CPUs busy on the whole machine, any process
    counts = result.counts()
    figures = {
        "configuration": label,
        "designs": len(result.designs),
        "built": result.built,
        "valid": counts[Outcome.VALID],
        "refused": counts[Outcome.REFUSED],
        "problems": result.problems,
        "wall_s": round(seconds, 2),
        "designs_per_minute": round(60.0 * result.built / seconds, 2),
        "machine_cpus_busy": round(busy, 2),
        "backend": result.backend,
    }
    print(
        f"{label:<28} {result.built:3d} designs in {seconds:7.1f} s  ->  "
        f"{figures['designs_per_minute']:6.1f} designs/min   ({counts[Outcome.VALID]} valid; "
        f"machine busy {busy:.2f} of {os.cpu_count()} CPUs)",
        flush=True,
    )
    return figures


def _cpu_seconds() -> float:
    """CPU time used by every process on the machine so far, s (Linux /proc/stat; 0 elsewhere)."""
    try:
        fields = Path("/proc/stat").read_text().splitlines()[0].split()[1:]
    except OSError:
        return 0.0
    user, nice, system = (int(value) for value in fields[:3])
    return (user + nice + system) / os.sysconf("SC_CLK_TCK")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sweep", type=Path, help="sweep file (default: a built-in 12-design sweep)"
    )
    parser.add_argument(
        "--out", type=Path, default=Path("bench_out"), help="output folder (default bench_out)"
    )
    parser.add_argument("--skip-dask", action="store_true", help="local pool only")
    args = parser.parse_args(argv)

    work = args.out / "sweep"
    work.mkdir(parents=True, exist_ok=True)
    sweep_path = args.sweep
    if sweep_path is None:
        sweep_path = work / "bench_sweep.toml"
        sweep_path.write_text(BENCH_SWEEP)
    load_before = os.getloadavg()
    print(
        f"sweep {sweep_path}; {os.cpu_count()} CPUs; load average {load_before[0]:.2f} (1 min)",
        flush=True,
    )

    # Start-up, once per process: the pool's fork server imports cadquery; timed apart from the
    # sweeps.
    warm_up = work / "warm_up.toml"
    warm_up.write_text("[base.resolution]\nsections = 16\npoints = 32\n[sweep]\nstl = false\n")
    start = time.perf_counter()
    run_sweep(load_sweep(warm_up), work / "warm_up", workers=1, rebuild=True, progress=False)
    startup = {"local_pool_first_use_s": round(time.perf_counter() - start, 2)}
    print(
        f"local pool start-up (first use in this process, one small design): "
        f"{startup['local_pool_first_use_s']:.1f} s",
        flush=True,
    )

    runs = [
        run_configuration("local pool, 1 worker", sweep_path, work / "local1", workers=1),
        run_configuration("local pool, 2 workers", sweep_path, work / "local2", workers=2),
    ]
    if not args.skip_dask:
        from dask.distributed import Client, LocalCluster

        start = time.perf_counter()
        with (
            LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):
            client.run(__import__, "torus_cad.propeller")  # each worker imports cadquery once
            startup["dask_local_cluster_s"] = round(time.perf_counter() - start, 2)
            print(
                f"Dask LocalCluster start-up (2 worker processes, cadquery imported): "
                f"{startup['dask_local_cluster_s']:.1f} s",
                flush=True,
            )
            runs.append(
                run_configuration(
                    "Dask LocalCluster, 2 workers", sweep_path, work / "dask2", client=client
                )
            )

    report = {
        "sweep": str(sweep_path),
        "cpus": os.cpu_count(),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "load_average_before": load_before,
        "load_average_after": os.getloadavg(),
        "startup": startup,
        "runs": runs,
    }
    path = args.out / "sweep_bench.json"
    path.write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
