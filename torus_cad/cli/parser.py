"""The ``torus-cad`` argument parser: every subcommand and its options; each runs through
torus_cad.cli.commands.run_command, which loads the command's own module."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from enum import Enum
from typing import Any

from torus_cad.cli.commands import run_command
from torus_cad.cli.exits import EXIT_BAD_INPUT
from torus_cad.cli.options import Bounds, integer, number, range_help
from torus_cad.errors import bounded_message
from torus_cad.runtime.cpus import available_cpus, max_cfd_threads, max_workers
from torus_cad.runtime.progress import is_terminal
from torus_cad.tolerances import (
    CFD_TETRAHEDRA_LIMIT,
    CFD_THREADS_LIMIT,
    CFD_THREADS_PER_CPU,
    DENSITY_LIMIT_G_CM3,
    DESIGN_TIME_LIMIT_MAX_S,
    GMSH_REPRODUCIBLE_THREADS,
    MAX_STUDY_TRIALS,
    PREVIEW_EDGE_RANGE,
    SIMULATE_AIRSPEED_LIMIT_M_S,
    SIMULATE_MAX_ITERATIONS,
    SIMULATE_MAX_SURFACE_REFINEMENT,
    SIMULATE_RPM_LIMIT,
    SIMULATE_THRUST_LIMIT_N,
    SIMULATE_TIME_LIMIT_MAX_S,
    THRUST_RUNS_RANGE,
    THRUST_TOLERANCE_RANGE,
    VORTEX_CHORDWISE_DEFAULT,
    VORTEX_CHORDWISE_RANGE,
    VORTEX_SPANWISE_DEFAULT,
    VORTEX_SPANWISE_RANGE,
    WORKERS_LIMIT,
    WORKERS_PER_CPU,
)

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
  torus-cad check my_prop.toml --set blades=4   would it build? (exit 0 / 2, no kernel, about 1 s)
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
    #: Options that set a design parameter (their action -> dotted schema key): their range, the
    #: schema's, is checked as they are parsed and shown in --help, once the subcommand is used (as
    #: ``table``).
    schema_ranges: dict[argparse.Action, str] = {}  # noqa: RUF012 - replaced, never mutated

    #: A progress line printed (on a terminal, without -q) as soon as the subcommand is chosen,
    #: before its schema options load the schema: the command says what it does within its first
    #: second.
    first_line: str = ""

    def parse_known_args(self, args: Any = None, namespace: Any = None) -> Any:  # type: ignore[override, unused-ignore]
        if self.first_line:
            _announce(self.first_line, sys.argv[1:] if args is None else list(args))
            self.first_line = ""
        self._add_schema_options()
        return super().parse_known_args(args, namespace)

    def format_help(self) -> str:
        self._add_schema_options()  # the generated reference (docs/reference/cli.md) shows them too
        return super().format_help()

    def _add_schema_options(self) -> None:
        """The options of ``table`` and the ranges of ``schema_ranges``, once."""
        if self.table:
            table, self.table = self.table, ""
            _add_table_arguments(self, table)
        if self.schema_ranges:
            ranges, self.schema_ranges = self.schema_ranges, {}
            _bind_schema_ranges(ranges)

    def error(self, message: str) -> None:  # type: ignore[override]
        """One line (a long value in it cut short), exit 2: argparse's messages quote what was
        typed."""
        self.exit(
            EXIT_BAD_INPUT,
            bounded_message(f"torus-cad: error: {message} (see {self.prog} --help)") + "\n",
        )


def _announce(text: str, args: list[str]) -> None:
    """``torus-cad: [   0.0 s] text`` on stderr when it is a terminal
    and ``args`` do not ask for quiet."""
    if is_terminal(sys.stderr) and not {"-q", "--quiet"} & set(args):
        sys.stderr.write(f"torus-cad: [{0.0:6.1f} s] {text}\n")
        sys.stderr.flush()


def _design_command(
    commands: Any, name: str, help: str, description: str, **options: Any
) -> _Parser:
    """A subcommand that reads a design: CONFIG (optional) and ``--set`` overrides."""
    parser: _Parser = commands.add_parser(name, help=help, description=description, **options)
    parser.add_argument(
        "config",
        nargs="?",
        help="TOML design file (default: the built-in propeller; see 'torus-cad defaults')",
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one parameter, dotted keys, TOML values (repeatable): "
        "--set hub.radius=12 --set centerline.p2=[20,3,25]",
    )
    return parser


#: ``--density``: the material density, g/cm^3.
DENSITY_RANGE = Bounds(0.0, DENSITY_LIMIT_G_CM3, low_open=True)
_DENSITY = number("--density", DENSITY_RANGE, "g/cm^3")
#: ``--time-limit`` of sweep: per design, s.
DESIGN_TIME_RANGE = Bounds(0.0, DESIGN_TIME_LIMIT_MAX_S, low_open=True)
_PICTURE_SIDES = f"each side {PREVIEW_EDGE_RANGE[0]}..{PREVIEW_EDGE_RANGE[1]}"
_WORKERS_NOTE = f"{WORKERS_PER_CPU} per CPU, at most {WORKERS_LIMIT}"
_THREADS_NOTE = f"{CFD_THREADS_PER_CPU} per CPU, at most {CFD_THREADS_LIMIT}"


def _option_type(key: str, kind: Any, bounds: Bounds, unit: str) -> Callable[[str], Any]:
    """The bounded parser of the option that sets the schema parameter ``key`` (``kind`` int or
    float: messages name the key, as the design file's do), else ``kind`` itself."""
    if kind is int:
        return integer(key, bounds, unit)
    if kind is float:
        return number(key, bounds, unit)
    return kind


def _add_table_arguments(parser: argparse.ArgumentParser, table: str) -> None:
    """One ``--name`` option per parameter of a schema table (default None: keep the design's
    value), a number checked against the parameter's range as it is parsed."""
    # the schema: loaded once the subcommand is used
    from torus_cad.cli.design_input import table_specs

    for spec in table_specs(table):
        name = spec.key.rpartition(".")[2]
        option = f"--{name.replace('_', '-')}"
        unit = f" ({spec.unit})" if spec.unit else ""
        if isinstance(spec.kind, type) and issubclass(spec.kind, Enum):
            parser.add_argument(
                option,
                dest=name,
                choices=[item.value for item in spec.choices],
                help=f"{spec.doc} (default {spec.default.value})",
            )
        else:
            parser.add_argument(
                option,
                dest=name,
                type=_option_type(spec.key, spec.kind, spec.bounds, spec.unit),
                metavar="X",
                help=f"{spec.doc}{unit}; {spec.bounds} (default {spec.default:g})",
            )


def _bind_schema_ranges(ranges: dict[argparse.Action, str]) -> None:
    """Give each option of ``ranges`` (action -> dotted schema key) its parameter's range: checked
    as parsed, in
    --help."""
    from torus_cad.parameters import parameter_specs

    specs = {spec.key: spec for spec in parameter_specs()}
    for action, key in ranges.items():
        spec = specs[key]
        action.type = _option_type(key, spec.kind, spec.bounds, spec.unit)
        action.help = f"{action.help}; {range_help(spec.bounds, spec.unit)}"


def _add_mesh_parser(commands: Any) -> None:
    from torus_cad.mesh.mesh_formats import MeshFormat

    mesh = _design_command(
        commands,
        "mesh",
        help="closed triangle mesh straight from the spec's math (STL, OBJ groups, PLY, VTK)",
        description="Mesh the propeller of CONFIG (or the "
        "default) from the spec's math: each blade's structured "
        "grid at exactly --sections x --points (points "
        "equally spaced in arc length, spec §5), the hub as a "
        "§6.2 grid with its bore, D-flat, set-screw hole and "
        "chamfers, united into one closed 2-manifold without "
        "intersecting triangles (manifold3d, meshlib). Writes "
        "<name>_mesh.<format> files and <name>_mesh.json, a "
        "quality report. The options override the design's "
        "[mesh] table. A mesh whose estimated memory is over "
        "the limit, a resolution too coarse for the blade "
        "and a root fillet are refused before anything is built.",
    )
    sections = mesh.add_argument(
        "--sections", metavar="N", help="sections along each blade (mesh.sections, default 100)"
    )
    points = mesh.add_argument(
        "--points",
        metavar="M",
        help="points around each section, equal arc length (mesh.points, default 400)",
    )
    # the schema's ranges, when used
    mesh.schema_ranges = {sections: "mesh.sections", points: "mesh.points"}
    mesh.add_argument(
        "--spacing",
        choices=["arc_length", "parameter"],
        help="sections evenly in the centerline's arc length or in its parameter s "
        "(mesh.spacing, default arc_length)",
    )
    mesh.add_argument(
        "--format",
        dest="formats",
        action="append",
        metavar="FORMAT[,FORMAT]",
        help="files to write instead of the design's, repeatable or comma-separated: "
        + ", ".join(item.value for item in MeshFormat)
        + " (default stl,obj)",
    )
    mesh.add_argument(
        "--no-compare",
        action="store_true",
        help="skip the B-rep comparison in the report (volume, OpenCascade's tessellation)",
    )
    _add_out_and_quiet(mesh, "mesh_out")


def _add_cfd_parser(commands: Any) -> None:
    cfd = _design_command(
        commands,
        "cfd",
        help="fluid domain and tetrahedral volume mesh for a rotating-propeller simulation (gmsh)",
        description="Mesh the fluid around the propeller "
        "of CONFIG (or the default) with gmsh: an outer "
        "cylinder, a rotating-zone cylinder around the "
        "propeller, conformal at their interface, tetrahedra "
        "refined near the blades. Writes <name>_cfd.msh (v4.1), <name>_cfd_v2.msh (v2.2 ASCII, for "
        "OpenFOAM's gmshToFoam), <name>_cfd.step, README.txt "
        "and <name>_cfd.json as one output set (see 'torus-cad "
        "verify'). The options override the design's [cfd] "
        "table; D is the tip diameter. A mesh estimated above "
        f"{CFD_TETRAHEDRA_LIMIT:,} tetrahedra is refused before any work. Needs the cfd extra: "
        "pip install -c constraints.txt -e '.[cfd]'.",
    )
    cfd.table = "cfd"  # its options, when the subcommand is used (_Parser.table)
    cfd.first_line = (
        "building the propeller and its fluid domain: loading the schema, the CAD kernel and gmsh"
    )
    threads = Bounds(0, max_cfd_threads())
    cfd.add_argument(
        "--threads",
        type=integer("--threads", threads, note="0 = one per CPU"),
        default=GMSH_REPRODUCIBLE_THREADS,
        metavar="N",
        help=f"gmsh threads, {range_help(threads)} ({_THREADS_NOTE}; default "
        f"{GMSH_REPRODUCIBLE_THREADS}: the same mesh on "
        "every run; 0 = one per CPU, whose meshes differ "
        "slightly from run to run)",
    )
    _add_out_and_quiet(cfd, "cfd_out")


def _add_simulate_parser(commands: Any) -> None:
    simulate = _design_command(
        commands,
        "simulate",
        help="run the propeller in OpenFOAM: thrust, torque, power, CT, CP (simulate extra)",
        description="Mesh the fluid around the propeller of "
        "CONFIG (or the default) at --level, write a complete "
        "OpenFOAM case (<name>_case/: steady MRF, k-omega "
        "SST, an Allrun that repeats the run) and run it with "
        "simpleFoam through foamlib. Writes <name>_performance.json "
        "(thrust, torque, power, J, CT, CP, efficiency "
        "or figure of merit, convergence, tonal noise at "
        "--observer positions) and <name>_performance.png (force "
        "and residual histories), <name>_noise.png and "
        "<name>_noise.csv (the noise's directivity, spectrum and "
        "signals). Needs OpenFOAM (v1912) and the simulate extra: "
        "pip install -c constraints.txt -e '.[simulate]'. With --solver "
        "vortex, a lifting-surface vortex lattice on the "
        "blade's camber surface with NeuralFoil's section polars "
        "instead (seconds, no OpenFOAM): the same report, plus "
        "<name>_loading.csv and .png (the loading along the "
        "blade) and <name>_wake.png.",
    )
    from torus_cad.simulate.thrust_target import (
        DEFAULT_MAX_RUNS,
        DEFAULT_TOLERANCE,
        PLAUSIBLE_CT_LIMIT,
    )

    rpm, thrust = (
        Bounds(0.0, SIMULATE_RPM_LIMIT),
        Bounds(0.0, SIMULATE_THRUST_LIMIT_N, low_open=True),
    )
    tolerance, runs = Bounds(*THRUST_TOLERANCE_RANGE), Bounds(*THRUST_RUNS_RANGE)
    speed = simulate.add_mutually_exclusive_group(required=True)
    speed.add_argument(
        "--rpm",
        type=number("--rpm", rpm),
        help=f"revolutions per minute, {range_help(rpm)} and "
        "at most the design's rpm at helical tip "
        "Mach 0.6, in the design's own sense of rotation (a 'cw' design clockwise seen from +z)",
    )
    speed.add_argument(
        "--thrust",
        type=number("--thrust", thrust, "N"),
        metavar="N",
        help=f"find the rpm that gives this thrust, {range_help(thrust, 'N')} and at most the "
        f"thrust at the rpm limit with CT {PLAUSIBLE_CT_LIMIT:g}): one mesh, a few solver runs on "
        "it (a secant step on sqrt(thrust)); the report lists every run",
    )
    simulate.add_argument(
        "--thrust-tolerance",
        type=number("--thrust-tolerance", tolerance),
        default=DEFAULT_TOLERANCE,
        metavar="FRACTION",
        help=f"--thrust stops within this fraction of the target, "
        f"{range_help(tolerance)} (default {DEFAULT_TOLERANCE:g})",
    )
    simulate.add_argument(
        "--thrust-runs",
        type=integer("--thrust-runs", runs),
        default=DEFAULT_MAX_RUNS,
        metavar="N",
        help=f"--thrust runs the solver at most this often, {range_help(runs)} "
        f"(default {DEFAULT_MAX_RUNS})",
    )
    simulate.add_argument(
        "--step",
        metavar="FILE",
        help="simulate the one solid of this STEP file instead of a "
        "design (outputs named after the file's stem; CONFIG and --set give only [cfd])",
    )
    simulate.add_argument(
        "--axis",
        choices=["+z", "-z", "+x", "-x", "+y", "-y"],
        default="+z",
        help="--step: the spin axis in the file's coordinates, through the solid's centroid "
        "(default +z); the thrust points along it",
    )
    simulate.add_argument(
        "--turning",
        choices=["cw", "ccw"],
        default="cw",
        help="--step: the sense of rotation seen from the + end of --axis (default cw)",
    )
    airspeed = Bounds(0.0, SIMULATE_AIRSPEED_LIMIT_M_S)
    simulate.add_argument(
        "--airspeed",
        type=number("--airspeed", airspeed, "m/s", "the solver is incompressible"),
        default=0.0,
        metavar="M_S",
        help=f"speed of the air arriving at the inlet, "
        f"{range_help(airspeed, 'm/s')} (default 0: still air)",
    )
    simulate.add_argument(
        "--solver",
        choices=["openfoam", "vortex"],
        default="openfoam",
        help="openfoam (default): RANS in OpenFOAM; vortex: the vortex lattice with section polars "
        "(seconds; takes none of the mesh and OpenFOAM options)",
    )
    chordwise, spanwise = Bounds(*VORTEX_CHORDWISE_RANGE), Bounds(*VORTEX_SPANWISE_RANGE)
    simulate.add_argument(
        "--chordwise",
        type=integer("--chordwise", chordwise),
        default=None,
        metavar="N",
        help=f"--solver vortex: rings across the chord, {range_help(chordwise)} "
        f"(default {VORTEX_CHORDWISE_DEFAULT})",
    )
    simulate.add_argument(
        "--spanwise",
        type=integer("--spanwise", spanwise),
        default=None,
        metavar="N",
        help=f"--solver vortex: strips along the blade, {range_help(spanwise)} "
        f"(default {VORTEX_SPANWISE_DEFAULT})",
    )
    simulate.add_argument(
        "--level",
        choices=["coarse", "medium", "fine"],
        default=None,
        help="mesh level (default coarse: about 52k cells for the default design)",
    )
    simulate.add_argument(
        "--mesher",
        choices=["snappy", "tet"],
        default=None,
        help="snappy (default): snappyHexMesh with prism layers on the propeller, the first layer "
        "sized for y+ 1; tet: the cfd command's gmsh tetrahedra, no layers",
    )
    simulate.add_argument(
        "--turbulence",
        choices=["kOmegaSST", "kOmegaSSTLM"],
        default=None,
        help="RANS model: kOmegaSST (default) or kOmegaSSTLM, k-omega SST with Langtry-Menter "
        "transition (two more equations; compared against the wind tunnel in the simulate how-to)",
    )
    refinement = Bounds(0, SIMULATE_MAX_SURFACE_REFINEMENT)
    simulate.add_argument(
        "--surface-refinement",
        type=integer("--surface-refinement", refinement),
        default=None,
        metavar="N",
        help=f"snappy mesher: halve the propeller's surface and edge cells N more times "
        f"than the level does, {range_help(refinement)} (default 0; each step about "
        "triples the cells; the prism layers keep the level's first layer, "
        "fewer of them where their stack would outgrow the finer surface cells)",
    )
    iterations, processes = Bounds(1, SIMULATE_MAX_ITERATIONS), Bounds(1, available_cpus())
    time_limit = Bounds(0.0, SIMULATE_TIME_LIMIT_MAX_S, low_open=True)
    simulate.add_argument(
        "--iterations",
        type=integer("--iterations", iterations),
        metavar="N",
        help=f"SIMPLE iterations, {range_help(iterations)} (default: the level's, 200 / 300 / 400)",
    )
    simulate.add_argument(
        "--processes",
        type=integer("--processes", processes, note="the CPUs available"),
        metavar="N",
        default=None,
        help=f"MPI processes for the solver, {range_help(processes)}: from 1 to the "
        "CPUs available (default: one per CPU)",
    )
    simulate.add_argument(
        "--time-limit",
        type=number("--time-limit", time_limit, "s"),
        default=3600.0,
        metavar="SECONDS",
        help=f"time budget of the run, {range_help(time_limit, 's')} (of the whole search with "
        "--thrust); refused before the solver starts if its estimate is over, stopped when it "
        "runs over (default 3600)",
    )
    from torus_cad.acoustics.observers import observer_option

    simulate.add_argument(
        "--observer",
        type=observer_option,
        action="append",
        metavar="DIST_M:ANGLE_DEG",
        help="where the tonal noise is heard: DIST_M m from the hub at ANGLE_DEG degrees from +z "
        "(ahead of the propeller; 90 = the rotor plane), e.g. 2:45; repeat for more "
        f"(default 1:0 1:30 1:60 1:90); {observer_option.ranges}",
    )
    simulate.add_argument(
        "--case-only", action="store_true", help="write the case without running it"
    )
    simulate.add_argument(
        "--mesh-from",
        metavar="CASE",
        help="reuse the mesh of an earlier case of this design and "
        "level (OUT/<name>_case) instead of meshing again: another rpm or airspeed",
    )
    simulate.add_argument(
        "--convergence",
        action="store_true",
        help="run all three levels into OUT/<level>/ and write <name>_convergence.json: "
        "Richardson-extrapolated thrust and torque, the "
        "observed order and the grid convergence index; with --solver vortex the three levels "
        "are lattices, the given one and two each sqrt(2) finer in every count",
    )
    _add_out_and_quiet(simulate, "simulate_out")


def _add_out_and_quiet(parser: argparse.ArgumentParser, default_out: str) -> None:
    """The output folder, --quiet and the handler, as every writing subcommand has them."""
    parser.add_argument(
        "--out", default=default_out, help=f"output folder (default: {default_out})"
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    parser.set_defaults(handler=run_command)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    return build_parser_and_commands()[0]


def build_parser_and_commands() -> tuple[
    argparse.ArgumentParser, dict[str, argparse.ArgumentParser]
]:
    """The argument parser with every subcommand, and the subcommands' own parsers (argparse keeps
    them nowhere public).

    Returns:
        ``(parser, commands)``: the program's parser (:func:`build_parser`), and each subcommand's
            parser by its
        name, in the order of ``--help``.
    """
    parser = _Parser(
        prog="torus-cad",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    commands = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=_Parser
    )

    build = _design_command(
        commands,
        "build",
        help="build a propeller: STEP, STL, blade-element table, JSON report",
        description="Build the propeller of CONFIG (or the default) and write one output set "
        "into --out: <name>.step, <name>.stl (not with --no-stl), <name>.3mf (only when "
        "--format or export.formats asks for 3mf), <name>_sections.csv and "
        "<name>_sections.png (the blade-element table and its picture), <name>.png (with "
        "--preview) and <name>.json, the report that lists them all.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    build.add_argument("--out", default="step_out", help="output folder (default: step_out)")
    build.add_argument(
        "--density",
        type=_DENSITY,
        default=1.24,
        help=(
            "material density for the mass, "
            f"{range_help(DENSITY_RANGE, 'g/cm^3')} (default 1.24, PLA)"
        ),
    )
    build.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    build.add_argument(
        "--format",
        dest="formats",
        action="append",
        metavar="FORMAT[,FORMAT]",
        help="files to write instead of the design's "
        "export.formats, repeatable or comma-separated: "
        "step, stl, 3mf (default step,stl)",
    )
    build.add_argument(
        "--require-printable",
        action="store_true",
        help="exit 2, writing nothing, when the blade is thinner than manufacturing.min_wall "
        "(thinnest section or trailing edge; see the JSON's printability)",
    )
    build.add_argument(
        "-v", "--verbose", action="store_true", help="print mass properties and stage times"
    )
    build.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    build.add_argument(
        "--preview", action="store_true", help="also render <name>.png (see 'torus-cad preview')"
    )
    build.add_argument(
        "--preview-size",
        default="1200x600",
        metavar="WxH",
        help=f"size of the --preview picture in pixels, {_PICTURE_SIDES} (default 1200x600)",
    )
    build.set_defaults(handler=run_command)

    check = _design_command(
        commands,
        "check",
        help="check a design before building it: every refusal that needs no kernel, in a second",
        description="Run every check that can refuse the "
        "design of CONFIG (or the default) before OpenCascade "
        "builds anything, as 'torus-cad build' runs them: "
        "the parameters, the design targets, the blade's ends "
        "inside the hub's inset, no fold-over inside a bend, "
        "sections dense enough, no self-intersection, blades "
        "clear of each other, the mounting features, the "
        "section fit's trailing edge and the STL's triangle "
        "budget. Exit 0 with one line (the margins to the "
        "fold and resolution limits, the walls against "
        "manufacturing.min_wall) when it passes; exit 2 with "
        "the build's own one-line refusal when it does not. "
        "Writes nothing and never loads the kernel.",
    )
    check.add_argument(
        "--no-stl", action="store_true", help="the build will write no STL (no triangle budget)"
    )
    check.add_argument(
        "--format",
        dest="formats",
        action="append",
        metavar="FORMAT[,FORMAT]",
        help="the files the build will write instead of the design's export.formats, as for build",
    )
    check.add_argument(
        "--require-printable",
        action="store_true",
        help="exit 2 when the blade is thinner than manufacturing.min_wall, as build does",
    )
    check.add_argument(
        "-q", "--quiet", action="store_true", help="print nothing when the design passes"
    )
    check.set_defaults(handler=run_command)

    preview = _design_command(
        commands,
        "preview",
        help="render a PNG picture: a view from above and a view along the axis",
        description="Build the propeller of CONFIG (or the "
        "default) and render a shaded picture of it off-screen: "
        "a view from above that shows every blade and a view "
        "along the spin axis, each blade in its own colour.",
    )
    preview.add_argument(
        "--out", metavar="FILE.png", help="picture to write (default: step_out/<name>.png)"
    )
    preview.add_argument(
        "--size",
        default="1200x600",
        metavar="WxH",
        help=f"picture size in pixels, {_PICTURE_SIDES} (default 1200x600)",
    )
    preview.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")
    preview.set_defaults(handler=run_command)

    verify = commands.add_parser(
        "verify",
        help="check that output sets are complete: every file of one build",
        description="Check the output sets in FOLDER and every folder under it (or only "
        "the set NAME in FOLDER): each <name>.json report lists the files of its build "
        "with their SHA-256; every one must be there and unchanged. Hidden folders (a "
        "build's staging) are not entered. Exit 0 if all are complete, 1 with one line "
        "per missing or mixed file of every set. A study folder (optimize --out) or a sweep folder "
        "(sweep --out) is checked whole: every set of its trials or designs and of best/, and no "
        "staging folder left by a stopped process.",
    )
    verify.add_argument(
        "folder", metavar="FOLDER", help="output folder, e.g. step_out (its sub-folders too)"
    )
    verify.add_argument(
        "name",
        nargs="?",
        metavar="NAME",
        help="check only the set <NAME>.json (default: every set)",
    )
    verify.add_argument(
        "-q", "--quiet", action="store_true", help="print nothing when the sets are complete"
    )
    verify.set_defaults(handler=run_command)

    defaults = _design_command(
        commands,
        "defaults",
        help="print the default design as commented TOML",
        description="Print the default design as a commented TOML file to start from; "
        "with --resolved, a design's spec parameters after its airfoil.naca, diameter "
        "and pitch are applied.",
    )
    defaults.add_argument(
        "--resolved",
        action="store_true",
        help="print the spec parameters the design file (and --set) resolve to",
    )
    defaults.set_defaults(handler=run_command)

    sweep = commands.add_parser(
        "sweep",
        help="build many variants of a design in parallel (local or Dask)",
        description="Build every design of a sweep file (a base design plus the "
        "parameters to vary: lists, grid ranges, or random / Latin-hypercube bounds) "
        "into OUT/designs/<id>/ and tabulate them in OUT/results.csv. Rerunning "
        "resumes: designs already done are skipped. Exit codes: 0 every design valid "
        "or refused; 1 a design failed, errored, crashed or timed out; 2 a bad sweep "
        "file (or more than 1,000,000 designs); 130 / 143 interrupted by Ctrl-C / SIGTERM "
        "(the table of what finished is written).",
    )
    sweep.add_argument(
        "sweep", metavar="SWEEP.toml", help="sweep file (see examples/sweep_example.toml)"
    )
    sweep.add_argument("--out", help="output folder (default: sweep_out/<sweep file name>)")
    workers = Bounds(1, max_workers())
    sweep.add_argument(
        "--workers",
        type=integer("--workers", workers, note=_WORKERS_NOTE),
        metavar="N",
        help=f"local worker processes, {range_help(workers)} ({_WORKERS_NOTE}; default: one per "
        "available core; more are capped at the cores, with one line, unless --oversubscribe)",
    )
    sweep.add_argument(
        "--oversubscribe",
        action="store_true",
        help="start --workers processes even when they are more than the available cores",
    )
    sweep.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask distributed cluster, e.g. tcp://host:8786 ('local': a LocalCluster "
        "of --workers processes); OUT must be on a file system the workers share",
    )
    sweep.add_argument(
        "--density",
        type=_DENSITY,
        default=None,
        help="material density for the mass, "
        f"{range_help(DENSITY_RANGE, 'g/cm^3')} (default: the sweep "
        "file's, else 1.24)",
    )
    sweep.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    sweep.add_argument(
        "--time-limit",
        type=number("--time-limit", DESIGN_TIME_RANGE, "s"),
        metavar="SECONDS",
        help="stop a design that runs longer and record it "
        f"as 'timeout', {range_help(DESIGN_TIME_RANGE, 's')} "
        "(default: the sweep file's time_limit_s, else 300; local pool only)",
    )
    sweep.add_argument(
        "--rebuild", action="store_true", help="build every design again, even those already done"
    )
    sweep.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary")
    sweep.set_defaults(handler=run_command)

    optimize = commands.add_parser(
        "optimize",
        help="search the design space for the best designs (optuna; local pool or Dask)",
        description="Run the study of STUDY.toml: optuna asks "
        "for designs within the [vary] ranges, each is built "
        "(and simulated for performance.* metrics) into "
        "OUT/trials/<number>/, its report's numbers answer the "
        "objectives and constraints. Writes OUT/results.csv "
        "(and .parquet), OUT/<name>_history.png and the best "
        "designs as TOML with their STEP/STL/JSON in OUT/best/. "
        "The study lives in OUT/<name>.db (SQLite) or a "
        "PostgreSQL server (--storage) shared by processes on "
        "many machines; rerunning continues it (--trials is "
        "the total). Exit codes: 0 done; 1 storage or "
        "workers unusable; 2 a bad study file or option; "
        "130 / 143 interrupted (rerun to continue).",
    )
    optimize.add_argument(
        "study", metavar="STUDY.toml", help="study file (see examples/optimize_light.toml)"
    )
    optimize.add_argument("--out", help="output folder (default: optimize_out/<study file name>)")
    trials = Bounds(1, MAX_STUDY_TRIALS)
    optimize.add_argument(
        "--trials",
        type=integer("--trials", trials),
        metavar="N",
        help=f"trials in all, {range_help(trials)} (default: the file's study.trials)",
    )
    optimize.add_argument(
        "--workers",
        type=integer("--workers", workers, note=_WORKERS_NOTE),
        metavar="K",
        help=f"local worker processes, {range_help(workers)} ({_WORKERS_NOTE}; the local pool "
        "runs at most one per CPU available, the default; --scheduler local starts this many)",
    )
    optimize.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run the trials on a Dask cluster, e.g. tcp://host:8786 ('local': a LocalCluster of "
        "--workers processes); OUT must be on a file system the workers share",
    )
    optimize.add_argument(
        "--storage",
        metavar="URL",
        help="the study's storage: sqlite:///path.db or postgresql://user@host/db (default: the "
        "file's study.storage, else OUT/<name>.db)",
    )
    optimize.add_argument("-q", "--quiet", action="store_true", help="no summary")
    optimize.set_defaults(handler=run_command)

    studio = _design_command(
        commands,
        "studio",
        help="design in the browser: parameters, live 3D view, downloads",
        description="Serve a local web page to design a propeller: a parameters panel, a "
        "live 3D view (a preview at once, the exact solid when it is built), readouts, and "
        "STEP / STL / TOML downloads. Starts from CONFIG (or the default design).",
    )
    port = Bounds(0, 65535)
    studio.add_argument(
        "--port",
        type=integer("--port", port, note="0: any free port"),
        default=8080,
        help=f"port to serve on, {range_help(port)} (default 8080; 0: any free port)",
    )
    studio.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on (default 127.0.0.1: only this machine can connect; "
        "0.0.0.0 serves every network, without a password)",
    )
    studio.add_argument(
        "--files",
        metavar="FOLDER",
        help="a folder whose files (e.g. airfoil "
        "coordinate files) designs uploaded in the page may "
        "name; otherwise they may name only the files uploaded with them",
    )
    studio.set_defaults(handler=run_command)
    _add_mesh_parser(commands)
    _add_cfd_parser(commands)
    _add_simulate_parser(commands)
    return parser, dict(commands.choices)
