"""Parameters in, propeller out: the pipeline that joins the geometry layer and the kernel.

This is the package's Python API::

    from torus_cad import build_propeller
    propeller = build_propeller("design.toml", overrides={"blades": 4})   # or None: the default
    propeller.solid          # cq.Solid, the fused propeller (mm)
    propeller.workplane      # cq.Workplane holding it, for further CadQuery work
    propeller.hub, propeller.blades, propeller.assembly()
    propeller.write("step_out")  # <name>.step, .stl, .json
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from OCP.TopoDS import TopoDS_Shape

from torus_cad.build_stages import Stage
from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.design.described_geometry import (
    wall_printability,
)
from torus_cad.design.design_targets import DesignTargets
from torus_cad.design.prepared_design import prepare_design
from torus_cad.errors import KernelError
from torus_cad.geometry.analysis.printability import Printability
from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.geometry.blade.handedness import Handedness, spin_to_push_air_down
from torus_cad.geometry.hub.mounting import HubMounting
from torus_cad.kernel.fuse import FuseRoute, joined_propeller, pattern_blades
from torus_cad.kernel.hub import hub_shape, run_out_hub
from torus_cad.kernel.loft import loft_solid
from torus_cad.kernel.mass_properties import MassProperties, mass_properties
from torus_cad.kernel.mirror import mirrored
from torus_cad.kernel.strict import StrictCheck, strict_valid_propeller
from torus_cad.kernel.topology import shape_bytes, shape_from_bytes
from torus_cad.kernel.wires import SectionCurves, section_curves
from torus_cad.outputs.output_set import write_output_set
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import TightBends
from torus_cad.runtime.stage_timer import StageTimer

if TYPE_CHECKING:
    import cadquery as cq

    from torus_cad.kernel.fillet.root_fillet import RootFillet

#: Pieces the blade's airfoil face is split into (in equal ranges of its section curves' parameter)
#: for the root fillet when the trailing edge is round (torus_cad.kernel.wires): the airfoil face is
#: then open, so the fillet's split of closed side faces does not apply. Fifths (split points at 20,
#: 40, 60, 80 % of the way from the lower to the upper end, none at the leading edge, near 50 %)
#: fillet round edges that fewer pieces do not (measured: the docs' measurements page).
ROUND_EDGE_FILLET_PIECES = 5


#: Default density for mass: PLA, a common printing plastic (g/cm^3).
DEFAULT_DENSITY_G_CM3 = 1.24


@dataclass
class Propeller:
    """A built propeller: the fused solid, its parts, and how it was made (mm; spin axis = z).

    The solid and its parts are OpenCascade's shapes (``shape``, ``hub_shape``, ``blade_shapes``);
    ``solid``, ``hub`` and ``blades`` give them as cadquery's, loading cadquery when first asked for
    (``torus-cad build`` never does: importing cadquery costs over a second of its start).

    Attributes:
        parameters: the design.
        shape: the fused propeller, one valid closed solid (OpenCascade's ``TopoDS_Shape``).
        hub_shape: the hub cylinder alone (radius R, length L, centred at the origin), before the
            fuse.
        blade_shapes: each blade alone, before the fuse, blade i at ``phase_deg + 360 i / n``
            degrees. The blades' ends reach into the hub, so hub and blades overlap; ``shape`` is
            the union.
        surface: blade 0's sampled surface from the geometry layer.
        section_curves: blade 0's section B-splines (plain arrays).
        stage_seconds: seconds per stage (keys: :class:`torus_cad.build_stages.Stage` values).
        fuse_route: how the blades were joined to the hub.
        design_targets: what the designer's inputs (airfoil.naca, diameter, pitch) resolved to;
            ``parameters`` are already the resolved spec parameters.
        mounting: the hub's bore, flat, set screw and chamfer, with the set screw's direction.
        face_parts: the part each face of ``solid`` came from, in the order of ``solid.Faces()``:
            -1 (:data:`torus_cad.geometry.blade.propeller_geometry.HUB_PART`) the hub, i blade i; a
            root fillet's faces are their blade's (:mod:`torus_cad.kernel.face_provenance`).
        root_fillet: the radii the root fillet has (None without one): the requested radius
            everywhere, or smaller along junction edges where the blade bends too tightly for it
            (:class:`torus_cad.kernel.fillet.root_fillet.RootFillet`).
        checks: the strict validity check ``solid`` passed (BRepCheck_Analyzer and
            BRepAlgoAPI_Check's small-edge and self-interference tests,
            :mod:`torus_cad.kernel.strict`).
    """

    parameters: PropellerParameters
    shape: TopoDS_Shape
    hub_shape: TopoDS_Shape
    blade_shapes: list[TopoDS_Shape]
    surface: BladeSurface
    section_curves: SectionCurves
    stage_seconds: dict[str, float] = field(default_factory=dict)
    fuse_route: FuseRoute = FuseRoute.ASSEMBLED
    design_targets: DesignTargets | None = None
    mounting: HubMounting = field(default_factory=HubMounting)
    face_parts: tuple[int, ...] = ()
    root_fillet: RootFillet | None = None
    checks: StrictCheck | None = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickled with its shapes as OpenCascade's binary BRep (as cadquery pickles its shapes);
        the cadquery wrappers are made again when asked for.

        Returns:
            The instance's fields by name, with ``shape``, ``hub_shape`` and each of
            ``blade_shapes`` as BRep bytes and without the cached cadquery views.
        """
        state = {
            name: value for name, value in self.__dict__.items() if name not in _CADQUERY_VIEWS
        }
        state["shape"], state["hub_shape"] = shape_bytes(self.shape), shape_bytes(self.hub_shape)
        state["blade_shapes"] = [shape_bytes(blade) for blade in self.blade_shapes]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(
            state,
            shape=shape_from_bytes(state["shape"]),
            hub_shape=shape_from_bytes(state["hub_shape"]),
            blade_shapes=[shape_from_bytes(blade) for blade in state["blade_shapes"]],
        )

    @functools.cached_property
    def solid(self) -> cq.Solid:
        """The fused propeller as a ``cq.Solid`` (the same OpenCascade solid as ``shape``).

        Returns:
            The fused solid, mm, spin axis z; made once, on first access (imports cadquery).
        """
        import cadquery as cq

        return cq.Solid(self.shape)

    @functools.cached_property
    def hub(self) -> cq.Solid:
        """The hub alone as a ``cq.Solid`` (``hub_shape``).

        Returns:
            The hub cylinder before the fuse, mm; made once, on first access (imports cadquery).
        """
        import cadquery as cq

        return cq.Solid(self.hub_shape)

    @functools.cached_property
    def blades(self) -> list[cq.Solid]:
        """Each blade alone as a ``cq.Solid`` (``blade_shapes``).

        Returns:
            One solid per blade, blade i at ``phase_deg + 360 i / n`` degrees, mm, before the
            fuse; made once, on first access (imports cadquery).
        """
        import cadquery as cq

        return [cq.Solid(blade) for blade in self.blade_shapes]

    @property
    def workplane(self) -> cq.Workplane:
        """A ``cq.Workplane`` on XY holding the fused solid; chain CadQuery operations on it.

        Returns:
            A new workplane on XY (mm) holding :attr:`solid`, each time it is asked for.
        """
        import cadquery as cq

        return cq.Workplane("XY").add(self.solid)

    def assembly(self, name: str | None = None, fused: bool = False) -> cq.Assembly:
        """A ``cq.Assembly`` of named, coloured parts: ``hub`` and ``blade_0`` .. ``blade_{n-1}``.

        With ``fused=True`` it holds the single fused solid instead, named ``propeller``.
        The assembly's name defaults to the design's name.

        Args:
            name: the assembly's name; None (or "") for ``parameters.name``.
            fused: hold the one fused solid (named ``propeller``) instead of the hub and blades.

        Returns:
            The assembly (mm; spin axis z), parts coloured as in the preview.
        """
        import cadquery as cq

        assembly = cq.Assembly(name=name or self.parameters.name)
        if fused:
            return assembly.add(self.solid, name="propeller", color=cq.Color(*HUB_COLOR))
        assembly.add(self.hub, name="hub", color=cq.Color(*HUB_COLOR))
        for index, blade in enumerate(self.blades):
            assembly.add(
                blade, name=f"blade_{index}", color=cq.Color(*blade_color(index, len(self.blades)))
            )
        return assembly

    def printability(self) -> Printability:
        """Thinnest blade wall and trailing-edge thickness against ``manufacturing.min_wall``
        (from the analytic section).

        Returns:
            The thinnest wall and trailing edge (mm), where along the blade (s) they are, and
            whether they reach ``manufacturing.min_wall``.
        """
        return design_printability(self.parameters)

    def spin_to_push_air_down(self) -> Handedness:
        """The turn, seen from +z, that pushes air toward -z: a flat-plate estimate
        (torus_cad.geometry.blade.handedness).

        Returns:
            CW or CCW, seen from +z, for the built blade (the mirror of a 'ccw' design included).

        Raises:
            ValueError: the surface was sampled without its trailing edge as a point.
        """
        spin = spin_to_push_air_down(self.surface.points, self.surface.trailing_edge_column)
        # the surface is the spec's blade, before the mirror
        if self.parameters.handedness == Handedness.CCW:
            return spin.opposite
        return spin

    def mass_properties(self, density_g_cm3: float = DEFAULT_DENSITY_G_CM3) -> MassProperties:
        """Volume (mm^3), area (mm^2), centroid (mm), spin-axis inertia and mass (g) for a density
        in g/cm^3 (default 1.24, PLA), to 1e-6 relative
        (see :func:`torus_cad.kernel.mass_properties.mass_properties`).

        Args:
            density_g_cm3: the material's density, g/cm^3.

        Returns:
            The fused solid's volume (mm^3), surface area (mm^2), centroid (mm), inertia about
            the spin axis (mm^5, and g mm^2 with the density), mass (g) and bounding box (mm).
        """
        return mass_properties(self.shape, density_g_cm3)

    def write(
        self,
        out_dir: str | Path,
        density_g_cm3: float = DEFAULT_DENSITY_G_CM3,
        stl: bool = True,
        sections_table: bool = False,
    ) -> dict[str, Path]:
        """Write ``<name>.step``, ``<name>.stl`` (unless ``stl`` is False), the blade-element table
        ``<name>_sections.csv`` and ``<name>_sections.png`` (if ``sections_table``) and
        ``<name>.json`` into ``out_dir``.

        The files are the formats of ``export.formats``, published together as one output set
        (torus_cad.outputs.output_set): all of them or none.

        Args:
            out_dir: the folder to write into; made if missing.
            density_g_cm3: the material's density for the report's mass, g/cm^3.
            stl: False leaves the STL out even if ``export.formats`` lists it.
            sections_table: also write the blade-element table (CSV and PNG).

        Returns:
            The written files' final paths by kind (e.g. ``"step"``, ``"stl"``, ``"json"``).

        Raises:
            BudgetError: the STL or 3MF would exceed its triangle budget (refused before writing).
            KernelError: OpenCascade could not export the solid, or a written file failed its
                read-back check.
            OutputError: an output file could not be written or published; the message names it.
            MissingExtraError: a library an export needs is not installed.
            OSError: ``out_dir`` cannot be made or written to.
        """
        return write_outputs(self, Path(out_dir), density_g_cm3, stl, sections_table)


#: The cached cadquery wrappers of a Propeller's shapes (not pickled: made again when asked for).
_CADQUERY_VIEWS = ("solid", "hub", "blades")


def design_printability(params: PropellerParameters) -> Printability:
    """The blade's printability from the analytic section alone (no kernel): see
    torus_cad.geometry.analysis.printability."""
    return wall_printability(params)


def build_propeller(
    design: PropellerParameters | str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
    progress: Callable[[Stage], None] | None = None,
) -> Propeller:
    """Build the fused propeller of ``design``.

    Args:
        design: a :class:`PropellerParameters`, the path of a TOML design file, or None for the
            default propeller.
        overrides: optional dotted-key changes applied on top of ``design``, in the design's
            units (mm, degrees), e.g. ``{"blades": 4, "hub.radius": 12.0}``.
        progress: optional callback, called with each :class:`Stage` as it starts.

    Returns:
        The built propeller: one valid closed solid in mm, spin axis z, with its hub, blades,
        sampled surface and the seconds each stage took.

    Raises:
        ParameterError: a bad parameter, override or design file (the message names the field).
        GeometryError: valid parameters that describe no sound propeller (refused before the
            kernel runs).
        KernelError: OpenCascade failed to loft, fuse, fillet or check the solid.
    """
    timer = StageTimer[Stage](progress)
    prepared = prepare_design(design, overrides, timer)
    params, surface, mounting = prepared.parameters, prepared.surface, prepared.mounting
    seam_deg = 0.0 if prepared.seam_deg is None else prepared.seam_deg
    with timer.stage(Stage.WIRES):
        curves = section_curves(prepared.fit)
        fillet_radius = params.hub.root_fillet_radius
        # A round trailing edge leaves the blade's airfoil face open: the fillet needs it in pieces.
        wires = curves.occ_wires(
            ROUND_EDGE_FILLET_PIECES if fillet_radius > 0.0 and curves.round_trailing_edge else 1
        )
    with timer.stage(Stage.LOFT):
        blade = loft_solid(wires, surface.s)
        hub = hub_shape(params.hub.radius, params.hub.length, seam_deg, mounting)
        angles_deg = [params.blade_angle_deg(i) for i in range(params.blades)]
        blades = pattern_blades(blade, angles_deg)
    root_fillet: RootFillet | None = None
    # blade 0 filleted once, then patterned (torus_cad.kernel.fillet.root_fillet)
    if fillet_radius > 0.0:
        with timer.stage(Stage.FILLET):
            run_out = (
                None
                if mounting.chamfer_mm > 0.0
                else functools.partial(
                    run_out_hub,
                    params.hub.radius,
                    params.hub.length,
                    seam_deg,
                    mounting,
                    reach=params.hub.radius + 4.0 * fillet_radius,
                )
            )
            # A sharp edge's side as one closed face: the fillet splits it in its own pieces
            # (kernel.fillet).
            closed = (
                blade
                if surface.lower_corner_index is not None
                else loft_solid(curves.occ_wires(1, False), surface.s)
            )
            # the root fillet's route is cadquery's (torus_cad.kernel.fillet.pattern)
            import cadquery as cq

            from torus_cad.kernel.fillet.pattern import fillet_pattern

            try:
                filleted = fillet_pattern(
                    cq.Solid(hub),
                    cq.Solid(closed),
                    angles_deg,
                    fillet_radius,
                    run_out,
                    reduce_where_tight=params.hub.root_fillet_tight_bends == TightBends.REDUCE,
                )
            except KernelError as error:
                if surface.lower_corner_index is None or surface.round_trailing_edge:
                    raise
                # The flat base's two corners stop OpenCascade's fillet; the round cap has none
                # (README).
                raise KernelError(
                    f"{error}; a flat trailing edge's corners stop the fillet: "
                    f"airfoil.trailing_edge_shape = 'round' takes it"
                ) from None
            solid, root_fillet = filleted.solid.wrapped, filleted
            route, face_parts = FuseRoute.ASSEMBLED, filleted.face_parts
    else:
        solid, fused = joined_propeller(hub, blade, blades, angles_deg, timer)
        route, face_parts = fused.route, fused.face_parts
    # before the mirror, which copies the faces and loses the pattern
    with timer.stage(Stage.STRICT_CHECK):
        solid, checks = strict_valid_propeller(
            solid, root_fillet is not None and surface.lower_corner_index is None
        )
    # the spec's blade is 'cw'; 'ccw' is its mirror image (an isometry)
    if params.handedness == Handedness.CCW:
        with timer.stage(Stage.MIRROR):
            solid = mirrored(solid)  # a transformed copy: the same faces in the same order
            hub, blades = (
                mirrored(hub, check=False),
                [mirrored(part, check=False) for part in blades],
            )
    return Propeller(
        params,
        solid,
        hub,
        blades,
        surface,
        curves,
        timer.seconds,
        route,
        prepared.targets,
        mounting,
        face_parts,
        root_fillet,
        checks,
    )


#: Another name for :func:`build_propeller`, for people who continue in CadQuery.
propeller_objects = build_propeller


def write_outputs(
    propeller: Propeller,
    out_dir: Path,
    density_g_cm3: float = DEFAULT_DENSITY_G_CM3,
    stl: bool = True,
    sections_table: bool = False,
) -> dict[str, Path]:
    """Write the files of ``export.formats`` (STEP, STL, 3MF; ``stl=False`` drops the STL), the
    blade-element table (``<name>_sections.csv`` and ``.png``, when ``sections_table``; ``torus-cad
    build`` writes it) and the JSON report as one output set (torus_cad.outputs.output_set); return
    the paths by kind."""
    return write_output_set(
        propeller, out_dir, density_g_cm3, stl=stl, sections_table=sections_table
    ).paths
