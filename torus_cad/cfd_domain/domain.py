"""The fluid domain around the propeller and its tetrahedral mesh, with gmsh (the ``cfd`` extra).

From the B-rep (written as STEP and imported by gmsh's OpenCascade kernel): an outer cylinder
along the spin axis, an inner rotating-zone cylinder enclosing the propeller, and the
propeller itself are fragmented together (so the zone's boundary is one conformal interface
shared by both regions), the propeller's volume is removed (its faces stay, as the wall),
and the fluid is meshed with tetrahedra: ``cells_per_chord`` elements across the smallest
chord on the propeller, finer where the surface curves (gmsh's curvature sizing), growing by
``growth_rate`` per element away from the propeller up to ``far_size``. Without curvature sizing
the trailing edges get a size field of their own; the surface mesh is checked for crossing
triangles and refined where they cross before the volume is meshed (a crossing surface stops
gmsh's 3D mesher), so coarse settings mesh too.

The files (STEP, both .msh, README.txt and the sealed report) are one output set
(torus_cad.outputs.output_set), named ``<name>_cfd``.

Physical groups (what solvers see as patches and zones):
``propeller`` (wall), ``rotating_interface`` (between the zones), ``inlet``, ``outlet``,
``farfield`` (the outer lateral surface); volumes ``rotating_zone`` and ``fluid`` (the
stationary outer region).
"""

from __future__ import annotations

import errno
import os
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.cfd_domain.estimate import CfdEstimate, check_cfd_budget
from torus_cad.cfd_domain.readme import readme_text
from torus_cad.cfd_domain.sizes import (
    CYLINDER_SEGMENTS,
    MIN_SIZE_FRACTION,
    TRAILING_EDGE_SIZE_PER_THICKNESS,
    Domain,
    TrailingEdges,
    domain_from_sizes,
    trailing_edges,
)
from torus_cad.errors import KernelError, MissingExtraError, ParameterError
from torus_cad.formats import StepSchema
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Cfd
from torus_cad.runtime.cpus import max_cfd_threads
from torus_cad.runtime.files import file_ends_with, write_failure
from torus_cad.runtime.stage_timer import StageTimer
from torus_cad.tolerances import GMSH_REPRODUCIBLE_THREADS

#: Names of the physical groups: surfaces, then volumes.
SURFACE_GROUPS = ("propeller", "rotating_interface", "inlet", "outlet", "farfield")
VOLUME_GROUPS = ("rotating_zone", "fluid")

#: Samples per parametric direction of each propeller face for gmsh's distance field.
DISTANCE_SAMPLING = 60
#: Samples of gmsh's distance field along each trailing edge.
TRAILING_EDGE_SAMPLING = 400
#: Local refinement where surface triangles cross: rounds at most, ball radius in longest edges of a
#: crossing triangle, new element size as a fraction of that edge.
REFINE_ROUNDS, REFINE_RADIUS_EDGES, REFINE_FACTOR = 4, 2.0, 0.35
#: What to change when gmsh cannot mesh the domain (a crossing surface mesh, a volume mesher stop).
CROSSING_ADVICE = (
    "Finer sizes near the trailing edge help: raise cfd.curvature_cells (the default 8 refines "
    "the trailing edge) or cfd.cells_per_chord (default 10)"
)
#: gmsh algorithms: 2D Frontal-Delaunay (gmsh falls back to MeshAdapt per face), 3D Delaunay.
ALGORITHM_2D, ALGORITHM_3D = 6, 1


def import_gmsh() -> Any:
    """The gmsh module, or MissingExtraError naming the extra (and the system libraries it
    needs)."""
    from torus_cad.runtime.extras import install_line, missing_extra_message

    try:
        import gmsh
    except ImportError:
        raise MissingExtraError(missing_extra_message("cfd", "cfd", "gmsh")) from None
    except OSError as error:
        raise MissingExtraError(
            f"gmsh's library does not load ({error}); install the cfd extra "
            f"({install_line('cfd')}) and the system libraries it links, on Debian: "
            "apt-get install libglu1-mesa libxcursor1 libxft2 libxinerama1 libgl1"
        ) from None
    return gmsh


