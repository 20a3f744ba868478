"""The ``torus-cad`` commands: one handler per subcommand, each parsing nothing and returning its exit code.

Handlers import numpy, CadQuery and the apps inside their bodies, so that the signal handlers are
installed (torus_cad.cli.main) before anything heavy loads.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.errors import GeometryError, IncompleteOutputError, OutputError, ParameterError
from torus_cad.runtime.stages import Stage
from torus_cad.tolerances import MIN_BLUNT_TRAILING_EDGE_MM

if TYPE_CHECKING:
    from torus_cad.parameters import PropellerParameters

EXIT_OK, EXIT_KERNEL_FAILURE, EXIT_BAD_INPUT = 0, 1, 2


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


def _require(command: str, extra: str, modules: Sequence[str] | None = None) -> None:
    """MissingExtraError (exit 2, one line: the extra and its install command) unless ``extra`` is installed."""
    from torus_cad.runtime.extras import require_extra

    require_extra(command, extra, modules)


def command_build(args: argparse.Namespace) -> int:
    from torus_cad.runtime.progress import StageProgress

    progress = StageProgress.for_terminal(quiet=args.quiet)  # stderr, only on a terminal
    progress(Stage.KERNEL_IMPORT)  # a line on the terminal before the seconds of importing the schema and cadquery
    from torus_cad.outputs.output_set import check_writable_folder, write_output_set
    from torus_cad.runtime.budgets import check_stl_budget

    params = load_parameters(args.config, args.overrides + _format_overrides(args.formats))
    size = _preview_size(args.preview_size, "--preview-size") if args.preview else None
    if args.require_printable:  # decided from the analytic section, before any work or file
        problem = params.printability().problem()
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
        from torus_cad.preview.picture import write_preview

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
                  f"there for it, and its radius varies down to {fillet['smallest_radius_mm']:.3g} mm", file=sys.stderr)
        closed = report["closed_file_trailing_edge_mm"]
        if closed is not None:
            print(f"warning: airfoil.file's open trailing edge is only {closed[0]:.3f}-{closed[1]:.3f} mm thick, under "
                  f"the {MIN_BLUNT_TRAILING_EDGE_MM:g} mm a blunt edge needs to mesh without crossing triangles: built "
                  f"sharp; set airfoil.trailing_edge_thickness >= {MIN_BLUNT_TRAILING_EDGE_MM:g} for a base", file=sys.stderr)
        if not report["printability"]["printable"]:
            print(f"warning: not printable: {propeller.printability().problem()}; "
                  "--require-printable refuses such a design", file=sys.stderr)
        if params.blades == 1:
            print(f"warning: a one-blade propeller is out of balance: static imbalance "
                  f"{report['balance']['static_imbalance_g_mm']:.3f} g mm; add a counterweight or use 2 or more blades",
                  file=sys.stderr)
    if args.verbose:
        print(f"centroid {tuple(round(c, 6) for c in report['centroid_mm'])} mm, "
              f"spin-axis inertia {report['spin_axis_inertia_g_mm2']:.4f} g mm^2")
        for stage, seconds in report["stage_seconds"].items():
            print(f"  {stage:<13} {seconds * 1000:8.1f} ms")
    return EXIT_OK


def command_check(args: argparse.Namespace) -> int:
    """Exit 0 with one line when the design passes every check the build makes before the kernel; 2 with the
    build's own one-line refusal otherwise. OpenCascade is never loaded (torus_cad.parameters.feasibility)."""
    from torus_cad.parameters.feasibility import check_design

    params = load_parameters(args.config, args.overrides + _format_overrides(args.formats))
    feasible = check_design(params, mesh=_writes_a_mesh(params, args.no_stl), walls=not args.quiet,
                            require_printable=args.require_printable, estimate_mesh_first=True)
    if not args.quiet:
        print(feasible.summary())
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


def command_preview(args: argparse.Namespace) -> int:
    from torus_cad.runtime.progress import StageProgress

    progress = StageProgress.for_terminal(quiet=args.quiet)
    progress(Stage.KERNEL_IMPORT)
    from torus_cad.outputs.output_set import check_writable_folder

    params = load_parameters(args.config, args.overrides)
    size = _preview_size(args.size, "--size")
    out = Path(args.out) if args.out else Path("step_out") / f"{params.name}.png"
    check_writable_folder(out.parent)  # before the build, not after it
    from torus_cad.preview.picture import write_preview
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params, progress=progress)
    path = write_preview(propeller, out, size, progress=progress)
    progress.finish()
    if not args.quiet:
        print(f"wrote {path} ({size[0]}x{size[1]} px)")
    return EXIT_OK


