"""Design parameters: one frozen, validated type, read from and written to TOML.

Units: lengths in mm, angles in degrees, airfoil quantities as fractions of the chord.
The centerline's control points live in the hub's local frame L (spec §3.1):
``x_L`` is the angle around the hub axis (degrees), ``y_L`` runs along the axis
pointing down (mm, toward -z) and ``z_L`` runs radially outward (mm). P1 is the
origin of L, P4 has ``z_L = 0``.

Every field is checked when a :class:`PropellerParameters` is made, whether from
Python, a dict or a TOML file; a bad value raises :class:`ParameterError` whose
one-line message names the field, its value and the allowed range.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from torus_cad.errors import ParameterError
from torus_cad.geometry.airfoil import NacaAirfoil
from torus_cad.tolerances import FOLD_RATIO_LIMIT, STL_ANGULAR_DEFLECTION, STL_LINEAR_DEFLECTION

Quartic = tuple[float, float, float, float, float]

FRAME_CHOICES = ("frenet", "rotation_minimizing")
STEP_SCHEMA_CHOICES = ("AP214", "AP242")
_NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


@dataclass(frozen=True)
class HubParameters:
    """Cylindrical hub on the z axis, centred at the origin (mm)."""

    radius: float = 10.0
    length: float = 20.0


@dataclass(frozen=True)
class AirfoilParameters:
    """NACA 4-digit section (spec §1), fractions of the chord."""

    max_camber: float = 0.02
    camber_position: float = 0.4
    thickness: float = 0.5
    camber_normal: bool = True
    pivot: float = 0.0


@dataclass(frozen=True)
class CenterlineParameters:
    """Control points P2, P3, P4 of the cubic centerline in frame L ([deg, mm, mm]); P1 is the origin."""

    p2: tuple[float, float, float] = (25.0, 3.0, 22.0)
    p3: tuple[float, float, float] = (75.0, 15.0, 22.0)
    p4: tuple[float, float] = (100.0, 18.0)
    frame: str = "frenet"


@dataclass(frozen=True)
class TransformParameters:
    """Quartics in s, highest power first: a s^4 + b s^3 + c s^2 + d s + e (spec §2)."""

    angle_of_attack: Quartic = (0.0, 0.0, 0.0, 0.0, 20.0)
    scale_x: Quartic = (0.0, 0.0, -16.0, 16.0, 6.0)
    scale_y: Quartic = (0.0, 0.0, -4.0, 4.0, 2.0)


@dataclass(frozen=True)
class ResolutionParameters:
    """Sampling of the blade surface: sections along the centerline, points around each section."""

    sections: int = 25
    points: int = 80


@dataclass(frozen=True)
class ExportParameters:
    """File export settings: STL deflections (mm, radians) and the STEP application protocol."""

    stl_linear_deflection: float = STL_LINEAR_DEFLECTION
    stl_angular_deflection: float = STL_ANGULAR_DEFLECTION
    step_schema: str = "AP214"


@dataclass(frozen=True)
class PropellerParameters:
    """Every input of a toroidal propeller; frozen and validated on construction."""

    name: str = "torus_propeller"
    blades: int = 3
    phase_deg: float = 0.0
    hub: HubParameters = field(default_factory=HubParameters)
    airfoil: AirfoilParameters = field(default_factory=AirfoilParameters)
    centerline: CenterlineParameters = field(default_factory=CenterlineParameters)
    transforms: TransformParameters = field(default_factory=TransformParameters)
    resolution: ResolutionParameters = field(default_factory=ResolutionParameters)
    export: ExportParameters = field(default_factory=ExportParameters)

    def __post_init__(self) -> None:
        _validate(self)

    @property
    def inset_radius(self) -> float:
        """R_inset = R - R/8 (spec §3.2), mm: the radius of the blade's ends."""
        return self.hub.radius - self.hub.radius / 8.0

    # -- conversions ---------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (lists for tuples), the same layout as the TOML file."""
        return _plain(dataclasses.asdict(self))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "PropellerParameters":
        """Build from a nested mapping (missing keys take defaults; unknown keys are refused)."""
        if not isinstance(data, Mapping):
            raise ParameterError(f"configuration must be a table of keys, got {type(data).__name__}")
        return _build(cls, data, prefix="")

    @classmethod
    def from_toml(cls, path: str | Path) -> "PropellerParameters":
        """Read a TOML configuration file; any problem raises ParameterError naming it."""
        path = Path(path)
        try:
            raw = path.read_bytes()
        except OSError as error:
            raise ParameterError(f"cannot read configuration {str(path)!r}: {error.strerror}") from None
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise ParameterError(f"configuration {str(path)!r} is not a UTF-8 text file") from None
        if not text.strip():
            raise ParameterError(f"configuration {str(path)!r} is empty")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            raise ParameterError(f"configuration {str(path)!r} is not valid TOML: {error}") from None
        return cls.from_dict(data)

    def to_toml(self, comments: bool = True) -> str:
        """The parameters as a TOML document that :meth:`from_toml` reads back unchanged."""
        return _to_toml(self.to_dict(), comments)

    def with_values(self, changes: Mapping[str, Any]) -> "PropellerParameters":
        """A copy with dotted-key changes applied, e.g. ``{"hub.radius": 12.0}``; validated."""
        data = self.to_dict()
        for dotted, value in changes.items():
            *parents, leaf = dotted.split(".")
            table = data
            for part in parents:
                if not isinstance(table.get(part), dict):
                    raise ParameterError(f"unknown key {dotted!r}{_suggest(part, table, _prefix_of(dotted, part))}")
                table = table[part]
            if leaf not in table:
                raise ParameterError(f"unknown key {dotted!r}{_suggest(leaf, table, _prefix_of(dotted, leaf))}")
            table[leaf] = value
        return type(self).from_dict(data)


