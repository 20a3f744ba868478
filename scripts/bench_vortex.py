#!/usr/bin/env python3
"""Benchmark the vortex solver (``simulate --solver vortex``) on the default design, beside
OpenFOAM's coarse level.

    python scripts/bench_vortex.py     # one point, the solver in this process and the whole command
    python scripts/bench_vortex.py --cfd
                                       # and `torus-cad simulate --level coarse` of the same point
    python scripts/bench_vortex.py --design examples/apc_10x7sf.toml --rpm 5000

Never part of the test suite. Prints, for one operating point at the default lattice: the solver's
stage times in this process (the blade's lattice, the inviscid solve, the polars and strip forces:
CPU seconds on one core: the BLAS libraries' threads are set to 1 before numpy loads, for the
commands too), then each command as a fresh process timed from outside (wall seconds and peak memory
of its process tree): ``simulate --solver vortex --rpm``, ``simulate --solver vortex --thrust`` (the
thrust of that point) and, with ``--cfd``, ``simulate --level coarse --processes 1``; and the ratios
of the vortex commands to the CFD one.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

# one core, before numpy loads
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

from bench_simulate import run_with_peak_memory  # noqa: E402


def solver_stages(design: Path | None, rpm: float) -> dict[str, float]:
    """CPU seconds of each stage of one point in this process (one core), and the thrust found."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.settings import OperatingPoint
    from torus_cad.vortex import vortex_performance as vortex
    from torus_cad.vortex.rotor import Discretisation, rotor_blade
    from torus_cad.vortex.solver import solve_inviscid

    params = PropellerParameters.from_toml(design) if design else PropellerParameters()
    import neuralfoil  # noqa: F401  (its import is the process's, not the solver's)

    discretisation = Discretisation()
    start = time.process_time()
    blade = rotor_blade(params, discretisation)
    lattice_s = time.process_time() - start
    point = OperatingPoint(rpm)
    inviscid = solve_inviscid(
        blade.camber_m,
        blade.blades,
        blade.spin,
        rpm * math.pi / 30.0,
        0.0,
        point.fluid.density_kg_m3,
        blade.tip_radius_m,
        discretisation.wake,
    )
    solve_s = time.process_time() - start - lattice_s
    result = vortex.vortex_performance(params, rpm)
    whole_s = time.process_time() - start - lattice_s - solve_s
    return {
        "blade lattice": lattice_s,
        "inviscid solve": solve_s,
        "whole point (again, with polars)": whole_s,
        "thrust_n": result.report["thrust_n"],
        "iterations": inviscid.iterations,
    }


def timed(command: list[str]) -> dict[str, Any]:
    """Wall seconds and peak memory (GB) of ``command`` as a fresh process; exit status."""
    start = time.perf_counter()
    done, peak = run_with_peak_memory(command, dict(os.environ))
    if done.returncode != 0:
        print(done.stderr, file=sys.stderr)
    return {"wall_s": time.perf_counter() - start, "peak_gb": peak / 1e9, "exit": done.returncode}


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--design", type=Path)
    parser.add_argument("--rpm", type=float, default=10000.0)
    parser.add_argument(
        "--cfd", action="store_true", help="also time OpenFOAM's coarse level of the same point"
    )
    args = parser.parse_args()
    stages = solver_stages(args.design, args.rpm)
    for name in ("blade lattice", "inviscid solve", "whole point (again, with polars)"):
        print(f"{name:34s} {stages[name]:7.2f} s CPU")
    print(f"{'wake iterations and sweeps':34s} {stages['iterations']:7d}")
    design = [str(args.design)] if args.design else []
    base = [sys.executable, "-m", "torus_cad", "simulate", *design, "--quiet"]
    with tempfile.TemporaryDirectory() as folder:
        runs = {
            "vortex --rpm": timed(
                base + ["--solver", "vortex", "--rpm", f"{args.rpm:g}", "--out", f"{folder}/a"]
            ),
            "vortex --thrust": timed(
                base
                + [
                    "--solver",
                    "vortex",
                    "--thrust",
                    f"{stages['thrust_n']:.6g}",
                    "--out",
                    f"{folder}/b",
                ]
            ),
        }
        if args.cfd:
            runs["openfoam coarse"] = timed(
                base
                + [
                    "--rpm",
                    f"{args.rpm:g}",
                    "--level",
                    "coarse",
                    "--processes",
                    "1",
                    "--out",
                    f"{folder}/c",
                ]
            )
    for name, run in runs.items():
        ratio = (
            f", {run['wall_s'] / runs['openfoam coarse']['wall_s']:.3f} of the CFD's"
            if "openfoam coarse" in runs and name != "openfoam coarse"
            else ""
        )
        print(
            f"{name:34s} {run['wall_s']:7.1f} s wall, "
            f"{run['peak_gb']:.2f} GB peak, exit {run['exit']}{ratio}"
        )
    print(json.dumps({"stages": stages, "runs": runs}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
