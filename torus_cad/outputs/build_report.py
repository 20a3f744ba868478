"""The build's JSON report (``<name>.json``): parameters, mass properties, balance, printability,
the checks the solid and its meshes passed, and the stage times.

It reads a built propeller through :class:`BuiltPropeller`, the attributes of
:class:`torus_cad.propeller.Propeller` it needs, so that the writers of the output set
(torus_cad.outputs.output_set) and the pipeline that builds the propeller do not import each other.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol

from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.kernel.mass_properties import balance

if TYPE_CHECKING:
    from OCP.TopoDS import TopoDS_Shape

    from torus_cad.design.design_targets import DesignTargets
    from torus_cad.geometry.analysis.printability import Printability
    from torus_cad.geometry.blade.blade_surface import BladeSurface
    from torus_cad.geometry.hub.mounting import HubMounting
    from torus_cad.kernel.fillet.root_fillet import RootFillet
    from torus_cad.kernel.fuse import FuseRoute
    from torus_cad.kernel.mass_properties import MassProperties
    from torus_cad.kernel.strict import StrictCheck
    from torus_cad.kernel.wires import SectionCurves
    from torus_cad.parameters import PropellerParameters


class BuiltPropeller(Protocol):
    """What the report and the output set read of a built propeller
    (:class:`torus_cad.propeller.Propeller`)."""

    parameters: PropellerParameters
    shape: TopoDS_Shape
    surface: BladeSurface
    section_curves: SectionCurves
    stage_seconds: dict[str, float]
    fuse_route: FuseRoute
    design_targets: DesignTargets | None
    mounting: HubMounting
    root_fillet: RootFillet | None
    checks: StrictCheck | None

    def mass_properties(self, density_g_cm3: float = ...) -> MassProperties: ...

    def printability(self) -> Printability: ...

    def spin_to_push_air_down(self) -> Handedness: ...


def build_report(
    propeller: BuiltPropeller,
    density_g_cm3: float,
    meshes: Mapping[str, dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """The JSON report: parameters, mass properties, balance, printability, validity and stage
    times.

    ``checks`` names every check the solid (and each written mesh, ``meshes``: {"stl" or "3mf":
    :meth:`torus_cad.kernel.mesh_check.MeshCheck.to_dict`}) passed."""
    properties = propeller.mass_properties(density_g_cm3)
    checks: dict[str, Any] = {} if propeller.checks is None else propeller.checks.to_dict()
    for kind, mesh in (meshes or {}).items():
        checks[f"{kind}_self_intersections"] = mesh["self_intersecting_pairs"] == 0
    return {
        "name": propeller.parameters.name,
        "parameters": propeller.parameters.to_dict(),
        "valid": True,
        "solids": 1,
        "checks": checks,
        **{f"{kind}_mesh": mesh for kind, mesh in (meshes or {}).items()},
        **properties.to_dict(),
        "balance": balance(propeller.shape, density_g_cm3).to_dict(),
        "printability": propeller.printability().to_dict(),
        "handedness": propeller.parameters.handedness.value,
        "spin_to_push_air_down": propeller.spin_to_push_air_down().value,
        "set_screw_angle_deg": _set_screw_angle_on_the_part_deg(propeller),
        "section_fit_error_mm": propeller.section_curves.fit_error,
        "stage_seconds": dict(propeller.stage_seconds),
        "fuse_route": propeller.fuse_route.value,
        "kind": propeller.parameters.kind.value,
        "closed_file_trailing_edge_mm": _closed_file_edge_mm(propeller.parameters),
        "root_fillet": None if propeller.root_fillet is None else propeller.root_fillet.to_dict(),
        **(
            {"design_targets": propeller.design_targets.to_dict()}
            if propeller.design_targets is not None and propeller.design_targets.requested
            else {}
        ),
    }


def _closed_file_edge_mm(params: PropellerParameters) -> tuple[float, float] | None:
    """The coordinate file's trailing edge closed because too thin to mesh (toroidal designs; None
    otherwise)."""
    if params.kind.value != "toroidal":
        return None
    return propeller_geometry(params).blade.closed_file_edge_mm


def _set_screw_angle_on_the_part_deg(propeller: BuiltPropeller) -> float | None:
    """Where the set-screw hole of the part as built points, degrees about +z from +x (None: no set
    screw).

    The mounting is chosen on the spec's (cw) blades; a ccw part is their mirror image through the
    XZ plane, which takes the direction at angle a to -a.
    """
    if not propeller.mounting.set_screw_diameter_mm:
        return None
    angle_deg = propeller.mounting.set_screw_angle_deg
    return (-angle_deg) % 360.0 if propeller.parameters.handedness == Handedness.CCW else angle_deg
