"""The command line's exit codes and its one-line messages on stderr (standard library only: loaded
first)."""

from __future__ import annotations

import sys
from pathlib import Path

from torus_cad.errors import bounded_message

EXIT_OK, EXIT_KERNEL_FAILURE, EXIT_BAD_INPUT = 0, 1, 2


def report_error(message: str, code: int) -> int:
    """Print ``torus-cad: message`` on stderr, one line, a long value in it cut short; return
    ``code``."""
    print(bounded_message(f"torus-cad: {message}"), file=sys.stderr)
    return code


def print_written(paths: dict[str, Path], summary: str, quiet: bool) -> int:
    """Unless ``quiet``: one ``wrote <path>`` line per file, then the summary line; the exit code
    (0)."""
    if not quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(summary)
    return EXIT_OK
