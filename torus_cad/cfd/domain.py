"""The fluid domain around the propeller and its tetrahedral mesh, with gmsh (the ``cfd`` extra).

From the B-rep (written as STEP and imported by gmsh's OpenCascade kernel): an outer cylinder
along the spin axis, an inner rotating-zone cylinder enclosing the propeller, and the
propeller itself are fragmented together (so the zone's boundary is one conformal interface
shared by both regions), the propeller's volume is removed (its faces stay, as the wall),
and the fluid is meshed with tetrahedra: ``cells_per_chord`` elements across the smallest
chord on the propeller, finer where the surface curves (gmsh's curvature sizing), growing by
``growth_rate`` per element away from the propeller up to ``far_size``.

Physical groups (what solvers see as patches and zones):
``propeller`` (wall), ``rotating_interface`` (between the zones), ``inlet``, ``outlet``,
``farfield`` (the outer lateral surface); volumes ``rotating_zone`` and ``fluid`` (the
stationary outer region).
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.cfd.readme import readme_text
from torus_cad.cfd.settings import MissingExtraError
from torus_cad.errors import KernelError, ParameterError
from torus_cad.geometry.propeller import PropellerGeometry
from torus_cad.geometry.transforms import evaluate_quartic
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Cfd, InletSide
from torus_cad.stages import StageTimer

#: Names of the physical groups: surfaces, then volumes.
SURFACE_GROUPS = ("propeller", "rotating_interface", "inlet", "outlet", "farfield")
VOLUME_GROUPS = ("rotating_zone", "fluid")

#: Samples per parametric direction of each propeller face for gmsh's distance field.
DISTANCE_SAMPLING = 60
#: Elements around the rotating zone's and the outer cylinder's circumference, at least.
CYLINDER_SEGMENTS = 64
#: Smallest element allowed, as a fraction of the surface size (bounds curvature refinement).
MIN_SIZE_FRACTION = 0.1
#: gmsh algorithms: 2D Frontal-Delaunay (gmsh falls back to MeshAdapt per face), 3D Delaunay.
ALGORITHM_2D, ALGORITHM_3D = 6, 1


def import_gmsh() -> Any:
    """The gmsh module, or MissingExtraError naming the extra (and the system libraries it needs)."""
    try:
        import gmsh
    except ImportError:
        raise MissingExtraError("gmsh is not installed: install the cfd extra, pip install 'torus_cad[cfd]'") from None
    except OSError as error:
        raise MissingExtraError(f"gmsh's library does not load ({error}); install the cfd extra "
                                "(pip install 'torus_cad[cfd]') and the system libraries it links, on Debian: "
                                "apt-get install libglu1-mesa libxcursor1 libxft2 libxinerama1 libgl1") from None
    return gmsh


@dataclass(frozen=True)
class Domain:
    """Sizes of the fluid domain and its mesh, mm (z along the spin axis).

    Attributes:
        tip_diameter: D, twice the largest distance of the blade surface from the axis.
        propeller_z: (low, high) axial extent of the propeller.
        outer_radius, outer_z: the outer cylinder; inlet at one end of ``outer_z``, outlet at the other.
        zone_radius, zone_z: the rotating-zone cylinder.
        inlet_z, outlet_z: axial positions of the inlet and outlet caps.
        surface_size: element size on the propeller (smallest chord / cells_per_chord).
        far_size: the largest element.
    """

    tip_diameter: float
    propeller_z: tuple[float, float]
    outer_radius: float
    outer_z: tuple[float, float]
    zone_radius: float
    zone_z: tuple[float, float]
    inlet_z: float
    outlet_z: float
    surface_size: float
    far_size: float

    @property
    def outer_volume(self) -> float:
        """Volume of the outer cylinder (the whole domain before the propeller is removed), mm^3."""
        return float(np.pi * self.outer_radius**2 * (self.outer_z[1] - self.outer_z[0]))

    @property
    def zone_volume(self) -> float:
        """Volume of the rotating-zone cylinder, mm^3."""
        return float(np.pi * self.zone_radius**2 * (self.zone_z[1] - self.zone_z[0]))


#: Grid on which the analytic blade is sampled for the tip radius.
TIP_RADIUS_GRID = (201, 200)


class CfdStage(StrEnum):
    """Stages of ``torus-cad cfd``; the value is the key in the report's ``stage_seconds``."""

    BREP = "brep"
    DOMAIN = "domain"
    SURFACE_MESH = "surface_mesh"
    VOLUME_MESH = "volume_mesh"
    WRITE = "write"


