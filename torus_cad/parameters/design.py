"""Every parameter of a toroidal propeller, each declared once (key, type, unit, default, range,
doc).

Units: lengths in mm, angles in degrees, airfoil quantities as fractions of the chord. The
centerline's control points live in the hub's local frame L (spec §3.1): ``x_L`` is the
angle around the hub axis (degrees), ``y_L`` runs along the axis pointing down (mm, toward
-z) and ``z_L`` runs radially outward (mm). P1 is the origin of L, P4 has ``z_L = 0``.

To add a parameter, declare it in its table below with :func:`param`; validation, the
commented TOML of ``torus-cad defaults``, the README's configuration table, the fuzz ranges,
the sweep's checks and the studio's panel follow from the declaration. Checks that involve
several fields are the tables' ``model_validator``s.
"""

from __future__ import annotations

import dataclasses
import re
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import AfterValidator, BeforeValidator, Field, model_validator

from torus_cad.errors import ParameterError, shown
from torus_cad.formats import ExportFormat, StepSchema
from torus_cad.geometry.blade.centerline import free_point_z_range_mm
from torus_cad.geometry.blade.frames import FrameKind
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.propeller_geometry import blade_angle_deg
from torus_cad.geometry.blade.station_table import StationTable, checked, read_station_file
from torus_cad.geometry.blade.transforms import quartic_minimum
from torus_cad.geometry.section.airfoil import (
    Naca5Airfoil,
    NacaAirfoil,
    naca4_numbers,
    naca_section,
)
from torus_cad.geometry.section.airfoil_file import load_airfoil_file
from torus_cad.geometry.section.section import Section as SectionShape
from torus_cad.parameters.document import Document
from torus_cad.parameters.schema import (
    AS_TUPLE,
    Bounds,
    Section,
    Vector2,
    Vector3,
    check_in_bounds,
    param,
)
from torus_cad.tolerances import (
    FOLD_RATIO_LIMIT,
    MIN_BLUNT_TRAILING_EDGE_MM,
    STATION_MAX_ROWS,
    STL_ANGULAR_DEFLECTION,
    STL_LINEAR_DEFLECTION,
)

_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")

#: One coefficient of a quartic law.
Coefficient = Annotated[float, Field(ge=-1e4, le=1e4)]
#: A quartic's coefficients, highest power first, each in [-1e4, 1e4].
QuarticCoefficients = Annotated[
    tuple[Coefficient, Coefficient, Coefficient, Coefficient, Coefficient], AS_TUPLE
]


def _checked_name(name: str) -> str:
    if not _NAME_PATTERN.fullmatch(name):
        raise ValueError(
            f"name = {shown(name)} must be 1-64 letters, digits, '_', '-' or '.', "
            "starting with a letter or digit"
        )
    return name


def free_point_z_bounds(hub_radius_mm: float) -> Bounds:
    """The range of a free control point's z_L (p2, p3), mm, as the schema checks it (its ends:
    torus_cad.geometry.blade.centerline.free_point_z_range_mm)."""
    return Bounds(*free_point_z_range_mm(hub_radius_mm), True)


class TightBends(StrEnum):
    """What the root fillet does where a blade face bends concavely, seen from outside, tighter than
    its radius near the hub (a rolling ball of that radius does not fit along it, and OpenCascade
    finds no constant-radius fillet): 'fail' (exit 1 naming a radius that works; the fillet has the
    requested radius everywhere or is not made) or 'reduce' (the radius is reduced there to half the
    bend's radius and blended along that junction loop; a warning and the report's root_fillet say
    so)."""

    FAIL = "fail"
    REDUCE = "reduce"


