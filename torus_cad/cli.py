"""Command line: ``torus-cad build | defaults | verify | ...``. Thin: parse, call the package, map errors to exit codes.

Exit codes: 0 success; 2 bad input (a one-line message naming the field, no traceback, no
file written); 1 the kernel or the file system failed (the cause named: OpenCascade, no space
left, permission denied, out of memory) or ``verify`` found an incomplete set; 130 / 143 / 129
interrupted by SIGINT / SIGTERM / SIGHUP (torus_cad.interrupts).

The signal handlers are installed before anything heavy is imported (this module imports only
the standard library and torus_cad's light modules at the top; numpy, CadQuery and the rest load
inside the commands), so an interrupt at any moment ends the command with one line.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.errors import GeometryError, IncompleteOutputError, OutputError, ParameterError, TorusCadError
from torus_cad.interrupts import exit_on_signals
from torus_cad.stages import Stage
from torus_cad.tolerances import MIN_BLUNT_TRAILING_EDGE_MM

if TYPE_CHECKING:
    from torus_cad.parameters import PropellerParameters

EXIT_OK, EXIT_KERNEL_FAILURE, EXIT_BAD_INPUT = 0, 1, 2

DESCRIPTION = """\
torus_cad turns a few design parameters into a toroidal propeller: airfoil sections (NACA 4- or
5-digit, or a coordinate file) swept along a cubic NURBS centerline, lofted into blades, patterned
around a cylindrical hub and fused in OpenCascade. It writes a STEP solid (for CAD/CAM), STL and
3MF meshes (for printing) and a JSON report (volume, mass properties, printability, checks);
further commands make CFD meshes and domains, sweeps and a browser studio.
"""

EPILOG = """\
examples:
  torus-cad build                          default propeller into step_out/
  torus-cad defaults > my_prop.toml        start a design from the commented defaults
  torus-cad build my_prop.toml --out parts/
  torus-cad build my_prop.toml --set blades=4 --set hub.radius=12
  torus-cad preview my_prop.toml --out prop.png --size 1600x800

units: mm and degrees. Control points are in the hub frame L: [x_L degrees around the axis,
y_L mm down the axis from 1 mm below the top face, z_L mm radially out from R - R/8].
"""


class _Parser(argparse.ArgumentParser):
    """argparse whose usage errors are one line and exit 2, like every other bad input.

    ``table``: the schema table whose parameters become options (``--name``), added when the
    subcommand is actually used: reading the schema loads pydantic, which ``build`` must not wait
    for before its first progress line.
    """

    table: str = ""

    def parse_known_args(self, args: Any = None, namespace: Any = None) -> Any:  # type: ignore[override, unused-ignore]
        if self.table:
            table, self.table = self.table, ""
            _add_table_arguments(self, table)
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"torus-cad: error: {message} (see {self.prog} --help)\n")


def _parse_override(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise ParameterError(f"--set {text!r} must look like key=value, e.g. hub.radius=12")
    key, raw = text.split("=", 1)
    from torus_cad.parameters.config_file import check_toml_shape

    check_toml_shape(f"{key.strip()} = {raw}", "--set", lines=False)  # too deep or too long: named, not a crash
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word: treat as a string (e.g. name=my_prop)
    except ValueError as error:  # e.g. an integer of more than 4300 digits
        raise ParameterError(f"--set {key.strip()}: {_first_clause(error)}") from None
    return key.strip(), value


def _as_declared_strings(changes: dict[str, Any]) -> dict[str, Any]:
    """``changes`` with a number given to a text parameter taken as its text: ``--set airfoil.naca=4415``
    means the designation '4415', as a user types it, not the integer TOML reads."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.parameters.schema import iter_parameter_specs

    text_keys = {spec.key for spec in iter_parameter_specs(PropellerParameters) if spec.kind is str}
    return {key: str(value) if key in text_keys and isinstance(value, int | float) and not isinstance(value, bool)
            else value for key, value in changes.items()}


def _first_clause(error: BaseException) -> str:
    """The error's message up to its first ';', on one line."""
    return " ".join(str(error).split(";")[0].split())[:200]


def load_parameters(config: str | None, overrides: Sequence[str] = ()) -> PropellerParameters:
    """Parameters from a TOML file (or the defaults) with ``key=value`` overrides applied."""
    from torus_cad.parameters import resolve_parameters  # imported here: the schema takes most of a second

    changes = _as_declared_strings(dict(_parse_override(item) for item in overrides))
    try:
        return resolve_parameters(config or None, changes)
    except ParameterError:
        raise
    except (OverflowError, ValueError) as error:  # reading input only: whatever fails here is bad input
        source = f"configuration {config!r}" if config else "a --set value"
        raise ParameterError(f"{source} holds a value that cannot be used: {_first_clause(error)}") from None