def tip_radius(geometry: PropellerGeometry) -> float:
    """Largest distance of the blade surface from the spin axis, mm (analytic surface, sampled densely)."""
    from torus_cad.geometry.surface import blade_surface

    points = blade_surface(geometry.blade, geometry.centerline(0), *TIP_RADIUS_GRID).points
    return float(max(np.hypot(points[..., 0], points[..., 1]).max(), geometry.hub.radius_mm))


def smallest_chord(geometry: PropellerGeometry) -> float:
    """Smallest chord Sx(s) over the blade, mm."""
    return float(evaluate_quartic(geometry.blade.laws.scale_x_mm, np.linspace(0.0, 1.0, 201)).min())


def domain_for(geometry: PropellerGeometry, settings: Cfd, propeller_z: tuple[float, float]) -> Domain:
    """The domain's sizes for a propeller spanning ``propeller_z`` (mm) axially."""
    diameter = 2.0 * tip_radius(geometry)
    centre = 0.5 * (propeller_z[0] + propeller_z[1])
    clearance = settings.zone_clearance * diameter
    zone_z = (propeller_z[0] - clearance, propeller_z[1] + clearance)
    upstream, downstream = settings.upstream * diameter, settings.downstream * diameter
    if settings.inlet_side == InletSide.PLUS_Z:
        inlet_z, outlet_z = centre + upstream, centre - downstream
    else:
        inlet_z, outlet_z = centre - upstream, centre + downstream
    outer_z = (min(inlet_z, outlet_z), max(inlet_z, outlet_z))
    if outer_z[0] >= zone_z[0] - clearance or outer_z[1] <= zone_z[1] + clearance:
        raise ParameterError(
            f"cfd.upstream = {settings.upstream:g} / cfd.downstream = {settings.downstream:g} put an end of the domain "
            f"inside the rotating zone (it spans z = {zone_z[0]:.1f} .. {zone_z[1]:.1f} mm, D = {diameter:.1f} mm); "
            "make them larger")
    return Domain(tip_diameter=diameter, propeller_z=propeller_z, outer_radius=settings.domain_radius * diameter,
                  outer_z=outer_z, zone_radius=settings.zone_radius * diameter, zone_z=zone_z, inlet_z=inlet_z,
                  outlet_z=outlet_z, surface_size=smallest_chord(geometry) / settings.cells_per_chord,
                  far_size=settings.far_size * diameter)


@contextmanager
def gmsh_session(gmsh: Any, threads: int) -> Iterator[None]:
    """gmsh initialised quietly for one model; finalised afterwards (unless the caller had it running)."""
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=threading.current_thread() is threading.main_thread())
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
    """Import the propeller, add the two cylinders, fragment, drop the propeller's volume, find the groups."""
    occ = gmsh.model.occ
    with gmsh_step("import the propeller STEP"):
        imported = occ.importShapes(str(step_path))
        solids = [tag for dim, tag in imported if dim == 3]
        if len(solids) != 1:
            raise KernelError(f"gmsh failed at step 'import the propeller STEP': expected one solid, got {len(solids)}")
    with gmsh_step("fragment the domain"):
        zone = occ.addCylinder(0, 0, domain.zone_z[0], 0, 0, domain.zone_z[1] - domain.zone_z[0], domain.zone_radius)
        outer = occ.addCylinder(0, 0, domain.outer_z[0], 0, 0, domain.outer_z[1] - domain.outer_z[0],
                                domain.outer_radius)
        _, pieces = occ.fragment([(3, outer)], [(3, zone), (3, solids[0])])
        occ.synchronize()
        propeller = {tag for _, tag in pieces[2]}
        rotating = {tag for _, tag in pieces[1]} - propeller
        fluid = {tag for _, tag in pieces[0]} - rotating - propeller
        if not (propeller and rotating and fluid):
            raise KernelError("gmsh failed at step 'fragment the domain': the propeller, rotating zone and outer "
                              "region did not come out as separate volumes")
        wall = _boundary(gmsh, propeller)
        occ.remove([(3, tag) for tag in sorted(propeller)])
        occ.synchronize()
    zone_faces, fluid_faces = _boundary(gmsh, rotating), _boundary(gmsh, fluid)
    interface = zone_faces & fluid_faces
    surfaces = {"propeller": sorted(wall), "rotating_interface": sorted(interface),
                "inlet": [], "outlet": [], "farfield": []}
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
        raise KernelError(f"gmsh failed at step 'find the boundaries': no faces for {', '.join(empty)}")
    return DomainEntities(surfaces, {"rotating_zone": sorted(rotating), "fluid": sorted(fluid)})