class Hub(Section):
    """Cylinder on the z axis, centred at the origin."""

    radius: float = param(
        10.0,
        unit="mm",
        ge=0.5,
        le=1000.0,
        fuzz=(4.0, 25.0),
        doc="R; the blade ends sit at R - R/8 (spec §3.2)",
    )
    length: float = param(
        20.0,
        unit="mm",
        gt=2.0,
        le=2000.0,
        fuzz=(8.0, 50.0),
        doc="L; the hub spans z in [-L/2, L/2]",
    )
    bore_diameter: float = param(
        0.0, unit="mm", ge=0.0, le=2000.0, doc="coaxial through-bore for a shaft; 0 = solid hub"
    )
    bore_flat_depth: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=1000.0,
        doc="D-flat for a D-cut shaft: how far the flat reaches into the bore; 0 = round bore",
    )
    set_screw_diameter: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=100.0,
        doc="radial set-screw hole at mid-length, between blades, onto the flat; 0 = none",
    )
    chamfer: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=100.0,
        doc="45-degree chamfer on the hub's outer end edges; 0 = none",
    )
    root_fillet_radius: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=20.0,
        doc="fillet along every blade-hub junction; 0 = sharp junction (the spec)",
    )
    root_fillet_tight_bends: TightBends = param(
        TightBends.FAIL,
        strict=False,
        doc="where a blade bends concavely tighter than the root fillet's radius: "
        "'fail' (exit 1, naming a radius that works) or 'reduce' (a smaller "
        "radius there, blended along that junction; the report says so)",
    )

    @model_validator(mode="after")
    def _mounting_fits(self) -> Self:
        """Limits that follow from the hub's own size (the blades' limits are checked with the
        geometry)."""
        bore_radius = self.bore_diameter / 2.0
        if self.bore_flat_depth > 0.0 and self.bore_diameter == 0.0:
            raise ValueError(
                f"hub.bore_flat_depth = {self.bore_flat_depth:g} mm "
                "needs a bore; set hub.bore_diameter"
            )
        if self.bore_flat_depth >= bore_radius > 0.0:
            raise ValueError(
                f"hub.bore_flat_depth = {self.bore_flat_depth:g} mm is out of range; allowed "
                f"[0, {bore_radius:g}) mm, less than the bore's radius"
            )
        if self.set_screw_diameter > 0.0 and self.bore_diameter == 0.0:
            raise ValueError(
                f"hub.set_screw_diameter = {self.set_screw_diameter:g} mm needs a bore to reach; "
                "set hub.bore_diameter"
            )
        if self.set_screw_diameter >= self.length - 2.0 * self.chamfer:
            raise ValueError(
                f"hub.set_screw_diameter = {self.set_screw_diameter:g} mm is out of range; allowed "
                f"[0, {self.length - 2.0 * self.chamfer:g}) mm, the hub's length less its chamfers"
            )
        if self.chamfer >= min(self.radius, self.length / 2.0):
            raise ValueError(
                f"hub.chamfer = {self.chamfer:g} mm is out of range; allowed "
                f"[0, {min(self.radius, self.length / 2.0):g}) mm"
            )
        return self


#: The spec's section numbers, which airfoil.naca and airfoil.file replace.
_NUMBERS = ("max_camber", "camber_position", "thickness")


class TrailingEdgeShape(StrEnum):
    """The end of a blunt trailing edge (``airfoil.trailing_edge_thickness`` > 0, or a coordinate
    file's open edge): torus_cad.geometry.blade.trailing_edge."""

    # a round cap tangent to both surfaces: no sharp edge (the root fillet rolls round it)
    ROUND = "round"
    FLAT = "flat"  # a straight base between two corners