class CfdStage(StrEnum):
    """Stages of ``torus-cad cfd``; the value is the key in the report's ``stage_seconds``."""

    BREP = "brep"
    DOMAIN = "domain"
    SURFACE_MESH = "surface_mesh"
    VOLUME_MESH = "volume_mesh"
    WRITE = "write"


@contextmanager
def gmsh_session(gmsh: Any, threads: int) -> Iterator[None]:
    """gmsh initialised quietly for one model; finalised afterwards (unless the caller had it
    running)."""
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(
            readConfigFiles=False,
            interruptible=threading.current_thread() is threading.main_thread(),
        )
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", threads or (os.cpu_count() or 1))
    gmsh.model.add("torus_cad_cfd")
    try:
        yield
    finally:
        gmsh.model.remove()
        if owner:
            gmsh.finalize()


@contextmanager
def gmsh_library(gmsh: Any) -> Iterator[None]:
    """gmsh initialised by the main thread for the block (a :func:`gmsh_session` inside then uses
    it).

    gmsh's initialize and finalize put the default handlers of SIGTERM and its kin back at the C
    level (Python still reports its own): here Python's handlers are set again after each, so a
    signal during meshing still ends the command with one line (torus_cad.runtime.interrupts). Only
    the main thread can do that; call this there, and mesh in a worker
    (torus_cad.cfd_domain.interruptible)."""
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    _reassert_signal_handlers()
    try:
        yield
    finally:
        gmsh.finalize()
        _reassert_signal_handlers()


def _reassert_signal_handlers() -> None:
    import signal

    from torus_cad.runtime.interrupts import EXIT_SIGNALS

    if threading.current_thread() is not threading.main_thread():
        return
    for signum in EXIT_SIGNALS:
        handler = signal.getsignal(signum)
        if handler is not None:
            signal.signal(signum, handler)


@contextmanager
def gmsh_step(name: str) -> Iterator[None]:
    """Turn a gmsh failure into a KernelError (exit 1) that names the step."""
    try:
        yield
    except Exception as error:  # gmsh raises plain Exception with its last error message
        if isinstance(error, KernelError):
            raise
        raise KernelError(f"gmsh failed at step '{name}': {error}") from None


@dataclass(frozen=True)
class DomainEntities:
    """gmsh entity tags of the groups, by group name."""

    surfaces: dict[str, list[int]]
    volumes: dict[str, list[int]]


def build_domain(gmsh: Any, step_path: Path, domain: Domain) -> DomainEntities:
    """Import the propeller, add the two cylinders, fragment, drop the propeller's volume, find the
    groups."""
    occ = gmsh.model.occ
    with gmsh_step("import the propeller STEP"):
        imported = occ.importShapes(str(step_path))
        solids = [tag for dim, tag in imported if dim == 3]
        if len(solids) != 1:
            raise KernelError(
                "gmsh failed at step 'import the propeller "
                f"STEP': expected one solid, got {len(solids)}"
            )
    with gmsh_step("fragment the domain"):
        zone = occ.addCylinder(
            0, 0, domain.zone_z[0], 0, 0, domain.zone_z[1] - domain.zone_z[0], domain.zone_radius
        )
        outer = occ.addCylinder(
            0,
            0,
            domain.outer_z[0],
            0,
            0,
            domain.outer_z[1] - domain.outer_z[0],
            domain.outer_radius,
        )
        _, pieces = occ.fragment([(3, outer)], [(3, zone), (3, solids[0])])
        occ.synchronize()
        propeller = {tag for _, tag in pieces[2]}
        rotating = {tag for _, tag in pieces[1]} - propeller
        fluid = {tag for _, tag in pieces[0]} - rotating - propeller
        if not (propeller and rotating and fluid):
            raise KernelError(
                "gmsh failed at step 'fragment the domain': the propeller, rotating zone and outer "
                "region did not come out as separate volumes"
            )
        wall = _boundary(gmsh, propeller)
        occ.remove([(3, tag) for tag in sorted(propeller)])
        occ.synchronize()
    zone_faces, fluid_faces = _boundary(gmsh, rotating), _boundary(gmsh, fluid)
    interface = zone_faces & fluid_faces
    surfaces = {
        "propeller": sorted(wall),
        "rotating_interface": sorted(interface),
        "inlet": [],
        "outlet": [],
        "farfield": [],
    }
    for tag in sorted(fluid_faces - interface):
        _, _, zmin, _, _, zmax = gmsh.model.getBoundingBox(2, tag)
        flat = zmax - zmin < 1e-6 * domain.outer_radius
        if flat and abs(zmin - domain.inlet_z) < 1e-3 * domain.outer_radius:
            surfaces["inlet"].append(tag)
        elif flat and abs(zmin - domain.outlet_z) < 1e-3 * domain.outer_radius:
            surfaces["outlet"].append(tag)
        else:
            surfaces["farfield"].append(tag)
    empty = [name for name, tags in surfaces.items() if not tags]
    if empty:
        raise KernelError(
            f"gmsh failed at step 'find the boundaries': no faces for {', '.join(empty)}"
        )
    return DomainEntities(surfaces, {"rotating_zone": sorted(rotating), "fluid": sorted(fluid)})


