#!/usr/bin/env python3
"""The vortex solver's discretisation study: three lattices, each finer than the last by one ratio
in every direction (rings across the chord, strips along the blade, wake steps a turn), the thrust
and torque of each, Richardson's extrapolation and Roache's GCI_fine
(torus_cad.simulate.coefficients.richardson). ``torus-cad simulate --solver vortex --convergence``
runs the same study on a design and publishes it; this script also varies one term at a time
(``--lattices``), prints blade 0's force strip by strip and takes the inviscid lattice alone.

    python scripts/vortex_convergence.py                             # the default design, 10000 rpm
    python scripts/vortex_convergence.py --design examples/apc_10x7sf.toml --rpm 5000
    python scripts/vortex_convergence.py --coarsest 4 15 12 --ratio 1.5 --inviscid
    python scripts/vortex_convergence.py --inviscid --lattices 6,30,24 8,30,24 11,30,24  # one term
    python scripts/vortex_convergence.py --inviscid --lattices 8,30,24 --wake first_step_fraction=1
    python scripts/vortex_convergence.py --inviscid --lattices 8,30,24 16,30,24 --strips

Prints one row a lattice (rings, strips, wake steps, thrust N, torque N mm, CPU seconds) and, for
thrust and torque, whether they change monotonically, the observed order and GCI_fine (not for
``--lattices``, which may vary one term at a time); with ``--strips`` (lattices of one strip count)
also blade 0's axial force strip by strip, one column a lattice, to find where a change comes from;
writes nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray


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
        "--strips",
        action="store_true",
        help="also blade 0's axial force (N) strip by strip, one column a lattice",
    )
    parser.add_argument(
        "--wake",
        nargs="+",
        default=[],
        metavar="FIELD=VALUE",
        help="the wake's layout changed (torus_cad.vortex.lattice.WakeShape's number fields)",
    )
    args = parser.parse_args(argv)
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.coefficients import richardson
    from torus_cad.vortex.pipeline import refined_lattice
    from torus_cad.vortex.rotor import Discretisation
    from torus_cad.vortex.vortex_performance import vortex_performance

    params = PropellerParameters.from_toml(args.design) if args.design else PropellerParameters()
    changes: dict[str, Any] = {  # JSON values: 1 an int, 0.4 a float, true a bool
        name: json.loads(value) for name, value in (text.split("=") for text in args.wake)
    }
    if args.lattices:
        lattices = [tuple(int(value) for value in text.split(",")) for text in args.lattices]
    else:  # as simulate --solver vortex --convergence refines its lattice
        chordwise, spanwise, steps = args.coarsest
        coarsest = Discretisation(chordwise, spanwise)
        coarsest = dataclasses.replace(
            coarsest, wake=dataclasses.replace(coarsest.wake, steps_per_turn=steps)
        )
        lattices = [
            (lattice.chordwise, lattice.spanwise, lattice.wake.steps_per_turn)
            for lattice in (refined_lattice(coarsest, level, args.ratio) for level in range(3))
        ]
    rows = []
    strip_forces = []
    first_result = None
    for chordwise, spanwise, steps in lattices:
        lattice = Discretisation(chordwise, spanwise)
        wake = dataclasses.replace(lattice.wake, steps_per_turn=steps, **changes)
        lattice = dataclasses.replace(lattice, wake=wake)
        start = time.process_time()
        result = vortex_performance(
            params, args.rpm, args.airspeed, lattice, viscous=not args.inviscid
        )
        report = result.report
        strip_forces.append((result.strips.s, result.ring_force_n[..., 2].sum(axis=1)))
        first_result = first_result or result
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
    if args.strips:
        _print_strips(strip_forces, _flow_across_chord(first_result, args.rpm, args.airspeed))
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


def _print_strips(
    strip_forces: list[tuple[NDArray[np.float64], NDArray[np.float64]]],
    flow_chord_cosine: NDArray[np.float64],
) -> None:
    """One row a strip: its centerline parameter s, the cosine of the angle between the flow the
    turning blade meets (rotation and inflow) and its chord (the first lattice's), and blade 0's
    axial force on it (N) in each lattice (those of the first lattice's strip count)."""
    s, _ = strip_forces[0]
    columns = [force for strip_s, force in strip_forces if len(strip_s) == len(s)]
    print("| s | cos(flow, chord) | " + " | ".join("axial force N" for _ in columns) + " |")
    for k, value in enumerate(s):
        forces = " | ".join(f"{column[k]:+.5f}" for column in columns)
        print(f"| {value:.3f} | {flow_chord_cosine[k]:+.3f} | {forces} |")


def _flow_across_chord(result: Any, rpm: float, airspeed: float) -> NDArray[np.float64]:
    """``(K - 1,)`` each strip's cosine between the kinematic flow at its middle and its chord
    (leading to trailing edge): near 0 where the chord stands across the flow."""
    from torus_cad.vortex.solver import kinematic_velocity

    camber = result.blade.camber_m
    middle = 0.5 * (camber[:-1] + camber[1:]).mean(axis=1)
    chord = camber[:-1, -1] + camber[1:, -1] - camber[:-1, 0] - camber[1:, 0]
    flow = kinematic_velocity(middle, rpm * np.pi / 30.0, result.blade.spin, airspeed)
    along = np.einsum("jk,jk->j", flow, chord)
    return np.asarray(
        along / (np.linalg.norm(flow, axis=1) * np.linalg.norm(chord, axis=1)), dtype=np.float64
    )


if __name__ == "__main__":
    sys.exit(main())