class Airfoil(Section):
    """The section (spec §1): NACA 4-digit numbers (fractions of the chord), a NACA designation, or
    a coordinate file."""

    max_camber: float = param(0.02, ge=0.0, le=0.095, doc="m (0 = symmetric section)")
    camber_position: float = param(
        0.4, ge=0.0, lt=1.0, fuzz=(0.1, 0.9), doc="p; in (0, 1) when m > 0"
    )
    thickness: float = param(0.5, gt=0.0, le=1.0, fuzz=(0.06, 1.0), doc="maximum thickness")
    camber_normal: bool = param(
        True, doc="thickness normal to the camber line (false: theta_c = 0, spec §1.2)"
    )
    pivot: float = param(
        0.0,
        ge=0.0,
        le=1.0,
        doc="chord fraction on the centerline, the centre of alpha (0 = leading edge, the spec)",
    )
    naca: str = param(
        "",
        doc="NACA designation instead of the numbers: 4-digit '2412' sets max_camber, "
        "camber_position, thickness; 5-digit '23012' (\"\" = use the numbers)",
    )
    file: str = param(
        "",
        doc="airfoil coordinate file (.dat, Selig or Lednicer layout) instead of the numbers; "
        'relative to the design file\'s folder ("" = none)',
    )
    trailing_edge_thickness: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=50.0,
        fuzz=(0.0, 0.0),
        doc="blunt trailing edge of this thickness on every section "
        "(0 = the spec's sharp edge; otherwise at least 0.05 mm)",
    )
    trailing_edge_shape: TrailingEdgeShape = param(
        TrailingEdgeShape.ROUND,
        strict=False,
        doc="end of a blunt trailing edge (and of a coordinate "
        "file's open one): 'round', a cap tangent to both "
        "surfaces (no sharp edge; the root fillet works with "
        "it), or 'flat', a straight base with two corners",
    )

    def section(self) -> SectionShape:
        """The chord-unit section this table describes (without the blunt trailing edge)."""
        if self.file:
            return load_airfoil_file(self.file)
        if self.naca:
            return naca_section(self.naca, self.camber_normal)
        return NacaAirfoil(
            self.max_camber, self.camber_position, self.thickness, self.camber_normal
        )

    @model_validator(mode="after")
    def _one_source_of_the_section(self) -> Self:
        """naca and file replace the numbers: a number other than its default (or, for a 4-digit
        designation, the designation's own value) contradicts them."""
        if self.naca and self.file:
            raise ValueError(
                f"airfoil.naca = {shown(self.naca)} conflicts "
                f"with airfoil.file = {shown(self.file)}: "
                "give one of them"
            )
        if not (self.naca or self.file):
            return self
        key = "naca" if self.naca else "file"
        implied = (
            dict(zip(_NUMBERS, naca4_numbers(self.naca))) if len(self.naca.strip()) == 4 else {}
        )
        if self.naca:
            naca_section(self.naca)  # raises ParameterError (a ValueError) naming airfoil.naca
        if self.file:
            try:
                load_airfoil_file(self.file)
            except ParameterError as error:
                raise ValueError(f"airfoil.file: {error}") from None
        for number in _NUMBERS:
            value, default = getattr(self, number), type(self).model_fields[number].default
            if value != default and value != implied.get(number, default):
                raise ValueError(
                    f"airfoil.{key} = {shown(getattr(self, key))} conflicts "
                    f"with airfoil.{number} = {shown(value)}: "
                    f"give the section by {key} or by its numbers, not both"
                )
        return self

    @model_validator(mode="after")
    def _blunt_edge_thick_enough(self) -> Self:
        """A blunt trailing edge thinner than MIN_BLUNT_TRAILING_EDGE_MM cannot be meshed without
        crossing triangles (torus_cad.geometry.blade.trailing_edge)."""
        thickness = self.trailing_edge_thickness
        if 0.0 < thickness < MIN_BLUNT_TRAILING_EDGE_MM:
            raise ValueError(
                f"airfoil.trailing_edge_thickness = {thickness:g} mm "
                "is too thin to mesh without crossing "
                f"triangles; allowed 0 (sharp) or {MIN_BLUNT_TRAILING_EDGE_MM:g} to 50 mm"
            )
        return self

    @model_validator(mode="after")
    def _camber_and_fold(self) -> Self:
        section = self.section()
        if not isinstance(section, NacaAirfoil | Naca5Airfoil):
            # a coordinate file: its surfaces were checked for crossing when it was read
            return self
        if self.naca:
            where_from = f"airfoil.naca = {shown(self.naca)}"
        else:
            if self.max_camber > 0.0:
                check_in_bounds(
                    "airfoil.camber_position", self.camber_position, Bounds(0.0, 1.0, True, True)
                )
            where_from = (
                f"airfoil.thickness = {self.thickness:g} is too thick for max_camber = "
                f"{self.max_camber:g} at camber_position = {self.camber_position:g}"
            )
        ratio, where = section.fold_ratio()
        if ratio >= FOLD_RATIO_LIMIT:
            raise ValueError(
                f"{where_from}: the lower surface folds over itself near chord "
                f"{where:.2f} (thickness exceeds the camber line's "
                "radius of curvature); reduce the thickness or "
                "the camber, move camber_position toward 0.5, or set camber_normal = false"
            )
        return self


