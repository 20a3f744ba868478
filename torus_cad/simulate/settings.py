"""What ``torus-cad simulate`` runs: mesh levels, the fluid, inflow turbulence, the operating
point's ranges.

Levels map to ``[cfd]`` sizes. All three share one domain (radius 3 D, inlet 2 D upstream and
outlet 4 D downstream of the propeller's centre) and differ only in element size: every size
(surface elements per chord, the growth per element, the largest element) is refined by
``REFINEMENT_RATIO`` = 2^(1/3) from one level to the next, so that Richardson extrapolation over
the three has one ratio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import Handedness, InletSide
from torus_cad.runtime.cpus import available_cpus
from torus_cad.tolerances import SIMULATE_AIRSPEED_LIMIT_M_S

#: Simulations (torus_cad.simulate): the incompressible solver is trusted up to this helical tip
#: Mach number (tip speed with the airspeed, over the speed of sound); faster rpm are refused.
SIMULATE_TIP_MACH_LIMIT = 0.6


class Level(StrEnum):
    """Mesh level of a simulation (``--level``)."""

    COARSE = "coarse"
    MEDIUM = "medium"
    FINE = "fine"


class Mesher(StrEnum):
    """How ``simulate`` meshes the fluid (``--mesher``): ``snappy`` (snappyHexMesh, prism layers on
    the propeller sized from a y+ target; the default) or ``tet`` (the ``cfd`` command's gmsh
    tetrahedra, no layers)."""

    SNAPPY = "snappy"
    TET = "tet"


class TurbulenceModel(StrEnum):
    """RANS model of ``simulate`` (``--turbulence``): ``kOmegaSST`` (the default), or
    ``kOmegaSSTLM``: the same model with Langtry and Menter's gamma-ReThetat transition equations
    (laminar boundary layers up to a predicted transition; two more transported fields, ``gammaInt``
    and ``ReThetat``)."""

    K_OMEGA_SST = "kOmegaSST"
    K_OMEGA_SST_LM = "kOmegaSSTLM"


def transition_onset_re_theta(intensity: float) -> float:
    """Langtry and Menter's transition-onset momentum-thickness Reynolds number for a free-stream
    turbulence intensity (a fraction), zero pressure gradient: the inflow value of ``ReThetat``."""
    tu_percent = max(100.0 * intensity, 0.027)  # the bound kOmegaSSTLM itself applies
    if tu_percent <= 1.3:
        return 1173.51 - 589.428 * tu_percent + 0.2196 / tu_percent**2
    return 331.5 * (tu_percent - 0.5658) ** -0.671


#: Element sizes are divided by this from one level to the next.
REFINEMENT_RATIO = 2.0 ** (1.0 / 3.0)

#: The domain every level uses, in tip diameters D (``[cfd]`` keys).
DOMAIN_D = {"domain_radius": 3.0, "upstream": 2.0, "downstream": 4.0}

#: The coarse level's sizes: at most 60,000 tetrahedra on the default design (trailing edges with
#: their own size field, as curvature sizing is off; the estimate: the docs' measurements page).
_COARSE_SIZES = {"cells_per_chord": 4.0, "growth_rate": 1.6, "far_size": 0.4}


def level_cfd(level: Level) -> dict[str, float]:
    """The ``[cfd]`` values of ``level`` (curvature refinement off: the sizes alone set the
    mesh)."""
    steps = list(Level).index(level)
    scale = REFINEMENT_RATIO**steps
    sizes = {
        "cells_per_chord": round(_COARSE_SIZES["cells_per_chord"] * scale, 3),
        "growth_rate": round(1.0 + (_COARSE_SIZES["growth_rate"] - 1.0) / scale, 4),
        "far_size": round(_COARSE_SIZES["far_size"] / scale, 4),
        "curvature_cells": 0.0,
    }
    return {**DOMAIN_D, **sizes}


#: The boundary-layer mesh (torus_cad.simulate.snappy) of the coarse level; the finer levels divide
#: the background cell and the first layer's height by REFINEMENT_RATIO per step (the refinement
#: levels below are counted from the background cell, so every size follows).
#: Background cubes per tip diameter D.
BACKGROUND_CELLS_PER_D = 3.0
#: snappyHexMesh refinement levels (each halves the background cell): inside the rotating zone, on
#: the propeller's surface, on its sharp edges (leading and trailing edges, hub rims).
ZONE_LEVEL, SURFACE_LEVEL, FEATURE_LEVEL = 2, 4, 5
#: Prism layers on the propeller and the thickness ratio of neighbouring layers.
LAYERS = 8
LAYER_EXPANSION_RATIO = 1.3
#: The layers' total height is at most this many of the propeller's surface cells: on a finer
#: surface (``--surface-refinement``) fewer layers are asked for, as snappyHexMesh drops most of a
#: taller stack (the simulate how-to's surface series).
LAYER_STACK_MAX_SURFACE_CELLS = 2.5
#: The y+ the first layer is sized for (the viscous sublayer: the blades' Reynolds number, about 1e4
#: at 0.75 R, leaves little log layer for a wall function to model), and where on the blade it is
#: estimated (a fraction of the tip radius).
Y_PLUS_TARGET = 1.0
Y_PLUS_REFERENCE_RADIUS = 0.75
#: The last layer is at least this fraction of the propeller's surface cell: across a larger jump
#: the face-weight check drops every layer (the docs' measurements page); where the
#: y+ target asks for thinner layers, the first layer is thickened to this and y+ comes out above
#: the target.
LAST_LAYER_MIN_FRACTION = 0.08

#: Default iterations of each level (steady SIMPLE).
LEVEL_ITERATIONS = {Level.COARSE: 200, Level.MEDIUM: 300, Level.FINE: 400}

#: Default time budget of one run (meshing, conversion and solver), seconds.
DEFAULT_TIME_LIMIT_S = 3600.0


@dataclass(frozen=True)
class Fluid:
    """An incompressible fluid: density kg/m^3, kinematic viscosity m^2/s, speed of sound m/s."""

    name: str
    density_kg_m3: float
    viscosity_m2_s: float
    speed_of_sound_m_s: float


#: Air at 15 C, sea level (ISA).
AIR_15C = Fluid("air at 15 C (ISA sea level)", 1.225, 1.46e-5, 340.3)

#: Inflow turbulence: intensity (fraction of the reference speed) and length scale (fraction of D).
TURBULENCE_INTENSITY = 0.01
TURBULENCE_LENGTH_D = 0.1
#: The reference speed for the inflow turbulence is the airspeed, or at least this fraction of the
#: tip speed (still air: the induced inflow), or at least 1 m/s.
TURBULENCE_TIP_SPEED_FRACTION = 0.1
_CMU = 0.09


@dataclass(frozen=True)
class OperatingPoint:
    """Where the propeller runs: rpm (>= 0, in the design's own sense of rotation), airspeed m/s
    (flowing from the inlet to the outlet), the fluid."""

    rpm: float
    airspeed_m_s: float = 0.0
    fluid: Fluid = AIR_15C

    def omega_rad_s(self, handedness: Handedness) -> float:
        """Angular velocity about +z, rad/s: negative for 'cw' (clockwise seen from +z), positive
        for 'ccw'."""
        sign = -1.0 if handedness == Handedness.CW else 1.0
        return sign * self.rpm * 2.0 * math.pi / 60.0

    def tip_speed_m_s(self, diameter_m: float) -> float:
        return self.rpm * math.pi * diameter_m / 60.0

    def inflow_turbulence(self, diameter_m: float) -> tuple[float, float]:
        """(k m^2/s^2, omega 1/s) of the inflow from ``TURBULENCE_INTENSITY`` and
        ``TURBULENCE_LENGTH_D``."""
        speed = max(
            self.airspeed_m_s, TURBULENCE_TIP_SPEED_FRACTION * self.tip_speed_m_s(diameter_m), 1.0
        )
        k = 1.5 * (TURBULENCE_INTENSITY * speed) ** 2
        return k, math.sqrt(k) / (_CMU**0.25 * TURBULENCE_LENGTH_D * diameter_m)


def rpm_limit(diameter_m: float, airspeed_m_s: float, fluid: Fluid = AIR_15C) -> float:
    """Highest rpm at which the helical tip Mach number stays within ``SIMULATE_TIP_MACH_LIMIT``."""
    tip_speed = math.sqrt(
        max((SIMULATE_TIP_MACH_LIMIT * fluid.speed_of_sound_m_s) ** 2 - airspeed_m_s**2, 0.0)
    )
    return tip_speed * 60.0 / (math.pi * diameter_m)


def check_operating_point(
    point: OperatingPoint, diameter_m: float, params: PropellerParameters
) -> None:
    """ParameterError naming the field, the value and the allowed range."""
    if not (
        math.isfinite(point.airspeed_m_s)
        and 0.0 <= point.airspeed_m_s <= SIMULATE_AIRSPEED_LIMIT_M_S
    ):
        raise ParameterError(
            f"--airspeed = {point.airspeed_m_s:g} m/s is out of range; allowed "
            f"[0, {SIMULATE_AIRSPEED_LIMIT_M_S:g}] m/s (the solver is incompressible)"
        )
    limit = rpm_limit(diameter_m, point.airspeed_m_s, point.fluid)
    if not (math.isfinite(point.rpm) and 0.0 <= point.rpm <= limit):
        raise ParameterError(
            f"--rpm = {point.rpm:g} is out of range; "
            f"allowed [0, {limit:.0f}] rpm (helical tip Mach "
            f"{SIMULATE_TIP_MACH_LIMIT:g} for D = {diameter_m * 1000:.1f} mm at "
            f"{point.airspeed_m_s:g} m/s; the solver is incompressible)"
        )
    if point.airspeed_m_s > 0.0 and params.cfd.inlet_side != InletSide.PLUS_Z:
        raise ParameterError(
            f"cfd.inlet_side = '{params.cfd.inlet_side.value}' puts the inlet behind the propeller "
            "(it pushes air toward -z); with --airspeed > 0 use '+z'"
        )


def check_count(name: str, value: int, low: int, high: int) -> int:
    """``value``, or ParameterError naming ``name`` and the range [low, high]."""
    if not low <= value <= high:
        raise ParameterError(f"{name} = {value} is out of range; allowed [{low}, {high}]")
    return value


def max_processes() -> int:
    """Processes a run may use: the CPUs this process may run on."""
    return available_cpus()


def with_level(params: PropellerParameters, level: Level) -> PropellerParameters:
    """``params`` with the ``[cfd]`` sizes of ``level``."""
    return params.with_values({f"cfd.{key}": value for key, value in level_cfd(level).items()})
