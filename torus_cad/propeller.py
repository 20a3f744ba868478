"""Parameters in, propeller out: the pipeline that joins the geometry layer and the kernel.

This is the package's Python API::

    from torus_cad import PropellerParameters, build_propeller
    propeller = build_propeller(PropellerParameters())     # or build_propeller("design.toml")
    propeller.solid          # cq.Solid, the fused propeller (mm)
    propeller.workplane()    # cq.Workplane holding it, for further CadQuery work
    propeller.hub, propeller.blades
    propeller.write("step_out")  # <name>.step, .stl, .json
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import cadquery as cq

from torus_cad.design_targets import DesignTargets, resolve_design_targets, write_sections_table
from torus_cad.errors import KernelError
from torus_cad.geometry.centerline import Centerline, blade_angle_deg
from torus_cad.geometry.feasibility import check_feasible
from torus_cad.geometry.hub import seam_angle_deg
from torus_cad.geometry.parameters import PropellerParameters, resolve_parameters
from torus_cad.geometry.surface import BladeSurface, blade_surface
from torus_cad.kernel.checks import MassProperties, mass_properties, precise_volume, single_valid_solid
from torus_cad.kernel.export import atomic_path, write_step, write_stl
from torus_cad.kernel.fuse import JOINS, fuse_all, fuse_pattern, pattern_blades
from torus_cad.kernel.hub import hub_solid
from torus_cad.kernel.loft import loft_solid
from torus_cad.kernel.wires import SectionCurves, fit_section_curves
from torus_cad.tolerances import VOLUME_CHECK_RELATIVE_PRECISION

#: The ways the blades are joined to the hub (see torus_cad.kernel.fuse): one blade-hub
#: intersection shared by all blades, then the shell assembled or the parts glued; or, as
#: the fallback, one general fuse of the hub and all blades.
FUSE_ROUTES = (*(f"shared intersection, {join}" for join in JOINS), "one fuse")

#: Default density for mass: PLA, a common printing plastic (g/cm^3).
DEFAULT_DENSITY_G_CM3 = 1.24


class StageTimer:
    """Wall-clock seconds per named stage, in the order the stages ran."""

    def __init__(self, on_start: Callable[[str], None] | None = None) -> None:
        self.seconds: dict[str, float] = {}
        self.on_start = on_start  # called with each stage's name as it starts (progress display)

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        if self.on_start is not None:
            self.on_start(name)
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - start


@dataclass
class Propeller:
    """A built propeller: the fused solid, its parts and how long each stage took.

    Attributes:
        parameters: the design.
        solid: the fused propeller, one valid closed solid (mm).
        hub: the hub cylinder alone.
        blades: every blade alone, blade i at theta_0 + 360 i / n.
        surface: blade 0's sampled surface from the geometry layer.
        section_curves: blade 0's section B-splines (plain arrays).
        stage_seconds: seconds per stage (section math, wires, loft, fuse, check, ...).
        fuse_route: how the blades were joined to the hub, one of FUSE_ROUTES: one
            blade-hub intersection reused for every blade (the usual route), or
            ``"one fuse"``, a general boolean of the hub and all blades (the fallback).
        design_targets: what the designer's inputs (airfoil.naca, diameter, pitch) resolved to;
            ``parameters`` are already the resolved spec parameters.
    """

    parameters: PropellerParameters
    solid: cq.Solid
    hub: cq.Solid
    blades: list[cq.Solid]
    surface: BladeSurface
    section_curves: SectionCurves
    stage_seconds: dict[str, float] = field(default_factory=dict)
    fuse_route: str = FUSE_ROUTES[0]
    design_targets: DesignTargets | None = None

    def workplane(self) -> cq.Workplane:
        """A cq.Workplane holding the fused solid."""
        return cq.Workplane("XY").add(self.solid)

    def mass_properties(self, density_g_cm3: float = DEFAULT_DENSITY_G_CM3) -> MassProperties:
        """Volume, area, centroid, spin-axis inertia and mass (OpenCascade, adaptive precision)."""
        return mass_properties(self.solid, density_g_cm3)

    def write(self, out_dir: str | Path, density_g_cm3: float = DEFAULT_DENSITY_G_CM3,
              stl: bool = True) -> dict[str, Path]:
        """Write ``<name>.step``, ``<name>.stl`` (unless ``stl`` is False) and ``<name>.json`` into ``out_dir``."""
        return write_outputs(self, Path(out_dir), density_g_cm3, stl)


def _section_chords(surface: BladeSurface) -> np.ndarray:
    trailing_edge = surface.trailing_edge_index or 0
    return np.linalg.norm(surface.points[:, trailing_edge] - surface.points[:, 0], axis=-1)


def build_propeller(design: PropellerParameters | str | Path | None = None,
                    progress: Callable[[str], None] | None = None) -> Propeller:
    """Build the fused propeller of ``design`` (parameters, a TOML path, or None for the default).

    ``progress``, if given, is called with each stage's name (``section_math``, ``wires``,
    ``loft``, ``fuse``, ``check``, ...) as the stage starts.

    Raises ParameterError for bad parameters, GeometryError for designs that cannot make a
    sound propeller (refused before the kernel runs), KernelError when OpenCascade fails.
    """
    timer = StageTimer(progress)
    with timer.stage("parameters"):
        params = resolve_parameters(design)
    with timer.stage("design_targets"):
        targets = resolve_design_targets(params)  # airfoil.naca, diameter, pitch -> the spec's parameters
        params = targets.parameters
    with timer.stage("section_math"):
        surface = blade_surface(params)
        check_feasible(params, surface, Centerline.for_blade(params))
        # The hub is symmetric about its axis; its seam goes where it crosses no blade root.
        seam_deg = seam_angle_deg(surface.points, params.hub.radius, params.blades)
    with timer.stage("wires"):
        curves = fit_section_curves(surface.points, surface.trailing_edge_index, _section_chords(surface),
                                    surface.lower_corner_index)
        wires = curves.wires()
    with timer.stage("loft"):
        blade = loft_solid(wires, surface.s)
        hub = hub_solid(params.hub.radius, params.hub.length, 0.0 if seam_deg is None else seam_deg)
        angles_deg = [blade_angle_deg(params, i) for i in range(params.blades)]
        blades = pattern_blades(blade, angles_deg)
    solid, route = _join_blades_to_hub(hub, blade, blades, angles_deg, timer)
    return Propeller(params, solid, hub, blades, surface, curves, timer.seconds, route, targets)


def _join_blades_to_hub(hub: cq.Solid, blade: cq.Solid, blades: list[cq.Solid], angles_deg: list[float],
                        timer: StageTimer) -> tuple[cq.Solid, str]:
    """The fused, checked propeller and the route that made it (one of FUSE_ROUTES).

    The shared-intersection route's result is checked for validity, which includes every
    edge's curve on the hub against its 3D curve. Where that route fails, one general fuse
    is used and its volume is checked as well.
    """
    try:
        with timer.stage("fuse"):
            fused, join = fuse_pattern(hub, blade, angles_deg)
        with timer.stage("check"):
            return single_valid_solid(fused, "joining the blades to the hub"), FUSE_ROUTES[JOINS.index(join)]
    except KernelError:
        pass  # the general fuse below decides
    with timer.stage("fuse"):
        fused = fuse_all(hub, blades)
    with timer.stage("check"):
        solid = single_valid_solid(fused, "fusing the blades with the hub")
        _check_volume(solid, hub, blade, len(blades))
    return solid, FUSE_ROUTES[-1]


def _check_volume(solid: cq.Solid, hub: cq.Solid, blade: cq.Solid, blades: int) -> None:
    """hub < fused <= hub + n x blade: a fuse that lost or doubled material is an error."""
    volume, hub_volume, blade_volume = (precise_volume(shape, VOLUME_CHECK_RELATIVE_PRECISION)
                                        for shape in (solid, hub, blade))
    if not hub_volume < volume <= (hub_volume + blades * blade_volume) * (1 + 10 * VOLUME_CHECK_RELATIVE_PRECISION):
        raise KernelError(f"the fused volume {volume:.3f} mm^3 is outside (hub {hub_volume:.3f}, "
                          f"hub + {blades} blades {hub_volume + blades * blade_volume:.3f}] mm^3")


def build_report(propeller: Propeller, density_g_cm3: float) -> dict:
    """The JSON report: parameters, mass properties, validity and stage times."""
    properties = propeller.mass_properties(density_g_cm3)
    return {
        "name": propeller.parameters.name,
        "parameters": propeller.parameters.to_dict(),
        "valid": True,
        "solids": 1,
        **properties.to_dict(),
        "section_fit_error_mm": propeller.section_curves.fit_error,
        "stage_seconds": dict(propeller.stage_seconds),
        "fuse_route": propeller.fuse_route,
        **({"design_targets": propeller.design_targets.to_dict()}
           if propeller.design_targets is not None and propeller.design_targets.requested else {}),
    }


def write_outputs(propeller: Propeller, out_dir: Path, density_g_cm3: float = DEFAULT_DENSITY_G_CM3,
                  stl: bool = True) -> dict[str, Path]:
    """Write STEP, STL and the JSON report atomically; return the paths by kind."""
    params = propeller.parameters
    timer = StageTimer()
    paths: dict[str, Path] = {}
    with timer.stage("step_write"):
        paths["step"] = write_step(propeller.solid, out_dir / f"{params.name}.step", params.name,
                                   params.export.step_schema)
    if stl:
        with timer.stage("stl_write"):
            paths["stl"] = write_stl(propeller.solid, out_dir / f"{params.name}.stl",
                                     params.export.stl_linear_deflection, params.export.stl_angular_deflection)
    with timer.stage("sections_table"):
        paths.update(write_sections_table(propeller.parameters, out_dir))
    propeller.stage_seconds.update(timer.seconds)
    report = build_report(propeller, density_g_cm3)
    paths["json"] = out_dir / f"{params.name}.json"
    with atomic_path(paths["json"]) as temp:
        temp.write_text(json.dumps(report, indent=2) + "\n")
    return paths