class Centerline(Section):
    """Frame L: [x_L deg around the axis, y_L mm down the axis, z_L mm radially out]; P1 =
    origin."""

    p2: Vector3 = param(
        (25.0, 3.0, 22.0), unit="deg, mm, mm", doc="free control point [x2, y2, z2]"
    )
    p3: Vector3 = param(
        (75.0, 15.0, 22.0), unit="deg, mm, mm", doc="free control point [x3, y3, z3]"
    )
    p4: Vector2 = param(
        (100.0, 18.0), unit="deg, mm", doc="[x4, y4], with z_L = 0: the blade returns into the hub"
    )
    frame: FrameKind = param(
        FrameKind.FRENET,
        strict=False,
        doc="'frenet' (spec §4) or 'rotation_minimizing' (beyond the spec)",
    )


class Transforms(Section):
    """Quartics in s in [0, 1], highest power first: a s^4 + b s^3 + c s^2 + d s + e (spec §2)."""

    angle_of_attack: QuarticCoefficients = param(
        (0.0, 0.0, 0.0, 0.0, 20.0), unit="deg", doc="alpha(s)"
    )
    scale_x: QuarticCoefficients = param(
        (0.0, 0.0, -16.0, 16.0, 6.0),
        unit="mm",
        doc="Sx(s): the chord, along N; must stay > 0 on [0, 1]",
    )
    scale_y: QuarticCoefficients = param(
        (0.0, 0.0, -4.0, 4.0, 2.0), unit="mm", doc="Sy(s): along B; must stay > 0 on [0, 1]"
    )

    @model_validator(mode="after")
    def _scales_positive(self) -> Self:
        for key in ("scale_x", "scale_y"):
            low, where = quartic_minimum(getattr(self, key))
            if low <= 0.0:
                raise ValueError(
                    f"transforms.{key} must stay positive on s in [0, 1], "
                    f"but reaches {low:.4g} mm at s = {where:.3f}"
                )
        return self


class Resolution(Section):
    """Sampling of the blade surface."""

    sections: int = param(25, ge=4, le=400, fuzz=(16, 36), doc="sections along the centerline")
    points: int = param(
        80,
        ge=16,
        le=2000,
        fuzz=(24, 48),
        doc="points around each section, equal arc length (spec §5)",
    )


class Manufacturing(Section):
    """What the workshop can make."""

    min_wall: float = param(
        0.8,
        unit="mm",
        gt=0.0,
        le=100.0,
        doc="thinnest wall a part may have: hub wall, blade thickness (0.8 = two 0.4 mm lines)",
    )


def _formats(value: Any) -> Any:
    """TOML lists as tuples of formats, each once, in the order given; at least one."""
    if isinstance(value, list | tuple):
        if not value:
            raise ValueError("export.formats must name at least one of step, stl, 3mf")
        try:
            formats = tuple(ExportFormat(item) for item in value)
        except ValueError:
            raise ValueError(
                f"export.formats = {shown(list(value))} is not allowed; choose from step, stl, 3mf"
            ) from None
        return tuple(dict.fromkeys(formats))
    return value


class Export(Section):
    """File output."""

    formats: Annotated[tuple[ExportFormat, ...], BeforeValidator(_formats)] = param(
        (ExportFormat.STEP, ExportFormat.STL),
        strict=False,
        doc="files to write: any of 'step', 'stl', '3mf' (3MF: one fused mesh object, millimetres)",
    )

    stl_linear_deflection: float = param(
        STL_LINEAR_DEFLECTION,
        unit="mm",
        gt=0.0,
        le=10.0,
        fuzz=(0.02, 0.5),
        doc="STL chordal deviation",
    )
    stl_angular_deflection: float = param(
        STL_ANGULAR_DEFLECTION,
        unit="rad",
        gt=0.0,
        le=1.5,
        fuzz=(0.2, 0.8),
        doc="STL angular deviation",
    )
    step_schema: StepSchema = param(StepSchema.AP214, strict=False, doc="STEP application protocol")


class SectionSpacing(StrEnum):
    """How ``torus-cad mesh`` spreads the sections along a blade."""

    # evenly in the centerline's arc length: rows of cells of equal length
    ARC_LENGTH = "arc_length"
    PARAMETER = "parameter"  # evenly in the centerline parameter s (as the B-rep's sections)


class InletSide(StrEnum):
    """The end of the CFD domain where the flow enters."""

    PLUS_Z = "+z"
    MINUS_Z = "-z"


