"""``torus-cad build``: the design checked, built in OpenCascade and written as one output set."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.build_stages import Stage
from torus_cad.cli.design_input import format_overrides, load_parameters, writes_a_mesh
from torus_cad.cli.exits import EXIT_OK
from torus_cad.design.described_geometry import wall_printability
from torus_cad.design.stl_budget import check_stl_budget
from torus_cad.errors import GeometryError
from torus_cad.outputs.output_set import check_writable_folder, write_output_set
from torus_cad.outputs.sections_table import design_sections_table_files
from torus_cad.preview.size import parse_size
from torus_cad.runtime.isolation import IsolatedCall, prefetch_modules
from torus_cad.tolerances import MIN_BLUNT_TRAILING_EDGE_MM


def run(args: argparse.Namespace) -> int:
    # its first line, the loading stage, is out already (torus_cad.cli.commands)
    progress = args.progress
    params = load_parameters(args.config, args.overrides + format_overrides(args.formats))
    size = parse_size(args.preview_size, "--preview-size") if args.preview else None
    if args.require_printable:  # decided from the analytic section, before any work or file
        problem = wall_printability(params).problem()
        if problem:
            raise GeometryError(f"not printable (--require-printable): {problem}")
    if writes_a_mesh(params, args.no_stl):
        # a mesh that would blow up is refused before anything is built (~7 ms)
        check_stl_budget(params)
    check_writable_folder(args.out)  # before the build, not after it
    # The blade-element table (matplotlib) is drawn in a child from now on, on the second core,
    # while this process loads the kernel and builds; its files join the output set
    # (torus_cad.outputs.output_set).
    with IsolatedCall(design_sections_table_files, params, what="the blade-element table") as table:
        # The kernel loads only now: a design refused above costs the schema, not OpenCascade's
        # second too.
        from torus_cad.propeller import build_propeller

        # the mesh checker loads while the strict check runs in its child
        if writes_a_mesh(params, args.no_stl):
            prefetch_modules("meshlib.mrmeshpy", "meshlib.mrmeshnumpy")
        propeller = build_propeller(params, progress=progress)
        progress(Stage.WRITE)
        extra_files = {}
        if size is not None:
            from torus_cad.preview.picture import write_preview

            extra_files["png"] = lambda path: write_preview(
                propeller, path, size, progress=progress
            )
        # One output set: the files, the blade-element table, the picture and the report appear
        # together.
        published = write_output_set(
            propeller,
            Path(args.out),
            args.density,
            stl=not args.no_stl,
            sections_table=table,
            extra_files=extra_files,
        )
    progress.finish()
    # not re-read: a same-name build may have replaced it
    paths, report = published.paths, published.report
    if not args.quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(
            f"volume {report['volume_mm3']:.3f} mm^3, area {report['surface_area_mm2']:.3f} mm^2, "
            f"mass {report['mass_g']:.3f} g at {args.density:g} g/cm^3"
        )
        fillet = report.get("root_fillet")
        if fillet is not None and not fillet["constant_radius"]:
            print(
                f"warning: the root fillet is {fillet['radius_mm']:g} mm except along "
                f"{fillet['varying_junction_per_blade_mm']:.2f} mm "
                "of each blade's junction: a blade bends too tightly "
                "there for it, and its radius varies down "
                f"to {fillet['smallest_radius_mm']:.3g} mm",
                file=sys.stderr,
            )
        closed = report["closed_file_trailing_edge_mm"]
        if closed is not None:
            print(
                "warning: airfoil.file's open trailing edge is only "
                f"{closed[0]:.3f}-{closed[1]:.3f} mm thick, under "
                f"the {MIN_BLUNT_TRAILING_EDGE_MM:g} mm a blunt edge "
                "needs to mesh without crossing triangles: built "
                "sharp; set airfoil.trailing_edge_thickness "
                f">= {MIN_BLUNT_TRAILING_EDGE_MM:g} for a base",
                file=sys.stderr,
            )
        if not report["printability"]["printable"]:
            print(
                f"warning: not printable: {propeller.printability().problem()}; "
                "--require-printable refuses such a design",
                file=sys.stderr,
            )
        if params.blades == 1:
            print(
                f"warning: a one-blade propeller is out of balance: static imbalance "
                f"{report['balance']['static_imbalance_g_mm']:.3f} g "
                "mm; add a counterweight or use 2 or more blades",
                file=sys.stderr,
            )
    if args.verbose:
        print(
            f"centroid {tuple(round(c, 6) for c in report['centroid_mm'])} mm, "
            f"spin-axis inertia {report['spin_axis_inertia_g_mm2']:.4f} g mm^2"
        )
        for stage, seconds in report["stage_seconds"].items():
            print(f"  {stage:<13} {seconds * 1000:8.1f} ms")
    return EXIT_OK