def _boundary(gmsh: Any, volumes: set[int]) -> set[int]:
    faces = gmsh.model.getBoundary(
        [(3, tag) for tag in sorted(volumes)], combined=False, oriented=False
    )
    return {abs(tag) for _, tag in faces}


def _trailing_edge_field(
    gmsh: Any, edges: TrailingEdges, domain: Domain, growth_rate: float
) -> int:
    """A size field around the trailing edges: ``TRAILING_EDGE_SIZE_PER_THICKNESS`` x their
    thickness (at least MIN_SIZE_FRACTION of the surface size) on them, growing by ``growth_rate``
    away.

    The edges are added to the model as free splines (in no physical group, not written), only for
    gmsh's distance field."""
    occ, fields = gmsh.model.occ, gmsh.model.mesh.field
    splines = [
        occ.addSpline([occ.addPoint(*map(float, point)) for point in curve])
        for curve in edges.curves_mm
    ]
    occ.synchronize()
    size = max(
        TRAILING_EDGE_SIZE_PER_THICKNESS * edges.thickness_mm,
        MIN_SIZE_FRACTION * domain.surface_size,
    )
    distance = fields.add("Distance")
    fields.setNumbers(distance, "CurvesList", splines)
    fields.setNumber(distance, "Sampling", TRAILING_EDGE_SAMPLING)
    field = fields.add("MathEval")
    fields.setString(field, "F", f"{size!r} + {growth_rate - 1.0!r} * F{distance}")
    return int(field)


def set_sizes(
    gmsh: Any,
    domain: Domain,
    settings: Cfd,
    entities: DomainEntities,
    edges: TrailingEdges | None = None,
) -> int:
    """Element sizes: ``surface_size`` on the propeller growing linearly with the distance from it
    (neighbours differ by about ``growth_rate``), capped at ``far_size``; on the two cylinders at
    most 1/CYLINDER_SEGMENTS of their circumference (so their facets keep the volumes within ~0.1
    %); curvature refinement on top; around the trailing ``edges`` (if given) sizes scaled to their
    thickness (:func:`_trailing_edge_field`). Returns the background field's tag.

    The edges are needed only without curvature refinement: with it, gmsh already gives the
    trailing edge (a crease, or a blunt edge's tight round or corners: the surface's highest
    curvature) elements of ``MeshSizeMin``, and the edge field's graded band around it would
    only add elements."""
    fields = gmsh.model.mesh.field
    distance = fields.add("Distance")
    fields.setNumbers(distance, "SurfacesList", entities.surfaces["propeller"])
    fields.setNumber(distance, "Sampling", DISTANCE_SAMPLING)
    growth = fields.add("MathEval")
    fields.setString(
        growth,
        "F",
        f"Min({domain.far_size!r}, {domain.surface_size!r} + "
        f"{settings.growth_rate - 1.0!r} * F{distance})",
    )
    limits = [growth]
    if edges is not None:
        limits.append(_trailing_edge_field(gmsh, edges, domain, settings.growth_rate))
    for group, radius in (
        ("rotating_interface", domain.zone_radius),
        ("farfield", domain.outer_radius),
    ):
        cap = fields.add("Constant")
        fields.setNumbers(cap, "SurfacesList", entities.surfaces[group])
        fields.setNumber(cap, "VIn", 2.0 * np.pi * radius / CYLINDER_SEGMENTS)
        limits.append(cap)
    smallest = fields.add("Min")
    fields.setNumbers(smallest, "FieldsList", limits)
    fields.setAsBackgroundMesh(smallest)
    options = {
        "Mesh.MeshSizeExtendFromBoundary": 0,
        "Mesh.MeshSizeFromPoints": 0,
        "Mesh.MeshSizeFromCurvature": settings.curvature_cells,
        "Mesh.MeshSizeMin": MIN_SIZE_FRACTION * domain.surface_size,
        "Mesh.MeshSizeMax": domain.far_size,
        "Mesh.Algorithm": ALGORITHM_2D,
        "Mesh.Algorithm3D": ALGORITHM_3D,
        "Mesh.Optimize": 1,
    }
    for name, value in options.items():
        gmsh.option.setNumber(name, value)
    return smallest