class Mesh(Section):
    """Surface mesh of `torus-cad mesh`: structured grids united into one closed mesh (spec §5,
    §7)."""

    sections: int = param(
        100, ge=4, le=20000, fuzz=(16, 40), doc="sections along each blade (grid rows)"
    )
    points: int = param(
        400,
        ge=16,
        le=50000,
        fuzz=(32, 100),
        doc="points around each section, equal arc length (spec §5)",
    )
    spacing: SectionSpacing = param(
        SectionSpacing.ARC_LENGTH,
        strict=False,
        doc="sections evenly in the centerline's 'arc_length' or in its 'parameter' s",
    )
    stl: bool = param(True, doc="write <name>_mesh.stl (binary)")
    stl_ascii: bool = param(False, doc="write <name>_mesh_ascii.stl, one named solid per part")
    obj: bool = param(True, doc="write <name>_mesh.obj, one group per part (hub, blade_0, ...)")
    ply: bool = param(False, doc="write <name>_mesh.ply (binary, per-face part index)")
    vtk: bool = param(False, doc="write <name>_mesh.vtk (legacy binary, per-face part index)")


class Cfd(Section):
    """Fluid domain and tetrahedral mesh of `torus-cad cfd` (gmsh); D = tip diameter."""

    domain_radius: float = param(4.0, unit="D", ge=1.0, le=50.0, doc="outer cylinder's radius")
    upstream: float = param(
        3.0, unit="D", ge=0.5, le=100.0, doc="inlet's distance from the propeller's centre"
    )
    downstream: float = param(
        6.0, unit="D", ge=0.5, le=200.0, doc="outlet's distance from the propeller's centre"
    )
    zone_radius: float = param(
        0.6,
        unit="D",
        gt=0.5,
        le=5.0,
        doc="rotating zone's radius (> 0.5: it encloses the blade tips)",
    )
    zone_clearance: float = param(
        0.1,
        unit="D",
        ge=0.01,
        le=2.0,
        doc="axial gap between the propeller and the rotating zone's end faces",
    )
    cells_per_chord: float = param(
        10.0, ge=2.0, le=200.0, doc="surface elements across the smallest chord"
    )
    curvature_cells: float = param(
        8.0, ge=0.0, le=100.0, doc="elements per 2 pi radians of surface curvature (0 = off)"
    )
    growth_rate: float = param(
        1.25, gt=1.0, le=3.0, doc="size ratio of neighbouring elements away from the propeller"
    )
    far_size: float = param(0.3, unit="D", ge=0.01, le=5.0, doc="largest element")
    inlet_side: InletSide = param(
        InletSide.PLUS_Z, strict=False, doc="end where the flow enters: '+z' or '-z'"
    )

    @model_validator(mode="after")
    def _room_outside_the_zone(self) -> Self:
        if self.domain_radius < 1.5 * self.zone_radius:
            raise ValueError(
                f"cfd.domain_radius = {self.domain_radius:g} must "
                "be at least 1.5 x cfd.zone_radius "
                f"= {1.5 * self.zone_radius:g} (room for the stationary region)"
            )
        return self


class DesignKind(StrEnum):
    """What kind of propeller a design describes."""

    TOROIDAL = "toroidal"  # the spec's looped blades on a centerline
    CONVENTIONAL = "conventional"  # open-tip blades from a station table ([conventional])


#: A column of a station table (TOML array of numbers, any length up to STATION_MAX_ROWS).
Column = Annotated[tuple[float, ...], AS_TUPLE]

#: The inline station columns and their names in messages.
_COLUMNS = ("r_over_R", "c_over_R", "beta", "thickness_ratio", "sweep")