def resolve_parameters(design: "PropellerParameters | str | Path | None" = None,
                       overrides: Mapping[str, Any] | None = None) -> PropellerParameters:
    """The parameters of ``design`` (parameters, a TOML path, or None for the default) with
    dotted-key ``overrides`` applied, e.g. ``{"blades": 4, "hub.radius": 12.0}`` (validated)."""
    if design is None:
        params = PropellerParameters()
    elif isinstance(design, PropellerParameters):
        params = design
    else:
        params = PropellerParameters.from_toml(design)
    return params.with_values(dict(overrides)) if overrides else params


# -- building from mappings ------------------------------------------------------------

def _suggest(key: str, known: Mapping[str, Any] | list[str], prefix: str = "") -> str:
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.5)
    if close:
        return f"; did you mean {prefix + close[0]!r}?"
    return f"; known keys: {', '.join(prefix + name for name in sorted(known))}"


def _prefix_of(dotted: str, part: str) -> str:
    return dotted[: dotted.rindex(part)] if part in dotted else ""


def _build(cls: type, data: Mapping[str, Any], prefix: str) -> Any:
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise ParameterError(f"unknown key {prefix + str(key)!r}{_suggest(str(key), list(fields), prefix)}")
    values: dict[str, Any] = {}
    for name, spec in fields.items():
        if name not in data:
            continue
        value = data[name]
        dotted = prefix + name
        nested = spec.default_factory if spec.default_factory is not dataclasses.MISSING else None
        if nested is not None and dataclasses.is_dataclass(nested):
            if not isinstance(value, Mapping):
                raise ParameterError(f"{dotted} must be a table ([{dotted}]), got {_describe(value)}")
            values[name] = _build(nested, value, prefix=dotted + ".")
        else:
            values[name] = _coerce(dotted, value, spec.default)
    return cls(**values)


def _describe(value: Any) -> str:
    return f"{type(value).__name__} {value!r}"


def _coerce(dotted: str, value: Any, default: Any) -> Any:
    """Check a leaf's type against its default's type and convert lists to tuples."""
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ParameterError(f"{dotted} must be true or false, got {_describe(value)}")
        return value
    if isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(f"{dotted} must be a whole number, got {_describe(value)}")
        return value
    if isinstance(default, float):
        return _number(dotted, value)
    if isinstance(default, str):
        if not isinstance(value, str):
            raise ParameterError(f"{dotted} must be a string, got {_describe(value)}")
        return value
    if isinstance(default, tuple):
        if not isinstance(value, (list, tuple)) or len(value) != len(default):
            raise ParameterError(f"{dotted} must be a list of {len(default)} numbers, got {_describe(value)}")
        return tuple(_number(f"{dotted}[{i}]", item) for i, item in enumerate(value))
    raise AssertionError(f"no coercion for {dotted}")  # pragma: no cover - schema bug