def _design_command(commands: Any, name: str, help: str, description: str, **options: Any) -> _Parser:
    """A subcommand that reads a design: CONFIG (optional) and ``--set`` overrides."""
    parser: _Parser = commands.add_parser(name, help=help, description=description, **options)
    parser.add_argument("config", nargs="?", help="TOML design file (default: the built-in propeller; "
                        "see 'torus-cad defaults')")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override one parameter, dotted keys, TOML values (repeatable): "
                             "--set hub.radius=12 --set centerline.p2=[20,3,25]")
    return parser


def _command_build(args: argparse.Namespace) -> int:
    from torus_cad.progress import StageProgress

    progress = StageProgress.for_terminal(quiet=args.quiet)  # stderr, only on a terminal
    progress(Stage.KERNEL_IMPORT)  # a line on the terminal before the seconds of importing the schema and cadquery
    from torus_cad.budgets import check_stl_budget
    from torus_cad.outputs import check_writable_folder, write_output_set

    params = load_parameters(args.config, args.overrides + _format_overrides(args.formats))
    size = _preview_size(args.preview_size, "--preview-size") if args.preview else None
    if args.require_printable:  # decided from the analytic section, before any work or file
        from torus_cad.geometry.extensions.printability import printability

        problem = printability(params.geometry(), params.manufacturing.min_wall).problem()
        if problem:
            raise GeometryError(f"not printable (--require-printable): {problem}")
    if _writes_a_mesh(params, args.no_stl):
        check_stl_budget(params)  # a mesh that would blow up is refused before anything is built (~7 ms)
    check_writable_folder(args.out)  # before the build, not after it
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params, progress=progress)
    progress(Stage.WRITE)
    extra_files = {}
    if size is not None:
        from torus_cad.preview import write_preview

        extra_files["png"] = lambda path: write_preview(propeller, path, size, progress=progress)
    # One output set: the files, the blade-element table, the picture and the report appear together.
    published = write_output_set(propeller, Path(args.out), args.density, stl=not args.no_stl,
                                 sections_table=True, extra_files=extra_files)
    progress.finish()
    paths, report = published.paths, published.report  # not re-read: a same-name build may have replaced it
    if not args.quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(f"volume {report['volume_mm3']:.3f} mm^3, area {report['surface_area_mm2']:.3f} mm^2, "
              f"mass {report['mass_g']:.3f} g at {args.density:g} g/cm^3")
        fillet = report.get("root_fillet")
        if fillet is not None and not fillet["constant_radius"]:
            print(f"warning: the root fillet is {fillet['radius_mm']:g} mm except along "
                  f"{fillet['varying_junction_per_blade_mm']:.2f} mm of each blade's junction: a blade bends too tightly "
                  f"there for it, and its radius varies down to {fillet['smallest_radius_mm']:.3g} mm")
        closed = report["closed_file_trailing_edge_mm"]
        if closed is not None:
            print(f"warning: airfoil.file's open trailing edge is only {closed[0]:.3f}-{closed[1]:.3f} mm thick, under "
                  f"the {MIN_BLUNT_TRAILING_EDGE_MM:g} mm a blunt edge needs to mesh without crossing triangles: built "
                  f"sharp; set airfoil.trailing_edge_thickness >= {MIN_BLUNT_TRAILING_EDGE_MM:g} for a base")
        if not report["printability"]["printable"]:
            print(f"warning: not printable: {propeller.printability().problem()}; "
                  "--require-printable refuses such a design")
        if params.blades == 1:
            print(f"warning: a one-blade propeller is out of balance: static imbalance "
                  f"{report['balance']['static_imbalance_g_mm']:.3f} g mm; add a counterweight or use 2 or more blades")
    if args.verbose:
        print(f"centroid {tuple(round(c, 6) for c in report['centroid_mm'])} mm, "
              f"spin-axis inertia {report['spin_axis_inertia_g_mm2']:.4f} g mm^2")
        for stage, seconds in report["stage_seconds"].items():
            print(f"  {stage:<13} {seconds * 1000:8.1f} ms")
    return EXIT_OK


def _format_overrides(formats: Sequence[str] | None) -> list[str]:
    """``--format step,3mf`` as the ``--set export.formats=[...]`` it stands for (the schema checks the names)."""
    if not formats:
        return []
    names = [name.strip() for item in formats for name in item.split(",") if name.strip()]
    return ["export.formats=[" + ", ".join(f'"{name}"' for name in names) + "]"]