class Conventional(Section):
    """A conventional (open-tip) blade from a station table, used when kind = 'conventional'."""

    diameter: float = param(
        254.0,
        unit="mm",
        gt=0.0,
        le=10000.0,
        fuzz=(100.0, 400.0),
        doc="tip diameter D = 2 R; the stations' r/R and c/R are fractions of R",
    )
    stations_file: str = param(
        "",
        doc="station table file: UIUC geometry ('r/R c/R beta' rows) or APC's PE0 "
        '(detected by content); relative to the design file\'s folder ("" = inline)',
    )
    r_over_R: Column = param((), doc="inline stations' r/R, increasing in (0, 1]")
    c_over_R: Column = param((), doc="inline stations' chord c/R")
    beta: Column = param(
        (), unit="deg", doc="inline stations' local pitch angle (pitch = 2 pi r tan beta)"
    )
    sweep: Column = param(
        (),
        unit="R",
        doc="inline stations' leading edge ahead of the blade's axis in the plane of "
        "rotation, /R (empty = stacked at 'stacking')",
    )
    thickness_ratio: Column = param(
        (),
        doc="t/c: at the stations, or at thickness_r_over_R when given "
        "(empty = the file's column, else the airfoil's own thickness)",
    )
    thickness_r_over_R: Column = param(
        (),
        doc="r/R of thickness_ratio's values, for a table without "
        "a thickness column (empty = thickness_ratio is per station)",
    )
    stacking: float = param(
        0.25,
        ge=0.0,
        le=1.0,
        doc="chord fraction of the sections' stacking point (0 = leading edge), in the plane z = 0",
    )

    @model_validator(mode="after")
    def _one_table(self) -> Self:
        """Stations from a file or inline, not both; inline columns of one length; readable file."""
        inline = [key for key in _COLUMNS[:3] if getattr(self, key)]
        if self.stations_file and inline:
            raise ValueError(
                f"conventional.stations_file conflicts with conventional.{inline[0]}: give the "
                "stations by a file or inline, not both"
            )
        if self.stations_file and self.sweep:
            raise ValueError(
                "conventional.sweep is for inline stations; a station file gives its own"
            )
        for key in (*_COLUMNS, "thickness_r_over_R"):
            if len(getattr(self, key)) > STATION_MAX_ROWS:
                raise ValueError(
                    f"conventional.{key} has {len(getattr(self, key))} values; allowed at most "
                    f"{STATION_MAX_ROWS}"
                )
        if self.thickness_r_over_R and len(self.thickness_r_over_R) != len(self.thickness_ratio):
            raise ValueError(
                "conventional.thickness_r_over_R and "
                "conventional.thickness_ratio must have the same "
                "length"
            )
        if self.stations_file:
            try:
                self.stations()
            except ParameterError as error:
                raise ValueError(f"conventional.stations_file: {error}") from None
        elif inline:
            self.stations()
        return self

    def given(self) -> bool:
        """Whether any station is given (a file or an inline column)."""
        return bool(self.stations_file or any(getattr(self, key) for key in _COLUMNS))

    def _inline(self) -> StationTable:
        """The inline columns as a station table (sweep and a per-station thickness optional)."""
        count = len(self.r_over_R)
        per_station_thickness = self.thickness_ratio if not self.thickness_r_over_R else ()
        for key, values in (
            ("c_over_R", self.c_over_R),
            ("beta", self.beta),
            ("sweep", self.sweep),
            ("thickness_ratio", per_station_thickness),
        ):
            if len(values) != count and (key in ("c_over_R", "beta") or values):
                raise ParameterError(
                    f"conventional.{key} has {len(values)} values but conventional.r_over_R "
                    f"has {count}"
                )

        def column(values: tuple[float, ...]) -> NDArray[np.float64] | None:
            return np.asarray(values, dtype=float) if values else None

        return StationTable(
            np.asarray(self.r_over_R, dtype=float),
            np.asarray(self.c_over_R, dtype=float),
            np.asarray(self.beta, dtype=float),
            column(per_station_thickness),
            column(self.sweep),
            source="conventional.r_over_R / c_over_R / beta",
        )

    def stations(self) -> StationTable:
        """The checked station table, with the thickness law of thickness_r_over_R applied
        (ParameterError naming the file's line or the inline station)."""
        table = (
            read_station_file(self.stations_file) if self.stations_file else checked(self._inline())
        )
        if not self.thickness_r_over_R:
            if self.thickness_ratio and self.stations_file:
                raise ParameterError(
                    "conventional.thickness_ratio with a station file needs "
                    "conventional.thickness_r_over_R (where its values apply)"
                )
            return table
        law = checked(
            StationTable(
                np.asarray(self.thickness_r_over_R, dtype=float),
                np.ones(len(self.thickness_r_over_R)),
                np.zeros(len(self.thickness_r_over_R)),
                np.asarray(self.thickness_ratio, dtype=float),
                source="conventional.thickness_r_over_R / thickness_ratio",
            )
        )
        thickness = np.interp(
            table.r_over_r,
            law.r_over_r,
            law.thickness_ratio if law.thickness_ratio is not None else np.ones(0),
        )
        return dataclasses.replace(table, thickness_ratio=thickness)


