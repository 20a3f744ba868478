"""Reading a configuration file safely: only a regular file, only up to a size limit, UTF-8 (BOM
allowed).

The reading itself is torus_cad.runtime.input_files's, shared with every other file a design names
(airfoil coordinate files): ``/dev/zero``, a named pipe, a socket or a folder is refused at once
(opened non-blocking, checked with ``fstat``), so the command can neither read gigabytes nor wait
forever.

:func:`parse_config_bytes` is the one path from bytes to a table, for every TOML file a person hands
the program (designs on disk or uploaded to the studio, sweep files, study files) and ``--set``
values alike: UTF-8 with or without a byte order mark, then a scan (:func:`check_toml_shape`) that
refuses values nested deeper than :data:`~torus_cad.tolerances.TOML_NESTING_LIMIT` or numbers
longer than :data:`~torus_cad.parameters.config_file.TOML_NUMBER_DIGITS_LIMIT` naming their key,
before the TOML reader (which recurses on nesting and refuses integers over 4300 digits without
saying where) sees them, and after it a walk (:func:`check_table_depth`) that refuses tables nested
deeper than the same limit through dotted keys or headers (``a.b.c.… = 1``, ``[a.b.c.…]``), which
the readers of sweeps and studies would otherwise follow down until Python's recursion limit.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

from torus_cad.errors import ParameterError, cut
from torus_cad.runtime.input_files import decode_text, read_untrusted_bytes, read_untrusted_text
from torus_cad.tolerances import CONFIG_FILE_MAX_BYTES, TOML_NESTING_LIMIT

#: Most digits one number in a TOML file may have (Python refuses integers of more than 4300).
TOML_NUMBER_DIGITS_LIMIT = 400


_DIGITS = re.compile(r"[0-9][0-9_]*")
_STRING_OPENERS = ('"""', "'''", '"', "'")


def read_config_text(
    path: str | Path, what: str = "configuration", max_bytes: int = CONFIG_FILE_MAX_BYTES
) -> str:
    """The text of the configuration file ``path``, or ParameterError (exit 2) naming it and the
    reason.

    Refused: anything but a regular file (folder, device, named pipe, socket), a file over
    ``max_bytes``, text that is not UTF-8, and an empty (or whitespace-only) file. A UTF-8 byte
    order mark, as some Windows editors write, is accepted and dropped. ``what`` names the file's
    role in messages ("configuration", "sweep file").
    """
    return read_untrusted_text(path, what, max_bytes)


def read_config_table(
    path: str | Path, what: str = "configuration", max_bytes: int = CONFIG_FILE_MAX_BYTES
) -> dict[str, Any]:
    """The TOML table of the file ``path``: :func:`read_config_text` then
    :func:`parse_config_bytes`'s checks."""
    return parse_config_bytes(read_untrusted_bytes(path, what, max_bytes), str(path), what)


def parse_config_bytes(raw: bytes, source: str, what: str = "configuration") -> dict[str, Any]:
    """The TOML table in ``raw`` (UTF-8, a byte order mark allowed), or ParameterError naming
    ``source``."""
    return parse_config_text(decode_text(raw, source, what), source, what)


def parse_config_text(text: str, source: str, what: str = "configuration") -> dict[str, Any]:
    """The TOML table in ``text``: :func:`check_toml_shape` first, then the TOML reader."""
    check_toml_shape(text, f"{what} {source!r}")
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ParameterError(f"{what} {source!r} is not valid TOML: {error}") from None
    check_table_depth(table, f"{what} {source!r}")
    return table


