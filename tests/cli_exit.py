"""``torus-cad``'s exit code for a command line run in this process."""

from __future__ import annotations

from collections.abc import Sequence

from torus_cad.cli import main


def exit_code(argv: Sequence[str]) -> int:
    """``main(argv)``'s exit code, also when the parser refuses the command line (argparse exits: an
    option out of its range, an unknown option, --help)."""
    try:
        return main(list(argv))
    except SystemExit as stop:
        return int(stop.code or 0)