def _number(dotted: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{dotted} must be a number, got {_describe(value)}")
    return float(value)


# -- validation ------------------------------------------------------------------------

def _check_range(dotted: str, value: float, low: float, high: float,
                 low_open: bool = False, high_open: bool = False) -> None:
    if not math.isfinite(value):
        raise ParameterError(f"{dotted} = {value!r} must be a finite number")
    too_low = value <= low if low_open else value < low
    too_high = value >= high if high_open else value > high
    if too_low or too_high:
        interval = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        raise ParameterError(f"{dotted} = {value:g} is out of range; allowed {interval}")


def _check_choice(dotted: str, value: str, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ParameterError(f"{dotted} = {value!r} is not allowed; choose one of {', '.join(choices)}")


def quartic_minimum(coefficients: Quartic) -> tuple[float, float]:
    """Minimum of a quartic (highest power first) on s in [0, 1]: ``(value, s)``.

    Checks the end points and every real root of the derivative inside [0, 1], so the
    answer is exact, not a sampled estimate.
    """
    derivative = np.polyder(np.asarray(coefficients, dtype=float))
    # np.roots divides by the leading coefficient: drop leading terms that are negligible
    # (e.g. subnormal) against the largest, or it overflows.
    significant = np.nonzero(np.abs(derivative) > 1e-12 * np.abs(derivative).max(initial=0.0))[0]
    derivative_roots = np.roots(derivative[significant[0]:]) if significant.size else []
    candidates = [0.0, 1.0] + [r.real for r in np.atleast_1d(derivative_roots)
                               if abs(r.imag) < 1e-12 and 0.0 <= r.real <= 1.0]
    values = np.polyval(coefficients, candidates)
    index = int(np.argmin(values))
    return float(values[index]), float(candidates[index])


def _validate(params: PropellerParameters) -> None:
    if not isinstance(params.name, str) or not _NAME_PATTERN.match(params.name):
        raise ParameterError(f"name = {params.name!r} must be 1-64 letters, digits, '_', '-' or '.', "
                             "starting with a letter or digit")
    if isinstance(params.blades, bool) or not isinstance(params.blades, int):
        raise ParameterError(f"blades must be a whole number, got {_describe(params.blades)}")
    _check_range("blades", params.blades, 1, 12)
    _check_range("phase_deg", params.phase_deg, -360.0, 360.0)

    hub = params.hub
    _check_range("hub.radius", hub.radius, 0.5, 1000.0)
    _check_range("hub.length", hub.length, 2.0, 2000.0, low_open=True)

    airfoil = params.airfoil
    _check_range("airfoil.max_camber", airfoil.max_camber, 0.0, 0.095)
    if airfoil.max_camber > 0.0:
        _check_range("airfoil.camber_position", airfoil.camber_position, 0.0, 1.0, low_open=True, high_open=True)
    else:
        _check_range("airfoil.camber_position", airfoil.camber_position, 0.0, 1.0, high_open=True)
    _check_range("airfoil.thickness", airfoil.thickness, 0.0, 1.0, low_open=True)
    _check_range("airfoil.pivot", airfoil.pivot, 0.0, 1.0)
    ratio, where = NacaAirfoil(airfoil.max_camber, airfoil.camber_position, airfoil.thickness,
                               airfoil.camber_normal).fold_ratio()
    if ratio >= FOLD_RATIO_LIMIT:
        raise ParameterError(
            f"airfoil.thickness = {airfoil.thickness:g} is too thick for max_camber = {airfoil.max_camber:g} at "
            f"camber_position = {airfoil.camber_position:g}: the lower surface folds over itself near chord "
            f"{where:.2f} (thickness exceeds the camber line's radius of curvature); reduce the thickness or "
            "the camber, move camber_position toward 0.5, or set camber_normal = false")

    centerline = params.centerline
    for key in ("p2", "p3", "p4"):
        point = getattr(centerline, key)
        _check_range(f"centerline.{key}[0]", point[0], -360.0, 360.0)
        if len(point) == 3:  # free control points may lie outside the hub; the curve is checked later
            _check_range(f"centerline.{key}[1]", point[1], -2.0 * hub.length, 2.0 * hub.length)
            _check_range(f"centerline.{key}[2]", point[2], -params.inset_radius, 100.0 * hub.radius,
                         low_open=True)
        else:  # P4 is the blade's second end: it must sit between the hub's end faces (y_L = -1 .. L - 1)
            _check_range(f"centerline.{key}[1]", point[1], -1.0, hub.length - 1.0, low_open=True, high_open=True)
    _check_choice("centerline.frame", centerline.frame, FRAME_CHOICES)

    transforms = params.transforms
    for key in ("angle_of_attack", "scale_x", "scale_y"):
        for i, coefficient in enumerate(getattr(transforms, key)):
            _check_range(f"transforms.{key}[{i}]", coefficient, -1e4, 1e4)
    for key in ("scale_x", "scale_y"):
        low, where = quartic_minimum(getattr(transforms, key))
        if low <= 0.0:
            raise ParameterError(f"transforms.{key} must stay positive on s in [0, 1], "
                                 f"but reaches {low:.4g} mm at s = {where:.3f}")

    resolution = params.resolution
    _check_range("resolution.sections", resolution.sections, 4, 400)
    _check_range("resolution.points", resolution.points, 16, 2000)

    export = params.export
    _check_range("export.stl_linear_deflection", export.stl_linear_deflection, 0.0, 10.0, low_open=True)
    _check_range("export.stl_angular_deflection", export.stl_angular_deflection, 0.0, 1.5, low_open=True)
    _check_choice("export.step_schema", export.step_schema, STEP_SCHEMA_CHOICES)


# -- TOML output -------------------------------------------------------------------------

_COMMENTS: dict[str, str] = {
    "name": "names the output files: <name>.step, <name>.stl, <name>.json",
    "blades": "number of blades n, 1..12",
    "phase_deg": "theta_0: angle of blade 0 around the hub axis (degrees), -360..360",
    "hub": "cylinder on the z axis, centred at the origin",
    "hub.radius": "R (mm); the blade ends sit at R - R/8 (spec 3.2)",
    "hub.length": "L (mm), > 2; the hub spans z in [-L/2, L/2]",
    "airfoil": "NACA 4-digit section (spec 1), fractions of the chord",
    "airfoil.max_camber": "m, 0..0.095 (0 = symmetric section)",
    "airfoil.camber_position": "p, in (0, 1) when m > 0",
    "airfoil.thickness": "maximum thickness, (0, 1]",
    "airfoil.camber_normal": "thickness normal to the camber line (false: theta_c = 0, spec 1.2)",
    "airfoil.pivot": "chord fraction on the centerline, the centre of alpha (0 = leading edge, as the spec)",
    "centerline": "frame L: [x_L degrees around the axis, y_L mm down the axis, z_L mm radially out]; P1 = origin",
    "centerline.p2": "[x2, y2, z2]",
    "centerline.p3": "[x3, y3, z3]",
    "centerline.p4": "[x4, y4]; z_L = 0, so the blade ends inside the hub",
    "centerline.frame": "'frenet' (spec 4) or 'rotation_minimizing' (beyond the spec; for straight or inflecting centerlines)",
    "transforms": "quartics in s in [0, 1], highest power first: a s^4 + b s^3 + c s^2 + d s + e (spec 2)",
    "transforms.angle_of_attack": "alpha(s), degrees",
    "transforms.scale_x": "Sx(s), mm (the chord, along N); must stay > 0",
    "transforms.scale_y": "Sy(s), mm (along B); must stay > 0",
    "resolution": "sampling of the blade surface",
    "resolution.sections": "sections along the centerline, 4..400",
    "resolution.points": "points around each section (equal arc length, spec 5), 16..2000",
    "export": "file output",
    "export.stl_linear_deflection": "STL chordal deviation (mm), (0, 10]",
    "export.stl_angular_deflection": "STL angular deviation (radians), (0, 1.5]",
    "export.step_schema": "'AP214' or 'AP242'",
}


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(item) for item in value) + "]"
    raise TypeError(f"cannot write {value!r} as TOML")  # pragma: no cover


def _to_toml(data: dict[str, Any], comments: bool) -> str:
    lines: list[str] = []

    def emit(key: str, dotted: str, value: Any) -> None:
        text = f"{key} = {_toml_value(value)}"
        note = _COMMENTS.get(dotted)
        lines.append(f"{text:<40} # {note}" if comments and note else text)

    for key, value in data.items():
        if not isinstance(value, dict):
            emit(key, key, value)
    for table, content in data.items():
        if isinstance(content, dict):
            lines.append("")
            header = f"[{table}]"
            note = _COMMENTS.get(table)
            lines.append(f"{header:<40} # {note}" if comments and note else header)
            for key, value in content.items():
                emit(key, f"{table}.{key}", value)
    return "\n".join(lines) + "\n"


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    return value
