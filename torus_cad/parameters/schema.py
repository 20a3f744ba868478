"""The machinery of the parameter schema: how a parameter is declared, checked and described.

Each parameter is declared once, as a field of a :class:`Section` made with :func:`param`
(default, unit, allowed range, one-line description). Everything else is derived from those
declarations: validation and its one-line messages (:func:`parameter_error`), the commented
TOML of ``torus-cad defaults``, the README's configuration table, the fuzz sampler's ranges,
the sweep's axis checks and the studio's panel (all through :func:`parameter_specs`).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Annotated, Any, get_args, get_origin

import annotated_types
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError
from pydantic.fields import FieldInfo

from torus_cad.errors import ParameterError, shown

# declared beside the command line's option ranges
from torus_cad.runtime.bounds import Bounds as Bounds


def _list_to_tuple(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


#: Put on a vector's annotation: TOML gives lists, the frozen parameters keep tuples.
AS_TUPLE = BeforeValidator(_list_to_tuple)

#: Fixed-length vectors of floats (elements unbounded; cross-field validators check them).
Vector2 = Annotated[tuple[float, float], AS_TUPLE]
Vector3 = Annotated[tuple[float, float, float], AS_TUPLE]


def param(
    default: Any,
    *,
    doc: str,
    unit: str = "",
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    fuzz: tuple[float, float] | None = None,
    strict: bool | None = None,
) -> Any:
    """Declare a parameter: its default, unit (``"mm"``, ``"deg"``, ...), allowed range and one-line
    doc.

    ``fuzz`` narrows the range the fuzz sampler draws from (default: the allowed range), for
    parameters whose allowed range is wider than the designs worth fuzzing.
    """
    extra: dict[str, Any] = {"unit": unit}
    if fuzz is not None:
        extra["fuzz"] = list(fuzz)
    return Field(
        default, description=doc, ge=ge, gt=gt, le=le, lt=lt, json_schema_extra=extra, strict=strict
    )


class Section(BaseModel):
    """Base of every table of parameters: frozen, strict types, no unknown keys, finite numbers."""

    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        strict=True,
        allow_inf_nan=False,
        use_enum_values=False,
        validate_default=False,
    )

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(
            f"parameters are frozen: make a changed copy with "
            f"with_values({{{name!r}: {value!r}}}) instead of setting {name}"
        )


# -- describing the declarations -------------------------------------------------------------------


def check_in_bounds(dotted: str, value: float, bounds: Bounds, unit: str = "") -> None:
    """Raise ValueError naming the field, the value and the interval when ``value`` lies outside."""
    if not bounds.contains(value):
        raise ValueError(
            f"{dotted} = {_value_text(value)} is out of range; "
            f"allowed {bounds}{' ' + unit if unit else ''}"
        )


def bounds_of(metadata: Sequence[Any]) -> Bounds:
    """The interval that annotated-types constraints (Ge, Gt, Le, Lt) describe."""
    bounds: dict[str, Any] = {}
    for item in metadata:
        if isinstance(item, annotated_types.Ge):
            bounds.update(low=item.ge, low_open=False)
        elif isinstance(item, annotated_types.Gt):
            bounds.update(low=item.gt, low_open=True)
        elif isinstance(item, annotated_types.Le):
            bounds.update(high=item.le, high_open=False)
        elif isinstance(item, annotated_types.Lt):
            bounds.update(high=item.lt, high_open=True)
    return Bounds(**bounds)


@dataclass(frozen=True)
class ParameterSpec:
    """One declared parameter, as the docs, the fuzz sampler, sweeps and the studio see it.

    Attributes:
        key: dotted key, e.g. ``"hub.radius"``.
        kind: ``bool``, ``int``, ``float``, ``str``, an Enum class, or ``tuple`` (a vector of
            floats).
        default: the default value (tuples for vectors, Enum members for choices).
        unit: ``"mm"``, ``"deg"``, ... or ``""``.
        doc: one-line description.
        bounds: allowed interval of the value (of each element for a vector; cross-field
            limits are checked by the section's validators and are not listed here).
        length: number of elements of a vector, else 0.
        fuzz: the interval the fuzz sampler draws from (the allowed one unless narrowed).
        choices: the allowed values of an Enum parameter, else ().
    """

    key: str
    kind: Any
    default: Any
    unit: str
    doc: str
    bounds: Bounds
    length: int = 0
    fuzz: Bounds | None = None
    choices: tuple[Any, ...] = ()

    @property
    def section(self) -> str:
        """The TOML table the parameter sits in (``""`` for top-level keys)."""
        return self.key.rpartition(".")[0]


def _unwrap(annotation: Any) -> tuple[Any, list[Any]]:
    """The bare type of an annotation and its Annotated metadata."""
    metadata: list[Any] = []
    while get_origin(annotation) is Annotated:
        annotation, *extra = get_args(annotation)
        metadata.extend(extra)
    return annotation, metadata


def _element_metadata(vector_type: Any) -> list[Any]:
    element = get_args(vector_type)[0]
    _, metadata = _unwrap(element)
    expanded: list[Any] = []
    for item in metadata:
        expanded.extend(item.metadata if isinstance(item, FieldInfo) else [item])
    return expanded


def _is_enum(kind: Any) -> bool:
    return isinstance(kind, type) and issubclass(kind, Enum)


def _spec(key: str, info: FieldInfo) -> ParameterSpec:
    kind, metadata = _unwrap(info.annotation)
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    unit, doc = str(extra.get("unit", "")), info.description or ""
    fuzz = Bounds(*extra["fuzz"]) if "fuzz" in extra else None  # type: ignore[misc]
    if get_origin(kind) is tuple and get_args(kind)[-1] is Ellipsis and _is_enum(get_args(kind)[0]):
        # a list of choices (export.formats): each element one of the Enum's values
        return ParameterSpec(
            key, tuple, info.default, unit, doc, Bounds(), choices=tuple(get_args(kind)[0])
        )
    if get_origin(kind) is tuple and get_args(kind)[-1] is Ellipsis:
        # a list of numbers of any length (a station table's column): length 0, no fuzz range
        return ParameterSpec(
            key, tuple, info.default, unit, doc, bounds_of(_element_metadata(kind))
        )
    if get_origin(kind) is tuple:
        bounds = bounds_of(_element_metadata(kind))
        return ParameterSpec(
            key, tuple, info.default, unit, doc, bounds, len(get_args(kind)), fuzz or bounds
        )
    bounds = bounds_of([*info.metadata, *metadata])
    if isinstance(kind, type) and issubclass(kind, Enum):
        return ParameterSpec(key, kind, info.default, unit, doc, bounds, choices=tuple(kind))
    return ParameterSpec(key, kind, info.default, unit, doc, bounds, fuzz=fuzz or bounds)


def iter_parameter_specs(model: type[BaseModel], prefix: str = "") -> Iterator[ParameterSpec]:
    """Every leaf parameter of ``model``, depth first in declaration order."""
    for name, info in model.model_fields.items():
        annotation, _ = _unwrap(info.annotation)
        if isinstance(annotation, type) and issubclass(annotation, BaseModel):
            yield from iter_parameter_specs(annotation, f"{prefix}{name}.")
        else:
            yield _spec(prefix + name, info)


def section_docs(model: type[BaseModel], prefix: str = "") -> dict[str, str]:
    """Dotted table name -> the table's one-line description (its class docstring's first line;
    empty for a table without a docstring)."""
    docs: dict[str, str] = {}
    for name, info in model.model_fields.items():
        annotation, _ = _unwrap(info.annotation)
        if isinstance(annotation, type) and issubclass(annotation, BaseModel):
            first_line, _, _ = (annotation.__doc__ or "").strip().partition("\n")
            docs[prefix + name] = first_line.strip().rstrip(".")
            docs.update(section_docs(annotation, f"{prefix}{name}."))
    return docs


# -- one-line messages from pydantic's errors ------------------------------------------------------

_TYPE_WORDS = {
    "int_type": "a whole number",
    "int_from_float": "a whole number",
    "float_type": "a number",
    "bool_type": "true or false",
    "string_type": "a string",
    "dict_type": "a table",
    "model_type": "a table",
    "tuple_type": "a list",
    "list_type": "a list",
}


def _dotted(location: Sequence[Any]) -> str:
    text = ""
    for part in location:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


#: What a TOML file calls the Python types its values arrive as (a message speaks TOML, not Python).
_TOML_WORDS: dict[type, str] = {
    bool: "boolean",
    int: "integer",
    float: "float",
    str: "string",
    list: "array",
    tuple: "array",
    dict: "table",
}


def _as_toml_lists(value: Any) -> Any:
    """``value`` with every tuple (what validation turns an array into) as a list, so it prints as
    ``[...]``."""
    if isinstance(value, list | tuple):
        return [_as_toml_lists(item) for item in value]
    if isinstance(value, dict):
        return {key: _as_toml_lists(item) for key, item in value.items()}
    return value


def _describe(value: Any) -> str:
    """The value in the words of a TOML file, its text cut short (40 characters): ``array of 25
    items [[1, 2, 3], ...``, ``string 'x'``."""
    word = next(
        (name for kind, name in _TOML_WORDS.items() if type(value) is kind), type(value).__name__
    )
    if isinstance(value, list | tuple):
        word += f" of {len(value)} item{'s' if len(value) != 1 else ''}"
    return f"{word} {shown(_as_toml_lists(value), 40)}"


def _value_text(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, int) and not isinstance(value, bool):
        text = (
            str(value)
            if abs(value) < 10**15
            else f"{float(value):g}"
            if abs(value) < 10**300
            else "a huge number"
        )
        return text
    return shown(value)


def closest_key(key: str, known: Sequence[str], prefix: str = "") -> str:
    """``"; did you mean 'prefix.key'?"`` for the known key closest to ``key``, else the known
    keys."""
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.5)
    if close:
        return f"; did you mean {prefix + close[0]!r}?"
    return f"; known keys: {', '.join(prefix + name for name in sorted(known))}"


def _model_at(model: type[BaseModel], location: Sequence[Any]) -> type[BaseModel] | None:
    for part in location:
        info = model.model_fields.get(str(part))
        annotation = _unwrap(info.annotation)[0] if info is not None else None
        if not (isinstance(annotation, type) and issubclass(annotation, BaseModel)):
            return None
        model = annotation
    return model


def _spec_at(model: type[BaseModel], location: Sequence[Any]) -> ParameterSpec | None:
    names = [str(part) for part in location if not isinstance(part, int)]
    key = ".".join(names)
    return next((spec for spec in iter_parameter_specs(model) if spec.key == key), None)


#: The top-level tables of a sweep file (torus_cad.batch.sweep_file), which no design has.
_SWEEP_TABLES = ("base", "sweep", "vary")


def _message(model: type[BaseModel], error: Any) -> str:
    location = tuple(error["loc"])
    kind, value = error["type"], error.get("input")
    field = _dotted(location)
    if kind == "extra_forbidden":
        parent = _model_at(model, location[:-1])
        known = list(parent.model_fields) if parent is not None else []
        prefix = _dotted(location[:-1]) + "." if len(location) > 1 else ""
        if field in _SWEEP_TABLES:  # a sweep file given to a command that reads one design
            return (
                f"unknown key {field!r}: this looks like a "
                "sweep file; run it with 'torus-cad sweep FILE'"
            )
        return f"unknown key {shown(field)}{closest_key(str(location[-1]), known, prefix)}"
    if kind == "value_error":
        cause = error.get("ctx", {}).get("error")
        return str(cause) if cause is not None else error["msg"]
    spec = _spec_at(model, location)
    if kind in ("model_type", "dict_type") and _model_at(model, location) is not None:
        return f"{field} must be a table ([{field}]), got {_describe(value)}"
    if kind in ("finite_number",):
        return f"{field} = {shown(value)} must be a finite number"
    if (
        kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal")
        and spec is not None
    ):
        try:
            check_in_bounds(field, value, spec.bounds, spec.unit)
        except ValueError as out_of_range:
            return str(out_of_range)
    if kind in ("enum", "is_instance_of") and spec is not None and spec.choices:
        choices = ", ".join(str(choice.value) for choice in spec.choices)
        return f"{field} = {shown(value)} is not allowed; choose one of {choices}"
    if (
        kind in ("tuple_type", "too_short", "too_long", "missing")
        and spec is not None
        and spec.length
    ):
        vector_field = _dotted([part for part in location if not isinstance(part, int)])
        return f"{vector_field} must be a list of {spec.length} numbers, got {_describe(value)}"
    if kind in _TYPE_WORDS:
        return f"{field} must be {_TYPE_WORDS[kind]}, got {_describe(value)}"
    return f"{field}: {error['msg']} (got {_describe(value)})"


def parameter_error(model: type[BaseModel], error: ValidationError) -> ParameterError:
    """The first of pydantic's errors as one ParameterError line naming the field, value and
    range."""
    return ParameterError(_message(model, error.errors(include_url=False)[0]))