class PropellerParameters(Document):
    """Every input of a toroidal propeller; frozen and validated on construction.

    Build it from keywords, :meth:`from_dict`, :meth:`from_toml` or :meth:`with_values`; every
    field's unit, default and range are in the parameters reference. An invalid value raises
    :class:`~torus_cad.errors.ParameterError` naming the field.

    Attributes:
        name: names the output files ``<name>.step/.stl/.json`` and the STEP product.
        kind: 'toroidal' (the spec's looped blades) or 'conventional' (open-tip blades from the
            ``conventional`` station table; ``centerline`` and ``transforms`` unused).
        blades: number of blades n; blade i sits at ``phase_deg + 360 i / n`` degrees.
        phase_deg: theta_0, the angle of blade 0 around the spin axis z, degrees.
        diameter: tip diameter to reach by scaling z_L of ``centerline.p2`` and ``p3``, mm
            (0 = as the control points give).
        pitch: geometric pitch of the outer half to reach by refitting
            ``transforms.angle_of_attack``, mm (0 = as the quartic gives).
        handedness: 'cw' (the spec's blade, turning clockwise seen from +z to push air toward
            -z) or 'ccw' (its mirror image).
        hub: the hub cylinder and its mounting (radius, length, bore, flat, set screw,
            chamfer, root fillet), mm.
        airfoil: the section: NACA numbers (fractions of the chord), a NACA designation or a
            coordinate file, and the blunt trailing edge (mm).
        centerline: the blade's control points p2, p3, p4 in the hub's frame L
            (degrees around the axis, mm down the axis, mm radially out) and the frame kind.
        transforms: quartics in s of the angle of attack (degrees) and the section's scales
            (mm).
        resolution: sampling of the blade surface for the solid (sections x points).
        export: output formats, STEP schema and STL deflections (mm, rad).
        mesh: the surface mesh of ``torus-cad mesh`` (grid sizes, spacing, file formats).
        cfd: the fluid domain and tetrahedral mesh of ``torus-cad cfd`` (lengths in tip
            diameters D).
        conventional: the station table of a conventional blade (diameter in mm, beta in
            degrees, the rest fractions of R or of the chord).
        manufacturing: what the workshop can make (``min_wall``, mm).
    """

    name: Annotated[str, AfterValidator(_checked_name)] = param(
        "torus_propeller", doc="names the output files <name>.step/.stl/.json and the STEP product"
    )
    kind: DesignKind = param(
        DesignKind.TOROIDAL,
        strict=False,
        doc="'toroidal' (the spec's looped blades) or 'conventional' (open-tip blades from the "
        "[conventional] station table; centerline and transforms unused)",
    )
    blades: int = param(
        3, ge=1, le=12, fuzz=(1, 8), doc="number of blades n; blade i at theta_0 + 360 i / n"
    )
    phase_deg: float = param(
        0.0,
        unit="deg",
        ge=-360.0,
        le=360.0,
        fuzz=(-180.0, 180.0),
        doc="theta_0: angle of blade 0 around the axis",
    )
    diameter: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=100000.0,
        fuzz=(0.0, 0.0),
        doc=(
            "tip diameter to reach by scaling z_L of "
            "centerline.p2 and p3 (0 = as the control points give)"
        ),
    )
    pitch: float = param(
        0.0,
        unit="mm",
        ge=0.0,
        le=100000.0,
        fuzz=(0.0, 0.0),
        doc="geometric pitch of the outer half to reach by refitting transforms.angle_of_attack "
        "(0 = as the quartic gives)",
    )
    handedness: Handedness = param(
        Handedness.CW,
        strict=False,
        doc="'cw': the spec's blade, which turns clockwise seen from +z to push air toward -z; "
        "'ccw': its exact mirror image, for counter-rotating pairs",
    )
    hub: Hub = Field(default_factory=Hub)
    airfoil: Airfoil = Field(default_factory=Airfoil)
    centerline: Centerline = Field(default_factory=Centerline)
    transforms: Transforms = Field(default_factory=Transforms)
    resolution: Resolution = Field(default_factory=Resolution)
    export: Export = Field(default_factory=Export)
    mesh: Mesh = Field(default_factory=Mesh)
    cfd: Cfd = Field(default_factory=Cfd)
    conventional: Conventional = Field(default_factory=Conventional)
    manufacturing: Manufacturing = Field(default_factory=Manufacturing)

    @model_validator(mode="after")
    def _hub_wall(self) -> Self:
        """The hub's wall around the bore (at the chamfered ends too) must be at least
        manufacturing.min_wall."""
        if self.hub.bore_diameter == 0.0:
            return self
        wall = self.hub.radius - self.hub.chamfer - self.hub.bore_diameter / 2.0
        if wall < self.manufacturing.min_wall:
            limit = 2.0 * (self.hub.radius - self.hub.chamfer - self.manufacturing.min_wall)
            raise ValueError(
                f"hub.bore_diameter = {self.hub.bore_diameter:g} mm "
                f"leaves a hub wall of {wall:.3g} mm, "
                f"thinner than manufacturing.min_wall = {self.manufacturing.min_wall:g} mm; "
                f"allowed at most {max(limit, 0.0):g} mm"
            )
        return self

    @model_validator(mode="after")
    def _kind_has_its_inputs(self) -> Self:
        """A conventional design needs stations and has no toroidal targets; a toroidal one no
        stations."""
        if self.kind == DesignKind.TOROIDAL:
            if self.conventional.given():
                raise ValueError(
                    "[conventional] stations are given but kind "
                    "= 'toroidal'; set kind = 'conventional'"
                )
            return self
        if not self.conventional.given():
            raise ValueError(
                "kind = 'conventional' needs stations: conventional.stations_file or the inline "
                "conventional.r_over_R, c_over_R and beta"
            )
        for key in ("diameter", "pitch"):
            if getattr(self, key):
                raise ValueError(
                    f"{key} = {getattr(self, key):g} mm is a toroidal design target; for kind = "
                    "'conventional' the station table sets "
                    "the blade (conventional.diameter the size)"
                )
        return self

    @model_validator(mode="after")
    def _control_points_fit_the_hub(self) -> Self:
        """Ranges of the control points that depend on the hub's size (toroidal designs; a
        conventional one has none)."""
        if self.kind == DesignKind.CONVENTIONAL:
            return self
        length = self.hub.length
        for key in ("p2", "p3", "p4"):
            point = getattr(self.centerline, key)
            check_in_bounds(f"centerline.{key}[0]", point[0], Bounds(-360.0, 360.0), "deg")
            # free control points may lie outside the hub; the curve is checked later
            if len(point) == 3:
                check_in_bounds(
                    f"centerline.{key}[1]", point[1], Bounds(-2.0 * length, 2.0 * length), "mm"
                )
                check_in_bounds(
                    f"centerline.{key}[2]", point[2], free_point_z_bounds(self.hub.radius), "mm"
                )
            else:  # P4 is the blade's second end: it must sit between the hub's end faces
                check_in_bounds(
                    f"centerline.{key}[1]", point[1], Bounds(-1.0, length - 1.0, True, True), "mm"
                )
        return self

    @classmethod
    def paths_relative_to(cls, data: dict[str, Any], folder: Path) -> dict[str, Any]:
        """A relative ``airfoil.file`` in a design file is relative to the design file's folder."""
        for table, key in (("airfoil", "file"), ("conventional", "stations_file")):
            values = data.get(table)
            if isinstance(values, dict) and isinstance(values.get(key), str) and values[key]:
                # "~/foils/x.dat" is the user's home, as in a shell
                path = Path(values[key]).expanduser()
                data = {
                    **data,
                    table: {**values, key: str(path if path.is_absolute() else folder / path)},
                }
        return data

    def blade_angle_deg(self, blade_index: int) -> float:
        """theta_i = theta_0 + 360 i / n (spec §6.1), degrees, of either kind."""
        return blade_angle_deg(self.phase_deg, blade_index, self.blades)


# ParameterError is what every caller catches; keep it importable from here.
__all__ = [
    "Airfoil",
    "Centerline",
    "Cfd",
    "Conventional",
    "DesignKind",
    "Export",
    "ExportFormat",
    "Handedness",
    "Hub",
    "InletSide",
    "Manufacturing",
    "Mesh",
    "ParameterError",
    "PropellerParameters",
    "Resolution",
    "SectionSpacing",
    "StepSchema",
    "Transforms",
]
