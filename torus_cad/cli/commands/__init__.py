"""The ``torus-cad`` commands: one module per subcommand (``torus_cad.cli.commands.<name>``), loaded
only when that command runs, each with ``run(args) -> exit code``.

The parser gives every subcommand the handler :func:`run_command`, which checks the command's extra
(a one-line MissingExtraError, exit 2, before anything of it loads), announces its first stage on a
terminal (``build`` and ``preview``: the seconds of loading the schema and the kernel), then imports
the command's module and runs it. The signal handlers are installed before (torus_cad.cli.main), so
an interrupt while a command's modules load ends it with one line too.
"""

from __future__ import annotations

import argparse
import importlib
from dataclasses import dataclass

from torus_cad.build_stages import Stage
from torus_cad.runtime.extras import require_extra
from torus_cad.runtime.progress import StageProgress


@dataclass(frozen=True)
class Command:
    """How a subcommand is started.

    Attributes:
        extra: the optional dependency group it needs, checked before its
            module loads; None for the core commands.
        loading: the stage announced (``torus-cad: [   0.0 s] ...`` on a terminal, not with ``-q``)
            before its module loads; the command then reports its later stages on that same clock
            (``args.progress``, a :class:`torus_cad.runtime.progress.StageProgress`).
    """

    extra: str | None = None
    loading: Stage | None = None


#: Every subcommand, by the name typed after ``torus-cad``; its module is
#: ``torus_cad.cli.commands.<name>``.
COMMANDS: dict[str, Command] = {
    "build": Command(loading=Stage.KERNEL_IMPORT),
    "check": Command(),
    "preview": Command(loading=Stage.KERNEL_IMPORT),
    "verify": Command(),
    "defaults": Command(),
    "sweep": Command(),
    "optimize": Command(extra="optimize"),
    "studio": Command(extra="studio"),
    "mesh": Command(extra="mesh"),
    "cfd": Command(extra="cfd"),
    "simulate": Command(extra="simulate"),
}


def run_command(args: argparse.Namespace) -> int:
    """Run the subcommand ``args.command``: its extra checked, its first stage announced, its module
    loaded."""
    command = COMMANDS[args.command]
    if command.extra is not None:
        require_extra(args.command, command.extra)
    if command.loading is not None:
        args.progress = StageProgress.for_terminal(quiet=args.quiet)  # stderr, only on a terminal
        args.progress(command.loading)
    module = importlib.import_module(f"{__name__}.{args.command}")
    code: int = module.run(args)
    return code
