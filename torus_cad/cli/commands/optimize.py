"""``torus-cad optimize``: a study of the design space run by optuna (its extra checked before this
loads)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.batch import BatchError
from torus_cad.cli.design_input import require
from torus_cad.cli.exits import EXIT_KERNEL_FAILURE, EXIT_OK
from torus_cad.errors import OutputError
from torus_cad.optimize import StudyInterrupted, read_study_file, run_study
from torus_cad.optimize.storage import StorageError
from torus_cad.optimize.study_file import Sampler


def run(args: argparse.Namespace) -> int:
    """Exit 0 when the study holds its trials (refused or failed designs included), 2 for a bad
    study file or option, 1 when the storage or the workers cannot be used, 130 / 143 / 129 on a
    signal (rerun to continue)."""
    spec = read_study_file(args.study)  # a bad study file raises ParameterError: exit 2
    if spec.sampler is Sampler.CMAES:
        require("optimize (sampler cmaes)", "optimize", ["cmaes"])
    if (args.storage or spec.storage).startswith("postgresql"):
        require("optimize (PostgreSQL storage)", "optimize", ["psycopg2"])
    if args.scheduler:
        require("optimize --scheduler", "optimize", ["dask.distributed"])
    out = Path(args.out) if args.out else Path("optimize_out") / Path(args.study).stem
    try:
        result = run_study(
            spec,
            out,
            trials=args.trials,
            workers=args.workers,
            scheduler=args.scheduler,
            storage=args.storage,
            progress=False if args.quiet else None,
        )
    except StudyInterrupted as interrupt:
        print(
            f"torus-cad: optimize interrupted by {interrupt.signal_name}: "
            f"{interrupt.result.ran} trials finished "
            "in this run; rerun the same command to continue",
            file=sys.stderr,
        )
        return interrupt.exit_code
    except (BatchError, StorageError, OutputError) as error:
        print(f"torus-cad: optimize failed: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if not args.quiet:
        print(result.summary())
    return EXIT_OK