@dataclass
class SurfaceRefinement:
    """What :func:`mesh_surfaces` did: rounds of local refinement and the crossing triangles each
    found."""

    rounds: int = 0
    crossing_triangles: list[int] = field(default_factory=list)
    smallest_size_mm: float = 0.0


def mesh_surfaces(
    gmsh: Any, domain: Domain, entities: DomainEntities, background: int
) -> SurfaceRefinement:
    """The 2D mesh of every surface, free of crossing triangles.

    Where triangles cross (a coarse mesh across a trailing edge thinner than its triangles), a
    ball of ``REFINE_RADIUS_EDGES`` of their longest edge around each gets elements of
    ``REFINE_FACTOR`` of that edge, and the surfaces holding them are meshed again, up to
    ``REFINE_ROUNDS`` times. KernelError naming the settings that help if crossings remain.
    """
    from torus_cad.cfd_domain.surface_check import find_crossings

    surfaces = sorted({tag for tags in entities.surfaces.values() for tag in tags})
    result = SurfaceRefinement(smallest_size_mm=MIN_SIZE_FRACTION * domain.surface_size)
    with gmsh_step("surface mesh"):
        gmsh.model.mesh.generate(2)
    balls: list[int] = []
    while True:
        crossings = find_crossings(gmsh, surfaces)
        result.crossing_triangles.append(len(crossings))
        if not len(crossings):
            return result
        if result.rounds == REFINE_ROUNDS:
            break
        result.rounds += 1
        sizes = REFINE_FACTOR * crossings.edge_mm
        balls += [
            _ball(gmsh, centre, REFINE_RADIUS_EDGES * edge, size)
            for centre, edge, size in zip(crossings.centres_mm, crossings.edge_mm, sizes)
        ]
        combined = gmsh.model.mesh.field.add("Min")
        gmsh.model.mesh.field.setNumbers(combined, "FieldsList", [background, *balls])
        gmsh.model.mesh.field.setAsBackgroundMesh(combined)
        result.smallest_size_mm = min(result.smallest_size_mm, float(sizes.min()))
        gmsh.option.setNumber("Mesh.MeshSizeMin", result.smallest_size_mm)
        with gmsh_step("surface mesh (refined where triangles crossed)"):
            gmsh.model.mesh.clear([(2, tag) for tag in crossings.surfaces])
            gmsh.model.mesh.generate(2)
    centre = crossings.centres_mm[0]
    raise KernelError(
        "gmsh's surface mesh still crosses itself near "
        f"({centre[0]:.2f}, {centre[1]:.2f}, {centre[2]:.2f}) mm "
        f"({len(crossings)} triangles) after {REFINE_ROUNDS} local "
        "refinements; the volume mesh would fail. "
        f"{CROSSING_ADVICE}"
    )


