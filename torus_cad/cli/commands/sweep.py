"""``torus-cad sweep``: many variants of a design built in parallel and tabulated."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.batch import BatchError, SweepInterrupted, load_sweep, run_sweep
from torus_cad.cli.design_input import require
from torus_cad.cli.exits import EXIT_KERNEL_FAILURE, EXIT_OK


def run(args: argparse.Namespace) -> int:
    """Exit 0 when every design is valid or refused, 1 when any failed (errored, crashed, timed
    out), 2 for a bad sweep file, 130 / 143 on SIGINT / SIGTERM (one line; the table of what
    finished is written)."""
    if args.scheduler:
        require("sweep --scheduler", "sweep")

    spec = load_sweep(args.sweep)  # a bad sweep file raises ParameterError: exit 2
    out = Path(args.out) if args.out else Path("sweep_out") / Path(args.sweep).stem
    try:
        result = run_sweep(
            spec,
            out,
            workers=args.workers,
            scheduler=args.scheduler,
            stl=False if args.no_stl else None,
            density_g_cm3=args.density,
            time_limit_s=args.time_limit,
            rebuild=args.rebuild,
            progress=False if args.quiet else None,
            oversubscribe=args.oversubscribe,
        )
    except SweepInterrupted as interrupt:
        partial = interrupt.result
        done = (
            f"{partial.counts_text()}; table written to {partial.tables['csv']}"
            if partial.tables
            else "nothing was built"
        )
        print(
            f"torus-cad: sweep interrupted by {interrupt.signal_name}: "
            f"{done}; rerun the same command to resume",
            file=sys.stderr,
        )
        return interrupt.exit_code
    except BatchError as error:
        print(f"torus-cad: sweep failed: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if not args.quiet:
        print(result.summary())
    # -q keeps a run quiet, not its failures: their causes go to stderr
    elif result.exit_code != EXIT_OK:
        print(result.summary(), file=sys.stderr)
    return result.exit_code
