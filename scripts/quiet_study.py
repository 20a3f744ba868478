#!/usr/bin/env python3
"""The worked quiet study's report: its Pareto designs, the chosen one re-simulated on the fine mesh
against the study's base design and a conventional propeller of the same diameter, all at the
study's target thrust, and what the study cost.

    torus-cad optimize examples/optimize_quiet.toml --out OUT --workers 2  # the study itself, first
    python scripts/quiet_study.py OUT                                      # then this
    python scripts/quiet_study.py OUT --levels vortex medium
        # both solvers side by side

Reads ``OUT/<name>_study.json`` (the Pareto designs and the worker seconds of each mesh level) and
``OUT/results.csv`` (every trial at the level it reached). The chosen design is the Pareto design
nearest the ideal point once both objectives are scaled to the front's range (the knee of the front:
neither the loudest nor the hungriest). Each of the three designs is solved to the target thrust at
each of ``--levels`` (a mesh level, or ``vortex``: the vortex solver) by ``torus-cad simulate
--thrust`` (a report already in ``OUT/<level>/<label>/`` is reused), and whether the levels rank the
three alike is printed. Prints Markdown tables and writes ``OUT/quiet_study.png`` (the trials and
front; the three designs' rpm, power, figure of merit and dB(A)). Never part of the test suite (CPU
hours of OpenFOAM).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent

#: The study's two objectives, in the study file's order (examples/optimize_quiet.toml); the noise's
#: observer (1 m from the hub in the rotor's plane) is the noise columns' too.
POWER, NOISE = "performance.power_w", "performance.noise[1:90].oaspl_dba"


def read_study(out: Path) -> tuple[dict[str, Any], list[dict[str, str]]]:
    """The study's summary (``<name>_study.json``) and its table's rows (``results.csv``)."""
    summary_path = next(out.glob("*_study.json"), None)
    if summary_path is None:
        raise SystemExit(f"{out}: no *_study.json; run torus-cad optimize with --out {out} first")
    with (out / "results.csv").open(newline="", encoding="utf-8") as table:
        rows = list(csv.DictReader(table))
    return json.loads(summary_path.read_text(encoding="utf-8")), rows


def knee(front: list[dict[str, Any]]) -> dict[str, Any]:
    """The Pareto design nearest the ideal point (each objective's best on the front), both
    objectives scaled to the front's range."""
    lows = [min(entry["values"][i] for entry in front) for i in (0, 1)]
    spans = [max(entry["values"][i] for entry in front) - lows[i] or 1.0 for i in (0, 1)]
    return min(
        front,
        key=lambda entry: sum(((entry["values"][i] - lows[i]) / spans[i]) ** 2 for i in (0, 1)),
    )


def solve(label: str, design: Path, level: str, args: argparse.Namespace) -> dict[str, Any]:
    """The design solved to the target thrust at ``level`` (a mesh level, or ``vortex``): a report
    in OUT/<level>/<label>/ reused, else one ``torus-cad simulate --thrust`` process."""
    out = args.out / level / label
    found = sorted(out.glob("*_performance.json"))
    if not found:
        fidelity = (
            ["--solver", "vortex"]
            if level == "vortex"
            else ["--level", level, "--processes", str(args.processes)]
        )
        command = [
            sys.executable,
            "-m",
            "torus_cad",
            "simulate",
            str(design),
            "--thrust",
            f"{args.thrust:g}",
            "--thrust-tolerance",
            f"{args.tolerance:g}",
            *fidelity,
            "--out",
            str(out),
            "-q",
        ]
        env = {
            **os.environ,
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
        }
        completed = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
        if completed.returncode != 0:
            raise SystemExit(
                f"{label}: simulate failed (exit {completed.returncode}): {completed.stderr[-400:]}"
            )
        found = sorted(out.glob("*_performance.json"))
    return dict(json.loads(found[0].read_text(encoding="utf-8")))


def dba(report: dict[str, Any]) -> float:
    """The performance report's A-weighted tonal level at the study's observer, dB(A), as the study
    reads it."""
    from torus_cad.optimize.metrics import metric_value

    return metric_value(NOISE, {}, report)


def front_table(
    summary: dict[str, Any], rows: list[dict[str, str]], chosen: dict[str, Any], study_level: str
) -> str:
    """The Pareto designs: their varied parameters and their values at the level they reached
    (``study_level`` for a study of one level, whose table has no level column)."""
    by_number = {int(row["number"]): row for row in rows}
    keys = list(summary["best"][0]["params"]) if summary["best"] else []
    lines = [
        "| trial | " + " | ".join(keys) + " | level | rpm | power (W) | dB(A) 1 m, 90° |",
        "|---" * (len(keys) + 5) + "|",
    ]
    for entry in sorted(summary["best"], key=lambda entry: entry["values"][0]):
        row = by_number[entry["number"]]
        mark = " (chosen)" if entry["number"] == chosen["number"] else ""
        cells = [f"{float(entry['params'][key]):.1f}" for key in keys]
        lines.append(
            f"| {entry['number']}{mark} | "
            + " | ".join(cells)
            + f" | {row.get('level', study_level)} | "
            f"{float(row['performance.rpm']):,.0f} | "
            f"{entry['values'][0]:.2f} | {entry['values'][1]:.1f} |"
        )
    return "\n".join(lines)


def comparison_table(results: dict[str, dict[str, Any]]) -> str:
    """One row per design at the target thrust, then the chosen design's and the conventional's
    differences from the base design."""
    lines = [
        "| design | rpm | thrust (N) | power (W) | figure "
        "of merit | dB(A) 1 m, 90° | cells | wall (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for label, report in results.items():
        lines.append(
            f"| {label} | {report['rpm']:,.0f} | "
            f"{report['thrust_n']:.4f} | {report['power_w']:.2f} | "
            f"{report['figure_of_merit']:.3f} | {dba(report):.1f} | {report.get('cells', 0):,} | "
            f"{report['wall_seconds']:.0f} |"
        )
    base = next(iter(results.values()))
    for label, report in list(results.items())[1:]:
        change = [
            f"{100.0 * (report[key] / base[key] - 1.0):+.1f} %"
            for key in ("rpm", "thrust_n", "power_w", "figure_of_merit")
        ]
        lines.append(
            f"| {label} against the base | "
            + " | ".join(change)
            + f" | {dba(report) - dba(base):+.1f} dB | | |"
        )
    return "\n".join(lines)


def cost_lines(summary: dict[str, Any], results: dict[str, dict[str, Any]]) -> list[str]:
    """The study's worker time by level and the fine runs' wall time, in CPU hours (one process each
    in the study; the fine runs' processes times their wall time)."""
    lines, study_s = [], 0.0
    for level, entry in summary.get("level_seconds", {}).items():
        study_s += entry["seconds"]
        lines.append(
            f"  {level}: {entry['trials']} trials, {entry['seconds'] / 3600:.2f} worker hours"
        )
    fine_s = sum(report["wall_seconds"] * report.get("processes", 1) for report in results.values())
    lines.append(
        f"  study: {study_s / 3600:.2f} CPU hours; the "
        f"{len(results)} re-simulations: {fine_s / 3600:.2f}"
    )
    return lines


def ranking_lines(by_level: dict[str, dict[str, dict[str, Any]]]) -> list[str]:
    """Each level's order of the designs by power and by dB(A) at the target thrust, and whether the
    levels agree."""
    lines = []
    for key, value in (("power", lambda report: report["power_w"]), ("dB(A)", dba)):
        orders = {
            level: sorted(results, key=lambda label: value(results[label]))
            for level, results in by_level.items()
        }
        for level, order in orders.items():
            lines.append(
                f"  {key}, {level}: " + " < ".join(label.split(" (")[0] for label in order)
            )
        lines.append(
            f"  {key}: the levels "
            f"{'agree' if len({tuple(o) for o in orders.values()}) == 1 else 'disagree'}"
        )
    return lines


def write_picture(
    rows: list[dict[str, str]],
    summary: dict[str, Any],
    chosen: dict[str, Any],
    results: dict[str, dict[str, Any]],
    path: Path,
    level: str,
    study_level: str,
) -> None:
    """Left: every valued trial (power against dB(A)) at the level it reached, the front and the
    chosen design;
    right: the three designs' numbers on ``level``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(
        1, 5, figsize=(17, 3.8), gridspec_kw={"width_ratios": [2.2, 1, 1, 1, 1]}
    )
    valued = [row for row in rows if row[POWER] and row[NOISE]]
    for level_name, style in (
        ("vortex", {"marker": "s", "color": "0.6", "s": 8}),
        ("coarse", {"marker": "^", "color": "0.7"}),
        ("medium", {"color": "tab:blue"}),
    ):
        group = [row for row in valued if row.get("level", study_level) == level_name]
        if group:
            axes[0].scatter(
                [float(r[POWER]) for r in group],
                [float(r[NOISE]) for r in group],
                label=f"trials, {level_name}" + ("" if level_name == "vortex" else " mesh"),
                **style,
            )
    front = sorted(summary["best"], key=lambda entry: entry["values"][0])
    axes[0].plot(
        [e["values"][0] for e in front],
        [e["values"][1] for e in front],
        "o-",
        color="tab:red",
        label="Pareto front",
    )
    axes[0].scatter(
        [chosen["values"][0]],
        [chosen["values"][1]],
        s=160,
        facecolors="none",
        edgecolors="k",
        label=f"chosen (trial {chosen['number']})",
    )
    axes[0].set_xlabel("power at 1 N (W)")
    axes[0].set_ylabel("tonal dB(A), 1 m, 90°")
    axes[0].grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    shown = {
        "rpm": ("rpm", lambda r: r["rpm"]),
        "power": ("power (W)", lambda r: r["power_w"]),
        "fm": ("figure of merit", lambda r: r["figure_of_merit"]),
        "dba": ("dB(A) 1 m, 90°", dba),
    }
    for axis, (title, value) in zip(axes[1:], shown.values()):
        values = [value(report) for report in results.values()]
        bars = axis.bar(range(len(values)), values, color=["C0", "C3", "C1"][: len(values)])
        axis.bar_label(bars, labels=[f"{v:.4g}" for v in values], fontsize=8)
        axis.set_xticks(range(len(values)), [label.split(" (")[0] for label in results], fontsize=8)
        axis.set_title(f"{title}, {level}", fontsize=9)
        axis.grid(axis="y", alpha=0.3)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "out", type=Path, help="the study's output folder (torus-cad optimize --out)"
    )
    parser.add_argument(
        "--base", type=Path, default=ROOT / "examples" / "optimize" / "quiet_prop.toml"
    )
    parser.add_argument(
        "--conventional",
        type=Path,
        default=ROOT / "examples" / "compare" / "conventional_127mm_3blade.toml",
    )
    parser.add_argument(
        "--thrust", type=float, default=1.0, help="target static thrust, N (the study's)"
    )
    parser.add_argument(
        "--tolerance", type=float, default=0.02, help="thrust tolerance (the study's)"
    )
    parser.add_argument(
        "--levels",
        nargs="+",
        default=["fine"],
        choices=("vortex", "coarse", "medium", "fine"),
        help="where the three designs are solved (default fine); the first is pictured",
    )
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument(
        "--study-level",
        default="coarse",
        choices=("vortex", "coarse", "medium", "fine"),
        help="the level of a study of one level (its table names none; default coarse)",
    )
    args = parser.parse_args()
    summary, rows = read_study(args.out)
    if not summary["best"]:
        raise SystemExit(f"{args.out}: the study has no Pareto design")
    chosen = knee(summary["best"])
    print(front_table(summary, rows, chosen, args.study_level))
    designs = {
        "base design": args.base,
        f"chosen (trial {chosen['number']})": Path(chosen["design"]),
        "conventional (same D, blades, hub)": args.conventional,
    }
    by_level = {
        level: {
            label: solve(label.split(" (")[0].replace(" ", "_"), design, level, args)
            for label, design in designs.items()
        }
        for level in args.levels
    }
    for level, results in by_level.items():
        print(f"\n{level}:\n" + comparison_table(results))
        print("\n".join(cost_lines(summary, results)))
    print("\n".join(ranking_lines(by_level)))
    write_picture(
        rows,
        summary,
        chosen,
        by_level[args.levels[0]],
        args.out / "quiet_study.png",
        args.levels[0],
        args.study_level,
    )
    print(f"wrote {args.out / 'quiet_study.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