def check_table_depth(table: dict[str, Any], where: str) -> None:
    """Refuse a table whose values are nested more than TOML_NESTING_LIMIT tables and lists deep.

    Dotted keys and table headers nest tables without brackets (``a.b.c = 1``, ``[a.b.c]``), so the
    scan of the text does not see them. ParameterError ``"{where}: KEY is nested more than N levels
    deep"``, KEY dotted (cut short when long). Walks without recursion, at most N levels down.
    """
    stack: list[tuple[Any, str, int]] = [(table, "", 0)]
    while stack:
        # a table or list at depth d sits within d - 1 others (the file's not counted)
        value, key, depth = stack.pop()
        if depth > TOML_NESTING_LIMIT and isinstance(value, dict | list):
            raise ParameterError(
                f"{where}: {cut(key)} is nested more than {TOML_NESTING_LIMIT} levels deep "
                "(lists or tables within each other)"
            )
        if isinstance(value, dict):
            stack.extend(
                (item, f"{key}.{name}" if key else str(name), depth + 1)
                for name, item in value.items()
            )
        elif isinstance(value, list):
            stack.extend((item, f"{key}[{index}]", depth + 1) for index, item in enumerate(value))


def check_toml_shape(text: str, where: str, key_prefix: str = "", lines: bool = True) -> None:
    """Refuse nesting deeper than TOML_NESTING_LIMIT and numbers of more than
    TOML_NUMBER_DIGITS_LIMIT digits.

    A light scan of the TOML text (strings and comments skipped, table headers followed) that
    names the key whose value breaks a limit (``hub.radius``; ``key_prefix`` is put before it).
    ParameterError ``"{where} line N: KEY ..."`` (without the line number if not ``lines``).
    """
    table, key, depth, line, index = "", "", 0, 1, 0
    at_line_start = True
    while index < len(text):
        char = text[index]
        if char == "\n":
            line, at_line_start, index = line + 1, depth == 0, index + 1
            continue
        if char in " \t\r":
            index += 1
            continue
        if char == "#":
            end = text.find("\n", index)
            index = len(text) if end < 0 else end
            continue
        opener = next((quote for quote in _STRING_OPENERS if text.startswith(quote, index)), None)
        if opener is not None and not (at_line_start and depth == 0):
            index, line = _skip_string(text, index, opener, line)
            continue
        if at_line_start and depth == 0:  # a table header or a key
            end = text.find("\n", index)
            end = len(text) if end < 0 else end
            if char == "[":
                table = text[index:end].split("#", 1)[0].strip().strip("[]").strip()
                index = end
                continue
            name, _, _ = text[index:end].partition("=")
            key = ".".join(part for part in (key_prefix, table, name.strip()) if part)
            index += len(name) + 1
            at_line_start = False
            continue
        if char in "[{":
            depth += 1
            if depth > TOML_NESTING_LIMIT:
                raise ParameterError(
                    f"{where}{f' line {line}' if lines else ''}: "
                    f"{key or 'a value'} is nested more than "
                    f"{TOML_NESTING_LIMIT} levels deep (lists or tables within each other)"
                )
        elif char in "]}":
            depth = max(depth - 1, 0)
        elif char.isdigit():
            run = _DIGITS.match(text, index)
            assert run is not None
            digits = len(run.group().replace("_", ""))
            if digits > TOML_NUMBER_DIGITS_LIMIT:
                raise ParameterError(
                    f"{where}{f' line {line}' if lines else ''}: "
                    f"{key or 'a value'} holds a number of {digits} digits; "
                    f"at most {TOML_NUMBER_DIGITS_LIMIT} are allowed"
                )
            index = run.end()
            continue
        index += 1


def _skip_string(text: str, index: int, quote: str, line: int) -> tuple[int, int]:
    """The index after the string that opens at ``index`` with ``quote``, and the line it ends
    on."""
    position = index + len(quote)
    while position < len(text):
        if text[position] == "\\" and quote.startswith('"'):
            position += 2
            continue
        if text.startswith(quote, position):
            return position + len(quote), line + text.count("\n", index, position)
        if text[position] == "\n" and len(quote) == 1:
            break  # an unterminated one-line string: the TOML reader says so
        position += 1
    return position, line + text.count("\n", index, position)
