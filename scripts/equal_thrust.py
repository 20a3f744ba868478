#!/usr/bin/env python3
"""Toroidal against conventional at the same thrust: rpm, power, figure of merit and tonal noise of
each.

    python scripts/equal_thrust.py                          # 0.05 N, coarse level, still air
    python scripts/equal_thrust.py --thrust 0.08 --level medium --out equal_out
    python scripts/equal_thrust.py --solver vortex --out equal_vortex
        # the vortex solver (seconds, no mesh)

Runs ``torus-cad simulate --thrust N`` on the default toroidal design (no design file) and on
``examples/compare/conventional_45mm_3blade.toml`` (a conventional propeller of the same tip
diameter, blade count and hub), each as a fresh process; prints a Markdown table (the noise columns:
overall SPL and dB(A) of the steady-loading and thickness tones at 1 m in the rotor's plane, from
the report's ``noise``) and writes ``OUT/equal_thrust.json``
and a bar chart (``--picture``, default ``OUT/equal_thrust.png``). Never part of the test suite
(two thrust searches, a few solver runs each).
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

#: label -> design file (None: the default toroidal design).
DESIGNS: dict[str, Path | None] = {
    "toroidal (default)": None,
    "conventional (same D, blades, hub)": ROOT
    / "examples"
    / "compare"
    / "conventional_45mm_3blade.toml",
}
#: What the table and the picture show: report key -> (heading, scale, unit).
QUANTITIES = {
    "rpm": ("rpm", 1.0, ""),
    "thrust_n": ("thrust", 1.0, "N"),
    "power_w": ("power", 1.0, "W"),
    "torque_nm": ("torque", 1000.0, "N mm"),
    "figure_of_merit": ("figure of merit", 1.0, ""),
}
#: The observer of the noise columns: 1 m from the hub in the rotor's plane (one of simulate's
#: defaults).
NOISE_OBSERVER = (1.0, 90.0)
#: Noise columns: the observer entry's key -> heading (differences in dB, not percent).
NOISE = {"oaspl_db": "tonal SPL 1 m, 90° (dB)", "oaspl_dba": "tonal 1 m, 90° (dB(A))"}


def noise_levels(report: dict[str, Any]) -> dict[str, float]:
    """The NOISE columns of a performance report, at NOISE_OBSERVER."""
    entry = next(
        entry
        for entry in report["noise"]["observers"]
        if (entry["distance_m"], entry["angle_deg"]) == NOISE_OBSERVER
    )
    return {key: entry[key] for key in NOISE}


def search(label: str, design: Path | None, args: argparse.Namespace) -> dict[str, Any]:
    """One ``torus-cad simulate --thrust`` process; its performance report with the process's wall
    seconds."""
    out = args.out / ("toroidal" if design is None else design.stem)
    command = [
        sys.executable,
        "-m",
        "torus_cad",
        "simulate",
        *([str(design)] if design else []),
        "--thrust",
        f"{args.thrust:g}",
        *_fidelity(args),
        "--out",
        str(out),
        "-q",
    ]
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    start = time.perf_counter()
    completed = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if completed.returncode != 0:
        raise SystemExit(
            f"{label}: simulate failed (exit {completed.returncode}): "
            f"{completed.stderr.strip()[-400:]}"
        )
    report = json.loads(next(out.glob("*_performance.json")).read_text(encoding="utf-8"))
    return {**report, "process_wall_seconds": time.perf_counter() - start}


def _fidelity(args: argparse.Namespace) -> list[str]:
    """simulate's options for the solver: the vortex solver, or OpenFOAM at a mesh level on some
    processes."""
    if args.solver == "vortex":
        return ["--solver", "vortex"]
    return ["--level", args.level, "--processes", str(args.processes)]


def table(results: dict[str, dict[str, Any]]) -> str:
    """A Markdown table: one row per design, then the conventional's difference from the toroidal in
    %."""
    headings = [
        f"{name} ({unit})" if unit else name for name, _, unit in QUANTITIES.values()
    ] + list(NOISE.values())
    lines = [
        "| design | " + " | ".join(headings) + " | cells | y+ mean |",
        "|---" * (len(QUANTITIES) + len(NOISE) + 3) + "|",
    ]
    for label, report in results.items():
        cells = [f"{report[key] * scale:.4g}" for key, (_, scale, _) in QUANTITIES.items()]
        cells += [f"{value:.1f}" for value in noise_levels(report).values()]
        mesh = (
            f" | {report['cells']:,} | {report['y_plus']['mean']:.3g} |"
            if "cells" in report
            else " | – | – |"
        )
        lines.append(f"| {label} | " + " | ".join(cells) + mesh)
    toroidal, conventional = results.values()
    change = [f"{100.0 * (conventional[key] / toroidal[key] - 1.0):+.1f} %" for key in QUANTITIES]
    change += [
        f"{noise_levels(conventional)[key] - noise_levels(toroidal)[key]:+.1f} dB" for key in NOISE
    ]
    lines.append("| conventional against toroidal | " + " | ".join(change) + " | | |")
    return "\n".join(lines)


def write_picture(
    results: dict[str, dict[str, Any]], path: Path, thrust_n: float, solver: str = "coarse RANS"
) -> None:
    """Bars of rpm, power, figure of merit and the tonal dB(A) at 1 m in the rotor's plane, one
    colour per design."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = ("rpm", "power_w", "figure_of_merit", "oaspl_dba")
    figure, axes = plt.subplots(1, len(shown), figsize=(13, 3.6))
    for axis, key in zip(axes, shown):
        if key in NOISE:
            title = NOISE[key]
            values = [noise_levels(report)[key] for report in results.values()]
        else:
            name, scale, unit = QUANTITIES[key]
            title = f"{name} ({unit})" if unit else name
            values = [report[key] * scale for report in results.values()]
        bars = axis.bar(range(len(values)), values, color=["C0", "C1"])
        axis.bar_label(bars, labels=[f"{value:.3g}" for value in values], fontsize=8)
        axis.set_xticks(range(len(values)), [label.split(" (")[0] for label in results], fontsize=8)
        axis.set_title(title)
        axis.grid(axis="y", alpha=0.3)
    figure.suptitle(f"At {thrust_n:g} N of static thrust (torus-cad simulate --thrust, {solver})")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--thrust", type=float, default=0.05, help="target static thrust, N (default 0.05)"
    )
    parser.add_argument("--level", default="coarse", choices=("coarse", "medium", "fine"))
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument(
        "--solver",
        default="openfoam",
        choices=("openfoam", "vortex"),
        help="OpenFOAM at --level (default), or the vortex solver (--level and --processes unused)",
    )
    parser.add_argument("--out", type=Path, default=ROOT / "equal_thrust_out")
    parser.add_argument(
        "--picture", type=Path, help="where the bar chart goes (default OUT/equal_thrust.png)"
    )
    args = parser.parse_args()
    results = {}
    for label, design in DESIGNS.items():
        results[label] = search(label, design, args)
        print(label, {key: results[label][key] for key in QUANTITIES}, flush=True)
    print(table(results))
    args.out.mkdir(parents=True, exist_ok=True)
    solver = "vortex lattice" if args.solver == "vortex" else f"{args.level} RANS"
    write_picture(results, args.picture or args.out / "equal_thrust.png", args.thrust, solver)
    keep = (
        *QUANTITIES,
        "cells",
        "y_plus",
        "process_wall_seconds",
        "thrust_search",
        "level",
        "solver",
        "noise",
    )
    summary = {label: {key: report.get(key) for key in keep} for label, report in results.items()}
    (args.out / "equal_thrust.json").write_text(json.dumps(summary, indent=2), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