def _boundary(gmsh: Any, volumes: set[int]) -> set[int]:
    faces = gmsh.model.getBoundary([(3, tag) for tag in sorted(volumes)], combined=False, oriented=False)
    return {abs(tag) for _, tag in faces}


def set_sizes(gmsh: Any, domain: Domain, settings: Cfd, entities: DomainEntities) -> None:
    """Element sizes: ``surface_size`` on the propeller growing linearly with the distance from it
    (neighbours differ by about ``growth_rate``), capped at ``far_size``; on the two cylinders at most
    1/CYLINDER_SEGMENTS of their circumference (so their facets keep the volumes within ~0.1 %);
    curvature refinement on top."""
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "SurfacesList", entities.surfaces["propeller"])
    field.setNumber(distance, "Sampling", DISTANCE_SAMPLING)
    growth = field.add("MathEval")
    field.setString(growth, "F", f"Min({domain.far_size!r}, {domain.surface_size!r} + "
                                 f"{settings.growth_rate - 1.0!r} * F{distance})")
    limits = [growth]
    for group, radius in (("rotating_interface", domain.zone_radius), ("farfield", domain.outer_radius)):
        cap = field.add("Constant")
        field.setNumbers(cap, "SurfacesList", entities.surfaces[group])
        field.setNumber(cap, "VIn", 2.0 * np.pi * radius / CYLINDER_SEGMENTS)
        limits.append(cap)
    smallest = field.add("Min")
    field.setNumbers(smallest, "FieldsList", limits)
    field.setAsBackgroundMesh(smallest)
    options = {"Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.MeshSizeFromPoints": 0,
               "Mesh.MeshSizeFromCurvature": settings.curvature_cells,
               "Mesh.MeshSizeMin": MIN_SIZE_FRACTION * domain.surface_size, "Mesh.MeshSizeMax": domain.far_size,
               "Mesh.Algorithm": ALGORITHM_2D, "Mesh.Algorithm3D": ALGORITHM_3D, "Mesh.Optimize": 1}
    for name, value in options.items():
        gmsh.option.setNumber(name, value)


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
    triangles = {name: sum(len(gmsh.model.mesh.getElementsByType(2, tag)[0]) for tag in tags)
                 for name, tags in entities.surfaces.items()}
    quality = gmsh.model.mesh.getElementQualities(np.concatenate(all_tags), "minSICN")
    return {"nodes": len(node_tags), "tetrahedra": tetrahedra, "tetrahedra_total": sum(tetrahedra.values()),
            "triangles": triangles, "sicn_min": float(quality.min()), "sicn_mean": float(quality.mean()),
            "sicn_below_0_1": int(np.sum(quality < 0.1)), "meshed_volume_mm3": volumes}


def write_msh(gmsh: Any, path: Path, version: float) -> None:
    """Write the mesh as .msh ``version`` (2.2 or 4.1), ASCII, physical groups only, atomically."""
    from torus_cad.kernel.export import atomic_path

    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    with atomic_path(path) as temp:
        staged = temp.with_name(temp.name + ".msh")  # gmsh picks the format from the suffix
        try:
            with gmsh_step(f"write {path.name}"):
                gmsh.write(str(staged))
            os.replace(staged, temp)
        finally:
            staged.unlink(missing_ok=True)


