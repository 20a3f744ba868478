"""A whole design document: read from and written to dicts and TOML, changed by dotted keys.

:class:`Document` is the base of :class:`torus_cad.parameters.PropellerParameters`; every
conversion goes through pydantic's validation, and every failure is one
:class:`ParameterError` line naming the field (:func:`torus_cad.parameters.schema.parameter_error`).
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import Enum
from pathlib import Path
from typing import Any, Self

from pydantic import ValidationError

from torus_cad.errors import ParameterError
from torus_cad.parameters.config_file import read_config_table
from torus_cad.parameters.schema import Section, iter_parameter_specs, parameter_error, section_docs


class Document(Section):
    """A validated, frozen tree of parameter tables."""

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Self:
        """Build from a nested mapping (missing keys take defaults; unknown keys are refused)."""
        if not isinstance(data, Mapping):
            raise ParameterError(
                f"configuration must be a table of keys, got {type(data).__name__}"
            )
        try:
            return cls.model_validate(dict(data))
        except ValidationError as error:
            raise parameter_error(cls, error) from None

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (lists for vectors, strings for choices): the layout of the TOML
        file."""
        return _plain(self.model_dump())

    @classmethod
    def from_toml(cls, path: str | Path) -> Self:
        """Read a TOML configuration file; any problem raises ParameterError naming it."""
        return cls.from_table(read_config_table(path), Path(path).resolve().parent)

    @classmethod
    def from_table(cls, data: dict[str, Any], folder: Path) -> Self:
        """Build from a parsed design file's table whose relative file paths are relative to
        ``folder``."""
        return cls.from_dict(cls.paths_relative_to(data, folder))

    @classmethod
    def paths_relative_to(cls, data: dict[str, Any], folder: Path) -> dict[str, Any]:
        """``data`` with its file paths (relative to the design file's ``folder``) made absolute;
        none here."""
        return data

    def to_toml(self, comments: bool = True) -> str:
        """The document as TOML that :meth:`from_toml` reads back unchanged (commented from the
        schema)."""
        notes = _comments(type(self)) if comments else {}
        return _to_toml(self.to_dict(), notes)

    def with_values(self, changes: Mapping[str, Any]) -> Self:
        """A copy with dotted-key changes applied, e.g. ``{"hub.radius": 12.0}``; validated.

        Args:
            changes: dotted key (``"blades"``, ``"hub.radius"``) to new value, in the
                parameters' units (mm, degrees); the rest of the document is kept.

        Returns:
            A new, validated document; ``self`` is not changed (it is frozen).

        Raises:
            ParameterError: an unknown key, a key that runs through a value that is not a
                table, or a value out of its range (the message names the field).
        """
        data = self.to_dict()
        for dotted, value in changes.items():
            *parents, leaf = dotted.split(".")
            table = data
            for depth, part in enumerate(parents):
                table = table.setdefault(part, {}) if isinstance(table, dict) else table
                if not isinstance(table, dict):
                    raise ParameterError(
                        f"unknown key {dotted!r}: {'.'.join(parents[: depth + 1])} is not a table"
                    )
            table[leaf] = value
        return type(self).from_dict(data)


def _comments(model: type[Section]) -> dict[str, str]:
    notes = section_docs(model)
    for spec in iter_parameter_specs(model):
        unit = f" ({spec.unit})" if spec.unit else ""
        choices = ", ".join(repr(str(choice.value)) for choice in spec.choices)
        bounded = spec.bounds.low is not None or spec.bounds.high is not None
        allowed = f"; one of {choices}" if choices else (f"; {spec.bounds}" if bounded else "")
        notes[spec.key] = f"{spec.doc}{unit}{allowed}"
    return notes


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


def _to_toml(data: dict[str, Any], notes: Mapping[str, str], prefix: str = "") -> str:
    lines: list[str] = []
    for key, value in data.items():
        if not isinstance(value, dict):
            text = f"{key} = {_toml_value(value)}"
            note = notes.get(prefix + key)
            lines.append(f"{text:<40} # {note}" if note else text)
    for key, value in data.items():
        if isinstance(value, dict):
            header = f"[{prefix}{key}]"
            note = notes.get(prefix + key)
            lines.extend(["", f"{header:<40} # {note}" if note else header])
            lines.append(_to_toml(value, notes, f"{prefix}{key}.").rstrip("\n"))
    return "\n".join(line for line in lines) + "\n"


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    if isinstance(value, Enum):
        return value.value
    return value
