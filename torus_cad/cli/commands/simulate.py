"""``torus-cad simulate``: the propeller run in OpenFOAM (its extra checked before this loads)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from torus_cad.acoustics.observers import DEFAULT_OBSERVERS
from torus_cad.cli.design_input import load_parameters
from torus_cad.cli.exits import EXIT_BAD_INPUT, EXIT_OK, report_error
from torus_cad.errors import ParameterError
from torus_cad.parameters.design import Handedness
from torus_cad.runtime.progress import StageProgress
from torus_cad.simulate.cli_output import IterationLine, summary_lines
from torus_cad.simulate.pipeline import Request, ThrustTarget, convergence_study, simulate, thrust_search
from torus_cad.simulate.run import MissingOpenFoamError
from torus_cad.simulate.settings import Level, Mesher, OperatingPoint, TurbulenceModel, max_processes


def run(args: argparse.Namespace) -> int:
    """Exit 0 on success, 2 for bad input or without OpenFOAM, 1 when the mesher or solver fails (diverged:
    the iteration and residual named, the case kept)."""
    _check_simulate_options(args)
    params = load_parameters(args.config, args.overrides)
    progress = StageProgress.for_terminal(quiet=args.quiet)
    step = None
    if args.step is not None:
        from torus_cad.cfd.step_body import Axis, load_step_propeller  # cadquery: only for a STEP file

        step = load_step_propeller(args.step, Axis(args.axis), Handedness(args.turning))
        params = params.with_values({"name": step.body.name, "handedness": args.turning})
    rpm = args.rpm if args.thrust is None else 0.0  # --thrust: the search sets each run's rpm
    request = Request(params, OperatingPoint(rpm, args.airspeed), Level(args.level), args.iterations,
                      max_processes() if args.processes is None else args.processes, args.case_only, args.time_limit,
                      Path(args.mesh_from) if args.mesh_from else None, Mesher(args.mesher), step,
                      TurbulenceModel(args.turbulence), _observers(args.observer), args.surface_refinement)
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


def _observers(given: list[Any] | None) -> tuple[Any, ...]:
    """The observers the user named (``--observer``), else the default four."""
    return tuple(given) if given else DEFAULT_OBSERVERS


def _check_simulate_options(args: argparse.Namespace) -> None:
    """ParameterError (exit 2) for options that do not go together."""
    if args.convergence and (args.case_only or args.mesh_from):
        raise ParameterError("--convergence meshes and runs all three levels; it takes neither --case-only nor --mesh-from")
    if args.thrust is not None and (args.convergence or args.case_only or args.mesh_from):
        raise ParameterError("--thrust meshes once and runs the solver a few times; it takes none of --convergence, "
                             "--case-only, --mesh-from")
    if args.step is None and (args.axis != "+z" or args.turning != "cw"):
        raise ParameterError("--axis and --turning describe a --step file; give --step FILE")
