#!/usr/bin/env python3
"""Validate ``torus-cad simulate`` against the wind tunnel: the APC 10x7 Slow Flyer beside UIUC's
measurements.

    python scripts/validate_apc_10x7sf.py                   # coarse level, every point, 2 processes
    python scripts/validate_apc_10x7sf.py --level medium --out validation_out
    python scripts/validate_apc_10x7sf.py --static 5000 --advance-ratios   # one static point only

Never part of the test suite (each point is minutes of OpenFOAM). The propeller is
``examples/apc_10x7sf_pe0.toml`` (APC's station table; ``--geometry uiuc``:
``examples/apc_10x7sf.toml``, UIUC's measured blade); the measurements are in
``validation/uiuc_apc_10x7sf/`` (read by ``studies/wind_tunnel.py``). The points are the static
test at 4000, 5000 and 6000 rpm and the 5000 rpm sweep at J = 0.2, 0.4 and 0.6: the first run
meshes, every other reuses its mesh (``--mesh-from``). Each point is a fresh ``torus-cad
simulate`` process.

Writes ``OUT/validation.json`` (every point: measured, computed, errors, cells, seconds),
``OUT/validation.md`` (the table the docs show) and ``OUT/validation_apc_10x7sf.png`` (CT, CP
against rpm at J = 0, and CT, CP, eta against J at 5000 rpm, measured beside computed), and
prints the table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from studies.wind_tunnel import (  # noqa: E402  (the checkout's studies/, beside the package)
    APC_10X7SF,
    APC_10X7SF_DIAMETER_M,
    Comparison,
    markdown_table,
    read_wind_tunnel,
)

#: The descriptions of the propeller: APC's station table (PE0) with the NACA 4412 stand-in or with
#: the E63 section APC names, and UIUC's measured geometry.
DESIGNS = {
    "pe0": ROOT / "examples" / "apc_10x7sf_pe0.toml",
    "e63": ROOT / "examples" / "apc_10x7sf_e63.toml",
    "uiuc": ROOT / "examples" / "apc_10x7sf.toml",
}


def simulate_point(
    rpm: float, advance_ratio: float, args: argparse.Namespace, out: Path, mesh_from: Path | None
) -> dict[str, Any]:
    """One ``torus-cad simulate`` run; its performance report with the process's wall seconds."""
    airspeed = advance_ratio * rpm / 60.0 * APC_10X7SF_DIAMETER_M
    command = [
        sys.executable,
        "-m",
        "torus_cad",
        "simulate",
        str(DESIGNS[args.geometry]),
        "--rpm",
        f"{rpm:g}",
        "--airspeed",
        f"{airspeed:.6g}",
        "--level",
        args.level,
        "--processes",
        str(args.processes),
        "--out",
        str(out),
        "-q",
        *args.simulate_args,
    ]
    if mesh_from is not None:
        command += ["--mesh-from", str(mesh_from)]
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    start = time.perf_counter()
    completed = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if completed.returncode != 0:
        raise SystemExit(
            f"simulate failed at {rpm:g} rpm, J = {advance_ratio:g} (exit {completed.returncode}): "
            f"{completed.stderr.strip().splitlines()[-1:]}"
        )
    report = json.loads(next(out.glob("*_performance.json")).read_text(encoding="utf-8"))
    return {**report, "process_wall_seconds": wall}


def points(args: argparse.Namespace) -> list[tuple[float, float]]:
    """(rpm, J) of every point, the meshing one first."""
    static = [(rpm, 0.0) for rpm in args.static]
    return static + [(args.sweep_rpm, j) for j in args.advance_ratios]


