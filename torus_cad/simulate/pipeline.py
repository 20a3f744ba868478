"""``torus-cad simulate``: mesh the design (snappyHexMesh with prism layers, or ``cfd``'s
tetrahedra), write its OpenFOAM case, run it, publish the numbers.

One run is one output set in ``OUT`` (torus_cad.outputs.output_set): the case is built and run
inside the set's staging folder; on success the case folder ``<name>_case/`` is renamed into place,
then ``<name>_performance.png``, the tonal noise's picture ``<name>_noise.png`` and signals
``<name>_noise.csv`` (torus_cad.acoustics, from the blade surface pressure at the last iteration)
and the sealed ``<name>_performance.json`` are published; an error or
an interrupt publishes nothing (the staging folder is removed). A case whose solver failed
(diverged, over its time budget) is kept as ``<name>_case_failed/`` for inspection.

:func:`simulate_async` is the coroutine (foamlib's AsyncFoamCase, or a subclass such as
AsyncSlurmFoamCase as ``runner``); many can run at once with :func:`simulate_many`. Meshing
(gmsh and OpenCascade, one model at a time) is serialised by a lock; the solvers share
``AsyncFoamCase.max_cpus``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import json
import math
import os
import secrets
import shutil
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.acoustics.observers import DEFAULT_OBSERVERS, Observer, check_observers
from torus_cad.errors import BudgetError, ParameterError
from torus_cad.outputs.output_set import OutputSet
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import InletSide
from torus_cad.runtime.files import owner_tag
from torus_cad.runtime.input_files import read_untrusted_bytes
from torus_cad.runtime.interrupts import deferred
from torus_cad.simulate.case import (
    BLADE_PRESSURE,
    WALL,
    CaseSpec,
    mesh_commands,
    solve_commands,
    write_case,
)
from torus_cad.simulate.coefficients import convergence_report, run_summary
from torus_cad.simulate.history import History, momentum_balance_force_n, read_y_plus
from torus_cad.simulate.plot import write_history_plot
from torus_cad.simulate.run import (
    ProgressCallback,
    SolverError,
    check_openfoam,
    openfoam_environ,
    run_command,
    run_solver,
    solvers_stopped_on_signals,
)
from torus_cad.simulate.settings import (
    DEFAULT_TIME_LIMIT_S,
    LEVEL_ITERATIONS,
    REFINEMENT_RATIO,
    TURBULENCE_INTENSITY,
    TURBULENCE_LENGTH_D,
    Y_PLUS_TARGET,
    Level,
    Mesher,
    OperatingPoint,
    TurbulenceModel,
    check_count,
    check_operating_point,
    max_processes,
    rpm_limit,
    with_level,
)
from torus_cad.simulate.thrust_target import (
    DEFAULT_MAX_RUNS,
    DEFAULT_TOLERANCE,
    INITIAL_CT,
    MAX_RUNS_RANGE,
    TOLERANCE_RANGE,
    ThrustRun,
    check_target,
    first_rpm,
    next_rpm,
    search_state,
)
from torus_cad.simulate.validity import check_step_propeller, validity_flags
from torus_cad.tolerances import (
    NOISE_MAX_OBSERVERS,
    REPORT_FILE_MAX_BYTES,
    SIMULATE_MAX_ITERATIONS,
    SIMULATE_MAX_SURFACE_REFINEMENT,
    SIMULATE_TIME_LIMIT_MAX_S,
)

if TYPE_CHECKING:
    from torus_cad.acoustics.noise_report import Noise
    from torus_cad.cfd_domain.step_body import StepPropeller

#: CPU seconds simpleFoam takes per cell and iteration (the default design's coarse layered mesh,
#: 51,845 cells: 300 iterations in 85 CPU seconds on each of 2 processes): the estimate a run's time
#: budget is checked against before the solver starts.
SOLVER_SECONDS_PER_CELL_ITERATION = 1.1e-5
MAX_ITERATIONS = SIMULATE_MAX_ITERATIONS  # simulate --iterations: torus_cad.tolerances'
#: The mesh's report in a case folder (mesher, level, checkMesh's verdict and cell types, layers).
MESH_REPORT = "mesh_report.json"


class MeshCheckError(SolverError):
    """checkMesh did not say "Mesh OK"; the message names the level and the failed checks."""


_MESH_LOCK: asyncio.Lock | None = None


def _mesh_lock() -> asyncio.Lock:
    global _MESH_LOCK
    if _MESH_LOCK is None:
        _MESH_LOCK = asyncio.Lock()
    return _MESH_LOCK


@dataclass(frozen=True)
class Request:
    """One simulation: the design, where it runs, the mesh level, iterations (None: the level's),
    MPI processes, whether to stop after writing the case, the time budget in seconds, and a case
    folder of an earlier run of the same design and level whose mesh to reuse (another rpm or
    airspeed without meshing again), the mesher (``snappy``: prism layers; ``tet``: gmsh
    tetrahedra), and a STEP propeller (``--step``) to simulate instead of building ``params`` (then
    ``params`` gives only the name, the sense of rotation and ``[cfd]``), the turbulence model, the
    observers of the tonal noise and the propeller's surface refinement beyond the level's (snappy
    mesher: its surface and edge cells halved that many times more)."""

    params: PropellerParameters
    point: OperatingPoint
    level: Level = Level.COARSE
    iterations: int | None = None
    processes: int = 1
    case_only: bool = False
    time_limit_s: float = DEFAULT_TIME_LIMIT_S
    mesh_from: Path | None = None
    mesher: Mesher = Mesher.SNAPPY
    step: StepPropeller | None = None
    turbulence: TurbulenceModel = TurbulenceModel.K_OMEGA_SST
    observers: tuple[Observer, ...] = DEFAULT_OBSERVERS
    surface_refinement: int = 0

    @property
    def run_iterations(self) -> int:
        return self.iterations if self.iterations is not None else LEVEL_ITERATIONS[self.level]


@dataclass
class Result:
    """What a run published: paths by kind ("case", "png", "json"), the report."""

    paths: dict[str, Path]
    report: dict[str, Any] = field(default_factory=dict)


def check_request(request: Request) -> float:
    """ParameterError (exit 2) for a value out of range (a ``--step`` propeller: its size and its
    mesh's estimate, torus_cad.simulate.validity); returns the tip diameter in m (of the design as
    built: its ``diameter`` / ``pitch`` / ``airfoil.naca`` targets applied)."""
    from torus_cad.cfd_domain.sizes import tip_radius
    from torus_cad.design.design_targets import resolve_design_targets

    check_count("--iterations", request.run_iterations, 1, MAX_ITERATIONS)
    check_count("--processes", request.processes, 1, max_processes())
    check_count(
        "--surface-refinement", request.surface_refinement, 0, SIMULATE_MAX_SURFACE_REFINEMENT
    )
    if request.surface_refinement and request.mesher != Mesher.SNAPPY:
        raise ParameterError(
            f"--surface-refinement = {request.surface_refinement} refines snappyHexMesh's surface; "
            "allowed only with --mesher snappy (the tet mesher sizes by [cfd] cells_per_chord)"
        )
    if not (
        math.isfinite(request.time_limit_s)
        and 0.0 < request.time_limit_s <= SIMULATE_TIME_LIMIT_MAX_S
    ):
        raise ParameterError(
            f"--time-limit = {request.time_limit_s:g} s is out of range; allowed "
            f"(0, {SIMULATE_TIME_LIMIT_MAX_S:g}] s"
        )
    if request.step is not None:
        check_step_propeller(
            request.step,
            request.level,
            request.surface_refinement,
            request.mesher,
            with_level(request.params, request.level).cfd,
        )
        diameter_m = request.step.body.tip_diameter_mm / 1000.0
    else:
        diameter_m = 2.0 * tip_radius(resolve_design_targets(request.params).parameters) / 1000.0
    check_operating_point(request.point, diameter_m, request.params)
    check_count("the number of --observer options", len(request.observers), 1, NOISE_MAX_OBSERVERS)
    check_observers(request.observers, diameter_m / 2.0)
    return diameter_m


def _flow_sign(params: PropellerParameters) -> float:
    return -1.0 if params.cfd.inlet_side == InletSide.PLUS_Z else 1.0


def _swap_folder(staged: Path, final: Path) -> None:
    """Rename ``staged`` onto ``final``, replacing a folder there (signals wait until it is
    done)."""
    trash = final.with_name(f".{final.name}.old-{owner_tag()}{secrets.token_hex(4)}")
    with deferred():
        if final.exists():
            os.replace(final, trash)
        os.replace(staged, final)
    shutil.rmtree(trash, ignore_errors=True)


def _remove_stale_report(out: Path, name: str) -> None:
    """Remove a performance set that described the case a new one replaces."""
    with deferred():
        for suffix in (".json", ".png"):
            (out / f"{name}_performance{suffix}").unlink(missing_ok=True)
        for suffix in (".png", ".csv"):
            (out / f"{name}_noise{suffix}").unlink(missing_ok=True)


async def _mesh_and_write(
    request: Request, case: Path, diameter_m: float, stage: Callable[[str], None] | None
) -> tuple[dict[str, Any], CaseSpec]:
    """Write the case and what its mesh is made from; the mesh report so far (``cells`` None until
    checkMesh)."""
    if request.mesher == Mesher.SNAPPY:
        return await _layered_and_write(request, case, diameter_m, stage)
    from torus_cad.cfd_domain.domain import CfdStage, write_body_domain, write_cfd_domain
    from torus_cad.runtime.stage_timer import StageTimer
    from torus_cad.tolerances import GMSH_REPRODUCIBLE_THREADS

    params, step = request.params, request.step
    async with _mesh_lock():
        if step is not None:
            body = dataclasses.replace(step.body, name=params.name)
            cfd_report, cfd_paths = await asyncio.to_thread(
                write_body_domain,
                body,
                params.cfd,
                case / "cfd",
                GMSH_REPRODUCIBLE_THREADS,
                None,
                StageTimer[CfdStage](stage),
            )
        else:
            # one mesh per design
            cfd_report, cfd_paths = await asyncio.to_thread(
                write_cfd_domain, params, case / "cfd", GMSH_REPRODUCIBLE_THREADS, stage
            )
    spec = _case_spec(request, diameter_m, f"cfd/{cfd_paths['msh_v2'].name}")
    write_case(case, spec)
    return _mesh_report(
        request,
        {
            "cfd": cfd_report["settings"],
            "gmsh_tetrahedra": cfd_report["tetrahedra_total"],
            "cfd_report": f"cfd/{params.name}_cfd.json",
        },
    ), spec


def _mesh_report(request: Request, extra: dict[str, Any]) -> dict[str, Any]:
    return {
        "name": request.params.name,
        "mesher": request.mesher.value,
        "level": request.level.value,
        "surface_refinement": request.surface_refinement,
        "cells": None,
        **extra,
    }


def surface_stl(request: Request, path: Path) -> Path:
    """The propeller's closed surface as a binary STL in mm: the design's B-rep (or the ``--step``
    solid, placed on +z) triangulated at the export deflections."""
    from torus_cad.kernel.writers.stl import write_stl
    from torus_cad.propeller import build_propeller
    from torus_cad.tolerances import STL_ANGULAR_DEFLECTION, STL_LINEAR_DEFLECTION

    path.parent.mkdir(parents=True, exist_ok=True)
    solid = (
        request.step.body.solid
        if request.step is not None
        else build_propeller(request.params).solid
    )
    return write_stl(solid, path, STL_LINEAR_DEFLECTION, STL_ANGULAR_DEFLECTION)


async def _layered_and_write(
    request: Request, case: Path, diameter_m: float, stage: Callable[[str], None] | None
) -> tuple[dict[str, Any], CaseSpec]:
    from torus_cad.simulate.snappy import (
        SURFACE_MM,
        first_cell_height_m,
        level_scale,
        write_layered_mesh,
    )

    params, point = request.params, request.point
    if stage:
        stage("surface")
    async with _mesh_lock():
        surface = await asyncio.to_thread(surface_stl, request, case / SURFACE_MM)
    first = first_cell_height_m(
        diameter_m, point.rpm, point.airspeed_m_s, Y_PLUS_TARGET, point.fluid
    )
    cfd = params.cfd
    layered = write_layered_mesh(
        surface,
        diameter_m * 1000.0,
        request.level,
        case,
        first,
        _flow_sign(params),
        {
            "domain_radius": cfd.domain_radius,
            "upstream": cfd.upstream,
            "downstream": cfd.downstream,
        },
        cfd.zone_radius,
        cfd.zone_clearance,
        request.surface_refinement,
    )
    spec = _case_spec(request, diameter_m, "")
    write_case(case, spec)
    return _mesh_report(
        request,
        {
            "y_plus_target": Y_PLUS_TARGET,
            "first_layer_m": layered.first_layer_m,
            "first_layer_for_y_plus_target_m": first / level_scale(request.level),
            "background_cell_m": layered.background_cell_m,
            "domain": dataclasses.asdict(layered.domain),
            "rpm_sized_for": point.rpm,
        },
    ), spec


def _case_spec(request: Request, diameter_m: float, msh_file: str) -> CaseSpec:
    params = request.params
    return CaseSpec(
        request.point,
        params.handedness,
        diameter_m,
        _flow_sign(params),
        request.run_iterations,
        request.processes,
        msh_file,
        request.mesher,
        request.turbulence,
    )


def _checked_mesh(case: Path, mesh_report: dict[str, Any]) -> dict[str, Any]:
    """``mesh_report`` with checkMesh's verdict, cells, cell types and largest non-orthogonality
    (and snappyHexMesh's layer report); MeshCheckError (exit 1) unless checkMesh said "Mesh OK"."""
    from torus_cad.simulate.snappy import layer_coverage, parse_check_mesh

    check = parse_check_mesh((case / "log.checkMesh").read_text(errors="replace"))
    report = {
        **mesh_report,
        "cells": check.cells,
        "cell_types": check.cell_types,
        "mesh_ok": check.ok,
        "max_non_orthogonality_deg": check.max_non_orthogonality,
    }
    snappy_log = case / "log.snappyHexMesh"
    if snappy_log.is_file():
        report["layers"] = layer_coverage(snappy_log.read_text(errors="replace"))
    (case / MESH_REPORT).write_text(json.dumps(report, indent=1), encoding="utf-8")
    if not check.ok:
        failed = "; ".join(check.failures) or "no verdict in log.checkMesh"
        raise MeshCheckError(
            f"checkMesh did not report 'Mesh OK' on the {report['level']} level "
            f"({report['mesher']} mesher): {failed}"
        )
    return report


def _mesh_source_report(request: Request) -> dict[str, Any]:
    """The mesh report of ``request.mesh_from``; ParameterError unless it is a checked case of the
    same design name, mesher and level (and ``[cfd]`` for the tet mesher). Nothing is written:
    checked before the output folder is made."""
    source, name = Path(request.mesh_from or ""), request.params.name
    report_path = source / MESH_REPORT
    if not ((source / "constant" / "polyMesh" / "boundary").is_file() and report_path.is_file()):
        raise ParameterError(
            f"--mesh-from {str(source)!r} is not a meshed case of {name!r} "
            f"(no constant/polyMesh/boundary or {MESH_REPORT})"
        )
    try:
        mesh_report = json.loads(
            read_untrusted_bytes(report_path, "mesh report", REPORT_FILE_MAX_BYTES)
        )
        made = (
            mesh_report["name"],
            mesh_report["mesher"],
            mesh_report["level"],
            mesh_report.get("surface_refinement", 0),
        )
    except (ParameterError, ValueError, KeyError, TypeError, RecursionError):
        raise ParameterError(
            f"--mesh-from {str(source)!r}: {MESH_REPORT} is not a mesh report"
        ) from None
    wanted = (name, request.mesher.value, request.level.value, request.surface_refinement)
    if made != wanted or (
        request.mesher == Mesher.TET
        and mesh_report.get("cfd") != request.params.cfd.model_dump(mode="json")
    ):
        raise ParameterError(
            f"--mesh-from {str(source)!r} was meshed for "
            f"design {made[0]!r}, mesher {made[1]!r}, level "
            f"{made[2]!r}, surface refinement {made[3]!r}, not {wanted[0]!r}, {wanted[1]!r}, "
            f"{wanted[2]!r}, {wanted[3]!r}"
            + (" (or with other [cfd] settings)" if request.mesher == Mesher.TET else "")
        )
    return mesh_report


def _reuse_mesh(request: Request, case: Path, diameter_m: float) -> tuple[dict[str, Any], CaseSpec]:
    """Copy the mesh (constant/polyMesh) and its report of ``request.mesh_from`` into ``case`` and
    write the dictionaries; ParameterError unless it is a checked case of the same design name,
    mesher and level."""
    mesh_report = _mesh_source_report(request)
    source, name = Path(request.mesh_from or ""), request.params.name
    report_path = source / MESH_REPORT
    if (source / "cfd").is_dir():
        shutil.copytree(source / "cfd", case / "cfd")
    shutil.copytree(source / "constant" / "polyMesh", case / "constant" / "polyMesh")
    shutil.copy2(report_path, case / MESH_REPORT)
    spec = _case_spec(
        request, diameter_m, f"cfd/{name}_cfd_v2.msh" if request.mesher == Mesher.TET else ""
    )
    write_case(case, spec)
    return mesh_report, spec


def _check_budget(cells: int, request: Request, elapsed_s: float) -> None:
    estimate = (
        cells * request.run_iterations * SOLVER_SECONDS_PER_CELL_ITERATION / request.processes
    )
    if elapsed_s + estimate > request.time_limit_s:
        raise BudgetError(
            f"the solver would take about {estimate:.0f} s "
            f"({cells:,} cells x {request.run_iterations} "
            f"iterations on {request.processes} process(es)), over what is left of --time-limit = "
            f"{request.time_limit_s:g} s; raise --time-limit, lower --iterations or use --processes"
        )


async def simulate_async(
    request: Request,
    out_dir: str | Path,
    progress: ProgressCallback | None = None,
    stage: Callable[[str], None] | None = None,
    runner: type | None = None,
) -> Result:
    """Mesh, write, run and publish one simulation (see the module doc). ``progress`` gets each
    iteration's status, ``stage`` each stage's name; ``runner`` is the foamlib case class
    (default AsyncFoamCase).

    Raises ParameterError / BudgetError (bad input, refused before it starts),
    MissingOpenFoamError, DivergedError / TimeBudgetError / SolverError (case kept as
    ``<name>_case_failed``), KernelError from the mesher.
    """
    start = time.perf_counter()
    diameter_m = check_request(request)
    if not request.case_only:
        check_openfoam()
    request, out = _at_level(request), Path(out_dir)
    if request.mesh_from is not None:
        _mesh_source_report(request)  # a wrong case is refused before the output folder is made
    name = request.params.name
    with OutputSet(out, f"{name}_performance") as output:
        assert output.staging is not None
        case = output.staging / f"{name}_case"
        if request.mesh_from is not None:
            mesh_report, spec = _reuse_mesh(request, case, diameter_m)
        else:
            mesh_report, spec = await _mesh_and_write(request, case, diameter_m, stage)
        if request.case_only:
            _swap_folder(case, out / f"{name}_case")
            _remove_stale_report(out, name)
            report = {
                "cells": mesh_report["cells"] or mesh_report.get("gmsh_tetrahedra"),
                "level": request.level.value,
                "mesher": request.mesher.value,
                "tip_diameter_m": diameter_m,
                **_step_entry(request),
                "validity": validity_flags(
                    diameter_m, request.point, mesh_report.get("first_layer_m"), None
                ),
            }
            return Result({"case": out / f"{name}_case"}, report)
        run = await _run_case(
            request,
            case,
            out,
            spec,
            mesh_report,
            diameter_m,
            start,
            stage,
            progress,
            runner,
            convert=request.mesh_from is None,
            mesh_s=time.perf_counter() - start,
        )
        noise = await _noise(request, case, stage)
        return _publish(output, request, case, out, run, start, noise=noise)


@dataclass
class _Run:
    """One solver run's report and force history."""

    report: dict[str, Any]
    history: History


def _at_level(request: Request) -> Request:
    return dataclasses.replace(request, params=with_level(request.params, request.level))


def _step_entry(request: Request) -> dict[str, Any]:
    return {"step": request.step.report()} if request.step is not None else {}


async def _run_case(
    request: Request,
    case: Path,
    out: Path,
    spec: CaseSpec,
    mesh_report: dict[str, Any],
    diameter_m: float,
    start: float,
    stage: Callable[[str], None] | None,
    progress: ProgressCallback | None,
    runner: type | None,
    convert: bool,
    mesh_s: float,
) -> _Run:
    """Run the mesh commands (if ``convert``: snappyHexMesh or gmshToFoam, then checkMesh, which
    must say "Mesh OK") and the solver in ``case``; the report of the run (``mesh_s``: the seconds
    its mesh took before OpenFOAM, meshed or copied; ``convert``: OpenFOAM's meshing and checking).
    The time budget counts from ``start`` (time.perf_counter). A failed solver's or mesh check's
    case is kept as ``OUT/<name>_case_failed``."""
    from foamlib import AsyncFoamCase

    run_start = time.perf_counter()
    if mesh_report.get("gmsh_tetrahedra"):  # the tet route knows its cells before OpenFOAM runs
        _check_budget(int(mesh_report["gmsh_tetrahedra"]), request, run_start - start)
    foam = (runner or AsyncFoamCase)(case)
    try:
        async with _mesh_lock() if request.mesher == Mesher.SNAPPY else contextlib.nullcontext():
            for command in mesh_commands(spec) if convert else []:
                if stage:
                    stage(command[0])
                await run_command(foam, command)
        if convert:
            mesh_report = _checked_mesh(case, mesh_report)
        convert_s = time.perf_counter() - run_start
        _check_budget(int(mesh_report["cells"]), request, time.perf_counter() - start)
        deadline = time.monotonic() + request.time_limit_s - (time.perf_counter() - start)
        if stage:
            stage("simpleFoam")
        history = await _solve(foam, spec, deadline, progress)
    except SolverError as error:
        kept = out / f"{request.params.name}_case_failed"
        _swap_folder(case, kept)
        raise type(error)(f"{error}; the case is kept in {kept}") from None
    report = _report(request, spec, mesh_report, history, diameter_m, read_y_plus(case))
    report.update(
        stage_seconds={
            "mesh": mesh_s,
            "convert": convert_s,
            "solve": time.perf_counter() - run_start - convert_s,
        },
        **_step_entry(request),
    )
    return _Run(report, history)


async def _noise(request: Request, case: Path, stage: Callable[[str], None] | None) -> Noise | None:
    """The tonal noise of the finished ``case`` at ``request.observers`` (None when the propeller
    does not turn)."""
    from torus_cad.acoustics.fwh import Medium
    from torus_cad.acoustics.noise_report import evaluate_noise
    from torus_cad.acoustics.pressure_surface import read_surface, surface_pressure_file

    omega = request.point.omega_rad_s(request.params.handedness)
    if omega == 0.0:
        return None
    if stage:
        stage("noise")
    fluid = request.point.fluid
    surface = read_surface(surface_pressure_file(case, BLADE_PRESSURE, WALL), fluid.density_kg_m3)
    blades = request.params.blades if request.step is None else 1
    noise = await asyncio.to_thread(
        evaluate_noise,
        surface,
        omega,
        blades,
        Medium(fluid.density_kg_m3, fluid.speed_of_sound_m_s),
        request.observers,
    )
    if request.step is not None:
        noise.report.update(
            blades=None,
            harmonics_of="the rotation frequency (a --step propeller's blade count is not known)",
        )
    else:
        noise.report["harmonics_of"] = "the blade-passing frequency"
    if request.point.airspeed_m_s > 0.0:
        noise.report["airspeed_note"] = "the airspeed's convection of the sound is neglected"
    return noise


def _publish(
    output: OutputSet,
    request: Request,
    case: Path,
    out: Path,
    run: _Run,
    start: float,
    extra: dict[str, Any] | None = None,
    noise: Noise | None = None,
) -> Result:
    """Publish ``case`` (as ``OUT/<name>_case``), the history plot, the noise picture and signals
    and the sealed report of ``run``."""
    params, name = request.params, request.params.name
    cells = run.report["cells"]
    title = (
        f"{name}: {run.report['rpm']:g} rpm, "
        f"{request.point.airspeed_m_s:g} m/s, {request.level.value} "
        f"({cells:,} cells)"
    )
    output.write(
        "png", lambda path: write_history_plot(run.history, params.handedness, path, title)
    )
    if noise is not None:
        output.write_files(lambda folder: _noise_files(noise, folder, name, title))
    report = {
        **run.report,
        **(extra or {}),
        "noise": noise.report if noise is not None else None,
        "wall_seconds": time.perf_counter() - start,
        "case": f"{name}_case",
    }
    with deferred():
        _swap_folder(case, out / f"{name}_case")
        paths = output.publish(report)
    return Result({"case": out / f"{name}_case", **paths}, output.sealed_report)


def _noise_files(noise: Noise, folder: Path, name: str, title: str) -> dict[str, Path]:
    from torus_cad.acoustics.noise_report import write_noise_csv, write_noise_plot

    return {
        "noise_png": write_noise_plot(noise, folder / f"{name}_noise.png", f"tonal noise, {title}"),
        "noise_csv": write_noise_csv(noise, folder / f"{name}_noise.csv"),
    }


async def _solve(
    foam: Any, spec: CaseSpec, deadline: float, progress: ProgressCallback | None
) -> History:
    commands = solve_commands(spec)
    for command in commands[: commands.index(["simpleFoam"])]:
        await run_command(foam, command)
    history = await run_solver(foam, spec.iterations, spec.processes, deadline, progress)
    for command in commands[commands.index(["simpleFoam"]) + 1 :]:
        await run_command(foam, command)
    return history


def _report(
    request: Request,
    spec: CaseSpec,
    mesh_report: dict[str, Any],
    history: History,
    diameter_m: float,
    y_plus: dict[str, float] | None,
) -> dict[str, Any]:
    point, fluid = request.point, request.point.fluid
    summary = run_summary(history, point, request.params.handedness, diameter_m)
    balance = momentum_balance_force_n(history, fluid.density_kg_m3)
    k, omega = point.inflow_turbulence(diameter_m)
    thrust = summary["thrust_n"]
    return {
        "name": request.params.name,
        "handedness": request.params.handedness.value,
        "rpm": point.rpm,
        "airspeed_m_s": point.airspeed_m_s,
        "omega_rad_s": spec.point.omega_rad_s(spec.handedness),
        "tip_diameter_m": diameter_m,
        **summary,
        "momentum_balance": {
            "thrust_n": float(balance[2]),
            "relative_difference": (float(balance[2]) / thrust - 1.0) if thrust else None,
        },
        "cells": int(mesh_report["cells"]),
        "iterations": int(history.last_iteration),
        "final_residuals": history.last_residuals(),
        "level": request.level.value,
        "processes": request.processes,
        "mesher": request.mesher.value,
        "mesh": mesh_report,
        "y_plus": y_plus,
        "validity": validity_flags(diameter_m, point, mesh_report.get("first_layer_m"), y_plus),
        "fluid": {
            "name": fluid.name,
            "density_kg_m3": fluid.density_kg_m3,
            "viscosity_m2_s": fluid.viscosity_m2_s,
        },
        "turbulence": {
            "model": f"{request.turbulence.value}, wall functions",
            "inflow_intensity": TURBULENCE_INTENSITY,
            "inflow_length_scale_m": TURBULENCE_LENGTH_D * diameter_m,
            "inflow_k_m2_s2": k,
            "inflow_omega_1_s": omega,
        },
        "conventions": "y_plus: min / area-weighted mean / "
        "max over the propeller's faces at the last iteration "
        "(OpenFOAM's yPlus function object); thrust > 0 pushes the fluid "
        "toward -z (the design's way); torque > 0 resists the design's "
        "rotation; CT = T/(rho n^2 D^4), CP = P/(rho n^3 D^5), n in rev/s, D the tip diameter",
    }


def simulate(
    request: Request,
    out_dir: str | Path,
    progress: ProgressCallback | None = None,
    stage: Callable[[str], None] | None = None,
) -> Result:
    """:func:`simulate_async` in its own event loop, with OpenFOAM's environment and SIGINT /
    SIGTERM stopping the solver."""
    with openfoam_environ(), solvers_stopped_on_signals():
        return asyncio.run(simulate_async(request, out_dir, progress, stage))


async def simulate_many(
    requests: Sequence[tuple[Request, str | Path]], runner: type | None = None
) -> list[Any]:
    """Run many simulations at once (each into its own folder); their Results, or the exception each
    raised. The solvers share ``AsyncFoamCase.max_cpus`` (foamlib's local pool); with
    ``runner=AsyncSlurmFoamCase`` each command is a Slurm job."""
    with openfoam_environ():
        return list(
            await asyncio.gather(
                *(simulate_async(request, out, runner=runner) for request, out in requests),
                return_exceptions=True,
            )
        )


@dataclass(frozen=True)
class ThrustTarget:
    """``--thrust``: the target thrust N, the tolerance (a fraction of it) and the most solver
    runs."""

    thrust_n: float
    tolerance: float = DEFAULT_TOLERANCE
    max_runs: int = DEFAULT_MAX_RUNS


def check_thrust_target(request: Request, target: ThrustTarget) -> tuple[float, float]:
    """ParameterError (exit 2) for a bad target, tolerance or run count; (tip diameter m, rpm
    limit)."""
    check_count("--thrust-runs", target.max_runs, *MAX_RUNS_RANGE)
    low, high = TOLERANCE_RANGE
    if not (math.isfinite(target.tolerance) and low <= target.tolerance <= high):
        raise ParameterError(
            f"--thrust-tolerance = {target.tolerance:g} is "
            f"out of range; allowed [{low:g}, {high:g}] "
            "(a fraction of the target)"
        )
    diameter_m = check_request(request)
    limit = rpm_limit(diameter_m, request.point.airspeed_m_s, request.point.fluid)
    check_target(target.thrust_n, limit, diameter_m, request.point.fluid.density_kg_m3)
    return diameter_m, limit


async def thrust_search_async(
    request: Request,
    target: ThrustTarget,
    out_dir: str | Path,
    progress: ProgressCallback | None = None,
    stage: Callable[[str], None] | None = None,
    runner: type | None = None,
) -> Result:
    """The rpm at which the propeller gives ``target.thrust_n`` (torus_cad.simulate.thrust_target):
    one mesh, then one solver run per rpm on it (each a case of its own in the staging folder, the
    mesh copied from the first), at most ``target.max_runs``. Publishes one set: the case, plot and
    report of the run closest to the target, the report's ``thrust_search`` listing every run.
    ``request.point.rpm`` is ignored (the first run's rpm comes from the target); the time budget
    covers the whole search.

    Raises what :func:`simulate_async` raises, and ParameterError for a target out of reach."""
    start = time.perf_counter()
    diameter_m, limit = check_thrust_target(request, target)
    check_openfoam()
    request, out = (
        _at_level(dataclasses.replace(request, case_only=False, mesh_from=None)),
        Path(out_dir),
    )
    created = not out.exists()
    try:
        return await _thrust_search(
            request, target, out, diameter_m, limit, start, progress, stage, runner
        )
    # out of reach: nothing published, and no folder left behind that was not there
    except ParameterError:
        if created and out.is_dir() and not any(out.iterdir()):
            out.rmdir()
        raise


async def _thrust_search(
    request: Request,
    target: ThrustTarget,
    out: Path,
    diameter_m: float,
    limit: float,
    start: float,
    progress: ProgressCallback | None,
    stage: Callable[[str], None] | None,
    runner: type | None,
) -> Result:
    """The search of :func:`thrust_search_async` into the output set ``out`` (rpm limit ``limit`` in
    rpm)."""
    fluid = request.point.fluid
    rpm = first_rpm(target.thrust_n, limit, diameter_m, fluid.density_kg_m3)
    name = request.params.name
    runs: list[ThrustRun] = []
    results: list[tuple[Path, _Run]] = []
    with OutputSet(out, f"{name}_performance") as output:
        assert output.staging is not None
        first_case = output.staging / "runs" / "0" / f"{name}_case"
        while True:
            run_request = dataclasses.replace(
                request, point=dataclasses.replace(request.point, rpm=rpm)
            )
            prepared = time.perf_counter()
            if not results:
                mesh_report, spec = await _mesh_and_write(
                    run_request, first_case, diameter_m, stage
                )
                case = first_case
            else:
                case = output.staging / "runs" / str(len(results)) / f"{name}_case"
                mesh_report, spec = _reuse_mesh(
                    dataclasses.replace(run_request, mesh_from=first_case), case, diameter_m
                )
            run = await _run_case(
                run_request,
                case,
                out,
                spec,
                mesh_report,
                diameter_m,
                start,
                stage,
                progress,
                runner,
                convert=not results,
                mesh_s=time.perf_counter() - prepared,
            )
            results.append((case, run))
            runs.append(ThrustRun(rpm, float(run.report["thrust_n"])))
            if stage:
                stage(f"run {len(runs)}: {rpm:.0f} rpm, thrust {runs[-1].thrust_n:.4g} N")
            state = search_state(runs, target.thrust_n, target.tolerance, target.max_runs, limit)
            if state.done:
                break
            rpm = next_rpm(runs, target.thrust_n, limit)
        chosen = runs.index(state.best)
        case, run = results[chosen]
        search = {
            "target_thrust_n": target.thrust_n,
            "tolerance": target.tolerance,
            "max_runs": target.max_runs,
            "rpm": state.best.rpm,
            "thrust_n": state.best.thrust_n,
            "within_tolerance": state.within_tolerance,
            "rpm_limit": limit,
            "chosen_run": chosen,
            "runs": [
                {
                    "rpm": item.rpm,
                    "thrust_n": item.thrust_n,
                    "torque_nm": result.report["torque_nm"],
                    "power_w": result.report["power_w"],
                    "figure_of_merit": result.report["figure_of_merit"],
                    "efficiency": result.report["efficiency"],
                    "converged": result.report["converged"],
                    "solve_seconds": result.report["stage_seconds"]["solve"],
                }
                for item, (_, result) in zip(runs, results)
            ],
            "method": "secant on sqrt(thrust) over rpm, one mesh; the first rpm from CT = "
            f"{INITIAL_CT:g}",
        }
        seconds = {
            key: sum(result.report["stage_seconds"][key] for _, result in results)
            for key in ("mesh", "convert", "solve")
        }
        # the chosen run's rpm: request.point.rpm is not the search's (0 from the command line: no
        # noise at all)
        chosen_request = dataclasses.replace(
            request, point=dataclasses.replace(request.point, rpm=state.best.rpm)
        )
        noise = await _noise(chosen_request, case, stage)
        return _publish(
            output,
            request,
            case,
            out,
            run,
            start,
            {"thrust_search": search, "stage_seconds": seconds},
            noise,
        )


def thrust_search(
    request: Request,
    target: ThrustTarget,
    out_dir: str | Path,
    progress: ProgressCallback | None = None,
    stage: Callable[[str], None] | None = None,
) -> Result:
    """:func:`thrust_search_async` in its own event loop, with OpenFOAM's environment and SIGINT /
    SIGTERM stopping the solver."""
    with openfoam_environ(), solvers_stopped_on_signals():
        return asyncio.run(thrust_search_async(request, target, out_dir, progress, stage))


def convergence_study(
    request: Request,
    out_dir: str | Path,
    progress: ProgressCallback | None = None,
    stage: Callable[[str], None] | None = None,
) -> Result:
    """The three levels (each a full run in ``OUT/<level>/``) and ``<name>_convergence.json``:
    Richardson-extrapolated thrust and torque, their observed order and Roache's grid convergence
    index (``gci_fine``, ``gci_medium``: fractions of the fine and medium values, safety factor
    1.25; ``gci_asymptotic_ratio`` GCI_medium / (r^p GCI_fine), ``in_asymptotic_range`` when it is
    within ``ASYMPTOTIC_RANGE_TOLERANCE`` of 1); all null unless the levels converge monotonically.
    Always: ``spread`` and ``uncertainty_fine`` (GCI_fine, or three times the spread where there is
    no GCI; ``uncertainty_method`` says which), fractions of the fine value
    (Extrapolation.report)."""
    out = Path(out_dir)
    # the finest mesh refused before the coarse runs
    check_request(dataclasses.replace(request, level=Level.FINE))
    runs = {}
    for level in Level:
        level_request = dataclasses.replace(request, level=level, case_only=False, mesh_from=None)
        runs[level] = simulate(level_request, out / level.value, progress, stage)
    levels = {
        level.value: {
            key: run.report[key]
            for key in (
                "cells",
                "thrust_n",
                "torque_nm",
                "ct",
                "cp",
                "converged",
                "y_plus",
                "validity",
                "wall_seconds",
            )
        }
        for level, run in runs.items()
    }
    report = convergence_report(request.params.name, request.point, REFINEMENT_RATIO, levels)
    with OutputSet(out, f"{request.params.name}_convergence") as output:
        paths = output.publish(report)
    return Result(paths, report)
