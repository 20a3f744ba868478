"""Wind-tunnel measurements (UIUC Propeller Data Site format) and the comparison of ``simulate``
against them.

The UIUC files are plain columns after a one-line header: a static test ``RPM CT CP`` (J = 0) and
advance-ratio sweeps ``J CT CP eta`` at about one rpm each. Coefficients follow UIUC's convention,
which is also ``simulate``'s: CT = T / (rho n^2 D^4), CP = P / (rho n^3 D^5), J = V / (n D), n in
rev/s, eta = J CT / CP. A measured value between two rows is linearly interpolated (the rows are
dense: about 250 rpm or 0.03 in J apart); outside the measured range nothing is extrapolated.

The targets of issue 32 are :data:`TARGETS`: a computed point is within them when
|CT - CT_meas| and |CP - CP_meas| are at most 10 % of the measurement and |eta - eta_meas| at
most 0.05 (eta only where J > 0).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

#: The APC 10x7 Slow Flyer's data as shipped in the project.
APC_10X7SF = Path(__file__).resolve().parent.parent / "validation" / "uiuc_apc_10x7sf"
#: Its tip diameter, 10 in (m).
APC_10X7SF_DIAMETER_M = 0.254

#: The issue's targets: relative error of CT and CP, absolute error of eta.
TARGETS = {"ct_relative": 0.10, "cp_relative": 0.10, "eta_absolute": 0.05}

_SWEEP_NAME = re.compile(r"_(\d{3,5})\.txt$")


class WindTunnelFormatError(ValueError):
    """A data file that is not in UIUC's column layout (the message names the file and line)."""


@dataclass(frozen=True)
class Measured:
    """Measured coefficients at one operating point (dimensionless; rpm in rev/min)."""

    rpm: float
    advance_ratio: float
    ct: float
    cp: float

    @property
    def efficiency(self) -> float | None:
        """eta = J CT / CP; None in still air (J = 0)."""
        return None if self.advance_ratio == 0.0 else self.advance_ratio * self.ct / self.cp


@dataclass(frozen=True)
class Table:
    """One UIUC file: its column names and rows, ``rows`` of shape (n, len(columns))."""

    columns: tuple[str, ...]
    rows: NDArray[np.float64]

    def column(self, name: str) -> NDArray[np.float64]:
        """The column called ``name`` (as in the file's header, e.g. ``CT``), shape (n,)."""
        return self.rows[:, self.columns.index(name)]


def read_table(path: Path, columns: Sequence[str]) -> Table:
    """Read a UIUC column file whose header names ``columns`` (in that order), rows sorted by the
    first column.

    Raises WindTunnelFormatError naming the file and line for another header, a row of another
    width, or a value that is not a finite number.
    """
    lines = [line.split() for line in path.read_text(encoding="ascii").splitlines()]
    if not lines or tuple(lines[0]) != tuple(columns):
        raise WindTunnelFormatError(f"{path.name} line 1: expected the header {' '.join(columns)}")
    rows = []
    for number, words in enumerate(lines[1:], start=2):
        if not words:
            continue
        if len(words) != len(columns):
            raise WindTunnelFormatError(
                f"{path.name} line {number}: {len(words)} values, expected {len(columns)}"
            )
        try:
            values = [float(word) for word in words]
        except ValueError:
            raise WindTunnelFormatError(f"{path.name} line {number}: not a number") from None
        if not all(math.isfinite(value) for value in values):
            raise WindTunnelFormatError(f"{path.name} line {number}: not a finite number")
        rows.append(values)
    if len(rows) < 2:
        raise WindTunnelFormatError(f"{path.name}: fewer than two rows of data")
    table = np.array(rows)
    return Table(tuple(columns), table[np.argsort(table[:, 0], kind="stable")])


def _interpolate(x: NDArray[np.float64], y: NDArray[np.float64], at: float, what: str) -> float:
    if not x[0] <= at <= x[-1]:
        raise ValueError(f"{what} = {at:g} is outside the measured range [{x[0]:g}, {x[-1]:g}]")
    return float(np.interp(at, x, y))