def command_defaults(args: argparse.Namespace) -> int:
    from torus_cad.parameters import PropellerParameters

    if not args.resolved:
        if args.config or args.overrides:
            raise ParameterError("torus-cad defaults takes a design file or --set only with --resolved")
        sys.stdout.write("# torus_cad design file: every key is optional and defaults to the value below.\n")
        sys.stdout.write(PropellerParameters().to_toml(comments=True))
        return EXIT_OK
    from torus_cad.parameters.design_targets import resolve_design_targets

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


def command_sweep(args: argparse.Namespace) -> int:
    """Exit 0 when every design is valid or refused, 1 when any failed (errored, crashed, timed out), 2 for a bad
    sweep file, 130 / 143 on SIGINT / SIGTERM (one line; the table of what finished is written)."""
    if args.scheduler:
        _require("sweep --scheduler", "sweep")
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


def command_optimize(args: argparse.Namespace) -> int:
    """Exit 0 when the study holds its trials (refused or failed designs included), 2 for a bad study file or
    option, 1 when the storage or the workers cannot be used, 130 / 143 / 129 on a signal (rerun to continue)."""
    _require("optimize", "optimize")
    from torus_cad.batch import BatchError
    from torus_cad.optimize import StudyInterrupted, load_study, run_study
    from torus_cad.optimize.storage import StorageError
    from torus_cad.optimize.study_file import Sampler

    spec = load_study(args.study)  # a bad study file raises ParameterError: exit 2
    if spec.sampler is Sampler.CMAES:
        _require("optimize (sampler cmaes)", "optimize", ["cmaes"])
    if (args.storage or spec.storage).startswith("postgresql"):
        _require("optimize (PostgreSQL storage)", "optimize", ["psycopg2"])
    if args.scheduler:
        _require("optimize --scheduler", "optimize", ["dask.distributed"])
    out = Path(args.out) if args.out else Path("optimize_out") / Path(args.study).stem
    try:
        result = run_study(spec, out, trials=args.trials, workers=args.workers, scheduler=args.scheduler,
                           storage=args.storage)
    except StudyInterrupted as interrupt:
        print(f"torus-cad: optimize interrupted by {interrupt.signal_name}: {interrupt.result.ran} trials finished "
              "in this run; rerun the same command to continue", file=sys.stderr)
        return interrupt.exit_code
    except (BatchError, StorageError, OutputError) as error:
        print(f"torus-cad: optimize failed: {error}", file=sys.stderr)
        return EXIT_KERNEL_FAILURE
    if not args.quiet:
        print(result.summary())
    return EXIT_OK


def command_studio(args: argparse.Namespace) -> int:
    """Exit 0 never on a signal: 130 / 143 / 129 with one line, as every command."""
    _require("studio", "studio")
    from torus_cad.runtime.interrupts import EXIT_SIGNALS
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


def command_verify(args: argparse.Namespace) -> int:
    """Exit 0 when every set is complete, 1 with one line per problem of every set (sub-folders included)."""
    from torus_cad.outputs.output_set import set_folders, set_names, verify_set

    folder = Path(args.folder)
    if not folder.is_dir():
        raise ParameterError(f"verify: {str(folder)!r} is not a folder")
    if not args.name and _batch_members(folder) is not None:
        return _verify_batch_folder(folder, args.quiet)
    sets = [(folder, args.name)] if args.name else [(where, name) for where in set_folders(folder)
                                                    for name in set_names(where)]
    if not sets:
        raise IncompleteOutputError(f"no output set in {str(folder)!r} or its sub-folders")
    problems = []
    for where, name in sets:
        try:
            checked = verify_set(where, name)
        except IncompleteOutputError as error:  # every problem of every set, not only the first
            prefix = "" if where == folder else f"{where.relative_to(folder)}/"
            problems += [f"{prefix}{problem}" for problem in error.problems]
            continue
        if not args.quiet:
            print(f"ok {checked.report.parent / name}: {', '.join(path.name for path in checked.files)}")
    for problem in problems:
        report_error(f"verify: {problem}", EXIT_KERNEL_FAILURE)
    return EXIT_KERNEL_FAILURE if problems else EXIT_OK


