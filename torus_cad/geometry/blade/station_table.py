"""A conventional propeller blade's station table, inline or read from a file (UIUC or APC layout).

A station table gives, at radii r/R (R the tip radius), the chord c/R, the local pitch angle
beta (degrees, between the chord line and the plane of rotation; geometric pitch 2 pi r tan beta)
and, optionally, the thickness ratio t/c and the leading edge's sweep (/R).

File layouts (detected by content):

* **UIUC** geometry file (``apcsf_10x7_geom.txt``): header lines (e.g. ``r/R c/R beta``), then
  rows of three numbers ``r/R c/R beta``.
* **APC PE0** file (``10x7SF-PERF.PE0``): a header with a ``STATION`` line and a units line, then
  rows ``STATION(in) CHORD(in) PITCH-QUOTED(in) PITCH-LE-TE PITCH-PRATHER SWEEP(in) THICKNESS-RATIO
  TWIST(deg) MAX-THICK ...`` up to the first blank line, and a ``RADIUS: <in>`` line; the
  performance tables that follow are ignored. beta = atan(quoted pitch / (2 pi r)); the sweep is
  APC's, the leading edge's distance ahead of the blade's axis in the plane of rotation.

A station file is untrusted input, read through :mod:`torus_cad.runtime.input_files` (a regular
file, at most :data:`~torus_cad.geometry.blade.station_table.STATION_FILE_MAX_BYTES`). Malformed
tables raise ParameterError naming the file and the line, never quoting it: a row that is not
numbers, missing columns, r/R not increasing or out of (0, 1], a chord <= 0 or absurdly large, a
beta out of range, too many rows (:data:`~torus_cad.tolerances.STATION_MAX_ROWS`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from torus_cad.errors import ParameterError
from torus_cad.runtime.input_files import decode_text, is_number_text, read_untrusted_bytes
from torus_cad.tolerances import STATION_MAX_ROWS

#: Allowed local pitch angle beta of a station (deg): a propeller blade's sections, not a feathered
#: one.
STATION_BETA_LIMIT_DEG = 85.0

#: Largest station file (a UIUC geometry file is < 1 kB, an APC PE0 file with its performance tables
#: ~ 100 kB).
STATION_FILE_MAX_BYTES = 1_000_000

#: Largest chord of a station as a fraction of the tip radius (c/R; real propellers: < 0.4).
STATION_MAX_CHORD_OVER_R = 2.0

#: Largest propeller radius an APC PE0 file may give (inches; 100 in = 5 m across).
STATION_MAX_RADIUS_IN = 100.0

#: Largest |sweep| of a station's leading edge as a fraction of the tip radius.
STATION_MAX_SWEEP_OVER_R = 2.0


#: What a station file is called in messages.
_WHAT = "station file"

#: Columns of an APC PE0 station row: station, chord, quoted pitch, LE-TE pitch, Prather pitch,
#: sweep, thickness ratio, twist (all rows have 13; the first 8 are read).
_PE0_COLUMNS = 8
_PE0_RADIUS = re.compile(r"^\s*RADIUS:\s*(\S+)")


@dataclass(frozen=True)
class StationTable:
    """Stations of a conventional blade, in increasing radius.

    Attributes:
        r_over_r: ``(n,)`` r/R, strictly increasing in (0, 1].
        chord_over_r: ``(n,)`` c/R > 0.
        beta_deg: ``(n,)`` local pitch angle, degrees.
        thickness_ratio: ``(n,)`` t/c, or None (the airfoil's own thickness).
        sweep_over_r: ``(n,)`` the leading edge's distance ahead of the blade's axis in the plane of
            rotation, /R, or None (sections stacked at the design's chord fraction).
        lines: ``(n,)`` the line of each station in its source (1-based; the index + 1 for an inline
            table).
        source: where the table came from, for messages.
    """

    r_over_r: NDArray[np.float64]
    chord_over_r: NDArray[np.float64]
    beta_deg: NDArray[np.float64]
    thickness_ratio: NDArray[np.float64] | None = None
    sweep_over_r: NDArray[np.float64] | None = None
    lines: NDArray[np.int64] | None = None
    source: str = "the inline table"


def _where(source: str, line: int) -> str:
    return f"{_WHAT} {source!r} line {line}"


def _numbers(fields: list[str], source: str, line: int) -> list[float]:
    """The fields as finite floats, or ParameterError naming the line and the field's position."""
    values = []
    for position, text in enumerate(fields, start=1):
        try:
            value = float(text)
        except ValueError:
            raise ParameterError(
                f"{_where(source, line)}: field {position} is not a number"
            ) from None
        if not math.isfinite(value):
            raise ParameterError(f"{_where(source, line)}: field {position} is not a finite number")
        values.append(value)
    return values


def read_station_file(path: str | Path) -> StationTable:
    """The station table of a UIUC geometry file or an APC PE0 file (module docstring), checked."""
    source = str(path)
    text = decode_text(read_untrusted_bytes(path, _WHAT, STATION_FILE_MAX_BYTES), source, _WHAT)
    lines = text.splitlines()
    if any(line.split()[:1] == ["STATION"] for line in lines):
        return checked(_pe0_table(lines, source))
    return checked(_uiuc_table(lines, source))


def _uiuc_table(lines: list[str], source: str) -> StationTable:
    """``r/R c/R beta`` rows after header lines (the first line starting with a number starts the
    rows)."""
    rows: list[list[float]] = []
    numbers: list[int] = []
    for number, line in enumerate(lines, start=1):
        fields = line.split()
        if not fields:
            continue
        if not rows and not is_number_text(fields[0]):
            continue  # a header line
        if len(fields) != 3:
            raise ParameterError(
                f"{_where(source, number)}: expected 3 columns (r/R c/R beta), got {len(fields)}"
            )
        rows.append(_numbers(fields, source, number))
        numbers.append(number)
        _check_row_count(len(rows), source, number)
    if not rows:
        raise ParameterError(
            f"{_WHAT} {source!r}: no station rows (expected "
            "'r/R c/R beta' rows, or an APC PE0 table)"
        )
    table = np.array(rows)
    return StationTable(
        table[:, 0], table[:, 1], table[:, 2], lines=np.array(numbers), source=source
    )


def _check_row_count(rows: int, source: str, line: int) -> None:
    if rows > STATION_MAX_ROWS:
        raise ParameterError(f"{_where(source, line)}: more than {STATION_MAX_ROWS} stations")


def _pe0_radius_in(lines: list[str], source: str) -> float:
    for number, line in enumerate(lines, start=1):
        match = _PE0_RADIUS.match(line)
        if match:
            (radius,) = _numbers([match.group(1)], source, number)
            if not 0.0 < radius <= STATION_MAX_RADIUS_IN:
                raise ParameterError(
                    f"{_where(source, number)}: the RADIUS is out of range; allowed "
                    f"(0, {STATION_MAX_RADIUS_IN:g}] in"
                )
            return radius
    raise ParameterError(f"{_WHAT} {source!r}: an APC PE0 table without a 'RADIUS:' line")


def _pe0_table(lines: list[str], source: str) -> StationTable:
    """APC's rows after the ``STATION`` header, to the first blank line once rows have started."""
    start = next(index for index, line in enumerate(lines) if line.split()[:1] == ["STATION"])
    rows: list[list[float]] = []
    numbers: list[int] = []
    for number, line in enumerate(lines[start + 1 :], start=start + 2):
        fields = line.split()
        if not fields:
            if rows:
                break
            continue
        if not rows and not is_number_text(fields[0]):
            continue  # the units line
        if len(fields) < _PE0_COLUMNS:
            raise ParameterError(
                f"{_where(source, number)}: expected at "
                f"least {_PE0_COLUMNS} columns (STATION CHORD "
                f"PITCH x3 SWEEP THICKNESS-RATIO TWIST), got {len(fields)}"
            )
        rows.append(_numbers(fields[:_PE0_COLUMNS], source, number))
        numbers.append(number)
        _check_row_count(len(rows), source, number)
    if not rows:
        raise ParameterError(f"{_WHAT} {source!r}: an APC PE0 table without station rows")
    radius = _pe0_radius_in(lines, source)
    table = np.array(rows)
    station = table[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = np.degrees(np.arctan2(table[:, 2], 2.0 * np.pi * station))
    return StationTable(
        station / radius,
        table[:, 1] / radius,
        beta,
        thickness_ratio=table[:, 6],
        sweep_over_r=table[:, 5] / radius,
        lines=np.array(numbers),
        source=source,
    )


def _fail(table: StationTable, index: int, reason: str) -> ParameterError:
    line = int(table.lines[index]) if table.lines is not None else index + 1
    if table.lines is None:  # an inline table: its source names the columns
        return ParameterError(f"{table.source}[{index}]: {reason}")
    return ParameterError(f"{_where(table.source, line)}: {reason}")


def checked(table: StationTable) -> StationTable:
    """``table`` if every station is sound, else ParameterError naming the first bad one's line."""
    count = len(table.r_over_r)
    columns = [table.chord_over_r, table.beta_deg, table.thickness_ratio, table.sweep_over_r]
    if any(column is not None and len(column) != count for column in columns):
        raise ParameterError(f"{table.source}: the station columns have different lengths")
    if count < 2:
        raise ParameterError(f"{table.source}: a blade needs at least 2 stations, got {count}")
    if count > STATION_MAX_ROWS:
        raise _fail(table, STATION_MAX_ROWS, f"more than {STATION_MAX_ROWS} stations")
    for index in range(count):
        _check_station(table, index)
    return table


def _check_station(table: StationTable, index: int) -> None:
    """ParameterError naming the station's line and the rule it breaks (never its values: a file's
    content)."""
    r, chord, beta = table.r_over_r[index], table.chord_over_r[index], table.beta_deg[index]
    if not 0.0 < r <= 1.0:
        raise _fail(table, index, "r/R is out of range; allowed (0, 1]")
    if index and not r > table.r_over_r[index - 1]:
        raise _fail(
            table, index, "r/R does not increase (r/R must grow strictly from station to station)"
        )
    if not 0.0 < chord <= STATION_MAX_CHORD_OVER_R:
        raise _fail(table, index, f"c/R is out of range; allowed (0, {STATION_MAX_CHORD_OVER_R:g}]")
    if not abs(beta) <= STATION_BETA_LIMIT_DEG:
        raise _fail(
            table,
            index,
            f"beta is out of range; allowed [-{STATION_BETA_LIMIT_DEG:g}, "
            f"{STATION_BETA_LIMIT_DEG:g}] deg",
        )
    if table.thickness_ratio is not None and not 0.0 < table.thickness_ratio[index] <= 0.5:
        raise _fail(table, index, "the thickness ratio is out of range; allowed (0, 0.5]")
    if (
        table.sweep_over_r is not None
        and not abs(table.sweep_over_r[index]) <= STATION_MAX_SWEEP_OVER_R
    ):
        raise _fail(
            table,
            index,
            f"sweep/R is out of range; allowed [-{STATION_MAX_SWEEP_OVER_R:g}, "
            f"{STATION_MAX_SWEEP_OVER_R:g}]",
        )
