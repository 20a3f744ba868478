"""``python -m torus_cad ...`` and the ``torus-cad`` command.

The signal handlers go in before anything else is imported: a Ctrl-C or SIGTERM while numpy
or CadQuery is still loading ends the command with one line and exit 130 / 143 like any other
moment (torus_cad.runtime.interrupts).
"""

import sys

from torus_cad.runtime.interrupts import exit_on_signals, hold_signals_until_exit


def main() -> int:
    """Run the torus-cad command line; return its exit code."""
    exit_on_signals()
    from torus_cad.cli import main as cli_main

    code = cli_main()
    hold_signals_until_exit()  # the work is done: a signal now must not turn exit 0 into "killed"
    return code


if __name__ == "__main__":
    sys.exit(main())
