"""``torus-cad preview``: the propeller built and rendered off-screen into a PNG."""

from __future__ import annotations

import argparse
from pathlib import Path

from torus_cad.cli.design_input import load_parameters
from torus_cad.cli.exits import EXIT_OK
from torus_cad.outputs.output_set import check_writable_folder
from torus_cad.preview.size import parse_size


def run(args: argparse.Namespace) -> int:
    # its first line, the loading stage, is out already (torus_cad.cli.commands)
    progress = args.progress
    params = load_parameters(args.config, args.overrides)
    size = parse_size(args.size, "--size")
    out = Path(args.out) if args.out else Path("step_out") / f"{params.name}.png"
    check_writable_folder(out.parent)  # before the build, not after it
    # The kernel and the renderer load only now: a design refused above costs the schema alone.
    from torus_cad.preview.picture import write_preview
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params, progress=progress)
    path = write_preview(propeller, out, size, progress=progress)
    progress.finish()
    if not args.quiet:
        print(f"wrote {path} ({size[0]}x{size[1]} px)")
    return EXIT_OK
