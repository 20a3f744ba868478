"""Histories a run writes under ``postProcessing/``: residuals, forces, moments, momentum fluxes, by
iteration.

OpenFOAM's function objects write one line per iteration (``Time`` = iteration for a steady
run); vectors are written as ``(x y z)``. Files are read whole: a few hundred lines.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from torus_cad.runtime.input_files import is_number_text
from torus_cad.simulate.case import FORCES, MOMENTUM_FLUX, OUTER_FORCES, RESIDUALS, WALL, Y_PLUS

#: Residuals reported, in this order (initial residuals of each equation's first solve).
RESIDUAL_NAMES = ("Ux", "Uy", "Uz", "p", "k", "omega")


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    """(header words of the last '# Time' line, data rows split on whitespace with parentheses
    removed)."""
    header: list[str] = []
    rows: list[list[str]] = []
    try:
        text = path.read_text(errors="replace")
    except FileNotFoundError:
        return header, rows
    lines = text.splitlines()
    if lines and not text.endswith("\n"):
        lines = lines[:-1]  # being written
    for line in lines:
        if line.startswith("#"):
            if line[1:].strip().startswith("Time"):
                header = line[1:].split()
            continue
        words = line.replace("(", " ").replace(")", " ").split()
        if words:
            rows.append(words)
    return header, rows


def _time_folder(root: Path, name: str) -> Path:
    """The function object's folder of the first time (``0``)."""
    folder = root / "postProcessing" / name
    times = sorted(
        folder.glob("*"),
        key=lambda path: float(path.name) if is_number_text(path.name) else math.inf,
    )
    return times[0] if times else folder / "0"


#: The forces function object's columns after the time (OpenFOAM v1912): total, pressure and viscous
#: vectors; the viscous ones are the last three.
FORCE_COLUMNS, VISCOUS_COLUMNS = 9, slice(6, 9)


def _vectors(path: Path, columns: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """(iterations (n,), the first ``columns`` numbers after the time (n, columns))."""
    _, rows = _rows(path)
    rows = [row for row in rows if len(row) > columns]
    if not rows:
        return np.zeros(0, dtype=int), np.zeros((0, columns))
    iterations = np.array([int(float(row[0])) for row in rows])
    return iterations, np.array([[float(value) for value in row[1 : 1 + columns]] for row in rows])


@dataclass
class History:
    """A run's histories by iteration. Arrays: ``iterations`` (n,), ``force_n`` / ``moment_nm``
    (n, 3) on the propeller (pressure and viscous), ``viscous_force_n`` / ``viscous_moment_nm``
    (n, 3) their viscous part (wall shear), ``residuals`` {name: (n,)}; the outer patches'
    ``outer_force_n`` (n, 3) (pressure and viscous) and ``momentum_flux_m4_s2`` {patch: (n, 3)} (sum
    of U phi, kinematic)."""

    iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    force_n: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    moment_nm: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    viscous_force_n: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    viscous_moment_nm: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    residual_iterations: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    residuals: dict[str, np.ndarray] = field(default_factory=dict)
    outer_force_n: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    momentum_flux_m4_s2: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def last_iteration(self) -> int:
        counts = [
            int(array[-1]) for array in (self.iterations, self.residual_iterations) if len(array)
        ]
        return min(counts) if counts else 0

    def last_residuals(self) -> dict[str, float]:
        return {name: float(values[-1]) for name, values in self.residuals.items() if len(values)}


def read_residuals(case: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(iterations, {equation: initial residuals}) from the solverInfo function object."""
    header, rows = _rows(_time_folder(case, RESIDUALS) / "solverInfo.dat")
    if not header or not rows:
        return np.zeros(0, dtype=int), {}
    columns = {
        name[: -len("_initial")]: index
        for index, name in enumerate(header)
        if name.endswith("_initial")
    }
    rows = [row for row in rows if len(row) == len(header)]
    iterations = np.array([int(float(row[0])) for row in rows], dtype=int)
    residuals = {
        name: np.array([float(row[columns[name]]) for row in rows])
        for name in RESIDUAL_NAMES
        if name in columns
    }
    return iterations, residuals


def read_history(case: str | Path, balance: bool = False) -> History:
    """The histories of ``case``; with ``balance`` also the outer patches' forces and momentum
    fluxes."""
    case = Path(case)
    iterations, force = _vectors(_time_folder(case, FORCES) / "force.dat", FORCE_COLUMNS)
    moment_iterations, moment = _vectors(_time_folder(case, FORCES) / "moment.dat", FORCE_COLUMNS)
    count = min(len(iterations), len(moment_iterations))
    history = History(
        iterations[:count],
        force[:count, :3],
        moment[:count, :3],
        force[:count, VISCOUS_COLUMNS],
        moment[:count, VISCOUS_COLUMNS],
    )
    history.residual_iterations, history.residuals = read_residuals(case)
    if balance:
        _, history.outer_force_n = _vectors(_time_folder(case, OUTER_FORCES) / "force.dat")
        for patch, name in MOMENTUM_FLUX.items():
            _, history.momentum_flux_m4_s2[patch] = _vectors(
                _time_folder(case, name) / "surfaceFieldValue.dat"
            )
    return history


def momentum_balance_force_n(history: History, density_kg_m3: float) -> np.ndarray:
    """Force of the fluid on the propeller from the momentum balance over the whole domain, N, (3,),
    last iteration.

    Steady flow, control volume = the fluid: the momentum leaving through the outer patches plus
    the pressure and viscous force on them equals the force on the propeller with the sign reversed,
    F = -(sum over inlet, outlet, far field of rho U phi + the forces function object's force
    there). With MRF the axial balance holds unchanged: the zone's frame term Omega x U is
    perpendicular to the axis, and on the zone's surfaces of revolution the relative and absolute
    fluxes are equal.
    """
    flux = sum(values[-1] for values in history.momentum_flux_m4_s2.values())
    return -(density_kg_m3 * np.asarray(flux) + history.outer_force_n[-1])


def read_y_plus(case: str | Path, patch: str = WALL) -> dict[str, float] | None:
    """y+ on ``patch`` at the last time the ``yPlus`` function object wrote: ``{"min", "mean",
    "max"}`` (the mean weighted by face area, as OpenFOAM's ``average`` column is); None when it
    wrote nothing."""
    _, rows = _rows(_time_folder(Path(case), Y_PLUS) / "yPlus.dat")
    values = [row for row in rows if len(row) >= 5 and row[1] == patch]
    if not values:
        return None
    low, high, mean = (float(word) for word in values[-1][2:5])
    return {"min": low, "mean": mean, "max": high}
