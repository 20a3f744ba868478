"""``torus-cad cfd``: the fluid domain and its tetrahedral mesh by gmsh (its extra checked before
this loads)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.cfd_domain.domain import gmsh_library, import_gmsh, summary_line, write_cfd_domain
from torus_cad.cfd_domain.estimate import check_cfd_budget
from torus_cad.cfd_domain.interruptible import run_in_worker
from torus_cad.cli.design_input import load_parameters, table_overrides
from torus_cad.cli.exits import print_written
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.kernel.mesh_check import import_meshlib
from torus_cad.outputs.output_set import check_writable_folder
from torus_cad.runtime.progress import StageProgress


def run(args: argparse.Namespace) -> int:
    params = load_parameters(args.config, args.overrides).with_values(table_overrides(args, "cfd"))
    progress = StageProgress.for_terminal(quiet=args.quiet)
    gmsh = import_gmsh()  # MissingExtraError (exit 2) when gmsh's library does not load
    import_meshlib()
    params = resolve_design_targets(params).parameters  # once, for the estimate and the mesh
    # a mesh that would blow up is refused before any work (a few s)
    estimate = check_cfd_budget(params)
    check_writable_folder(args.out)
    if not args.quiet:
        print(f"torus-cad cfd: {estimate.line()}", file=sys.stderr, flush=True)
    # gmsh set up here, meshing in a worker thread: a signal during a long gmsh call ends the
    # command at once (cfd.worker, cfd.domain.gmsh_library); the waiting thread prints the heartbeat
    # of a long stage
    with gmsh_library(gmsh):
        report, paths = run_in_worker(
            lambda: write_cfd_domain(
                params, Path(args.out), threads=args.threads, progress=progress, estimate=estimate
            ),
            on_wait=progress.heartbeat,
        )
    progress.finish()
    return print_written(paths, summary_line(report), args.quiet)
