#!/usr/bin/env python3
"""The vortex solver's discretisation study: three lattices, each finer than the last by one ratio
in every direction (rings across the chord, strips along the blade, wake steps a turn), the thrust
and torque of each, Richardson's extrapolation and Roache's GCI_fine
(torus_cad.simulate.coefficients.richardson, as simulate --convergence does for OpenFOAM's levels).

    python scripts/vortex_convergence.py                             # the default design, 10000 rpm
    python scripts/vortex_convergence.py --design examples/apc_10x7sf.toml --rpm 5000
    python scripts/vortex_convergence.py --coarsest 4 15 12 --ratio 1.5 --inviscid
    python scripts/vortex_convergence.py --inviscid --lattices 6,30,24 8,30,24 11,30,24  # one term
    python scripts/vortex_convergence.py --inviscid --lattices 8,30,24 --first-step-fraction 1

Prints one row a lattice (rings, strips, wake steps, thrust N, torque N mm, CPU seconds) and, for
thrust and torque, whether they change monotonically, the observed order and GCI_fine (not for
``--lattices``, which may vary one term at a time); writes nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--design", type=Path)
    parser.add_argument("--rpm", type=float, default=10000.0)
    parser.add_argument("--airspeed", type=float, default=0.0)
    parser.add_argument(
        "--coarsest",
        type=int,
        nargs=3,
        default=(4, 15, 12),
        metavar=("CHORDWISE", "SPANWISE", "STEPS"),
        help=(
            "the coarsest lattice: rings across the chord, "
            "strips, wake steps a turn (default 4 15 12)"
        ),
    )
    parser.add_argument(
        "--ratio",
        type=float,
        default=2.0**0.5,
        help="refinement ratio between lattices (default sqrt 2)",
    )
    parser.add_argument("--inviscid", action="store_true", help="no section polars")
    parser.add_argument(
        "--lattices",
        nargs="+",
        metavar="C,S,W",
        help="these lattices (rings, strips, wake steps a turn) instead of three; no GCI",
    )
    parser.add_argument(
        "--first-step-fraction",
        type=float,
        help="the wake's first segment, a fraction of its even step (default the solver's)",
    )
    args = parser.parse_args(argv)
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.coefficients import richardson
    from torus_cad.vortex.rotor import Discretisation
    from torus_cad.vortex.vortex_performance import vortex_performance

    params = PropellerParameters.from_toml(args.design) if args.design else PropellerParameters()
    if args.lattices:
        lattices = [tuple(int(value) for value in text.split(",")) for text in args.lattices]
    else:
        lattices = [
            tuple(max(2, round(value * args.ratio**level)) for value in args.coarsest)
            for level in range(3)
        ]
    rows = []
    for chordwise, spanwise, steps in lattices:
        lattice = Discretisation(chordwise, spanwise)
        wake = dataclasses.replace(lattice.wake, steps_per_turn=steps)
        if args.first_step_fraction is not None:
            wake = dataclasses.replace(wake, first_step_fraction=args.first_step_fraction)
        lattice = dataclasses.replace(lattice, wake=wake)
        start = time.process_time()
        report = vortex_performance(
            params, args.rpm, args.airspeed, lattice, viscous=not args.inviscid
        ).report
        rows.append(
            (
                chordwise,
                spanwise,
                steps,
                report["thrust_n"],
                report["torque_nm"],
                time.process_time() - start,
            )
        )
        print(
            f"| {chordwise} | {spanwise} | {steps} | "
            f"{report['thrust_n']:.6g} | {report['torque_nm'] * 1000:.6g} | "
            f"{rows[-1][-1]:.1f} |",
            flush=True,
        )
    if args.lattices:
        return 0
    for name, column in (("thrust", 3), ("torque", 4)):
        study = richardson(rows[0][column], rows[1][column], rows[2][column], args.ratio)
        if study.converges_monotonically:
            print(
                f"{name}: monotonic, observed order "
                f"{study.order:.2f}, GCI_fine {study.gci_fine:.2%}"
            )
        else:
            print(f"{name}: not monotonic ({', '.join(f'{row[column]:.6g}' for row in rows)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
