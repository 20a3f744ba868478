"""``torus-cad check``: every refusal the build makes before the kernel, without loading the
kernel."""

from __future__ import annotations

import argparse

from torus_cad.cli.design_input import format_overrides, load_parameters, writes_a_mesh
from torus_cad.cli.exits import EXIT_OK
from torus_cad.design.design_checks import check_design


def run(args: argparse.Namespace) -> int:
    """Exit 0 with one line when the design passes every check the build makes before the kernel
    (and a note line for what only the kernel decides: a root fillet round a knife trailing edge); 2
    with the build's own one-line refusal otherwise. OpenCascade is never loaded
    (torus_cad.design.design_checks)."""
    params = load_parameters(args.config, args.overrides + format_overrides(args.formats))
    feasible = check_design(
        params,
        mesh=writes_a_mesh(params, args.no_stl),
        walls=not args.quiet,
        require_printable=args.require_printable,
        estimate_mesh_first=True,
    )
    if not args.quiet:
        print(feasible.summary())
        for note in feasible.undecided:
            print(f"note: {note}")
    return EXIT_OK
