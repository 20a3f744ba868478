"""``torus-cad verify``: output sets complete, every file of one build (a study's or sweep's folder
whole)."""

from __future__ import annotations

import argparse
from pathlib import Path

from torus_cad.cli.exits import EXIT_KERNEL_FAILURE, EXIT_OK, report_error
from torus_cad.errors import IncompleteOutputError, ParameterError
from torus_cad.outputs.output_set import (
    folders_under,
    is_case_folder,
    set_folders,
    set_names,
    staging_folders,
    verify_set,
)

#: What an OpenFOAM case this project writes holds (``simulate``'s case folder, ``--case-only``
#: too).
CASE_ENTRIES = (
    "system/controlDict",
    "system/fvSchemes",
    "system/fvSolution",
    "constant",
    "0",
    "Allrun",
)


def run(args: argparse.Namespace) -> int:
    """Exit 0 when every set is complete, 1 with one line per problem of every set (sub-folders
    included)."""
    folder = Path(args.folder)
    if not folder.is_dir():
        raise ParameterError(f"verify: {str(folder)!r} is not a folder")
    if not args.name and _batch_members(folder) is not None:
        return _verify_batch_folder(folder, args.quiet)
    sets = (
        [(folder, args.name)]
        if args.name
        else [(where, name) for where in set_folders(folder) for name in set_names(where)]
    )
    cases = [] if args.name else [where for where in folders_under(folder) if is_case_folder(where)]
    if not sets and not cases:
        raise IncompleteOutputError(f"no output set in {str(folder)!r} or its sub-folders")
    problems = [] if args.name else _debris(_staging_under(folder)[0], folder)
    for case in cases:
        missing = [entry for entry in CASE_ENTRIES if not (case / entry).exists()]
        if missing:
            problems.append(
                f"{case.relative_to(folder)}: incomplete "
                f"OpenFOAM case: {', '.join(missing)} missing"
            )
        elif not args.quiet:
            print(f"ok {case}: OpenFOAM case ({', '.join(CASE_ENTRIES)})")
    for where, name in sets:
        try:
            checked = verify_set(where, name)
        except IncompleteOutputError as error:  # every problem of every set, not only the first
            prefix = "" if where == folder else f"{where.relative_to(folder)}/"
            problems += [f"{prefix}{problem}" for problem in error.problems]
            continue
        if not args.quiet:
            print(
                f"ok {checked.report.parent / name}: "
                f"{', '.join(path.name for path in checked.files)}"
            )
    for problem in problems:
        report_error(f"verify: {problem}", EXIT_KERNEL_FAILURE)
    return EXIT_KERNEL_FAILURE if problems else EXIT_OK


def _staging_under(folder: Path) -> tuple[list[Path], list[Path]]:
    """The staging folders at any depth under ``folder``: those left by stopped processes, and the
    others."""
    left: list[Path] = []
    running: list[Path] = []
    for where in folders_under(folder):
        stopped, other = staging_folders(where)
        left += stopped
        running += other
    return left, running


def _debris(left: list[Path], folder: Path) -> list[str]:
    """A problem for every staging folder in ``left`` (left by a stopped process), named from
    ``folder``."""
    return [
        f"staging folder {str(path.relative_to(folder))!r} left "
        "by a stopped process (the next run there "
        "removes it)"
        for path in left
    ]


def _batch_members(folder: Path) -> list[Path] | None:
    """The trial folders of a study folder (``trials/<number>/``) or the design folders of a sweep
    folder (``designs/<id>/``); None for any other folder."""
    from torus_cad.batch.table import DESIGNS_DIR

    # torus_cad.optimize.trial_job.TRIALS_DIR (optuna is not needed here)
    for members in ("trials", DESIGNS_DIR):
        if (folder / members).is_dir():
            return sorted(
                path
                for path in (folder / members).iterdir()
                if path.is_dir() and not path.is_symlink()
            )
    return None


def _verify_batch_folder(folder: Path, quiet: bool) -> int:
    """``verify`` of a study or sweep folder: every output set of its trials or designs and of
    ``best/`` complete, and no staging folder left by a stopped process (the next run of the study
    or sweep removes them). IncompleteOutputError (exit 1) naming the first problems and their
    count."""
    folders = [folder, *(_batch_members(folder) or [])] + (
        [folder / "best"] if (folder / "best").is_dir() else []
    )
    left, running = _staging_under(folder)  # at any depth: a trial's simulate/<level>/ folder too
    problems: list[str] = _debris(left, folder)
    sets = 0
    in_progress = len(running)
    for member in folders:
        for name in set_names(member) if member != folder else []:
            try:
                verify_set(member, name)
                sets += 1
            except IncompleteOutputError as error:
                problems.append(f"{member.relative_to(folder)}/{error}")
    if problems:
        more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
        raise IncompleteOutputError(
            f"{str(folder)!r}: {len(problems)} problem{'s' if len(problems) > 1 else ''}: "
            + "; ".join(problems[:3])
            + more
        )
    if not quiet:
        busy = (
            f"; {in_progress} staging folder{'s' if in_progress > 1 else ''} of running processes"
            if in_progress
            else ""
        )
        print(
            f"ok {folder}: {sets} complete output "
            f"set{'s' if sets != 1 else ''} in {len(folders) - 1} folders, "
            f"no staging folder left by a stopped process{busy}"
        )
    return EXIT_OK
