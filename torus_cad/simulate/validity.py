"""What ``torus-cad simulate`` can serve, and how far a result stays within its physics.

Before any work (ParameterError / BudgetError, exit 2, nothing written): a ``--step`` propeller's
tip diameter must lie in :data:`STEP_DIAMETER_RANGE_MM`, and its layered (snappyHexMesh) mesh,
estimated from the solid's surface area by :func:`estimate_layered_cells`, must stay under
:data:`LAYERED_CELL_LIMIT` (the refusal is worded as ``cfd``'s,
:func:`torus_cad.cfd_domain.estimate.over_limit_error`).

After the mesh is written and after a run, :func:`validity_flags` lists what lies outside the
physics the case was set up for: a first prism layer that is not thin against the blade, a chord
Reynolds number outside the turbulence model's range, a mean y+ far from the one the first layer was
sized for. They go into the report's ``validity`` and onto the terminal as ``warning:`` lines.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from torus_cad.cfd_domain.estimate import over_limit_error
from torus_cad.errors import ParameterError
from torus_cad.simulate.settings import (
    BACKGROUND_CELLS_PER_D,
    SURFACE_LEVEL,
    Y_PLUS_REFERENCE_RADIUS,
    Y_PLUS_TARGET,
    ZONE_LEVEL,
    Level,
    Mesher,
    OperatingPoint,
)
from torus_cad.simulate.snappy import REFERENCE_CHORD_D, level_scale, reference_reynolds

if TYPE_CHECKING:
    from torus_cad.cfd_domain.step_body import StepPropeller
    from torus_cad.parameters.design import Cfd

#: --step tip diameters (mm): from 5 mm, where the smallest prism cell (fine level,
#: --surface-refinement 4, an edge cell) stays over snappyHexMesh's minVol 1e-18 m^3 (3.3 mm) and
#: the tip Mach limit still reaches a chord Reynolds number of 5e3 (the default design's at 10,000
#: rpm), to 2 m, where tessellating at STL_LINEAR_DEFLECTION (an absolute 0.05 mm) already gives
#: 294k triangles, 0.8 GB and 9 s on the default design's shape (it grows with D: 10 m segfaulted
#: under 3 GB, 1 km took 22 GB).
STEP_DIAMETER_RANGE_MM = (5.0, 2000.0)
#: The most cells the estimate may give a layered mesh: it errs 1.0x to 2.4x high on the seven
#: measured meshes, so the largest let through is about the APC's --surface-refinement 4 mesh
#: (966,950 cells, estimated 1.66M; 1.9 GB, 18 min), near the 2.6 GB of ``cfd``'s
#: CFD_TETRAHEDRA_LIMIT.
LAYERED_CELL_LIMIT = 2_000_000
#: Cells per surface face (the solid's area over the level's surface cell squared): the APC 10x7
#: SF's coarse mesh, 20,006 cells, rounded up, the higher of the two fits (the default design's
#: 51,822 give 12).
CELLS_PER_SURFACE_FACE = 31.0
#: Each --surface-refinement step multiplies the cells near the surface by this: the most the APC's
#: series grew per step (1.9, 2.5, 3.1, 3.3; the default's 3.2 and 3.8 with its lower
#: CELLS_PER_SURFACE_FACE).
SURFACE_REFINEMENT_GROWTH = 3.3
#: Peak memory of a layered run: a fixed part and per cell (the default's coarse 52k cells 0.95 GB,
#: the APC's 967k cells 1.9 GB: the docs' simulation-accuracy page).
MEMORY_BASE_GB, MEMORY_PER_CELL_KB = 0.9, 1.04
#: A first prism layer thicker than this fraction of the chord at 0.75 R is flagged: the default
#: design's and the APC's are 0.22 to 0.3 %; at 1 % the eight layers stand a quarter chord tall,
#: several blade thicknesses.
FIRST_LAYER_MAX_CHORD_FRACTION = 0.01
#: The chord Reynolds number at 0.75 R outside which the flow model is flagged: below 1e3 the
#: laminar layer (5 / sqrt(Re) of the chord) is over 16 % of the chord thick, not the thin wall
#: layer kOmegaSST's wall treatment and the y+ sizing assume; above 1e7 lies beyond the airfoil and
#: flat-plate cases SST was calibrated on.
REYNOLDS_RANGE = (1.0e3, 1.0e7)
#: The mean y+ on the propeller is flagged outside [target / 10, target x 30]: the flat-plate sizing
#: lands within tens of percent (mean 1.13 for 1 on the default design, the APC's coarse 12 to 15
#: with its first layer raised); beyond 30 the first cell is in the log layer, below 0.1 the flow is
#: not the one sized for.
Y_PLUS_MEAN_RANGE = (0.1 * Y_PLUS_TARGET, 30.0 * Y_PLUS_TARGET)


def _millimetres(value_mm: float) -> str:
    """``0.1``, ``45.1``, ``1,000,006``: a length in mm as read on a terminal."""
    return f"{value_mm:,.0f}" if value_mm >= 1.0e4 else f"{value_mm:.3g}"


def estimate_layered_cells(
    area_mm2: float,
    z_extent_mm: float,
    diameter_mm: float,
    level: Level,
    surface_refinement: int,
    cfd: Cfd,
) -> int:
    """The cells of the snappyHexMesh mesh of a propeller of surface ``area_mm2`` (mm^2), axial
    extent ``z_extent_mm`` and tip diameter ``diameter_mm`` (mm) at ``level`` and
    ``surface_refinement``, in the domain of ``cfd`` (D units): the background box, the rotating
    zone at ``ZONE_LEVEL`` and the cells near the surface (:data:`CELLS_PER_SURFACE_FACE` per
    surface face, x :data:`SURFACE_REFINEMENT_GROWTH` per refinement)."""
    cell = diameter_mm / BACKGROUND_CELLS_PER_D / level_scale(level)
    box = (
        (2.0 * cfd.domain_radius * diameter_mm / cell) ** 2
        * (cfd.upstream + cfd.downstream)
        * diameter_mm
        / cell
    )
    zone_length = z_extent_mm + 2.0 * cfd.zone_clearance * diameter_mm
    zone = (
        math.pi * (cfd.zone_radius * diameter_mm) ** 2 * zone_length / (cell / 2.0**ZONE_LEVEL) ** 3
    )
    faces = area_mm2 / (cell / 2.0**SURFACE_LEVEL) ** 2
    return int(
        box + zone + CELLS_PER_SURFACE_FACE * faces * SURFACE_REFINEMENT_GROWTH**surface_refinement
    )


def check_step_propeller(
    step: StepPropeller, level: Level, surface_refinement: int, mesher: Mesher, cfd: Cfd
) -> None:
    """ParameterError (exit 2) when the STEP propeller's tip diameter is outside
    :data:`STEP_DIAMETER_RANGE_MM`; BudgetError (exit 2) when its layered mesh (``mesher`` snappy)
    is estimated over :data:`LAYERED_CELL_LIMIT`. ``cfd`` holds the level's domain (D units).
    Nothing is meshed or written."""
    from torus_cad.kernel.mass_properties import surface_area_mm2

    low, high = STEP_DIAMETER_RANGE_MM
    diameter = step.body.tip_diameter_mm
    if not low <= diameter <= high:
        raise ParameterError(
            f"--step {step.source!r}: tip diameter {_millimetres(diameter)} mm is out of range; "
            f"allowed [{low:g}, {high:g}] mm (the sizes the mesher and the flow model serve)"
        )
    if mesher != Mesher.SNAPPY:
        return
    area = surface_area_mm2(step.body.solid)
    cells = estimate_layered_cells(
        area, step.body.solid.BoundingBox().zlen, diameter, level, surface_refinement, cfd
    )
    if cells > LAYERED_CELL_LIMIT:
        memory = MEMORY_BASE_GB + MEMORY_PER_CELL_KB * cells / 1.0e6
        raise over_limit_error(
            f"--step {step.source!r}: the layered mesh",
            cells,
            "cells",
            f"{memory:.1f} GB of memory ({level.value} level, --surface-refinement "
            f"{surface_refinement}, a surface of {area / diameter**2:.3g} D^2)",
            LAYERED_CELL_LIMIT,
            "lower --surface-refinement or --level",
        )


def validity_flags(
    diameter_m: float,
    point: OperatingPoint,
    first_layer_m: float | None,
    y_plus: dict[str, Any] | None,
) -> list[str]:
    """What lies outside the physics the case was set up for, one sentence each (empty: nothing).
    ``diameter_m`` the tip diameter (m); ``first_layer_m`` the first prism layer asked of the mesher
    (m; None: no layers); ``y_plus`` the run's y+ (``min``, ``mean``, ``max``; None before a
    run)."""
    flags = []
    chord = REFERENCE_CHORD_D * diameter_m
    if first_layer_m is not None and first_layer_m > FIRST_LAYER_MAX_CHORD_FRACTION * chord:
        flags.append(
            f"the first prism layer, {first_layer_m * 1e3:.3g} mm, "
            f"is {first_layer_m / chord:.3g} x the "
            f"chord at {Y_PLUS_REFERENCE_RADIUS:g} R ({chord * 1e3:.3g} mm), over "
            f"{FIRST_LAYER_MAX_CHORD_FRACTION:g}: the layers are not thin against the blade"
        )
    reynolds = reference_reynolds(diameter_m, point.rpm, point.airspeed_m_s, point.fluid)
    low, high = REYNOLDS_RANGE
    if reynolds > 0.0 and not low <= reynolds <= high:
        flags.append(
            f"the chord Reynolds number at {Y_PLUS_REFERENCE_RADIUS:g} R "
            f"is {reynolds:.3g}, outside the "
            f"turbulence model's [{low:.0e}, {high:.0e}]: "
            "forces and y+ are not those of its physics"
        )
    low, high = Y_PLUS_MEAN_RANGE
    if y_plus is not None and not low <= y_plus["mean"] <= high:
        flags.append(
            f"the mean y+ on the propeller is {y_plus['mean']:.3g}, "
            f"outside [{low:g}, {high:g}] around the "
            f"first layer's target {Y_PLUS_TARGET:g}: the wall is not resolved as sized"
        )
    return flags
