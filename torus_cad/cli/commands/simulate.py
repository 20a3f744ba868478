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
from torus_cad.simulate.pipeline import (
    Request,
    ThrustTarget,
    convergence_study,
    simulate,
    thrust_search,
)
from torus_cad.simulate.run import MissingOpenFoamError
from torus_cad.simulate.settings import (
    Level,
    Mesher,
    OperatingPoint,
    TurbulenceModel,
    max_processes,
)


def run(args: argparse.Namespace) -> int:
    """Exit 0 on success, 2 for bad input or without OpenFOAM, 1 when the mesher or solver fails
    (diverged: the iteration and residual named, the case kept)."""
    _check_simulate_options(args)
    params = load_parameters(args.config, args.overrides)
    progress = StageProgress.for_terminal(quiet=args.quiet)
    if args.solver == "vortex":
        return _run_vortex(args, params, progress)
    step = None
    if args.step is not None:
        # cadquery: only for a STEP file
        from torus_cad.cfd_domain.step_body import Axis, load_step_propeller

        step = load_step_propeller(args.step, Axis(args.axis), Handedness(args.turning))
        params = params.with_values({"name": step.body.name, "handedness": args.turning})
    rpm = args.rpm if args.thrust is None else 0.0  # --thrust: the search sets each run's rpm
    request = Request(
        params,
        OperatingPoint(rpm, args.airspeed),
        Level(args.level or Level.COARSE.value),
        args.iterations,
        max_processes() if args.processes is None else args.processes,
        args.case_only,
        args.time_limit,
        Path(args.mesh_from) if args.mesh_from else None,
        Mesher(args.mesher or Mesher.SNAPPY.value),
        step,
        TurbulenceModel(args.turbulence or TurbulenceModel.K_OMEGA_SST.value),
        _observers(args.observer),
        args.surface_refinement or 0,
    )
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


#: Options of the OpenFOAM route that the vortex solver does not take (argparse's destination, the
#: option).
_OPENFOAM_ONLY = (
    ("step", "--step"),
    ("level", "--level"),
    ("mesher", "--mesher"),
    ("turbulence", "--turbulence"),
    ("surface_refinement", "--surface-refinement"),
    ("iterations", "--iterations"),
    ("processes", "--processes"),
    ("mesh_from", "--mesh-from"),
)
#: Options of the vortex solver alone.
_VORTEX_ONLY = (("chordwise", "--chordwise"), ("spanwise", "--spanwise"))


def _run_vortex(args: argparse.Namespace, params: Any, progress: StageProgress) -> int:
    """``--solver vortex``: one point, the rpm for ``--thrust``, or the three lattices of
    ``--convergence``, published as the OpenFOAM route publishes."""
    from torus_cad.simulate.cli_output import convergence_lines
    from torus_cad.vortex.pipeline import (
        VortexRequest,
        simulate_vortex,
        vortex_convergence_study,
        vortex_summary_lines,
        vortex_thrust_search,
    )
    from torus_cad.vortex.rotor import Discretisation

    defaults = Discretisation()
    lattice = Discretisation(
        args.chordwise or defaults.chordwise, args.spanwise or defaults.spanwise
    )
    request = VortexRequest(
        params, OperatingPoint(args.rpm or 0.0, args.airspeed), lattice, _observers(args.observer)
    )
    if args.convergence:
        result = vortex_convergence_study(request, Path(args.out), stage=progress)
        lines = [f"wrote {path}" for path in result.paths.values()]
        lines += convergence_lines(result.report)
    elif args.thrust is not None:
        result = vortex_thrust_search(
            request,
            args.thrust,
            Path(args.out),
            stage=progress,
            tolerance=args.thrust_tolerance,
            max_runs=args.thrust_runs,
        )
        lines = vortex_summary_lines(result)
    else:
        result = simulate_vortex(request, Path(args.out), stage=progress)
        lines = vortex_summary_lines(result)
    progress.finish()
    if not args.quiet:
        print("\n".join(lines))
    return EXIT_OK


def _observers(given: list[Any] | None) -> tuple[Any, ...]:
    """The observers the user named (``--observer``), else the default four."""
    return tuple(given) if given else DEFAULT_OBSERVERS


def _check_simulate_options(args: argparse.Namespace) -> None:
    """ParameterError (exit 2) for options that do not go together."""
    if args.convergence and (args.case_only or args.mesh_from):
        raise ParameterError(
            "--convergence meshes and runs all three levels; "
            "it takes neither --case-only nor --mesh-from"
        )
    if args.thrust is not None and (args.convergence or args.case_only or args.mesh_from):
        raise ParameterError(
            "--thrust meshes once and runs the solver a few times; it takes none of --convergence, "
            "--case-only, --mesh-from"
        )
    if args.solver == "vortex":
        given = [option for key, option in _OPENFOAM_ONLY if getattr(args, key) is not None]
        given += ["--case-only"] if args.case_only else []
        if given:
            raise ParameterError(
                f"{given[0]} belongs to OpenFOAM; --solver vortex takes none of the mesh and "
                "OpenFOAM options"
            )
    else:
        given = [option for key, option in _VORTEX_ONLY if getattr(args, key) is not None]
        if given:
            raise ParameterError(f"{given[0]} sets the vortex lattice; give --solver vortex")
    if args.step is None and (args.axis != "+z" or args.turning != "cw"):
        raise ParameterError("--axis and --turning describe a --step file; give --step FILE")