def write_cfd_domain(params: PropellerParameters, out_dir: str | Path, threads: int = 0,
                     progress: Callable[[str], None] | None = None) -> tuple[dict[str, Any], dict[str, Path]]:
    """Build the B-rep, the domain of ``params.cfd`` and its mesh (gmsh with ``threads`` threads, 0 = one
    per CPU); write STEP, both .msh files, README.txt and ``<name>_cfd.json``. Returns the report and paths.

    Raises MissingExtraError without gmsh, ParameterError / GeometryError for bad input (nothing
    written), KernelError naming the step when OpenCascade or gmsh fails.
    """
    from torus_cad.kernel.checks import precise_volume
    from torus_cad.kernel.export import atomic_path, write_step
    from torus_cad.propeller import build_propeller

    gmsh = import_gmsh()
    settings = params.cfd
    out = Path(out_dir)
    timer = StageTimer[CfdStage](progress)
    cpu_start, wall_start = time.process_time(), time.perf_counter()
    with timer.stage(CfdStage.BREP):
        propeller = build_propeller(params)
        box = propeller.solid.BoundingBox()
        domain = domain_for(params.geometry(), settings, (box.zmin, box.zmax))
        paths = {"step": write_step(propeller.solid, out / f"{params.name}.step", params.name,
                                    params.export.step_schema)}
        propeller_volume = precise_volume(propeller.solid)
    with gmsh_session(gmsh, threads):
        with timer.stage(CfdStage.DOMAIN):
            entities = build_domain(gmsh, paths["step"], domain)
            set_sizes(gmsh, domain, settings, entities)
            add_groups(gmsh, entities)
        with timer.stage(CfdStage.SURFACE_MESH), gmsh_step("surface mesh"):
            gmsh.model.mesh.generate(2)
        with timer.stage(CfdStage.VOLUME_MESH), gmsh_step("volume mesh"):
            gmsh.model.mesh.generate(3)
        statistics = mesh_statistics(gmsh, entities)
        with timer.stage(CfdStage.WRITE):
            paths["msh"] = out / f"{params.name}_cfd.msh"
            write_msh(gmsh, paths["msh"], 4.1)
            paths["msh_v2"] = out / f"{params.name}_cfd_v2.msh"
            write_msh(gmsh, paths["msh_v2"], 2.2)
            gmsh_version = gmsh.__version__
    expected = {"rotating_zone": domain.zone_volume - propeller_volume,
                "fluid": domain.outer_volume - domain.zone_volume}
    meshed = statistics["meshed_volume_mm3"]
    report: dict[str, Any] = {
        "name": params.name, "gmsh_version": gmsh_version, "threads": threads,
        "settings": settings.model_dump(mode="json"),
        "domain_mm": {**asdict(domain), "outer_volume_mm3": domain.outer_volume, "zone_volume_mm3": domain.zone_volume},
        "propeller_volume_mm3": propeller_volume,
        "physical_groups": {"surfaces": list(SURFACE_GROUPS), "volumes": list(VOLUME_GROUPS)},
        **statistics,
        "expected_volume_mm3": expected,
        "volume_relative_difference": {name: meshed[name] / expected[name] - 1.0 for name in expected},
        "fluid_total_relative_difference": sum(meshed.values()) / sum(expected.values()) - 1.0,
        "stage_seconds": timer.seconds,
        "wall_seconds": time.perf_counter() - wall_start, "cpu_seconds": time.process_time() - cpu_start,
    }
    with atomic_path(out / "README.txt") as temp:
        temp.write_text(readme_text(params.name, report))
    paths["readme"] = out / "README.txt"
    report["files"] = {key: path.name for key, path in paths.items()}
    paths["json"] = out / f"{params.name}_cfd.json"
    with atomic_path(paths["json"]) as temp:
        temp.write_text(json.dumps(report, indent=2) + "\n")
    return report, paths


def summary_line(report: dict[str, Any]) -> str:
    """One terminal line: element counts, worst SICN, volume check, time."""
    tets = report["tetrahedra"]
    return (f"cfd: {report['tetrahedra_total']:,} tetrahedra (rotating_zone {tets['rotating_zone']:,}, fluid "
            f"{tets['fluid']:,}), {report['triangles']['propeller']:,} triangles on the propeller; worst SICN "
            f"{report['sicn_min']:.3f}; fluid volume {report['fluid_total_relative_difference']:+.3%} of the "
            f"domain minus the propeller; {report['wall_seconds']:.1f} s")