def write_picture(rows: list[dict[str, Any]], data: Any, path: Path) -> None:
    """CT and CP against rpm (J = 0) and CT, CP, eta against J at the sweep's rpm, measured as
    lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (static_axes, sweep_axes) = plt.subplots(1, 2, figsize=(11, 4.2))
    table = data.static
    static_axes.plot(table.column("RPM"), table.column("CT"), "C0-", label="CT measured (UIUC)")
    static_axes.plot(table.column("RPM"), table.column("CP"), "C1-", label="CP measured (UIUC)")
    computed = [row for row in rows if row["advance_ratio"] == 0.0]
    static_axes.plot(
        [row["rpm"] for row in computed],
        [row["ct"] for row in computed],
        "C0o",
        label="CT simulate",
    )
    static_axes.plot(
        [row["rpm"] for row in computed],
        [row["cp"] for row in computed],
        "C1s",
        label="CP simulate",
    )
    static_axes.set(xlabel="rpm", ylabel="coefficient", title="static (J = 0)")
    sweep = [row for row in rows if row["advance_ratio"] > 0.0]
    if sweep:
        measured = data.sweeps[min(data.sweeps, key=lambda key: abs(key - sweep[0]["rpm"]))]
        j = measured.column("J")
        for column, style in (("CT", "C0"), ("CP", "C1"), ("eta", "C2")):
            sweep_axes.plot(j, measured.column(column), f"{style}-", label=f"{column} measured")
        sweep_axes.plot(
            [row["advance_ratio"] for row in sweep],
            [row["ct"] for row in sweep],
            "C0o",
            label="CT simulate",
        )
        sweep_axes.plot(
            [row["advance_ratio"] for row in sweep],
            [row["cp"] for row in sweep],
            "C1s",
            label="CP simulate",
        )
        sweep_axes.plot(
            [row["advance_ratio"] for row in sweep],
            [row["efficiency"] for row in sweep],
            "C2^",
            label="eta simulate",
        )
        sweep_axes.set(
            xlabel="advance ratio J", ylim=(0.0, 0.9), title=f"{sweep[0]['rpm']:.0f} rpm"
        )
    for axes in (static_axes, sweep_axes):
        axes.grid(alpha=0.3)
        axes.legend(fontsize=7)
    figure.suptitle("APC 10x7 Slow Flyer: torus-cad simulate against the UIUC wind tunnel")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--level", default="coarse", choices=("coarse", "medium", "fine"))
    parser.add_argument(
        "--geometry",
        default="pe0",
        choices=sorted(DESIGNS),
        help="the blade from APC's station table with a "
        "NACA 4412 (pe0, default) or with the E63 (e63), or "
        "UIUC's measured geometry (uiuc)",
    )
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument(
        "--static",
        type=float,
        nargs="*",
        default=[5000.0, 4000.0, 5987.0],
        help="rpm at J = 0 (UIUC measured up to 5987)",
    )
    parser.add_argument("--sweep-rpm", type=float, default=5000.0)
    parser.add_argument("--advance-ratios", type=float, nargs="*", default=[0.2, 0.4, 0.6])
    parser.add_argument("--out", type=Path, default=ROOT / "validation_out")
    parser.add_argument(
        "--simulate-args",
        nargs=argparse.REMAINDER,
        default=[],
        help="passed on to every torus-cad simulate (e.g. --iterations 400)",
    )
    args = parser.parse_args()
    data = read_wind_tunnel(APC_10X7SF)
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    comparisons: list[Comparison] = []
    mesh_from: Path | None = None
    for rpm, j in points(args):
        out = args.out / f"{args.geometry}_{args.level}_{rpm:.0f}_J{j:.2f}"
        report = simulate_point(rpm, j, args, out, mesh_from)
        mesh_from = mesh_from or next(out.glob("*_case"))
        measured = data.static_point(rpm) if j == 0.0 else data.sweep_point(rpm, j)
        comparison = Comparison(measured, float(report["ct"]), float(report["cp"]))
        comparisons.append(comparison)
        rows.append(
            {
                "rpm": rpm,
                "advance_ratio": j,
                "ct": comparison.ct,
                "cp": comparison.cp,
                "efficiency": comparison.efficiency,
                "measured": measured.__dict__,
                "ct_error": comparison.ct_error,
                "cp_error": comparison.cp_error,
                "efficiency_error": comparison.efficiency_error,
                "within_targets": comparison.within_targets,
                "cells": report.get("cells"),
                "y_plus": report.get("y_plus"),
                "converged": report.get("converged"),
                "thrust_n": report["thrust_n"],
                "torque_nm": report["torque_nm"],
                "process_wall_seconds": report["process_wall_seconds"],
            }
        )
        print(
            f"{rpm:.0f} rpm, J = {j:.2f}: CT {comparison.ct:.4f}"
            f" ({100 * comparison.ct_error:+.1f} %), "
            f"CP {comparison.cp:.4f} ({100 * comparison.cp_error:+.1f} %), "
            f"{report['process_wall_seconds']:.0f} s",
            flush=True,
        )
    table = markdown_table(comparisons)
    (args.out / "validation.json").write_text(
        json.dumps({"level": args.level, "geometry": args.geometry, "points": rows}, indent=2)
        + "\n",
        encoding="utf-8",
    )
    (args.out / "validation.md").write_text(table + "\n", encoding="utf-8")
    write_picture(rows, data, args.out / "validation_apc_10x7sf.png")
    print(table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