def _ball(gmsh: Any, centre: np.ndarray, radius: float, size: float) -> int:
    """A gmsh Ball field: ``size`` (mm) within ``radius`` (mm) of ``centre``, no limit outside."""
    ball = gmsh.model.mesh.field.add("Ball")
    for key, value in (
        ("XCenter", centre[0]),
        ("YCenter", centre[1]),
        ("ZCenter", centre[2]),
        ("Radius", radius),
        ("VIn", size),
        ("VOut", 1e22),
    ):
        gmsh.model.mesh.field.setNumber(ball, key, float(value))
    return int(ball)


def add_groups(gmsh: Any, entities: DomainEntities) -> None:
    for name in SURFACE_GROUPS:
        gmsh.model.addPhysicalGroup(2, entities.surfaces[name], name=name)
    for name in VOLUME_GROUPS:
        gmsh.model.addPhysicalGroup(3, entities.volumes[name], name=name)


def tetrahedra_volume(nodes: np.ndarray, tets: np.ndarray) -> float:
    """Total volume (mm^3) of ``(k, 4)`` tetrahedra over ``(n, 3)`` nodes (0-based)."""
    a, b, c, d = (nodes[tets[:, i]] for i in range(4))
    return float(np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))).sum() / 6.0)


def mesh_statistics(gmsh: Any, entities: DomainEntities) -> dict[str, Any]:
    """Element counts per group, worst and mean SICN, meshed volume per volume group."""
    node_tags, coordinates, _ = gmsh.model.mesh.getNodes()
    nodes = np.zeros((int(node_tags.max()) + 1, 3))
    nodes[node_tags.astype(np.int64)] = coordinates.reshape(-1, 3)
    tetrahedra, volumes, all_tags = {}, {}, []
    for name, tags in entities.volumes.items():
        count, volume = 0, 0.0
        for tag in tags:
            element_tags, element_nodes = gmsh.model.mesh.getElementsByType(4, tag)
            tets = element_nodes.astype(np.int64).reshape(-1, 4)
            count += len(tets)
            volume += tetrahedra_volume(nodes, tets)
            all_tags.append(element_tags)
        tetrahedra[name], volumes[name] = count, volume
    triangles = {
        name: sum(len(gmsh.model.mesh.getElementsByType(2, tag)[0]) for tag in tags)
        for name, tags in entities.surfaces.items()
    }
    quality = gmsh.model.mesh.getElementQualities(np.concatenate(all_tags), "minSICN")
    return {
        "nodes": len(node_tags),
        "tetrahedra": tetrahedra,
        "tetrahedra_total": sum(tetrahedra.values()),
        "triangles": triangles,
        "sicn_min": float(quality.min()),
        "sicn_mean": float(quality.mean()),
        "sicn_below_0_1": int(np.sum(quality < 0.1)),
        "meshed_volume_mm3": volumes,
    }


def write_msh(gmsh: Any, path: Path, version: float) -> Path:
    """Write the mesh to ``path`` (a ``.msh`` name: gmsh picks the format from the suffix) as .msh
    ``version`` (2.2 or 4.1), ASCII, physical groups only; return ``path``.

    gmsh does not report a failed write (a full disk, a file size limit); the file is checked to
    end with its last section, and OSError names the cause otherwise.
    """
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    try:
        gmsh.write(str(path))
    except Exception as error:  # gmsh raises plain Exception with its last error message
        raise OSError(errno.EIO, f"gmsh could not write it ({error})", str(path)) from None
    if not file_ends_with(path, MSH_LAST_LINE, tail=64):
        raise write_failure(path)
    return path


#: The last line of an ASCII .msh file (2.2 and 4.1).
MSH_LAST_LINE = b"$EndElements"


@dataclass(frozen=True)
class PropellerBody:
    """What the fluid domain starts from: a propeller solid whose spin axis is +z through the origin
    (mm).

    Attributes:
        solid: the one valid solid (a cadquery Shape).
        name: names the files (``<name>_cfd.*``) and the STEP product.
        tip_diameter_mm: D, twice the largest distance of the solid from the axis.
        chord_mm: the smallest chord, which sets the element size on the propeller (``chord /
            cells_per_chord``).
        trailing_edges: lines for the trailing-edge size field (used when curvature sizing is off),
            or None.
        blades: the blade count for the report, or None if unknown.
        step_schema: the protocol of the STEP the domain writes.
    """

    solid: Any
    name: str
    tip_diameter_mm: float
    chord_mm: float
    trailing_edges: TrailingEdges | None = None
    blades: int | None = None
    step_schema: StepSchema = StepSchema.AP214