def _batch_members(folder: Path) -> list[Path] | None:
    """The trial folders of a study folder (``trials/<number>/``) or the design folders of a sweep folder
    (``designs/<id>/``); None for any other folder."""
    from torus_cad.batch.table import DESIGNS_DIR

    for members in ("trials", DESIGNS_DIR):  # torus_cad.optimize.study.TRIALS_DIR (optuna is not needed here)
        if (folder / members).is_dir():
            return sorted(path for path in (folder / members).iterdir() if path.is_dir() and not path.is_symlink())
    return None


def _verify_batch_folder(folder: Path, quiet: bool) -> int:
    """``verify`` of a study or sweep folder: every output set of its trials or designs and of ``best/``
    complete, and no staging folder left by a stopped process (the next run of the study or sweep removes
    them). IncompleteOutputError (exit 1) naming the first problems and their count."""
    from torus_cad.outputs.output_set import set_names, staging_folders, verify_set

    folders = [folder, *(_batch_members(folder) or [])] + ([folder / "best"] if (folder / "best").is_dir() else [])
    problems: list[str] = []
    sets = in_progress = 0
    for member in folders:
        left, other = staging_folders(member)
        problems += [f"staging folder {str(path.relative_to(folder))!r} left by a stopped process "
                     "(the next run removes it)" for path in left]
        in_progress += len(other)
        for name in set_names(member) if member != folder else []:
            try:
                verify_set(member, name)
                sets += 1
            except IncompleteOutputError as error:
                problems.append(f"{member.relative_to(folder)}/{error}")
    if problems:
        more = f" (and {len(problems) - 3} more)" if len(problems) > 3 else ""
        raise IncompleteOutputError(f"{str(folder)!r}: {len(problems)} problem{'s' if len(problems) > 1 else ''}: "
                                    + "; ".join(problems[:3]) + more)
    if not quiet:
        busy = f"; {in_progress} staging folder{'s' if in_progress > 1 else ''} of running processes" \
            if in_progress else ""
        print(f"ok {folder}: {sets} complete output set{'s' if sets != 1 else ''} in {len(folders) - 1} folders, "
              f"no staging folder left by a stopped process{busy}")
    return EXIT_OK


def _mesh_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """``[mesh]`` values given on the command line (they override the design file's)."""
    from torus_cad.mesh.settings import format_overrides

    overrides: dict[str, Any] = {f"mesh.{key}": getattr(args, key) for key in ("sections", "points", "spacing")
                                 if getattr(args, key) is not None}
    if args.formats:
        overrides.update(format_overrides(name for text in args.formats for name in text.split(",")))
    return overrides


def command_mesh(args: argparse.Namespace) -> int:
    _require("mesh", "mesh")
    from torus_cad.mesh.pipeline import summary_line, write_surface_mesh
    from torus_cad.outputs.output_set import check_writable_folder
    from torus_cad.runtime.progress import StageProgress

    params = load_parameters(args.config, args.overrides).with_values(_mesh_overrides(args))
    check_writable_folder(args.out)  # a folder the set cannot go into is refused before the mesh is built
    progress = StageProgress.for_terminal(quiet=args.quiet)
    report, paths = write_surface_mesh(params, Path(args.out), compare=not args.no_compare, progress=progress)
    progress.finish()
    return _print_written(paths, summary_line(report), args.quiet)


def _table_overrides(args: argparse.Namespace, table: str) -> dict[str, Any]:
    return {spec.key: getattr(args, spec.key.rpartition(".")[2]) for spec in table_specs(table)
            if getattr(args, spec.key.rpartition(".")[2]) is not None}


def command_cfd(args: argparse.Namespace) -> int:
    from torus_cad.runtime.progress import StageProgress

    _require("cfd", "cfd")
    params = load_parameters(args.config, args.overrides).with_values(_table_overrides(args, "cfd"))
    progress = StageProgress.for_terminal(quiet=args.quiet)
    from torus_cad.cfd.domain import gmsh_library, import_gmsh, summary_line, write_cfd_domain
    from torus_cad.cfd.estimate import check_cfd_budget
    from torus_cad.cfd.surface_check import import_meshlib
    from torus_cad.cfd.worker import run_in_worker
    from torus_cad.outputs.output_set import check_writable_folder
    from torus_cad.parameters.design_targets import resolve_design_targets

    gmsh = import_gmsh()  # MissingExtraError (exit 2) when gmsh's library does not load
    import_meshlib()
    params = resolve_design_targets(params).parameters  # once, for the estimate and the mesh
    estimate = check_cfd_budget(params)  # a mesh that would blow up is refused before any work (a few s)
    check_writable_folder(args.out)
    if not args.quiet:
        print(f"torus-cad cfd: {estimate.line()}", file=sys.stderr, flush=True)
    # gmsh set up here, meshing in a worker thread: a signal during a long gmsh call ends the command
    # at once (cfd.worker, cfd.domain.gmsh_library); the waiting thread prints the heartbeat of a long stage
    with gmsh_library(gmsh):
        report, paths = run_in_worker(lambda: write_cfd_domain(params, Path(args.out), threads=args.threads,
                                                               progress=progress, estimate=estimate),
                                      on_wait=progress.heartbeat)
    progress.finish()
    return _print_written(paths, summary_line(report), args.quiet)


