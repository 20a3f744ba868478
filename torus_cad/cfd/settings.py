"""Settings of ``torus-cad cfd``: domain sizes (multiples of the tip diameter D), mesh sizes, growth."""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass
from enum import StrEnum

from torus_cad.errors import ParameterError, TorusCadError


class MissingExtraError(TorusCadError):
    """An optional dependency is not installed; the message names the extra that installs it."""


class InletSide(StrEnum):
    """Which end of the domain the flow enters: ``+z`` (the top end cap) or ``-z``."""

    PLUS_Z = "+z"
    MINUS_Z = "-z"


#: (low, high, help) of each numeric setting; the help text names the unit.
_RANGES: dict[str, tuple[float, float, str]] = {
    "domain_radius": (1.0, 50.0, "outer cylinder radius, multiples of the tip diameter D"),
    "upstream": (0.5, 100.0, "inlet distance from the propeller's centre, multiples of D"),
    "downstream": (0.5, 200.0, "outlet distance from the propeller's centre, multiples of D"),
    "zone_radius": (0.51, 5.0, "rotating-zone radius, multiples of D (> 0.5: it encloses the tips)"),
    "zone_clearance": (0.01, 2.0, "axial gap between the propeller and the rotating zone's end faces, multiples of D"),
    "cells_per_chord": (2.0, 200.0, "surface elements across the smallest chord (sets the blade size)"),
    "curvature_cells": (0.0, 100.0, "elements per 2 pi radians of surface curvature (0 = off)"),
    "growth_rate": (1.02, 3.0, "size ratio of neighbouring elements away from the propeller"),
    "far_size": (0.01, 5.0, "largest element, multiples of D"),
    "threads": (0, 256, "gmsh threads (0 = one per CPU)"),
}


@dataclass(frozen=True)
class CfdSettings:
    """The fluid domain and its mesh. Lengths are multiples of the tip diameter D unless noted.

    Attributes:
        domain_radius: outer cylinder's radius.
        upstream, downstream: distances of the inlet and the outlet from the propeller's axial centre.
        zone_radius: the rotating zone's radius (> 0.5: it must enclose the blade tips).
        zone_clearance: axial gap between the propeller and each end face of the rotating zone.
        cells_per_chord: elements across the smallest chord: the surface size on the propeller.
        curvature_cells: elements per 2 pi of surface curvature (gmsh MeshSizeFromCurvature; 0 = off).
        growth_rate: how fast elements grow away from the propeller (ratio of neighbours).
        far_size: the largest element.
        inlet_side: where the flow enters (inlet end cap; the outlet is the other one).
        threads: gmsh threads, 0 = one per CPU.
    """

    domain_radius: float = 4.0
    upstream: float = 3.0
    downstream: float = 6.0
    zone_radius: float = 0.6
    zone_clearance: float = 0.1
    cells_per_chord: float = 10.0
    curvature_cells: float = 8.0
    growth_rate: float = 1.25
    far_size: float = 0.3
    inlet_side: InletSide = InletSide.PLUS_Z
    threads: int = 0

    def __post_init__(self) -> None:
        for name, (low, high, _) in _RANGES.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                raise ParameterError(f"cfd.{name} = {value!r} is out of range; allowed [{low:g}, {high:g}]")
        try:
            object.__setattr__(self, "inlet_side", InletSide(self.inlet_side))
        except ValueError:
            raise ParameterError(f"cfd.inlet_side = {self.inlet_side!r} is not allowed; allowed: '+z', '-z'") from None
        if self.domain_radius < 1.5 * self.zone_radius:
            raise ParameterError(f"cfd.domain_radius = {self.domain_radius:g} must be at least 1.5 x cfd.zone_radius "
                                 f"= {1.5 * self.zone_radius:g} (room for the outer region)")

    @staticmethod
    def option_names() -> list[str]:
        """Names of the settings, which are also the command line's option destinations."""
        return [item.name for item in dataclasses.fields(CfdSettings)]

    @staticmethod
    def add_arguments(parser: argparse.ArgumentParser) -> None:
        """One ``--option`` per setting (default None: keep the setting's default)."""
        defaults = CfdSettings()
        for name, (_, _, text) in _RANGES.items():
            kind = int if name == "threads" else float
            parser.add_argument(f"--{name.replace('_', '-')}", dest=name, type=kind, metavar="X",
                                help=f"{text} (default {getattr(defaults, name):g})")
        parser.add_argument("--inlet-side", dest="inlet_side", choices=[item.value for item in InletSide],
                            help=f"end where the flow enters (default {defaults.inlet_side.value})")
