#!/usr/bin/env python3
"""Does the vortex solver rank toroidal designs as OpenFOAM's fine level does? The eight designs of
rank_levels.py at 10,000 rpm in still air, Spearman's rho of thrust and of figure of merit.

    python scripts/rank_vortex.py                   # the fine level's figures as the docs give them
    python scripts/rank_vortex.py --cfd rank_out/rank_levels.json
                                                    # or those of your own rank_levels.py run
    python scripts/rank_vortex.py --chordwise 6 --spanwise 20

Prints one markdown table (thrust and figure of merit: fine CFD, the vortex solver with its polars
and the inviscid lattice, and the differences) and Spearman's rho (scipy.stats.spearmanr) for each
pair; writes nothing. Each design is solved in this process
(torus_cad.vortex.vortex_performance.vortex_performance); a design whose solve does not converge is
left out of the table and the ranks, with a line on stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

from rank_levels import DESIGNS  # noqa: E402

#: The fine level's thrust (N) and figure of merit of each design, measured by ``python
#: scripts/rank_levels.py`` (docs/how-to/simulate.md, "Does the coarse level rank designs as the
#: fine one does?").
FINE_CFD = {
    "default": (0.06364, 0.1944),
    "pitch_low": (0.06217, 0.1893),
    "pitch_high": (0.06427, 0.1941),
    "chord_narrow": (0.05788, 0.1824),
    "chord_wide": (0.06385, 0.1908),
    "two_blades": (0.05358, 0.1914),
    "four_blades": (0.07318, 0.1947),
    "chord_very_narrow": (0.05223, 0.1701),
}


def _fine_cfd(path: Path | None) -> dict[str, tuple[float, float]]:
    if path is None:
        return FINE_CFD
    designs = json.loads(path.read_text())["designs"]
    return {
        name: (entry["fine"]["thrust_n"], entry["fine"]["figure_of_merit"])
        for name, entry in designs.items()
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--cfd", type=Path, help="rank_levels.py's rank_levels.json (default: the documented runs)"
    )
    parser.add_argument("--rpm", type=float, default=10000.0)
    parser.add_argument("--chordwise", type=int, default=8)
    parser.add_argument("--spanwise", type=int, default=30)
    args = parser.parse_args(argv)
    from scipy.stats import spearmanr

    from torus_cad.cli.design_input import load_parameters
    from torus_cad.errors import KernelError
    from torus_cad.vortex.rotor import Discretisation
    from torus_cad.vortex.vortex_performance import vortex_performance

    cfd = _fine_cfd(args.cfd)
    rows: dict[str, Any] = {}
    for name, overrides in DESIGNS.items():
        params = load_parameters(None, overrides)
        start = time.perf_counter()
        try:
            report = vortex_performance(
                params, args.rpm, 0.0, Discretisation(args.chordwise, args.spanwise)
            ).report
        except KernelError as error:  # ranked without it, and said so
            print(f"{name}: left out, {error}", file=sys.stderr, flush=True)
            continue
        rows[name] = report
        print(f"{name}: {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    print(
        "| design | thrust N, fine CFD | thrust N, vortex | Δ "
        "| inviscid thrust N | Δ | FM, fine CFD | FM, vortex |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, report in rows.items():
        thrust, merit = cfd[name]
        inviscid = report["inviscid_thrust_n"]
        print(
            f"| {name} | {thrust:.5f} | {report['thrust_n']:.5f} | "
            f"{report['thrust_n'] / thrust - 1:+.1%} | "
            f"{inviscid:.5f} | {inviscid / thrust - 1:+.1%} | "
            f"{merit:.4f} | {report['figure_of_merit']:.4f} |"
        )
    names = list(rows)
    for label, values in (
        ("thrust (vortex)", [rows[n]["thrust_n"] for n in names]),
        ("thrust (inviscid lattice)", [rows[n]["inviscid_thrust_n"] for n in names]),
    ):
        print(
            f"Spearman's rho, {label} against fine CFD: "
            f"{spearmanr(values, [cfd[n][0] for n in names])[0]:.3f}"
        )
    merit_rho = spearmanr([rows[n]["figure_of_merit"] for n in names], [cfd[n][1] for n in names])[
        0
    ]
    print(f"Spearman's rho, figure of merit (vortex) against fine CFD: {merit_rho:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
