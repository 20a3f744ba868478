"""The sweep file: TOML with a base design, the sweep's settings and the parameters to vary.

::

    [base]                       # the design every variant starts from
    config = "my_prop.toml"      # optional, relative to the sweep file; inline tables override it
    [base.airfoil]
    file = "airfoils/clarky.dat" # relative to the sweep file (in [vary] too), as in a design file
    [base.resolution]
    sections = 16

    [sweep]
    mode = "grid"                # "grid" | "random" | "latin_hypercube"
    samples = 20                 # random / latin_hypercube only: how many designs
    seed = 1                     # random / latin_hypercube only (default 0)
    stl = true                   # write STL files (default true)
    density_g_cm3 = 1.24         # material density for the mass (default: PLA)
    time_limit_s = 300           # a design running longer is stopped and recorded as "timeout"

    [vary]                       # dotted parameter keys; "key[i]" addresses one vector element
    "hub.radius" = [9.0, 10.0, 11.0]               # a list of values (any mode)
    blades = {start = 2, stop = 4, step = 1}       # a range, stop included (any mode)
    "centerline.p2[2]" = {low = 18.0, high = 26.0} # bounds (random / latin_hypercube only)

The [sweep] table is a pydantic model (:class:`SweepTable`), like the parameters. Everything is
checked here, before any design is generated: keys, types, finite values, and
the number of designs against :data:`torus_cad.batch.sweep_file.MAX_SWEEP_DESIGNS`, estimated
from the axis sizes without listing them. Every problem is a one-line ParameterError that
names the key (exit code 2 at the command line).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any, TypeGuard

from pydantic import Field, ValidationError

from torus_cad.errors import ParameterError, shown
from torus_cad.parameters import ParameterSpec, PropellerParameters, parameter_specs
from torus_cad.parameters.config_file import read_config_table
from torus_cad.parameters.schema import (
    Bounds,
    Section,
    check_in_bounds,
    closest_key,
    param,
    parameter_error,
)
from torus_cad.tolerances import DENSITY_LIMIT_G_CM3, DESIGN_TIME_LIMIT_MAX_S

#: Most designs one sweep may hold (grid product or samples), checked from the axis sizes before
#: any design is generated. Beyond it the design list and table alone take gigabytes, and at
#: ~2 designs/s per machine the sweep would run for weeks.
MAX_SWEEP_DESIGNS = 1_000_000


__all__ = [
    "Fail",
    "Leaf",
    "SweepMode",
    "SweepSpec",
    "VaryAxis",
    "axis_paths_relative_to",
    "check_distinct_axes",
    "checked_value",
    "estimate_designs",
    "flatten_vary",
    "load_sweep",
    "parse_sweep",
    "resolve_leaf",
]


class SweepMode(StrEnum):
    """How the designs are drawn from the ``[vary]`` axes."""

    GRID = "grid"  #: the Cartesian product of the lists and ranges
    RANDOM = "random"  #: independent uniform samples
    LATIN_HYPERCUBE = "latin_hypercube"  #: a Latin hypercube (scipy.stats.qmc)


#: Default per-design time limit of a sweep, s (a design takes about a second at the default
#: resolution).
DEFAULT_TIME_LIMIT_S = 300.0

_TOP_KEYS = ("base", "sweep", "vary")
_SPEC_KEYS = {"low", "high", "start", "stop", "step", "num"}
_KEY_PATTERN = re.compile(
    r"^(?P<path>[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*)(?:\[(?P<index>\d+)\])?$"
)
# range values are rounded to 12 decimals so 0.1 steps give 0.3, not 0.30000000000000004
_RANGE_DIGITS = 12

Fail = Callable[[str], ParameterError]


@dataclass(frozen=True)
class VaryAxis:
    """One varied parameter.

    Attributes:
        key: the key as written in ``[vary]``, e.g. ``"centerline.p2[2]"``; also its table column.
        path: the dotted parameter path split at the dots, e.g. ``("centerline", "p2")``.
        index: the vector element addressed by ``[i]``, or None for the whole value.
        values: the candidate values of a list or range (empty for bounds).
        low, high: the bounds for random / Latin-hypercube sampling (None for lists and ranges),
            in the parameter's unit (mm, degrees, ...).
        integer: True when the parameter is a whole number (bounds then give ints, ``high``
            included).
    """

    key: str
    path: tuple[str, ...]
    index: int | None
    values: tuple[Any, ...] = ()
    low: float | None = None
    high: float | None = None
    integer: bool = False

    @property
    def is_bounds(self) -> bool:
        """True for ``{low, high}`` bounds, False for a list or range of values."""
        return self.low is not None

    def pick(self, unit: float) -> Any:
        """The value at ``unit`` in [0, 1): a point between the bounds or one of the values."""
        if self.is_bounds:
            assert self.low is not None and self.high is not None
            if self.integer:
                low, high = int(self.low), int(self.high)
                return min(high, low + math.floor(unit * (high - low + 1)))
            return float(self.low + unit * (self.high - self.low))
        return self.values[min(len(self.values) - 1, math.floor(unit * len(self.values)))]

    def describe(self) -> Any:
        """The axis for ``sweep.json``: its bounds or its values (plain JSON data)."""
        return {"low": self.low, "high": self.high} if self.is_bounds else list(self.values)


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file.

    Attributes:
        name: the sweep's name (``[sweep] name``, default the file's stem).
        base: the design every variant starts from.
        mode: how designs are drawn from the axes.
        axes: the varied parameters, in file order.
        samples: designs to draw (random / latin_hypercube), None for a grid.
        seed: the random seed (random / latin_hypercube).
        stl: write an STL file for each design.
        density_g_cm3: material density for the mass, g/cm^3 (None: the package default, PLA).
        time_limit_s: wall-clock limit per design on the local pool, s.
        source: where the sweep came from (a path or ``"<dict>"``), for messages.
    """

    name: str
    base: PropellerParameters
    mode: SweepMode = SweepMode.GRID
    axes: tuple[VaryAxis, ...] = ()
    samples: int | None = None
    seed: int = 0
    stl: bool = True
    density_g_cm3: float | None = None
    time_limit_s: float = DEFAULT_TIME_LIMIT_S
    source: str = "<dict>"

    @property
    def design_count(self) -> int:
        """Designs the sweep asks for before duplicates are merged (at most MAX_SWEEP_DESIGNS)."""
        if self.mode is SweepMode.GRID:
            return math.prod(len(axis.values) for axis in self.axes)
        assert self.samples is not None
        return self.samples


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file; any problem raises a one-line ParameterError naming the key."""
    path = Path(path)
    source = f"sweep file {str(path)!r}"
    # untrusted like a design: regular file, capped, BOM allowed
    data = read_config_table(path, "sweep file")
    return parse_sweep(data, base_dir=path.parent, name=path.stem, source=source)


def parse_sweep(
    data: Mapping[str, Any], base_dir: str | Path = ".", name: str = "sweep", source: str = "sweep"
) -> SweepSpec:
    """Check a sweep given as a mapping (the parsed TOML); ``base.config`` and file paths in the
    design (``airfoil.file``, inline or varied) are relative to ``base_dir``, the sweep file's
    folder."""

    def fail(message: str) -> ParameterError:
        return ParameterError(f"{source}: {message}")

    if not isinstance(data, Mapping):
        raise fail(f"must be a table, got {type(data).__name__}")
    for key in data:
        if key not in _TOP_KEYS:
            raise fail(f"unknown table [{key}]{closest_key(str(key), _TOP_KEYS)}")
    folder = Path(base_dir).resolve()
    base = _parse_base(data.get("base", {}), folder, fail)
    settings = _parse_settings(data.get("sweep", {}), name, fail)
    mode = settings["mode"]
    vary = data.get("vary", {})
    if not isinstance(vary, Mapping):
        raise fail("[vary] must be a table of parameter keys")
    axes = tuple(
        axis_paths_relative_to(_parse_axis(key, spec, mode, fail), folder)
        for key, spec in flatten_vary(vary)
    )
    check_distinct_axes(axes, fail)
    if mode is SweepMode.GRID:
        _check_budget(
            math.prod(len(axis.values) for axis in axes),
            [(axis.key, len(axis.values)) for axis in axes],
            fail,
        )
    return SweepSpec(base=base, axes=axes, source=source, **settings)


def estimate_designs(axis_sizes: Iterable[float]) -> float:
    """Designs of a grid with these axis sizes (a float: it may be astronomic or infinite)."""
    return math.prod(float(size) for size in axis_sizes)


def _check_budget(count: float, sizes: list[tuple[str, float]], fail: Fail) -> None:
    """Refuse a sweep of more than MAX_SWEEP_DESIGNS designs, with the estimate and the limit."""
    if count <= MAX_SWEEP_DESIGNS:
        return
    product = " x ".join(f"{_count(size)} ({key})" for key, size in sizes) if len(sizes) > 1 else ""
    raise fail(
        f"the sweep has {_count(count)} designs{' = ' + product if product else ''}; the limit is "
        f"{MAX_SWEEP_DESIGNS:,} designs per sweep; use coarser steps or fewer values"
    )


def _count(value: float) -> str:
    """A design count for a message: digits with separators, or powers of ten when astronomic."""
    if not math.isfinite(value):
        return "more than 1e308"
    return f"{int(value):,}" if value < 1e12 else f"{value:.2e}"


class SweepTable(Section):
    """[sweep]: how the designs are drawn, what each writes, and its time limit."""

    mode: SweepMode = param(SweepMode.GRID, strict=False, doc="grid | random | latin_hypercube")
    samples: int | None = param(None, ge=1, doc="random / latin_hypercube only: how many designs")
    seed: int = param(
        0, ge=0, le=2**63 - 1, doc="random / latin_hypercube only: the sampler's seed"
    )
    name: str = param("", doc="the sweep's name (default: the file's stem)")
    stl: bool = param(True, doc="write each design's STL too")
    density_g_cm3: float | None = param(
        None,
        unit="g/cm^3",
        gt=0.0,
        le=DENSITY_LIMIT_G_CM3,
        doc="material density for the mass (default: PLA, 1.24)",
    )
    time_limit_s: float = param(
        DEFAULT_TIME_LIMIT_S,
        unit="s",
        gt=0.0,
        le=DESIGN_TIME_LIMIT_MAX_S,
        doc="a design running longer is stopped and recorded as 'timeout'",
    )


class _SettingsTable(Section):
    sweep: SweepTable = Field(default_factory=SweepTable)


def _parse_settings(settings: Any, name: str, fail: Fail) -> dict[str, Any]:
    """The ``[sweep]`` table as SweepSpec keyword arguments (validated by :class:`SweepTable`)."""
    try:
        table = _SettingsTable.model_validate({"sweep": settings}).sweep
    except ValidationError as error:
        raise fail(str(parameter_error(_SettingsTable, error))) from None
    if table.mode is SweepMode.GRID and table.samples is not None:
        raise fail("sweep.samples applies to mode = 'random' or 'latin_hypercube', not 'grid'")
    if table.mode is not SweepMode.GRID:
        if table.samples is None:
            raise fail(
                "sweep.samples must be a whole number >= 1 "
                f"for mode = {table.mode.value!r}, got None"
            )
        _check_budget(table.samples, [], fail)
    return {
        "name": table.name or name,
        "mode": table.mode,
        "samples": table.samples,
        "seed": table.seed,
        "stl": table.stl,
        "density_g_cm3": table.density_g_cm3,
        "time_limit_s": table.time_limit_s,
    }


def _parse_base(table: Any, base_dir: Path, fail: Fail) -> PropellerParameters:
    if not isinstance(table, Mapping):
        raise fail('[base] must be a table of design parameters (or config = "path.toml")')
    inline = dict(table)
    config = inline.pop("config", None)
    # as the build reads a design file
    inline = PropellerParameters.paths_relative_to(inline, base_dir)
    if config is None:
        merged: dict[str, Any] = PropellerParameters().to_dict()
    elif isinstance(config, str):
        config_path = Path(config) if Path(config).is_absolute() else base_dir / config
        try:
            merged = PropellerParameters.from_toml(config_path).to_dict()
        except ParameterError as error:
            raise fail(f"base.config: {error}") from None
    else:
        raise fail(f"base.config must be a path string, got {shown(config)}")
    _deep_merge(merged, inline)
    try:
        return PropellerParameters.from_dict(merged)
    except ParameterError as error:
        raise fail(f"[base] {error}") from None


def axis_paths_relative_to(axis: VaryAxis, folder: Path) -> VaryAxis:
    """``axis`` with each value that is a file path (``airfoil.file``) made relative to ``folder``,
    by the rule of a design file (:meth:`PropellerParameters.paths_relative_to`).

    Args:
        axis: a varied parameter with its values (a vector element or bounds are returned as they
            are).
        folder: the folder of the file that gave the values.

    Returns:
        ``axis``, or a copy whose file-path values are resolved against ``folder``.
    """
    if axis.index is not None or axis.is_bounds:
        return axis

    def resolved(value: Any) -> Any:
        data: dict[str, Any] = {axis.path[-1]: value}
        for part in reversed(axis.path[:-1]):
            data = {part: data}
        data = PropellerParameters.paths_relative_to(data, folder)
        for part in axis.path:
            data = data[part]
        return data

    return dataclasses.replace(axis, values=tuple(resolved(value) for value in axis.values))


def _deep_merge(target: dict[str, Any], changes: Mapping[str, Any]) -> None:
    for key, value in changes.items():
        if isinstance(value, Mapping) and isinstance(target.get(key), dict):
            _deep_merge(target[key], value)
        else:
            target[key] = value


def flatten_vary(vary: Mapping[str, Any], prefix: str = "") -> Iterable[tuple[str, Any]]:
    """``hub.radius = [..]`` (a nested TOML table) and ``"hub.radius" = [..]`` mean the same.

    Args:
        vary: a ``[vary]`` table as read, its keys dotted or nested.
        prefix: the dotted key of the tables ``vary`` is inside (for the recursion).

    Returns:
        ``(dotted key, spec)`` pairs, one per varied parameter, in the table's order.
    """
    for key, value in vary.items():
        if isinstance(value, Mapping) and not set(value) <= _SPEC_KEYS:
            yield from flatten_vary(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", value


def check_distinct_axes(axes: tuple[VaryAxis, ...], fail: Fail) -> None:
    """No two axes may set the same parameter (or the same element of a vector).

    Args:
        axes: the varied parameters.
        fail: makes the error raised for two axes that set the same parameter.

    Returns:
        None; raises ``fail``'s error naming both keys when two axes overlap.
    """
    seen: dict[tuple[str, ...], list[VaryAxis]] = {}
    for axis in axes:
        for other in seen.get(axis.path, []):
            if other.index is None or axis.index is None or other.index == axis.index:
                raise fail(f"vary.{axis.key!r} and vary.{other.key!r} set the same parameter")
        seen.setdefault(axis.path, []).append(axis)


@dataclass(frozen=True)
class Leaf:
    """What one axis sets, as the schema declares it: a whole parameter or one element of a vector.

    Attributes:
        key: the dotted key with the element, e.g. ``"centerline.p2[2]"``, for range messages.
        kind: ``bool``, ``int``, ``float``, ``str``, an Enum class, or ``tuple`` (a whole vector).
        length: elements of a whole vector, else 0.
        bounds: the allowed interval of the value (of each element of a vector).
        unit: the parameter's unit, for messages.
        choices: the allowed values of a choice parameter (an Enum's values), else ().
    """

    key: str
    kind: Any
    length: int
    bounds: Bounds
    unit: str
    choices: tuple[str, ...] = ()

    @property
    def numeric(self) -> bool:
        """An int or float: ranges and bounds apply."""
        return self.kind in (int, float)


def _specs() -> dict[str, ParameterSpec]:
    return {spec.key: spec for spec in parameter_specs()}


def resolve_leaf(key: str, fail: Fail) -> tuple[tuple[str, ...], int | None, Leaf]:
    """The parameter path, vector index and schema entry that ``key`` names.

    Args:
        key: a varied key, e.g. ``"hub.radius"`` or ``"centerline.p2[2]"``.
        fail: makes the error raised for a key that names no parameter that can be varied.

    Returns:
        ``(path, index, leaf)``: the table path, the vector element (None for a whole parameter) and
            what the
        schema declares for it.
    """
    where = f"vary.{shown(key)}"
    match = _KEY_PATTERN.match(key)
    if not match:
        raise fail(f'{where} is not a parameter key; write e.g. "hub.radius" or "centerline.p2[2]"')
    dotted = match["path"]
    index = None if match["index"] is None else int(match["index"])
    if dotted == "name":
        raise fail(f"{where}: the name cannot be varied; each design is named by its id")
    specs = _specs()
    spec = specs.get(dotted)
    if spec is None:
        inside = [known for known in specs if known.startswith(dotted + ".")]
        if inside:
            raise fail(f"{where} is a table; vary one of its keys, e.g. {inside[0]!r}")
        raise fail(f"{where}: unknown key {dotted!r}{closest_key(dotted, list(specs))}")
    path = tuple(dotted.split("."))
    if index is None:  # a choice is one of its Enum's values, as written in a design file
        choices = tuple(str(choice.value) for choice in spec.choices)
        return (
            path,
            index,
            Leaf(
                dotted, str if choices else spec.kind, spec.length, spec.bounds, spec.unit, choices
            ),
        )
    if spec.kind is not tuple:
        raise fail(f"{where}: {dotted} is not a vector, so [{index}] does not apply")
    if index >= spec.length:
        raise fail(f"{where}: index {index} is out of range; {dotted} has {spec.length} elements")
    return path, index, Leaf(key, float, 0, spec.bounds, spec.unit)


def _parse_axis(key: str, spec: Any, mode: SweepMode, fail: Fail) -> VaryAxis:
    where = f"vary.{shown(key)}"
    path, index, leaf = resolve_leaf(key, fail)

    def value_of(item: Any, what: str) -> Any:
        return checked_value(item, leaf, f"{where} {what}", fail)

    integer = leaf.kind is int
    if isinstance(spec, list):
        if not spec:
            raise fail(f"{where} is an empty list")
        values = tuple(value_of(item, f"item {i}") for i, item in enumerate(spec))
        return VaryAxis(key, path, index, values=values, integer=integer)
    if not isinstance(spec, Mapping):
        raise fail(
            f"{where} must be a list, {{start, stop, "
            f"step}} / {{start, stop, num}} or {{low, high}}, "
            f"got {shown(spec)}"
        )
    keys = set(spec)
    if not leaf.numeric:
        raise fail(f"{where}: ranges and bounds need a number parameter; give a list of values")
    if keys == {"low", "high"}:
        if mode is SweepMode.GRID:
            raise fail(
                f"{where}: bounds {{low, high}} need sweep.mode = 'random' or 'latin_hypercube'; "
                "a grid takes a list or {start, stop, step}"
            )
        low, high = value_of(spec["low"], "low"), value_of(spec["high"], "high")
        if not low < high:
            raise fail(f"{where}: low = {low!r} must be below high = {high!r}")
        return VaryAxis(key, path, index, low=low, high=high, integer=integer)
    if keys in ({"start", "stop", "step"}, {"start", "stop", "num"}):
        start, stop = value_of(spec["start"], "start"), value_of(spec["stop"], "stop")
        return VaryAxis(
            key,
            path,
            index,
            values=_range_values(spec, start, stop, leaf, where, fail),
            integer=integer,
        )
    raise fail(
        f"{where} has keys {sorted(keys)}; use {{start, "
        f"stop, step}}, {{start, stop, num}} or {{low, high}}"
    )


def _range_values(
    spec: Mapping[str, Any], start: Any, stop: Any, leaf: Leaf, where: str, fail: Fail
) -> tuple[Any, ...]:
    """The values of ``{start, stop, step}`` (stop included when it falls on a step) or ``{start,
    stop, num}``.

    The number of values is checked against the budget before any value is made; ``start``
    and ``stop`` are in range, so every value between them is.
    """
    if stop < start:
        raise fail(f"{where}: stop = {stop!r} must not be below start = {start!r}")
    if "num" in spec:
        num = spec["num"]
        if not _is_int(num) or num < 1:
            raise fail(f"{where}: num must be a whole number >= 1, got {shown(num)}")
        if leaf.kind is int:
            raise fail(
                f"{where}: {{start, stop, num}} is for float parameters; use {{start, stop, step}}"
            )
        _check_budget(num, [], lambda message: fail(f"{where}: {message}"))
        return (
            (start,)
            if num == 1
            else tuple(
                round(start + (stop - start) * i / (num - 1), _RANGE_DIGITS) for i in range(num)
            )
        )
    step = _checked_type(spec["step"], leaf, f"{where} step", fail)
    if not step > 0:
        raise fail(f"{where}: step must be positive, got {shown(step)}")
    spans = (stop - start) / step  # a float even for ints: inf when step is tiny
    _check_budget(spans + 1.0, [], lambda message: fail(f"{where}: {message}"))
    count = math.floor(spans + 1e-9) + 1
    return tuple(
        start + i * step if leaf.kind is int else round(start + i * step, _RANGE_DIGITS)
        for i in range(count)
    )


def checked_value(item: Any, leaf: Leaf, where: str, fail: Fail) -> Any:
    """``item`` of the parameter's type and inside its range (each element of a vector).

    Args:
        item: a value as read from the file.
        leaf: the parameter (or vector element) it is for (:func:`resolve_leaf`).
        where: names the value in a message, e.g. ``"vary.hub.radius item 0"``.
        fail: makes the error raised for a value of the wrong type, out of range or not a choice.

    Returns:
        The value as the parameter's type (an int as float for a float parameter, a vector as a
            list).
    """
    value = _checked_type(item, leaf, where, fail)
    if leaf.choices:
        if value not in leaf.choices:
            raise fail(
                f"{where} = {shown(value)} is not allowed; choose one of {', '.join(leaf.choices)}"
            )
        return value
    numbers = value if isinstance(value, list) else [value] if leaf.numeric else []
    for position, number in enumerate(numbers):
        element = f"{leaf.key}[{position}]" if isinstance(value, list) else leaf.key
        try:
            check_in_bounds(element, number, leaf.bounds, leaf.unit)
        except ValueError as error:
            raise fail(f"{where}: {error}") from None
    return value


def _checked_type(item: Any, leaf: Leaf, where: str, fail: Fail) -> Any:
    """``item`` as the parameter's type: ints stay ints, ints become floats for float keys, no NaN
    or inf."""
    if leaf.kind is bool:
        if not isinstance(item, bool):
            raise fail(f"{where} must be true or false, got {shown(item)}")
        return item
    if leaf.kind is int:
        if not _is_int(item):
            raise fail(f"{where} must be a whole number{_within(leaf)}, got {shown(item)}")
        return item
    if leaf.kind is float:
        if not _is_number(item) or not math.isfinite(item):
            raise fail(f"{where} must be a finite number{_within(leaf)}, got {shown(item)}")
        return float(item)
    if leaf.kind is str:
        if not isinstance(item, str):
            raise fail(f"{where} must be a string, got {shown(item)}")
        return item
    if leaf.kind is tuple:
        if (
            not isinstance(item, list)
            or len(item) != leaf.length
            or not all(_is_number(x) and math.isfinite(x) for x in item)
        ):
            raise fail(
                f"{where} must be a list of {leaf.length} finite "
                f"numbers (a whole vector), got {shown(item)}"
            )
        return [float(x) for x in item]
    raise fail(
        f"{where}: cannot vary this parameter"
    )  # pragma: no cover - the schema has no other kinds


def _within(leaf: Leaf) -> str:
    """`` in [low, high] unit`` of a numeric parameter, for a message; empty for the others."""
    return f" in {leaf.bounds}{' ' + leaf.unit if leaf.unit else ''}" if leaf.numeric else ""


def _is_int(value: Any) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