def design_body(params: PropellerParameters) -> PropellerBody:
    """The built B-rep of ``params`` as a :class:`PropellerBody` (the analytic tip radius and
    smallest chord)."""
    from torus_cad.cfd_domain.sizes import smallest_chord, tip_radius
    from torus_cad.propeller import build_propeller

    edges = trailing_edges(params) if params.cfd.curvature_cells == 0.0 else None
    return PropellerBody(
        build_propeller(params).solid,
        params.name,
        2.0 * tip_radius(params),
        smallest_chord(params),
        edges,
        params.blades,
        params.export.step_schema,
    )


def write_cfd_domain(
    params: PropellerParameters,
    out_dir: str | Path,
    threads: int = GMSH_REPRODUCIBLE_THREADS,
    progress: Callable[[str], None] | None = None,
    estimate: CfdEstimate | None = None,
) -> tuple[dict[str, Any], dict[str, Path]]:
    """Build the B-rep of ``params`` and mesh its domain (:func:`write_body_domain` with
    ``params.cfd``); ``estimate``: the budget's, if already checked (else checked here: BudgetError
    over the element budget).

    Raises MissingExtraError without gmsh or meshlib, BudgetError over the element budget,
    ParameterError / GeometryError for bad input (nothing written), KernelError naming the step when
    OpenCascade or gmsh fails, OutputError naming the file when it cannot be written.
    """
    from torus_cad.design.design_targets import resolve_design_targets
    from torus_cad.kernel.mesh_check import import_meshlib

    import_gmsh()
    import_meshlib()
    # the domain's sizes from the propeller as built: diameter and pitch met (else D is the control
    # points')
    params = resolve_design_targets(params).parameters
    estimate = check_cfd_budget(params) if estimate is None else estimate
    timer = StageTimer[CfdStage](progress)
    started = time.process_time(), time.perf_counter()
    with timer.stage(CfdStage.BREP):
        body = design_body(params)
    return write_body_domain(body, params.cfd, out_dir, threads, estimate, timer, started)