def command_simulate(args: argparse.Namespace) -> int:
    """Exit 0 on success, 2 for bad input or without OpenFOAM, 1 when the mesher or solver fails (diverged:
    the iteration and residual named, the case kept)."""
    from torus_cad.runtime.progress import StageProgress

    _require("simulate", "simulate")
    _check_simulate_options(args)
    params = load_parameters(args.config, args.overrides)
    progress = StageProgress.for_terminal(quiet=args.quiet)
    from torus_cad.simulate.cli_output import IterationLine, summary_lines
    from torus_cad.simulate.pipeline import Request, ThrustTarget, convergence_study, simulate, thrust_search
    from torus_cad.simulate.run import MissingOpenFoamError
    from torus_cad.simulate.settings import Level, Mesher, OperatingPoint, TurbulenceModel, max_processes
    step = None
    if args.step is not None:
        from torus_cad.cfd.step_body import Axis, load_step_propeller
        from torus_cad.parameters.design import Handedness

        step = load_step_propeller(args.step, Axis(args.axis), Handedness(args.turning))
        params = params.with_values({"name": step.body.name, "handedness": args.turning})
    rpm = args.rpm if args.thrust is None else 0.0  # --thrust: the search sets each run's rpm
    request = Request(params, OperatingPoint(rpm, args.airspeed), Level(args.level), args.iterations,
                      max_processes() if args.processes is None else args.processes, args.case_only, args.time_limit,
                      Path(args.mesh_from) if args.mesh_from else None, Mesher(args.mesher), step,
                      TurbulenceModel(args.turbulence))
    line = IterationLine.for_terminal(quiet=args.quiet)
    try:
        if args.convergence:
            result = convergence_study(request, Path(args.out), progress=line, stage=progress)
        elif args.thrust is not None:
            target = ThrustTarget(args.thrust, args.thrust_tolerance, args.thrust_runs)
            result = thrust_search(request, target, Path(args.out), progress=line, stage=progress)
        else:
            result = simulate(request, Path(args.out), progress=line, stage=progress)
    except MissingOpenFoamError as error:
        return report_error(str(error), EXIT_BAD_INPUT)
    finally:
        line.close()
    progress.finish()
    if not args.quiet:
        for text in summary_lines(result, convergence=args.convergence):
            print(text)
    return EXIT_OK


def _check_simulate_options(args: argparse.Namespace) -> None:
    """ParameterError (exit 2) for options that do not go together."""
    if args.convergence and (args.case_only or args.mesh_from):
        raise ParameterError("--convergence meshes and runs all three levels; it takes neither --case-only nor --mesh-from")
    if args.thrust is not None and (args.convergence or args.case_only or args.mesh_from):
        raise ParameterError("--thrust meshes once and runs the solver a few times; it takes none of --convergence, "
                             "--case-only, --mesh-from")
    if args.step is None and (args.axis != "+z" or args.turning != "cw"):
        raise ParameterError("--axis and --turning describe a --step file; give --step FILE")


def _preview_size(text: str, option: str) -> tuple[int, int]:
    from torus_cad.preview.picture import parse_size

    return parse_size(text, option)  # raises ParameterError (exit 2) for a bad WxH


def table_specs(table: str) -> list[Any]:
    from torus_cad.parameters import parameter_specs

    return [spec for spec in parameter_specs() if spec.section == table]


def report_error(message: str, code: int) -> int:
    """Print ``torus-cad: message`` on stderr, one line, a long value in it cut short; return ``code``."""
    from torus_cad.errors import bounded_message

    print(bounded_message(f"torus-cad: {message}"), file=sys.stderr)
    return code


def _print_written(paths: dict[str, Path], summary: str, quiet: bool) -> int:
    """Unless ``quiet``: one ``wrote <path>`` line per file, then the summary line; the exit code (0)."""
    if not quiet:
        for path in paths.values():
            print(f"wrote {path}")
        print(summary)
    return EXIT_OK
