"""Command line: ``torus-cad build | defaults | verify | ...``. Thin: parse, call the package, map
errors to exit codes.

Exit codes: 0 success; 2 bad input (a one-line message naming the field, no traceback, no
file written); 1 the kernel or the file system failed (the cause named: OpenCascade, no space
left, permission denied, out of memory) or ``verify`` found an incomplete set; 130 / 143 / 129
interrupted by SIGINT / SIGTERM / SIGHUP (torus_cad.runtime.interrupts).

The signal handlers are installed before anything heavy is imported (this module imports only
the standard library and torus_cad's light modules at the top; numpy, CadQuery and the rest load
with the command's own module, torus_cad.cli.commands.<name>), so an interrupt at any moment ends
the command with one line.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from torus_cad.cli.exits import EXIT_BAD_INPUT, EXIT_KERNEL_FAILURE, EXIT_OK, report_error
from torus_cad.cli.parser import build_parser
from torus_cad.errors import (
    GeometryError,
    IncompleteOutputError,
    MissingExtraError,
    OutputError,
    ParameterError,
    TorusCadError,
)
from torus_cad.runtime.interrupts import exit_on_signals

__all__ = ["EXIT_BAD_INPUT", "EXIT_KERNEL_FAILURE", "EXIT_OK", "build_parser", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``torus-cad``; returns the exit code."""
    restore_signals = exit_on_signals()  # first: an interrupt while importing is clean too
    try:
        args = build_parser().parse_args(
            _joined_signed_values(sys.argv[1:] if argv is None else list(argv))
        )
        handler: Callable[[argparse.Namespace], int] = args.handler
        return _run(handler, args)
    finally:
        restore_signals()


#: Options whose values start with '-' ('--axis -x'): argparse would take such a value for an
#: option.
_SIGNED_VALUE_OPTIONS = ("--axis",)


def _joined_signed_values(argv: list[str]) -> list[str]:
    """``argv`` with ``--axis -x`` written as ``--axis=-x``, which argparse reads as the value."""
    joined: list[str] = []
    for word in argv:
        if (
            joined
            and joined[-1] in _SIGNED_VALUE_OPTIONS
            and word.startswith("-")
            and word[1:] in ("x", "y", "z")
        ):
            joined[-1] = f"{joined[-1]}={word}"
        else:
            joined.append(word)
    return joined


def _run(handler: Callable[[argparse.Namespace], int], args: argparse.Namespace) -> int:
    """The handler's exit code; every failure becomes one line on stderr and its exit code."""
    try:
        return handler(args)
    except (ParameterError, GeometryError) as error:
        return report_error(f"error: {error}", EXIT_BAD_INPUT)
    except MissingExtraError as error:
        return report_error(str(error), EXIT_BAD_INPUT)
    except IncompleteOutputError as error:
        return report_error(f"verify: {error}", EXIT_KERNEL_FAILURE)
    except OutputError as error:
        return report_error(f"build failed: {error}", EXIT_KERNEL_FAILURE)
    except TorusCadError as error:
        return report_error(f"kernel failure: {error}", EXIT_KERNEL_FAILURE)
    except MemoryError:
        return report_error(
            "out of memory; lower resolution.sections / "
            "resolution.points or raise the STL deflections",
            EXIT_KERNEL_FAILURE,
        )
    except OSError as error:
        where = f" {error.filename!r}" if error.filename else ""
        return report_error(
            f"cannot write output{where}: {error.strerror or error}", EXIT_KERNEL_FAILURE
        )
    # main() called outside the main thread, where no handler could be installed
    except KeyboardInterrupt:
        return report_error("interrupted", 130)
    # an import that require_extra did not foresee: still named, with its extra
    except ModuleNotFoundError as error:
        return report_error(_missing_module_message(args.command, error), EXIT_BAD_INPUT)
    except Exception as error:
        return report_error(
            f"internal error ({type(error).__name__}): "
            f"{error}; please report it with the design file",
            EXIT_KERNEL_FAILURE,
        )


def _missing_module_message(command: str, error: ModuleNotFoundError) -> str:
    """One line for a module missing at run time: the extra that installs it and the install
    command."""
    from torus_cad.runtime.extras import extra_of_module, install_line, missing_extra_message

    module = error.name or str(error)
    extra = extra_of_module(module)
    if extra is not None:
        return missing_extra_message(command, extra, module)
    return f"{command} needs {module}, which is not installed: {install_line()}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