@dataclass(frozen=True)
class WindTunnelData:
    """A propeller's static test and its advance-ratio sweeps, keyed by the sweep's nominal rpm."""

    static: Table
    sweeps: dict[int, Table]

    def static_point(self, rpm: float) -> Measured:
        """CT and CP of the static test at ``rpm`` (interpolated between the measured rpm)."""
        rpms = self.static.column("RPM")
        return Measured(
            rpm,
            0.0,
            _interpolate(rpms, self.static.column("CT"), rpm, "rpm"),
            _interpolate(rpms, self.static.column("CP"), rpm, "rpm"),
        )

    def sweep_point(self, rpm: float, advance_ratio: float) -> Measured:
        """CT and CP at ``advance_ratio`` from the sweep whose rpm (to the nearest 100) is nearest
        ``rpm``."""
        nominal = min(self.sweeps, key=lambda key: abs(key - rpm))
        table = self.sweeps[nominal]
        js = table.column("J")
        return Measured(
            float(nominal),
            advance_ratio,
            _interpolate(js, table.column("CT"), advance_ratio, "J"),
            _interpolate(js, table.column("CP"), advance_ratio, "J"),
        )


def read_wind_tunnel(folder: Path = APC_10X7SF) -> WindTunnelData:
    """The static file (``*_static_*.txt``) and every sweep (``*_RRRR.txt``) in ``folder``.

    UIUC measures one rpm in two runs over two ranges of tunnel speed (e.g. 5003 and 5006 rpm):
    runs whose rpm rounds to the same hundred are one sweep, their rows merged in order of J."""
    statics = sorted(folder.glob("*_static_*.txt"))
    if len(statics) != 1:
        raise WindTunnelFormatError(
            f"{folder.name}: expected one *_static_*.txt file, found {len(statics)}"
        )
    runs: dict[int, list[NDArray[np.float64]]] = {}
    columns = ("J", "CT", "CP", "eta")
    for path in sorted(folder.glob("*.txt")):
        match = _SWEEP_NAME.search(path.name)
        if path in statics or match is None or "_geom" in path.name:
            continue
        runs.setdefault(round(int(match.group(1)), -2), []).append(read_table(path, columns).rows)
    sweeps = {}
    for rpm, tables in runs.items():
        rows = np.concatenate(tables)
        sweeps[rpm] = Table(columns, rows[np.argsort(rows[:, 0], kind="stable")])
    return WindTunnelData(read_table(statics[0], ("RPM", "CT", "CP")), sweeps)


@dataclass(frozen=True)
class Comparison:
    """A computed point beside its measurement: errors and whether each is within
    :data:`TARGETS`."""

    measured: Measured
    ct: float
    cp: float

    @property
    def ct_error(self) -> float:
        """(CT_computed - CT_measured) / CT_measured."""
        return (self.ct - self.measured.ct) / self.measured.ct

    @property
    def cp_error(self) -> float:
        """(CP_computed - CP_measured) / CP_measured."""
        return (self.cp - self.measured.cp) / self.measured.cp

    @property
    def efficiency(self) -> float | None:
        """The computed eta = J CT / CP (None at J = 0)."""
        j = self.measured.advance_ratio
        return None if j == 0.0 else j * self.ct / self.cp

    @property
    def efficiency_error(self) -> float | None:
        """eta_computed - eta_measured (None at J = 0)."""
        measured = self.measured.efficiency
        return None if measured is None or self.efficiency is None else self.efficiency - measured

    @property
    def within_targets(self) -> bool:
        """Every error within :data:`TARGETS`."""
        eta_error = self.efficiency_error
        return (
            abs(self.ct_error) <= TARGETS["ct_relative"]
            and abs(self.cp_error) <= TARGETS["cp_relative"]
            and (eta_error is None or abs(eta_error) <= TARGETS["eta_absolute"])
        )


def markdown_table(comparisons: Sequence[Comparison], solver: str = "CFD") -> str:
    """The comparison as a Markdown table (one row per point), as the docs show it; ``solver`` heads
    the computed
    columns."""
    lines = [
        f"| rpm | J | CT meas. | CT {solver} | ΔCT | CP meas. "
        f"| CP {solver} | ΔCP | η meas. | η {solver} | Δη | "
        "within |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for item in comparisons:
        measured, eta, eta_error = item.measured, item.efficiency, item.efficiency_error
        eta_cells = (
            ("–", "–", "–")
            if eta is None or eta_error is None or measured.efficiency is None
            else (f"{measured.efficiency:.3f}", f"{eta:.3f}", f"{eta_error:+.3f}")
        )
        lines.append(
            f"| {measured.rpm:.0f} | {measured.advance_ratio:.2f} | "
            f"{measured.ct:.4f} | {item.ct:.4f} | "
            f"{100 * item.ct_error:+.1f} % | {measured.cp:.4f} | "
            f"{item.cp:.4f} | {100 * item.cp_error:+.1f} % | "
            f"{' | '.join(eta_cells)} | {'yes' if item.within_targets else 'no'} |"
        )
    return "\n".join(lines)
