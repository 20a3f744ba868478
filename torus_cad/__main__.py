"""``python -m torus_cad ...`` and the ``torus-cad`` command.

The signal handlers go in before anything else is imported: a Ctrl-C or SIGTERM while numpy
or CadQuery is still loading ends the command with one line and exit 130 / 143 like any other
moment (torus_cad.interrupts).
"""

import sys

from torus_cad.interrupts import exit_on_signals


def main() -> int:
    """Run the torus-cad command line; return its exit code."""
    exit_on_signals()
    from torus_cad.cli import main as cli_main

    return cli_main()


if __name__ == "__main__":
    sys.exit(main())
