"""Printability (issue 13): how thin the blade gets, from the analytic section (no mesh, no kernel).

Definitions (mm):

* **wall(s, x)**: the blade's thickness at chord fraction x of the section at s, measured
  between the upper and the lower surface point of that chord station. In chord units the two
  points are y_t(x) on either side of the camber line along its normal n_c(x) (spec §1.2; along
  y when ``camber_normal`` is False); the section transform (rotation by alpha(s), then scaling by
  Sx(s), Sy(s), spec §2.3) is affine, and placing the section on the frame is a rigid motion, so
  wall(s, x) = 2 y_t(x) |diag(Sx, Sy) R(alpha) n_c(x)|, exactly.
* **thinnest wall**: the smallest, over s in [0, 1], of the section's thickest wall
  max_x wall(s, x): the thinnest section of the blade. Where it is below the printer's minimum
  wall, no two perimeter lines fit anywhere in that section. Reported with its s and the chord
  fraction x of that section's thickest point.
* **trailing-edge thickness**: the smallest wall(s, 1) over s: 0 for the spec's sharp edge,
  the base of a blunt edge otherwise. The edges of every section taper below any printer's
  wall, so the sharp edge's zero is reported here, separately, instead of being the "thinnest
  wall" of every blade.
* **printable**: both the thinnest wall and the trailing-edge thickness reach ``min_wall``.

Both minima are found on a fine grid and polished with a bounded scalar minimisation.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar

from torus_cad.geometry.transforms import (
    SectionLaws,
    evaluate_quartic,
    rotation_matrices,
)

#: Grid sizes of the search (s, and chord fraction x clustered at both edges).
_S_SAMPLES, _X_SAMPLES = 201, 401


@dataclass(frozen=True)
class Printability:
    """The blade's walls against the printer's minimum wall (mm); see the module docstring."""

    thinnest_wall_mm: float
    thinnest_wall_s: float
    thinnest_wall_chord_fraction: float
    trailing_edge_thickness_mm: float
    trailing_edge_thinnest_s: float
    min_wall_mm: float
    printable: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)

    def problem(self) -> str:
        """'' when printable, else one line naming the section and the limit."""
        if self.thinnest_wall_mm < self.min_wall_mm:
            return (f"the blade section at s = {self.thinnest_wall_s:.3f} is at most {self.thinnest_wall_mm:.3f} mm "
                    f"thick (at chord fraction {self.thinnest_wall_chord_fraction:.3f}), thinner than "
                    f"manufacturing.min_wall = {self.min_wall_mm:g} mm")
        if self.trailing_edge_thickness_mm < self.min_wall_mm:
            return (f"the trailing edge of the section at s = {self.trailing_edge_thinnest_s:.3f} is "
                    f"{self.trailing_edge_thickness_mm:.3f} mm thick, thinner than manufacturing.min_wall = "
                    f"{self.min_wall_mm:g} mm (a blunt trailing edge can make it printable)")
        return ""


def wall_mm(airfoil: Any, laws: SectionLaws, s: ArrayLike, x: ArrayLike) -> NDArray[np.float64]:
    """wall(s, x) of the module docstring, mm, for every pair of the grid: ``(len(s), len(x))``.

    ``airfoil`` offers ``half_thickness(x)``, ``camber_slope(x)`` and ``camber_normal``.
    """
    s, x = np.atleast_1d(np.asarray(s, float)), np.atleast_1d(np.asarray(x, float))
    theta = np.arctan(airfoil.camber_slope(x)) if airfoil.camber_normal else np.zeros_like(x)
    normal = np.stack([-np.sin(theta), np.cos(theta)], axis=-1)  # (len(x), 2), unit
    rotated = np.einsum("kij,xj->kxi", rotation_matrices(evaluate_quartic(laws.angle_of_attack_deg, s)), normal)
    scales = np.stack([evaluate_quartic(laws.scale_x_mm, s), evaluate_quartic(laws.scale_y_mm, s)], axis=-1)
    stretch = np.linalg.norm(rotated * scales[:, None, :], axis=-1)
    return 2.0 * np.asarray(airfoil.half_thickness(x), float)[None, :] * stretch


def printability(airfoil: Any, laws: SectionLaws, min_wall_mm: float) -> Printability:
    """Thinnest wall, trailing-edge thickness and the printable flag of a blade (module docstring)."""
    x_grid = 0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, _X_SAMPLES))
    s_grid = np.linspace(0.0, 1.0, _S_SAMPLES)

    def thickest(s: float) -> tuple[float, float]:
        walls = wall_mm(airfoil, laws, [s], x_grid)[0]
        index = int(np.argmax(walls))
        low, high = x_grid[max(index - 1, 0)], x_grid[min(index + 1, len(x_grid) - 1)]
        best = minimize_scalar(lambda x: -wall_mm(airfoil, laws, [s], [x])[0, 0], bounds=(low, high),
                               method="bounded", options={"xatol": 1e-10})
        return (-float(best.fun), float(best.x)) if -best.fun >= walls[index] else (float(walls[index]), float(x_grid[index]))

    section_walls = wall_mm(airfoil, laws, s_grid, x_grid).max(axis=1)
    s_wall = _polish_minimum(lambda s: thickest(s)[0], s_grid, section_walls)
    wall, x_wall = thickest(s_wall)
    edge = wall_mm(airfoil, laws, s_grid, [1.0])[:, 0]
    s_edge = _polish_minimum(lambda s: float(wall_mm(airfoil, laws, [s], [1.0])[0, 0]), s_grid, edge)
    edge_thickness = max(float(wall_mm(airfoil, laws, [s_edge], [1.0])[0, 0]), 0.0)  # no -1e-15 for a sharp edge
    return Printability(wall, s_wall, x_wall, edge_thickness, s_edge, min_wall_mm,
                        bool(wall >= min_wall_mm and edge_thickness >= min_wall_mm))


def _polish_minimum(function: Any, grid: NDArray[np.float64], values: NDArray[np.float64]) -> float:
    """The argument of the smallest of ``values`` on ``grid``, refined between its neighbours."""
    index = int(np.argmin(values))
    low, high = grid[max(index - 1, 0)], grid[min(index + 1, len(grid) - 1)]
    best = minimize_scalar(function, bounds=(low, high), method="bounded", options={"xatol": 1e-10})
    return float(best.x) if best.fun <= values[index] else float(grid[index])
