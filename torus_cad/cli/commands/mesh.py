"""``torus-cad mesh``: a closed triangle mesh straight from the spec's math (its extra checked
before this loads)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from torus_cad.cli.design_input import load_parameters
from torus_cad.cli.exits import print_written
from torus_cad.mesh.mesh_formats import format_overrides
from torus_cad.mesh.pipeline import summary_line, write_surface_mesh
from torus_cad.outputs.output_set import check_writable_folder
from torus_cad.runtime.progress import StageProgress


def _mesh_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """``[mesh]`` values given on the command line (they override the design file's)."""
    overrides: dict[str, Any] = {
        f"mesh.{key}": getattr(args, key)
        for key in ("sections", "points", "spacing")
        if getattr(args, key) is not None
    }
    if args.formats:
        overrides.update(
            format_overrides(name for text in args.formats for name in text.split(","))
        )
    return overrides


def run(args: argparse.Namespace) -> int:
    params = load_parameters(args.config, args.overrides).with_values(_mesh_overrides(args))
    # a folder the set cannot go into is refused before the mesh is built
    check_writable_folder(args.out)
    progress = StageProgress.for_terminal(quiet=args.quiet)
    report, paths = write_surface_mesh(
        params, Path(args.out), compare=not args.no_compare, progress=progress
    )
    progress.finish()
    return print_written(paths, summary_line(report), args.quiet)
