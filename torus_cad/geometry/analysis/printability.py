"""Printability: how thin the blade gets, from the analytic section (no mesh, no kernel).

Definitions (mm):

* **wall(s, u)**: the blade's thickness at the chord station u of the section at s, measured
  between the upper and the lower surface point of that station (the sections' half parameter:
  0 at the leading edge, 1 at the trailing edge; for NACA sections the chord position is u^2 and
  the two points are y_t on either side of the camber line along its normal, spec §1.2). The
  section transform (rotation by alpha(s), then scaling by Sx(s), Sy(s), spec §2.3) is affine and
  placing the section on the frame is a rigid motion, so wall(s, u) = |diag(Sx, Sy) R(alpha)
  (upper(u) - lower(u))|, exactly; for NACA sections 2 y_t |diag(Sx, Sy) R(alpha) n_c|. A blunt
  trailing edge (``airfoil.trailing_edge_thickness``) is in the sections at every s.
* **exposed span** [s_in, s_out]: the sections a printer lays down as blade, those whose centre
  (the centerline point) lies outside the hub, from where the centerline leaves the hub's
  cylinder or end plane to where it comes back. The blade's ends are buried in the hub (they
  start at R_inset, spec §3.2), and the sections that straddle the hub's surface are joined to
  it (and to the root fillet), so their walls are not blade walls. Found from the centerline's
  crossings of the hub surface, refined to 1e-12 in s.
* **thinnest wall**: the smallest, over s in the exposed span, of the section's thickest wall
  max_u wall(s, u): the thinnest section of the blade. Where it is below the printer's minimum
  wall, no two perimeter lines fit anywhere in that section. Reported with its s and the chord
  fraction (chord units, the middle of the station) of that section's thickest point.
* **trailing-edge thickness**: the smallest wall(s, u = 1) over the exposed span: 0 for the spec's
  sharp edge, the base of a blunt edge otherwise. The edges of every section taper below any
  printer's wall, so the sharp edge's zero is reported here, separately, instead of being the
  "thinnest wall" of every blade.
* **printable**: both the thinnest wall and the trailing-edge thickness reach ``min_wall``. A blunt
  edge (``airfoil.trailing_edge_thickness``, mm) is that thick at every section, so a blade whose
  thinnest wall reaches ``min_wall`` is printable with a blunt edge of ``min_wall`` or more, which
  is what :meth:`Printability.problem` advises.

Both minima are found on a fine grid and polished with a bounded scalar minimisation.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq, minimize_scalar

from torus_cad.geometry.blade.blade_surface import sections_along
from torus_cad.geometry.blade.conventional_blade import ConventionalBlade
from torus_cad.geometry.blade.propeller_geometry import BladeGeometry, PropellerGeometry
from torus_cad.geometry.blade.transforms import SectionLaws, evaluate_quartic, rotation_matrices

#: A wall equal to min_wall up to this relative rounding counts as reaching it (a 0.8 mm blunt edge
#: evaluates to 0.7999999...).
_ROUNDING = 1e-9

#: Grid sizes of the search (s, and the half parameter u, dense at the trailing edge).
_S_SAMPLES, _X_SAMPLES = 201, 401


@dataclass(frozen=True)
class Printability:
    """The blade's walls against the printer's minimum wall (mm); see the module docstring."""

    thinnest_wall_mm: float
    thinnest_wall_s: float
    thinnest_wall_chord_fraction: float
    trailing_edge_thickness_mm: float
    trailing_edge_thinnest_s: float
    exposed_s: tuple[float, float]
    min_wall_mm: float
    printable: bool

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)

    def problem(self) -> str:
        """'' when printable, else one line naming the section and the limit."""
        if self.printable:
            return ""
        if self.thinnest_wall_mm < self.min_wall_mm * (1.0 - _ROUNDING):
            return (
                f"the blade section at s = {self.thinnest_wall_s:.3f} is "
                f"at most {self.thinnest_wall_mm:.3f} mm "
                f"thick (at chord fraction {self.thinnest_wall_chord_fraction:.3f}), thinner than "
                f"manufacturing.min_wall = {self.min_wall_mm:g} mm"
            )
        if self.trailing_edge_thickness_mm < self.min_wall_mm * (1.0 - _ROUNDING):
            return (
                f"the trailing edge of the section at s = {self.trailing_edge_thinnest_s:.3f} is "
                f"{self.trailing_edge_thickness_mm:.3f} mm "
                "thick, thinner than manufacturing.min_wall = "
                f"{self.min_wall_mm:g} mm (a blunt trailing "
                "edge at least as thick makes it printable: "
                f"airfoil.trailing_edge_thickness = {self.min_wall_mm:g})"
            )
        return ""


def wall_mm(blade: BladeGeometry, s: ArrayLike, u: ArrayLike) -> NDArray[np.float64]:
    """wall(s, u) of the module docstring, mm, for every pair of the grid: ``(len(s), len(u))``.

    ``u`` is the half parameter of the sections (0 = leading edge, 1 = trailing edge; the
    chord position is u^2 for NACA sections).
    """
    s, u = np.atleast_1d(np.asarray(s, float)), np.atleast_1d(np.asarray(u, float))
    across = np.stack(
        [
            section.points_on_half(u, True) - section.points_on_half(u, False)
            for section in sections_along(blade, s)
        ]
    )  # (len(s), len(u), 2), chord units
    matrices = _section_matrices(blade.laws, s)
    return np.linalg.norm(np.einsum("kij,kuj->kui", matrices, across), axis=-1)


def chord_fraction(blade: BladeGeometry, s: float, u: float) -> float:
    """Chord position (x in chord units) of the middle of the chord station ``u`` of the section at
    ``s``."""
    section = sections_along(blade, [s])[0]
    return float(
        0.5 * (section.points_on_half([u], True)[0, 0] + section.points_on_half([u], False)[0, 0])
    )


def _section_matrices(laws: SectionLaws, s: NDArray[np.float64]) -> NDArray[np.float64]:
    """diag(Sx, Sy) R(alpha) for every s: ``(k, 2, 2)`` (the pivot's shift cancels in a
    difference)."""
    scales = np.stack(
        [evaluate_quartic(laws.scale_x_mm, s), evaluate_quartic(laws.scale_y_mm, s)], axis=-1
    )
    return scales[:, :, None] * rotation_matrices(evaluate_quartic(laws.angle_of_attack_deg, s))


def exposed_span(geometry: PropellerGeometry) -> tuple[float, float]:
    """[s_in, s_out] of the module docstring: where blade 0's centerline leaves the hub and comes
    back.

    (0, 1) for a centerline that never leaves the hub (the kernel then has no blade to print).
    """
    centerline, hub = geometry.centerline(0), geometry.hub

    def outside_mm(s: ArrayLike) -> NDArray[np.float64]:
        """Positive outside the hub: max(r - R, |z| - L/2), mm, per s."""
        points = centerline.points(s)
        return np.maximum(
            np.hypot(points[:, 0], points[:, 1]) - hub.radius_mm,
            np.abs(points[:, 2]) - hub.length_mm / 2,
        )

    grid = np.linspace(0.0, 1.0, _S_SAMPLES)
    out = outside_mm(grid) > 0.0
    if not out.any():
        return 0.0, 1.0
    first, last = int(np.argmax(out)), len(grid) - 1 - int(np.argmax(out[::-1]))

    def crossing(low: float, high: float) -> float:
        return float(brentq(lambda s: float(outside_mm([s])[0]), low, high, xtol=1e-12))

    s_in = crossing(grid[first - 1], grid[first]) if first > 0 else 0.0
    s_out = crossing(grid[last], grid[last + 1]) if last < len(grid) - 1 else 1.0
    return s_in, s_out


def printability(geometry: PropellerGeometry, min_wall_mm: float) -> Printability:
    """Thinnest wall, trailing-edge thickness and the printable flag of the blade over its exposed
    span (module docstring)."""
    blade = geometry.blade
    span = exposed_span(geometry)
    u_grid = np.sin(np.linspace(0.0, 0.5 * np.pi, _X_SAMPLES))  # dense at the trailing edge
    s_grid = np.linspace(*span, _S_SAMPLES)

    def thickest(s: float) -> tuple[float, float]:
        walls = wall_mm(blade, [s], u_grid)[0]
        index = int(np.argmax(walls))
        low, high = u_grid[max(index - 1, 0)], u_grid[min(index + 1, len(u_grid) - 1)]
        best = minimize_scalar(
            lambda u: -wall_mm(blade, [s], [u])[0, 0],
            bounds=(low, high),
            method="bounded",
            options={"xatol": 1e-10},
        )
        return (
            (-float(best.fun), float(best.x))
            if -best.fun >= walls[index]
            else (float(walls[index]), float(u_grid[index]))
        )

    section_walls = wall_mm(blade, s_grid, u_grid).max(axis=1)
    s_wall = _polish_minimum(lambda s: thickest(s)[0], s_grid, section_walls)
    wall, u_wall = thickest(s_wall)
    edge = wall_mm(blade, s_grid, [1.0])[:, 0]
    s_edge = _polish_minimum(lambda s: float(wall_mm(blade, [s], [1.0])[0, 0]), s_grid, edge)
    edge_thickness = float(wall_mm(blade, [s_edge], [1.0])[0, 0])
    # the spec's sharp edge: exactly 0
    edge_thickness = 0.0 if edge_thickness < 1e-12 else edge_thickness
    return Printability(
        wall,
        s_wall,
        chord_fraction(blade, s_wall, u_wall),
        edge_thickness,
        s_edge,
        span,
        min_wall_mm,
        bool(min(wall, edge_thickness) >= min_wall_mm * (1.0 - _ROUNDING)),
    )


def _polish_minimum(function: Any, grid: NDArray[np.float64], values: NDArray[np.float64]) -> float:
    """The argument of the smallest of ``values`` on ``grid``, refined between its neighbours."""
    index = int(np.argmin(values))
    low, high = grid[max(index - 1, 0)], grid[min(index + 1, len(grid) - 1)]
    best = minimize_scalar(function, bounds=(low, high), method="bounded", options={"xatol": 1e-10})
    return float(best.x) if best.fun <= values[index] else float(grid[index])


#: Radii and chord stations of the conventional printability search.
_PRINT_RADII, _PRINT_CHORD_STATIONS = 401, 401


def conventional_printability(blade: ConventionalBlade, min_wall_mm: float) -> Printability:
    """The blade's walls outside the hub against ``min_wall_mm`` (this module's
    definitions; s is the sampling parameter of :meth:`ConventionalBlade.section_radii_mm`).

    wall(r, u) = c(r) |upper(u) - lower(u)| of the thickness-scaled section (placing it is a rigid
    motion); the trailing edge is the section's own (0 for a sharp one)."""
    s, r_mm = blade.section_radii_mm(_PRINT_RADII)
    exposed = r_mm >= blade.hub.radius_mm
    s, r_mm = s[exposed], r_mm[exposed]
    u = np.sin(np.linspace(0.0, 0.5 * np.pi, _PRINT_CHORD_STATIONS))
    chord = blade.chord_mm(r_mm)
    walls = np.stack(
        [
            np.linalg.norm(
                section.points_on_half(u, True) - section.points_on_half(u, False), axis=-1
            )
            for section in (blade.section_at(float(r)) for r in r_mm)
        ]
    )
    walls *= chord[:, None]
    thickest = walls.max(axis=1)
    row = int(np.argmin(thickest))
    column = int(np.argmax(walls[row]))
    section = blade.section_at(float(r_mm[row]))
    fraction = float(
        0.5
        * (
            section.points_on_half(u[column : column + 1], True)[0, 0]
            + section.points_on_half(u[column : column + 1], False)[0, 0]
        )
    )
    edge = walls[:, -1]
    edge_row = int(np.argmin(edge))
    edge_mm = 0.0 if edge[edge_row] < 1e-12 else float(edge[edge_row])
    wall_mm = float(thickest[row])
    return Printability(
        wall_mm,
        float(s[row]),
        fraction,
        edge_mm,
        float(s[edge_row]),
        (float(s[0]), 1.0),
        min_wall_mm,
        bool(min(wall_mm, edge_mm) >= min_wall_mm * (1.0 - 1e-9)),
    )