def write_body_domain(
    body: PropellerBody,
    settings: Cfd,
    out_dir: str | Path,
    threads: int = GMSH_REPRODUCIBLE_THREADS,
    estimate: CfdEstimate | None = None,
    timer: StageTimer[CfdStage] | None = None,
    started: tuple[float, float] | None = None,
) -> tuple[dict[str, Any], dict[str, Path]]:
    """The domain of ``settings`` around ``body`` and its mesh (gmsh with ``threads`` threads, 0 =
    one per CPU; one thread gives the same mesh on every run, see
    :data:`torus_cad.tolerances.GMSH_REPRODUCIBLE_THREADS`); publish ``<name>_cfd.step``,
    ``<name>_cfd.msh``, ``<name>_cfd_v2.msh``, ``README.txt`` and the sealed report
    ``<name>_cfd.json`` as one output set (torus_cad.outputs.output_set). ``estimate`` (if any) goes
    into the report; ``timer`` times the stages (and reports them to its progress callback);
    ``started``: the CPU and wall clock (time.process_time, time.perf_counter) the report's seconds
    count from (default: now). Returns the report as written and the final paths (the report last).
    """
    from torus_cad import __version__
    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.outputs.output_set import OutputSet

    if (
        isinstance(threads, bool)
        or not isinstance(threads, int)
        or not 0 <= threads <= max_cfd_threads()
    ):
        raise ParameterError(
            f"threads = {threads!r} is out of range; allowed "
            f"[0, {max_cfd_threads()}] (0 = one per CPU)"
        )
    gmsh = import_gmsh()
    timer = timer if timer is not None else StageTimer[CfdStage](None)
    name = f"{body.name}_cfd"
    cpu_start, wall_start = (
        started if started is not None else (time.process_time(), time.perf_counter())
    )
    with OutputSet(out_dir, name) as output:
        with gmsh_session(gmsh, threads):
            with timer.stage(CfdStage.DOMAIN):
                box = body.solid.BoundingBox()
                domain = domain_from_sizes(
                    body.tip_diameter_mm, body.chord_mm, settings, (box.zmin, box.zmax)
                )
                # gmsh's input, not the design's file (build checks that one): a user's own STEP
                # solid (simulate --step) is meshed as it comes, without a read-back check of its
                # copy.
                step = output.write(
                    "step",
                    lambda path: write_step(
                        body.solid,
                        path,
                        body.name,
                        body.step_schema,
                        program=f"torus_cad {__version__}",
                        check_readback=False,
                    ),
                )
                propeller_volume = precise_volume(body.solid)
                entities = build_domain(gmsh, step, domain)
                edges = body.trailing_edges if settings.curvature_cells == 0.0 else None
                background = set_sizes(gmsh, domain, settings, entities, edges)
                add_groups(gmsh, entities)
            with timer.stage(CfdStage.SURFACE_MESH):
                refinement = mesh_surfaces(gmsh, domain, entities, background)
            with timer.stage(CfdStage.VOLUME_MESH):
                mesh_volumes(gmsh)
            statistics = mesh_statistics(gmsh, entities)
            with timer.stage(CfdStage.WRITE):
                output.write("msh", lambda path: write_msh(gmsh, path, 4.1))
                output.write_files(
                    lambda folder: {"msh_v2": write_msh(gmsh, folder / f"{name}_v2.msh", 2.2)}
                )
                gmsh_version = gmsh.__version__
        expected = {
            "rotating_zone": domain.zone_volume - propeller_volume,
            "fluid": domain.outer_volume - domain.zone_volume,
        }
        meshed = statistics["meshed_volume_mm3"]
        report: dict[str, Any] = {
            "name": body.name,
            "blades": body.blades,
            "gmsh_version": gmsh_version,
            "threads": threads,
            "settings": settings.model_dump(mode="json"),
            "domain_mm": {
                **asdict(domain),
                "outer_volume_mm3": domain.outer_volume,
                "zone_volume_mm3": domain.zone_volume,
            },
            "propeller_volume_mm3": propeller_volume,
            "physical_groups": {"surfaces": list(SURFACE_GROUPS), "volumes": list(VOLUME_GROUPS)},
            "estimate": asdict(estimate) if estimate is not None else None,
            "surface_refinement": asdict(refinement),
            **statistics,
            "expected_volume_mm3": expected,
            "volume_relative_difference": {
                key: meshed[key] / expected[key] - 1.0 for key in expected
            },
            "fluid_total_relative_difference": sum(meshed.values()) / sum(expected.values()) - 1.0,
            "stage_seconds": timer.seconds,
            "wall_seconds": time.perf_counter() - wall_start,
            "cpu_seconds": time.process_time() - cpu_start,
        }
        output.write_files(
            lambda folder: {
                "readme": _write_text(folder / "README.txt", readme_text(body.name, report))
            }
        )
        paths = output.publish(report)
        return output.sealed_report, paths


def _write_text(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def mesh_volumes(gmsh: Any) -> None:
    """The tetrahedra; a gmsh stop becomes a KernelError that says which settings help."""
    try:
        gmsh.model.mesh.generate(3)
    except Exception as error:  # gmsh raises plain Exception with its last error message
        raise KernelError(
            f"gmsh failed at step 'volume mesh': {error}. {CROSSING_ADVICE}"
        ) from None


def summary_line(report: dict[str, Any]) -> str:
    """One terminal line: element counts, worst SICN, volume check, time."""
    tets = report["tetrahedra"]
    return (
        f"cfd: {report['tetrahedra_total']:,} tetrahedra "
        f"(rotating_zone {tets['rotating_zone']:,}, fluid "
        f"{tets['fluid']:,}), {report['triangles']['propeller']:,}"
        " triangles on the propeller; worst SICN "
        f"{report['sicn_min']:.3f}; fluid volume "
        f"{report['fluid_total_relative_difference']:+.3%} of the "
        f"domain minus the propeller; {report['wall_seconds']:.1f} s"
    )
