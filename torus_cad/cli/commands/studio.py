"""``torus-cad studio``: the design page served in the browser (its extra checked before this
loads)."""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path

from torus_cad.cli.design_input import load_parameters
from torus_cad.cli.exits import EXIT_KERNEL_FAILURE
from torus_cad.errors import OutputError, ParameterError
from torus_cad.runtime.interrupts import EXIT_SIGNALS
from torus_cad.studio.server import check_host, serve


def run(args: argparse.Namespace) -> int:
    """Exit 0 never on a signal: 130 / 143 / 129 with one line, as every command."""
    check_host(args.host)
    files = Path(args.files) if args.files else None
    if files is not None and not files.is_dir():
        raise ParameterError(f"--files {args.files!r} is not a folder")
    # a bad design exits 2 before the server starts
    params = load_parameters(args.config, args.overrides)
    try:
        code = serve(params, port=args.port, host=args.host, files_folder=files)
    except OutputError as error:  # the port is in use: not a build that failed
        print(f"torus-cad: studio: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if code:
        name = next(
            signal.Signals(signum).name
            for signum, exit_code in EXIT_SIGNALS.items()
            if exit_code == code
        )
        print(f"torus-cad: studio stopped by {name}", file=sys.stderr)
    return code