def _writes_a_mesh(params: PropellerParameters, no_stl: bool) -> bool:
    """Whether the build tessellates the solid for a file (STL, 3MF): then its triangle budget applies."""
    from torus_cad.parameters.design import ExportFormat

    formats = params.export.formats
    return (ExportFormat.STL in formats and not no_stl) or ExportFormat.THREE_MF in formats


def _preview_size(text: str, option: str) -> tuple[int, int]:
    from torus_cad.preview import parse_size

    return parse_size(text, option)  # raises ParameterError (exit 2) for a bad WxH


def _command_preview(args: argparse.Namespace) -> int:
    from torus_cad.progress import StageProgress

    progress = StageProgress.for_terminal(quiet=args.quiet)
    progress(Stage.KERNEL_IMPORT)
    from torus_cad.outputs import check_writable_folder

    params = load_parameters(args.config, args.overrides)
    size = _preview_size(args.size, "--size")
    out = Path(args.out) if args.out else Path("step_out") / f"{params.name}.png"
    check_writable_folder(out.parent)  # before the build, not after it
    from torus_cad.preview import write_preview
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params, progress=progress)
    path = write_preview(propeller, out, size, progress=progress)
    progress.finish()
    if not args.quiet:
        print(f"wrote {path} ({size[0]}x{size[1]} px)")
    return EXIT_OK


def _command_defaults(args: argparse.Namespace) -> int:
    from torus_cad.parameters import PropellerParameters

    if not args.resolved:
        if args.config or args.overrides:
            raise ParameterError("torus-cad defaults takes a design file or --set only with --resolved")
        sys.stdout.write("# torus_cad design file: every key is optional and defaults to the value below.\n")
        sys.stdout.write(PropellerParameters().to_toml(comments=True))
        return EXIT_OK
    from torus_cad.design_targets import resolve_design_targets

    params = load_parameters(args.config, args.overrides)
    targets = resolve_design_targets(params)
    sys.stdout.write("# torus_cad design file: the spec's parameters that the design's airfoil.naca, diameter and\n"
                     "# pitch resolved to (" + (", ".join(f"{key} = {value!r}" for key, value in targets.requested.items())
                                                or "none set") + "); it builds the same propeller.\n")
    if targets.tip_diameter_mm is not None:
        sys.stdout.write(f"# tip diameter {targets.tip_diameter_mm:.3f} mm")
        if targets.pitch_fit is not None:
            achieved = ", ".join(f"{value:.2f}" for value in targets.pitch_fit.pitch_at_75_mm)
            sys.stdout.write(f"; geometric pitch at 75 % of the tip radius {achieved} mm")
        sys.stdout.write("\n")
    sys.stdout.write(targets.parameters.to_toml(comments=True))
    return EXIT_OK


