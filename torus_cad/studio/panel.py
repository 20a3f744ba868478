"""The parameters panel, derived from the parameter schema: no hand-kept list of fields.

Every declared parameter (torus_cad.parameters: its dotted key, type, unit, allowed range and
one-line doc) becomes a :class:`PanelField` in the :class:`PanelGroup` of its TOML table, so a
parameter added to the schema appears in the studio by itself. This module is plain data and
conversions (no web framework): the page's state names, the state values of a design, and the
design a page's state describes.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import Enum, StrEnum
from pathlib import Path
from typing import Any

from torus_cad.errors import ParameterError
from torus_cad.parameters.schema import Bounds, ParameterSpec

#: Prefix of the page's state names of parameters (state names must be JavaScript identifiers).
STATE_PREFIX = "p_"

#: A slider gets at most this many steps; finer values go through the number field.
SLIDER_STEPS = 200


class FieldKind(StrEnum):
    """How a parameter is entered."""

    INTEGER = "integer"
    NUMBER = "number"
    BOOLEAN = "boolean"
    CHOICE = "choice"
    CHOICES = "choices"  # several of the choices (e.g. export.formats)
    # a list of numbers of any length (a station table's column), typed as "1, 2.5, 3"
    NUMBERS = "numbers"
    TEXT = "text"


@dataclass(frozen=True)
class PanelField:
    """One parameter as the panel shows it.

    Attributes:
        key: dotted key, e.g. ``"hub.radius"`` (a vector is one field with several elements).
        kind: how it is entered.
        label: the field's name in its group, e.g. ``"radius"``.
        unit: ``"mm"``, ``"deg"``, ... or ``""``.
        doc: one-line description.
        state_names: the page's state name of each element (one for a scalar).
        low, high: allowed interval (of each element), None when unbounded.
        low_open, high_open: whether an end is excluded.
        slider: ``(low, high, step)`` of a slider, or None for a number field only.
        choices: allowed values of a choice.
        element_units: the unit of each element (a control point's are ``deg, mm, mm``).
        read_only: a file path: shown, never taken from the page (the server would read it).
    """

    key: str
    kind: FieldKind
    label: str
    unit: str
    doc: str
    state_names: tuple[str, ...]
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    slider: tuple[float, float, float] | None = None
    choices: tuple[str, ...] = ()
    element_units: tuple[str, ...] = ()
    read_only: bool = False

    @property
    def is_vector(self) -> bool:
        """Whether the field has several elements (e.g. a control point)."""
        return len(self.state_names) > 1

    @property
    def range_text(self) -> str:
        """The allowed interval as text, e.g. ``"[0.5, 1000] mm"`` (empty when unbounded)."""
        if self.low is None and self.high is None:
            return ""
        low = "-inf" if self.low is None else f"{self.low:g}"
        high = "inf" if self.high is None else f"{self.high:g}"
        text = (
            f"{'(' if self.low_open or self.low is None else '['}{low}, {high}"
            f"{')' if self.high_open or self.high is None else ']'}"
        )
        return f"{text} {self.unit}".strip()

    @property
    def hint(self) -> str:
        """The field's help line: its doc and allowed range."""
        allowed = f"; allowed {self.range_text}" if self.range_text else ""
        return f"{self.doc}{allowed}"


@dataclass(frozen=True)
class PanelGroup:
    """The fields of one TOML table (``section == ""``: the top-level keys)."""

    section: str
    title: str
    doc: str
    fields: tuple[PanelField, ...]


def state_name(key: str, element: int | None = None) -> str:
    """The page's state name of a dotted key (and vector element): ``hub.radius`` ->
    ``p_hub__radius``."""
    name = STATE_PREFIX + key.replace(".", "__")
    return name if element is None else f"{name}__{element}"


def _nice_step(span: float) -> float:
    """A round step (1, 2 or 5 times a power of ten) giving at most SLIDER_STEPS steps over
    ``span``."""
    raw = span / SLIDER_STEPS
    power = 10.0 ** math.floor(math.log10(raw))
    return next(factor * power for factor in (1.0, 2.0, 5.0, 10.0) if factor * power >= raw)


def _slider(kind: FieldKind, explore: Bounds | None) -> tuple[float, float, float] | None:
    """A slider over the range worth exploring (the schema's fuzz range), when it is finite."""
    if (
        explore is None
        or explore.low is None
        or explore.high is None
        or explore.high <= explore.low
    ):
        return None
    if kind is FieldKind.INTEGER:
        return (float(math.ceil(explore.low)), float(math.floor(explore.high)), 1.0)
    return (float(explore.low), float(explore.high), _nice_step(explore.high - explore.low))


def _kind(spec: ParameterSpec) -> FieldKind:
    if spec.choices and spec.kind is tuple:
        return FieldKind.CHOICES
    if spec.kind is tuple and not spec.length:
        return FieldKind.NUMBERS
    if spec.choices or (isinstance(spec.kind, type) and issubclass(spec.kind, Enum)):
        return FieldKind.CHOICE
    if spec.kind is bool:
        return FieldKind.BOOLEAN
    if spec.kind is int:
        return FieldKind.INTEGER
    if spec.kind in (float, tuple):
        return FieldKind.NUMBER
    return FieldKind.TEXT


def panel_field(spec: ParameterSpec, read_only: bool = False) -> PanelField:
    """The panel field of one schema parameter (``read_only`` for a file path)."""
    kind = _kind(spec)
    names = (
        tuple(state_name(spec.key, i) for i in range(spec.length))
        if spec.length
        else (state_name(spec.key),)
    )
    bounds = spec.bounds
    choices = tuple(
        str(choice.value if isinstance(choice, Enum) else choice) for choice in spec.choices
    )
    numeric_scalar = kind in (FieldKind.INTEGER, FieldKind.NUMBER) and not spec.length
    slider = _slider(kind, spec.fuzz or bounds) if numeric_scalar else None
    return PanelField(
        spec.key,
        kind,
        spec.key.rpartition(".")[2],
        spec.unit,
        spec.doc,
        names,
        bounds.low,
        bounds.high,
        bounds.low_open,
        bounds.high_open,
        slider,
        choices,
        _element_units(spec.unit, len(names)),
        read_only,
    )


def _element_units(unit: str, count: int) -> tuple[str, ...]:
    """``"deg, mm, mm"`` names each element's unit; a single unit applies to all."""
    parts = [part.strip() for part in unit.split(",")]
    return tuple(parts) if len(parts) == count else (unit,) * count


def panel_groups(
    specs: Iterable[ParameterSpec],
    section_docs: Mapping[str, str] | None = None,
    path_keys: Iterable[str] = (),
) -> list[PanelGroup]:
    """The panel's groups in the schema's order: top-level keys first, then one group per table;
    the fields of ``path_keys`` (file paths) read-only."""
    fields: dict[str, list[PanelField]] = {}
    paths = set(path_keys)
    for spec in specs:
        fields.setdefault(spec.key.rpartition(".")[0], []).append(
            panel_field(spec, spec.key in paths)
        )
    docs = dict(section_docs or {})
    order = ([""] if "" in fields else []) + [section for section in fields if section]
    return [
        PanelGroup(section, section or "propeller", docs.get(section, ""), tuple(fields[section]))
        for section in order
    ]


def schema_groups() -> list[PanelGroup]:
    """The panel's groups of the installed parameter schema."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.parameters.schema import iter_parameter_specs, section_docs

    specs = list(iter_parameter_specs(PropellerParameters))
    return panel_groups(
        specs, section_docs(PropellerParameters), path_keys(PropellerParameters, specs)
    )


def path_keys(model: Any, specs: Iterable[ParameterSpec]) -> set[str]:
    """The text parameters that name files: those the schema resolves against a design file's folder
    (``paths_relative_to``), found by asking it about a relative name in each text parameter."""
    probe, folder = "studio-probe", Path("/studio-probe-folder")
    keys = set()
    for spec in specs:
        if spec.kind is not str:
            continue
        *tables, leaf = spec.key.split(".")
        data: dict[str, Any] = {leaf: probe}
        for table in reversed(tables):
            data = {table: data}
        if _lookup(model.paths_relative_to(data, folder), spec.key) != probe:
            keys.add(spec.key)
    return keys


def _plain(value: Any) -> Any:
    return value.value if isinstance(value, Enum) else value


def _lookup(data: Mapping[str, Any], key: str) -> Any:
    for part in key.split("."):
        data = data[part]
    return data


def state_values(design: Mapping[str, Any], groups: Iterable[PanelGroup]) -> dict[str, Any]:
    """The page's state of a design (``PropellerParameters.to_dict()``): state name -> value."""
    values: dict[str, Any] = {}
    for group in groups:
        for field in group.fields:
            value = _plain(_lookup(design, field.key))
            if field.kind is FieldKind.CHOICES:
                values[field.state_names[0]] = [_plain(item) for item in value]
            elif field.kind is FieldKind.NUMBERS:
                values[field.state_names[0]] = ", ".join(f"{float(item):g}" for item in value)
            elif field.is_vector:
                values.update({name: _plain(item) for name, item in zip(field.state_names, value)})
            else:
                values[field.state_names[0]] = value
    return values


_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def _number(field: PanelField, label: str, raw: Any) -> Any:
    """A typed number from the page (a number, or the text of a number field)."""
    if isinstance(raw, bool):
        raise ParameterError(f"{label} must be a number, got {raw!r}")
    if isinstance(raw, (int, float)):
        value: Any = raw
    else:
        text = str(raw).strip()
        if not _NUMBER.match(text):
            raise ParameterError(
                f"{label} must be a number, got {text!r}" if text else f"{label} needs a value"
            )
        value = float(text)
    if field.kind is FieldKind.INTEGER and float(value).is_integer():
        return int(value)
    # A whole number typed into a float field stays a float; a fraction in an integer field is
    # passed on as a float so that the schema refuses it with its own message.
    return float(value)


def _value(field: PanelField, values: Mapping[str, Any]) -> Any:
    if field.kind in (FieldKind.INTEGER, FieldKind.NUMBER):
        if field.is_vector:
            return [
                _number(field, f"{field.key}[{index}]", values[name])
                for index, name in enumerate(field.state_names)
            ]
        return _number(field, field.key, values[field.state_names[0]])
    raw = values[field.state_names[0]]
    if field.kind is FieldKind.BOOLEAN:
        return bool(raw)
    if field.kind is FieldKind.CHOICES:
        return [str(item) for item in raw or []]
    if field.kind is FieldKind.NUMBERS:
        items = [
            item for item in re.split(r"[,\s]+", "" if raw is None else str(raw).strip()) if item
        ]
        return [_number(field, f"{field.key}[{index}]", item) for index, item in enumerate(items)]
    return "" if raw is None else str(raw)


def design_from_state(values: Mapping[str, Any], groups: Iterable[PanelGroup]) -> dict[str, Any]:
    """The nested design (``PropellerParameters.from_dict`` input) the page's state describes.

    Raises ParameterError, naming the field, for text that is not a number.
    """
    design: dict[str, Any] = {}
    for group in groups:
        table = design
        for part in group.section.split(".") if group.section else []:
            table = table.setdefault(part, {})
        for field in group.fields:
            table[field.label] = _value(field, values)
    return design


_KEY_AT_START = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*)(?:\[(\d+)\])?")


def field_of_message(message: str, groups: Iterable[PanelGroup]) -> tuple[str, int | None] | None:
    """The field (dotted key, vector element or None) a one-line refusal names first, if any."""
    match = _KEY_AT_START.match(message)
    keys = {field.key for group in groups for field in group.fields}
    if match is None:
        return None
    key = match.group(1)
    while key and key not in keys:  # "transforms.scale_x must ..." or "unknown key 'hub.radus'"
        key = key.rpartition(".")[0]
    if not key:
        return None
    return key, int(match.group(2)) if match.group(2) is not None else None
