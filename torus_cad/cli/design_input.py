"""The design a command reads: a TOML file (or the defaults) with ``--set key=value`` overrides, and
the command-line options that stand for schema keys. Loaded by the commands that read a design (the
schema takes most of a second), never by the parser's start-up."""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from typing import Any

from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters, parameter_specs, resolve_parameters
from torus_cad.parameters.config_file import check_toml_shape
from torus_cad.parameters.design import ExportFormat
from torus_cad.parameters.schema import ParameterSpec, iter_parameter_specs
from torus_cad.runtime.extras import require_extra


def _parse_override(text: str) -> tuple[str, Any]:
    if "=" not in text:
        raise ParameterError(f"--set {text!r} must look like key=value, e.g. hub.radius=12")
    key, raw = text.split("=", 1)
    # too deep or too long: named, not a crash
    check_toml_shape(f"{key.strip()} = {raw}", "--set", lines=False)
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        value = raw  # a bare word: treat as a string (e.g. name=my_prop)
    except ValueError as error:  # e.g. an integer of more than 4300 digits
        raise ParameterError(f"--set {key.strip()}: {_first_clause(error)}") from None
    return key.strip(), value


def _as_declared_strings(changes: dict[str, Any]) -> dict[str, Any]:
    """``changes`` with a number given to a text parameter taken as its text: ``--set
    airfoil.naca=4415`` means the designation '4415', as a user types it, not the integer TOML
    reads."""
    text_keys = {spec.key for spec in iter_parameter_specs(PropellerParameters) if spec.kind is str}
    return {
        key: str(value)
        if key in text_keys and isinstance(value, int | float) and not isinstance(value, bool)
        else value
        for key, value in changes.items()
    }


def _first_clause(error: BaseException) -> str:
    """The error's message up to its first ';', on one line."""
    return " ".join(str(error).split(";")[0].split())[:200]


def load_parameters(config: str | None, overrides: Sequence[str] = ()) -> PropellerParameters:
    """Parameters from a TOML file (or the defaults) with ``key=value`` overrides applied."""
    changes = _as_declared_strings(dict(_parse_override(item) for item in overrides))
    try:
        return resolve_parameters(config or None, changes)
    except ParameterError:
        raise
    # reading input only: whatever fails here is bad input
    except (OverflowError, ValueError) as error:
        source = f"configuration {config!r}" if config else "a --set value"
        raise ParameterError(
            f"{source} holds a value that cannot be used: {_first_clause(error)}"
        ) from None


def require(command: str, extra: str, modules: Sequence[str] | None = None) -> None:
    """MissingExtraError (exit 2, one line: the extra and its install command) unless ``extra`` is
    installed."""
    require_extra(command, extra, modules)


def format_overrides(formats: Sequence[str] | None) -> list[str]:
    """``--format step,3mf`` as the ``--set export.formats=[...]`` it stands for (the schema checks
    the names)."""
    if not formats:
        return []
    names = [name.strip() for item in formats for name in item.split(",") if name.strip()]
    return ["export.formats=[" + ", ".join(f'"{name}"' for name in names) + "]"]


def writes_a_mesh(params: PropellerParameters, no_stl: bool) -> bool:
    """Whether the build tessellates the solid for a file (STL, 3MF): then its triangle budget
    applies."""
    formats = params.export.formats
    return (ExportFormat.STL in formats and not no_stl) or ExportFormat.THREE_MF in formats


def table_specs(table: str) -> list[ParameterSpec]:
    """The parameters of one schema table (``cfd``, ...): its command's options."""
    return [spec for spec in parameter_specs() if spec.section == table]


def table_overrides(args: Any, table: str) -> dict[str, Any]:
    """The values of ``table``'s options given on the command line (dotted key -> value)."""
    return {
        spec.key: getattr(args, spec.key.rpartition(".")[2])
        for spec in table_specs(table)
        if getattr(args, spec.key.rpartition(".")[2]) is not None
    }