def _positive_density(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--density must be a number in g/cm^3, got {text!r}") from None
    if not 0.0 < value <= 25.0:
        raise argparse.ArgumentTypeError(f"--density = {value:g} is out of range; allowed (0, 25] g/cm^3")
    return value


def _command_sweep(args: argparse.Namespace) -> int:
    """Exit 0 when every design is valid or refused, 1 when any failed (errored, crashed, timed out), 2 for a bad
    sweep file, 130 / 143 on SIGINT / SIGTERM (one line; the table of what finished is written)."""
    from torus_cad.batch import BatchError, SweepInterrupted, load_sweep, run_sweep

    spec = load_sweep(args.sweep)  # a bad sweep file raises ParameterError: exit 2
    out = Path(args.out) if args.out else Path("sweep_out") / Path(args.sweep).stem
    try:
        result = run_sweep(spec, out, workers=args.workers, scheduler=args.scheduler,
                           stl=False if args.no_stl else None, density_g_cm3=args.density,
                           time_limit_s=args.time_limit, rebuild=args.rebuild, progress=False if args.quiet else None,
                           oversubscribe=args.oversubscribe)
    except SweepInterrupted as interrupt:
        partial = interrupt.result
        done = (f"{partial.counts_text()}; table written to {partial.tables['csv']}" if partial.tables
                else "nothing was built")
        print(f"torus-cad: sweep interrupted by {interrupt.signal_name}: {done}; rerun the same command to resume",
              file=sys.stderr)
        return interrupt.exit_code
    except BatchError as error:
        print(f"torus-cad: sweep failed: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if not args.quiet:
        print(result.summary())
    return result.exit_code


def _command_optimize(args: argparse.Namespace) -> int:
    """Exit 0 when the study holds its trials (refused or failed designs included), 2 for a bad study file or
    option, 1 when the storage or the workers cannot be used, 130 / 143 / 129 on a signal (rerun to continue)."""
    try:
        from torus_cad.optimize import StudyInterrupted, load_study, run_study
        from torus_cad.optimize.storage import StorageError
    except ImportError as error:
        print(f"torus-cad: optimize needs the optimize extra ({error.name} is missing): "
              "pip install 'torus_cad[optimize]'", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    from torus_cad.batch import BatchError

    spec = load_study(args.study)  # a bad study file raises ParameterError: exit 2
    out = Path(args.out) if args.out else Path("optimize_out") / Path(args.study).stem
    try:
        result = run_study(spec, out, trials=args.trials, workers=args.workers, scheduler=args.scheduler,
                           storage=args.storage)
    except StudyInterrupted as interrupt:
        print(f"torus-cad: optimize interrupted by {interrupt.signal_name}: {interrupt.result.ran} trials finished "
              "in this run; rerun the same command to continue", file=sys.stderr)
        return interrupt.exit_code
    except (BatchError, StorageError) as error:
        print(f"torus-cad: optimize failed: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if not args.quiet:
        print(result.summary())
    return EXIT_OK


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--port must be a whole number, got {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"--port = {value} is out of range; allowed [0, 65535] (0: any free port)")
    return value


def _command_studio(args: argparse.Namespace) -> int:
    """Exit 0 never on a signal: 130 / 143 / 129 with one line, as every command."""
    from torus_cad.interrupts import EXIT_SIGNALS
    from torus_cad.studio.app import check_host, serve

    check_host(args.host)
    files = Path(args.files) if args.files else None
    if files is not None and not files.is_dir():
        raise ParameterError(f"--files {args.files!r} is not a folder")
    params = load_parameters(args.config, args.overrides)  # a bad design exits 2 before the server starts
    try:
        code = serve(params, port=args.port, host=args.host, files_folder=files)
    except OutputError as error:  # the port is in use: not a build that failed
        print(f"torus-cad: studio: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if code:
        import signal

        name = next(signal.Signals(signum).name for signum, exit_code in EXIT_SIGNALS.items() if exit_code == code)
        print(f"torus-cad: studio stopped by {name}", file=sys.stderr)
    return code


def _command_verify(args: argparse.Namespace) -> int:
    from torus_cad.outputs import set_names, verify_set

    folder = Path(args.folder)
    if not folder.is_dir():
        raise ParameterError(f"verify: {str(folder)!r} is not a folder")
    names = [args.name] if args.name else set_names(folder)
    if not names:
        raise IncompleteOutputError(f"no output set in {str(folder)!r}")
    for name in names:
        checked = verify_set(folder, name)  # IncompleteOutputError names the file: exit 1
        if not args.quiet:
            print(f"ok {checked.report.parent / name}: {', '.join(path.name for path in checked.files)}")
    return EXIT_OK


def _mesh_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """``[mesh]`` values given on the command line (they override the design file's)."""
    from torus_cad.mesh.settings import format_overrides

    overrides: dict[str, Any] = {f"mesh.{key}": getattr(args, key) for key in ("sections", "points", "spacing")
                                 if getattr(args, key) is not None}
    if args.formats:
        overrides.update(format_overrides(name for text in args.formats for name in text.split(",")))
    return overrides


def _command_mesh(args: argparse.Namespace) -> int:
    from torus_cad.mesh.pipeline import summary_line, write_surface_mesh
    from torus_cad.outputs import check_writable_folder
    from torus_cad.progress import StageProgress

    params = load_parameters(args.config, args.overrides).with_values(_mesh_overrides(args))
    check_writable_folder(args.out)  # a folder the set cannot go into is refused before the mesh is built
    progress = StageProgress.for_terminal(quiet=args.quiet)
    report, paths = write_surface_mesh(params, Path(args.out), compare=not args.no_compare, progress=progress)
    progress.finish()
    if not args.quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(summary_line(report))
    return EXIT_OK


def _table_specs(table: str) -> list[Any]:
    from torus_cad.parameters import parameter_specs

    return [spec for spec in parameter_specs() if spec.section == table]


def _add_table_arguments(parser: argparse.ArgumentParser, table: str) -> None:
    """One ``--name`` option per parameter of a schema table (default None: keep the design's value)."""
    from enum import Enum

    for spec in _table_specs(table):
        name = spec.key.rpartition(".")[2]
        unit = f" ({spec.unit})" if spec.unit else ""
        if isinstance(spec.kind, type) and issubclass(spec.kind, Enum):
            parser.add_argument(f"--{name.replace('_', '-')}", dest=name, choices=[item.value for item in spec.choices],
                                help=f"{spec.doc} (default {spec.default.value})")
        else:
            parser.add_argument(f"--{name.replace('_', '-')}", dest=name, type=spec.kind, metavar="X",
                                help=f"{spec.doc}{unit}; {spec.bounds} (default {spec.default:g})")


def _table_overrides(args: argparse.Namespace, table: str) -> dict[str, Any]:
    return {spec.key: getattr(args, spec.key.rpartition(".")[2]) for spec in _table_specs(table)
            if getattr(args, spec.key.rpartition(".")[2]) is not None}


def _command_cfd(args: argparse.Namespace) -> int:
    from torus_cad.cfd.settings import MissingExtraError
    from torus_cad.progress import StageProgress

    params = load_parameters(args.config, args.overrides).with_values(_table_overrides(args, "cfd"))
    if args.threads < 0:
        raise ParameterError(f"--threads = {args.threads} is out of range; allowed 0 (one per CPU) or more")
    progress = StageProgress.for_terminal(quiet=args.quiet)
    try:
        from torus_cad.cfd.domain import gmsh_library, import_gmsh, summary_line, write_cfd_domain
        from torus_cad.cfd.estimate import check_cfd_budget
        from torus_cad.cfd.surface_check import import_meshlib
        from torus_cad.cfd.worker import run_in_worker
        from torus_cad.outputs import check_writable_folder

        gmsh = import_gmsh()
        import_meshlib()
        estimate = check_cfd_budget(params)  # a mesh that would blow up is refused before any work (a few s)
        check_writable_folder(args.out)
        # gmsh set up here, meshing in a worker thread: a signal during a long gmsh call ends the command
        # at once (cfd.worker, cfd.domain.gmsh_library)
        with gmsh_library(gmsh):
            report, paths = run_in_worker(lambda: write_cfd_domain(params, Path(args.out), threads=args.threads,
                                                                   progress=progress, estimate=estimate))
    except MissingExtraError as error:
        print(f"torus-cad: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    progress.finish()
    if not args.quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(summary_line(report))
    return EXIT_OK


def _command_simulate(args: argparse.Namespace) -> int:
    """Exit 0 on success, 2 for bad input or without OpenFOAM, 1 when the mesher or solver fails (diverged:
    the iteration and residual named, the case kept)."""
    from torus_cad.progress import StageProgress

    params = load_parameters(args.config, args.overrides)
    if args.convergence and (args.case_only or args.mesh_from):
        raise ParameterError("--convergence meshes and runs all three levels; it takes neither --case-only nor --mesh-from")
    progress = StageProgress.for_terminal(quiet=args.quiet)
    try:
        from torus_cad.simulate.cli_output import IterationLine, summary_lines
        from torus_cad.simulate.pipeline import Request, convergence_study, simulate
        from torus_cad.simulate.run import MissingOpenFoamError
        from torus_cad.simulate.settings import Level, OperatingPoint, max_processes
    except ImportError as error:
        print(f"torus-cad: {error.name or error} is not installed: install the simulate extra, "
              "pip install 'torus_cad[simulate]'", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    request = Request(params, OperatingPoint(args.rpm, args.airspeed), Level(args.level), args.iterations,
                      max_processes() if args.processes is None else args.processes, args.case_only, args.time_limit,
                      Path(args.mesh_from) if args.mesh_from else None)
    line = IterationLine.for_terminal(quiet=args.quiet)
    try:
        if args.convergence:
            result = convergence_study(request, Path(args.out), progress=line, stage=progress)
        else:
            result = simulate(request, Path(args.out), progress=line, stage=progress)
    except MissingOpenFoamError as error:
        return _error(str(error), EXIT_BAD_INPUT)
    finally:
        line.close()
    progress.finish()
    if not args.quiet:
        for text in summary_lines(result, convergence=args.convergence):
            print(text)
    return EXIT_OK


def _add_mesh_parser(commands: Any) -> None:
    from torus_cad.mesh.settings import MeshFormat

    mesh = _design_command(
        commands, "mesh", help="closed triangle mesh straight from the spec's math (STL, OBJ groups, PLY, VTK)",
        description="Mesh the propeller of CONFIG (or the default) from the spec's math: each blade's structured "
        "grid at exactly --sections x --points (points equally spaced in arc length, spec §5), the hub as a "
        "§6.2 grid with its bore, D-flat, set-screw hole and chamfers, united into one closed 2-manifold without "
        "intersecting triangles (manifold3d, meshlib). Writes "
        "<name>_mesh.<format> files and <name>_mesh.json, a quality report. The options override the design's "
        "[mesh] table. A mesh whose estimated memory is over the limit, a resolution too coarse for the blade "
        "and a root fillet are refused before anything is built.")
    mesh.add_argument("--sections", type=int, metavar="N", help="sections along each blade (mesh.sections, default 100)")
    mesh.add_argument("--points", type=int, metavar="M",
                      help="points around each section, equal arc length (mesh.points, default 400)")
    mesh.add_argument("--spacing", choices=["arc_length", "parameter"],
                      help="sections evenly in the centerline's arc length or in its parameter s "
                           "(mesh.spacing, default arc_length)")
    mesh.add_argument("--format", dest="formats", action="append", metavar="FORMAT[,FORMAT]",
                      help="files to write instead of the design's, repeatable or comma-separated: "
                           + ", ".join(item.value for item in MeshFormat) + " (default stl,obj)")
    mesh.add_argument("--no-compare", action="store_true",
                      help="skip the B-rep comparison in the report (volume, OpenCascade's tessellation)")
    _add_out_and_quiet(mesh, "mesh_out", _command_mesh)


def _add_cfd_parser(commands: Any) -> None:
    from torus_cad.tolerances import CFD_TETRAHEDRA_LIMIT

    cfd = _design_command(
        commands, "cfd", help="fluid domain and tetrahedral volume mesh for a rotating-propeller simulation (gmsh)",
        description="Mesh the fluid around the propeller of CONFIG (or the default) with gmsh: an outer "
        "cylinder, a rotating-zone cylinder around the propeller, conformal at their interface, tetrahedra "
        "refined near the blades. Writes <name>_cfd.msh (v4.1), <name>_cfd_v2.msh (v2.2 ASCII, for "
        "OpenFOAM's gmshToFoam), <name>_cfd.step, README.txt and <name>_cfd.json as one output set (see 'torus-cad "
        "verify'). The options override the design's [cfd] table; D is the tip diameter. A mesh estimated above "
        f"{CFD_TETRAHEDRA_LIMIT:,} tetrahedra is refused before any work. Needs the cfd extra: "
        "pip install 'torus_cad[cfd]'.")
    cfd.table = "cfd"  # its options, when the subcommand is used (_Parser.table)
    cfd.add_argument("--threads", type=int, default=0, metavar="N", help="gmsh threads (default 0: one per CPU)")
    _add_out_and_quiet(cfd, "cfd_out", _command_cfd)


def _add_simulate_parser(commands: Any) -> None:
    simulate = _design_command(
        commands, "simulate", help="run the propeller in OpenFOAM: thrust, torque, power, CT, CP (simulate extra)",
        description="Mesh the fluid around the propeller of CONFIG (or the default) at --level, write a complete "
        "OpenFOAM case (<name>_case/: steady MRF, k-omega SST, an Allrun that repeats the run) and run it with "
        "simpleFoam through foamlib. Writes <name>_performance.json (thrust, torque, power, J, CT, CP, efficiency "
        "or figure of merit, convergence) and <name>_performance.png (force and residual histories). Needs "
        "OpenFOAM (v1912) and the simulate extra: pip install 'torus_cad[simulate]'.")
    simulate.add_argument("--rpm", type=float, required=True, help="revolutions per minute, >= 0, in the design's "
                          "own sense of rotation (a 'cw' design clockwise seen from +z)")
    simulate.add_argument("--airspeed", type=float, default=0.0, metavar="M_S",
                          help="speed of the air arriving at the inlet, m/s (default 0: still air)")
    simulate.add_argument("--level", choices=["coarse", "medium", "fine"], default="coarse",
                          help="mesh level (default coarse: about 53k cells for the default design)")
    simulate.add_argument("--iterations", type=int, metavar="N", help="SIMPLE iterations (default: the level's, "
                          "300 / 400 / 500)")
    simulate.add_argument("--processes", type=int, metavar="N", default=None,
                          help="MPI processes for the solver (default: one per CPU)")
    simulate.add_argument("--time-limit", type=float, default=3600.0, metavar="SECONDS",
                          help="time budget of the run; refused before the solver starts if its estimate is over, "
                               "stopped when it runs over (default 3600)")
    simulate.add_argument("--case-only", action="store_true", help="write the case without running it")
    simulate.add_argument("--mesh-from", metavar="CASE", help="reuse the mesh of an earlier case of this design and "
                          "level (OUT/<name>_case) instead of meshing again: another rpm or airspeed")
    simulate.add_argument("--convergence", action="store_true",
                          help="run all three levels into OUT/<level>/ and write <name>_convergence.json: "
                               "Richardson-extrapolated thrust and torque and the observed order")
    _add_out_and_quiet(simulate, "simulate_out", _command_simulate)


def _add_out_and_quiet(parser: argparse.ArgumentParser, default_out: str,
                       handler: Callable[[argparse.Namespace], int]) -> None:
    """The output folder, --quiet and the handler, as every writing subcommand has them."""
    parser.add_argument("--out", default=default_out, help=f"output folder (default: {default_out})")
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    parser.set_defaults(handler=handler)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = _Parser(prog="torus-cad", description=DESCRIPTION, epilog=EPILOG,
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)

    build = _design_command(commands, "build", help="build a propeller: STEP + STL + JSON report",
                            description="Build the propeller of CONFIG (or the default) and write "
                            "<name>.step, <name>.stl and <name>.json into --out.", epilog=EPILOG,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    build.add_argument("--out", default="step_out", help="output folder (default: step_out)")
    build.add_argument("--density", type=_positive_density, default=1.24,
                       help="material density for the mass, g/cm^3 (default 1.24, PLA)")
    build.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    build.add_argument("--format", dest="formats", action="append", metavar="FORMAT[,FORMAT]",
                       help="files to write instead of the design's export.formats, repeatable or comma-separated: "
                            "step, stl, 3mf (default step,stl)")
    build.add_argument("--require-printable", action="store_true",
                       help="exit 2, writing nothing, when the blade is thinner than manufacturing.min_wall "
                            "(thinnest section or trailing edge; see the JSON's printability)")
    build.add_argument("-v", "--verbose", action="store_true", help="print mass properties and stage times")
    build.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    build.add_argument("--preview", action="store_true", help="also render <name>.png (see 'torus-cad preview')")
    build.add_argument("--preview-size", default="1200x600", metavar="WxH",
                       help="size of the --preview picture in pixels (default 1200x600)")
    build.set_defaults(handler=_command_build)

    preview = _design_command(
        commands, "preview", help="render a PNG picture: a view from above and a view along the axis",
        description="Build the propeller of CONFIG (or the default) and render a shaded picture of it off-screen: "
        "a view from above that shows every blade and a view along the spin axis, each blade in its own colour.")
    preview.add_argument("--out", metavar="FILE.png", help="picture to write (default: step_out/<name>.png)")
    preview.add_argument("--size", default="1200x600", metavar="WxH",
                         help="picture size in pixels, each side 64..8000 (default 1200x600)")
    preview.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    preview.set_defaults(handler=_command_preview)

    verify = commands.add_parser("verify", help="check that output sets are complete: every file of one build",
                                 description="Check the output sets in FOLDER (or only NAME): each <name>.json "
                                 "report lists the files of its build with their SHA-256; every one must be there "
                                 "and unchanged. Exit 0 if all are complete, 1 naming the first missing or mixed "
                                 "file.")
    verify.add_argument("folder", metavar="FOLDER", help="output folder, e.g. step_out")
    verify.add_argument("name", nargs="?", metavar="NAME", help="check only the set <NAME>.json (default: every set)")
    verify.add_argument("-q", "--quiet", action="store_true", help="print nothing when the sets are complete")
    verify.set_defaults(handler=_command_verify)

    defaults = _design_command(commands, "defaults", help="print the default design as commented TOML",
                               description="Print the default design as a commented TOML file to start from; "
                               "with --resolved, a design's spec parameters after its airfoil.naca, diameter "
                               "and pitch are applied.")
    defaults.add_argument("--resolved", action="store_true",
                          help="print the spec parameters the design file (and --set) resolve to")
    defaults.set_defaults(handler=_command_defaults)

    sweep = commands.add_parser("sweep", help="build many variants of a design in parallel (local or Dask)",
                                description="Build every design of a sweep file (a base design plus the "
                                "parameters to vary: lists, grid ranges, or random / Latin-hypercube bounds) "
                                "into OUT/designs/<id>/ and tabulate them in OUT/results.csv. Rerunning "
                                "resumes: designs already done are skipped. Exit codes: 0 every design valid "
                                "or refused; 1 a design failed, errored, crashed or timed out; 2 a bad sweep "
                                "file (or more than 1,000,000 designs); 130 / 143 interrupted by Ctrl-C / SIGTERM "
                                "(the table of what finished is written).")
    sweep.add_argument("sweep", metavar="SWEEP.toml", help="sweep file (see examples/sweep_example.toml)")
    sweep.add_argument("--out", help="output folder (default: sweep_out/<sweep file name>)")
    sweep.add_argument("--workers", type=int, metavar="N",
                       help="local worker processes (default: one per available core; more are capped at the "
                            "cores, with one line, unless --oversubscribe)")
    sweep.add_argument("--oversubscribe", action="store_true",
                       help="start --workers processes even when they are more than the available cores")
    sweep.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on a Dask distributed cluster, e.g. tcp://host:8786 ('local': a LocalCluster "
                            "of --workers processes); OUT must be on a file system the workers share")
    sweep.add_argument("--density", type=_positive_density, default=None,
                       help="material density for the mass, g/cm^3 (default: the sweep file's, else 1.24)")
    sweep.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    sweep.add_argument("--time-limit", type=float, metavar="SECONDS",
                       help="stop a design that runs longer and record it as 'timeout' (default: the sweep "
                            "file's time_limit_s, else 300; local pool only)")
    sweep.add_argument("--rebuild", action="store_true", help="build every design again, even those already done")
    sweep.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary")
    sweep.set_defaults(handler=_command_sweep)

    optimize = commands.add_parser(
        "optimize", help="search the design space for the best designs (optuna; local pool or Dask)",
        description="Run the study of STUDY.toml: optuna asks for designs within the [vary] ranges, each is built "
        "(and simulated for performance.* metrics) into OUT/trials/<number>/, its report's numbers answer the "
        "objectives and constraints. Writes OUT/results.csv (and .parquet), OUT/<name>_history.png and the best "
        "designs as TOML with their STEP/STL/JSON in OUT/best/. The study lives in OUT/<name>.db (SQLite) or a "
        "PostgreSQL server (--storage) shared by processes on many machines; rerunning continues it (--trials is "
        "the total). Exit codes: 0 done; 1 storage or workers unusable; 2 a bad study file or option; "
        "130 / 143 interrupted (rerun to continue).")
    optimize.add_argument("study", metavar="STUDY.toml", help="study file (see examples/optimize_light.toml)")
    optimize.add_argument("--out", help="output folder (default: optimize_out/<study file name>)")
    optimize.add_argument("--trials", type=int, metavar="N", help="trials in all (default: the file's study.trials)")
    optimize.add_argument("--workers", type=int, metavar="K",
                          help="local worker processes (default and most: the CPUs available)")
    optimize.add_argument("--scheduler", metavar="ADDRESS",
                          help="run the trials on a Dask cluster, e.g. tcp://host:8786 ('local': a LocalCluster of "
                               "--workers processes); OUT must be on a file system the workers share")
    optimize.add_argument("--storage", metavar="URL",
                          help="the study's storage: sqlite:///path.db or postgresql://user@host/db (default: the "
                               "file's study.storage, else OUT/<name>.db)")
    optimize.add_argument("-q", "--quiet", action="store_true", help="no summary")
    optimize.set_defaults(handler=_command_optimize)

    studio = _design_command(commands, "studio", help="design in the browser: parameters, live 3D view, downloads",
                             description="Serve a local web page to design a propeller: a parameters panel, a "
                             "live 3D view (a preview at once, the exact solid when it is built), readouts, and "
                             "STEP / STL / TOML downloads. Starts from CONFIG (or the default design).")
    studio.add_argument("--port", type=_port, default=8080, help="port to serve on (default 8080; 0: any free port)")
    studio.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1: only this machine can connect; "
                             "0.0.0.0 serves every network, without a password)")
    studio.add_argument("--files", metavar="FOLDER",
                        help="a folder whose files (e.g. airfoil coordinate files) designs uploaded in the page may "
                             "name; otherwise they may name only the files uploaded with them")
    studio.set_defaults(handler=_command_studio)
    _add_mesh_parser(commands)
    _add_cfd_parser(commands)
    _add_simulate_parser(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``torus-cad``; returns the exit code."""
    restore_signals = exit_on_signals()  # first: an interrupt while importing is clean too
    try:
        args = build_parser().parse_args(argv)
        handler: Callable[[argparse.Namespace], int] = args.handler
        return _run(handler, args)
    finally:
        restore_signals()


def _error(message: str, code: int) -> int:
    print(f"torus-cad: {message}", file=sys.stderr)
    return code


def _run(handler: Callable[[argparse.Namespace], int], args: argparse.Namespace) -> int:
    """The handler's exit code; every failure becomes one line on stderr and its exit code."""
    try:
        return handler(args)
    except (ParameterError, GeometryError) as error:
        return _error(f"error: {error}", EXIT_BAD_INPUT)
    except IncompleteOutputError as error:
        return _error(f"verify: {error}", EXIT_KERNEL_FAILURE)
    except OutputError as error:
        return _error(f"build failed: {error}", EXIT_KERNEL_FAILURE)
    except TorusCadError as error:
        return _error(f"kernel failure: {error}", EXIT_KERNEL_FAILURE)
    except MemoryError:
        return _error("out of memory; lower resolution.sections / resolution.points or raise the STL deflections",
                      EXIT_KERNEL_FAILURE)
    except OSError as error:
        where = f" {error.filename!r}" if error.filename else ""
        return _error(f"cannot write output{where}: {error.strerror or error}", EXIT_KERNEL_FAILURE)
    except KeyboardInterrupt:  # main() called outside the main thread, where no handler could be installed
        return _error("interrupted", 130)
    except Exception as error:
        return _error(f"internal error ({type(error).__name__}): {error}; please report it with the design file",
                      EXIT_KERNEL_FAILURE)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
