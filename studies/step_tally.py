"""Random designs over the whole design space for the STEP read-back tally
(``scripts/step_readback_tally.py``).

Every option that changes the solid's topology is drawn: the fuzz sampler's toroidal designs
(:func:`studies.fuzz.random_design_dict`, any blade count, both frames) with the workshop features
(bores, D-flats, set screws, chamfers, blunt trailing edges, ccw), a flat or round blunt trailing
edge, a root fillet on one design in four (on a round trailing edge, which the fillet needs, and
half of them with ``root_fillet_tight_bends = 'reduce'``), and a conventional station-table design
on one in five (diameter, blade count, chord and pitch drawn around
``examples/compare/conventional_45mm_3blade``'s).
"""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from studies.fuzz import random_design_dict, workshop_features

#: Shares of the designs: conventional, with a root fillet, a blunt trailing edge that is flat.
CONVENTIONAL_SHARE = 0.2
FILLET_SHARE = 0.25
FLAT_TRAILING_EDGE_SHARE = 0.5

#: The conventional designs' stations (r/R) and the base table's chord (c/R) and t/c at them.
_R_OVER_R = (0.46, 0.55, 0.65, 0.75, 0.85, 0.95, 1.0)
_C_OVER_R = (0.36, 0.34, 0.31, 0.28, 0.25, 0.22, 0.20)
_THICKNESS = (0.10, 0.095, 0.09, 0.085, 0.08, 0.08, 0.08)


def tally_design_dict(seed: int, fillet_share: float = FILLET_SHARE) -> dict[str, Any]:
    """The design of ``seed`` as a nested dict (the TOML layout), named ``tally_<seed>``; a root
    fillet on ``fillet_share`` of the designs."""
    rng = np.random.default_rng([seed, 45])
    design = (
        _conventional(seed, rng)
        if rng.random() < CONVENTIONAL_SHARE
        else random_design_dict(seed, workshop=True)
    )
    design["name"] = f"tally_{seed}"
    airfoil = design.setdefault("airfoil", {})
    if (
        airfoil.get("trailing_edge_thickness", 0.0) > 0.0
        and rng.random() < FLAT_TRAILING_EDGE_SHARE
    ):
        airfoil["trailing_edge_shape"] = "flat"
    if rng.random() < fillet_share:
        hub = design.setdefault("hub", {})
        hub["root_fillet_radius"] = float(rng.uniform(0.2, 1.0))
        hub["root_fillet_tight_bends"] = "reduce" if rng.random() < 0.5 else "fail"
        airfoil["trailing_edge_shape"] = "round"
        airfoil["trailing_edge_thickness"] = max(
            airfoil.get("trailing_edge_thickness", 0.0), float(rng.uniform(0.2, 0.8))
        )
    return design


def _conventional(seed: int, rng: np.random.Generator) -> dict[str, Any]:
    """A conventional design: the base table's chord scaled by 0.6-1.5, a constant geometric pitch
    of 0.3-1.2 D, 2-6 blades, a tip diameter of 30-300 mm and a hub just inside the root station."""
    diameter = float(math.exp(rng.uniform(math.log(30.0), math.log(300.0))))
    radius = diameter / 2.0
    pitch = float(rng.uniform(0.3, 1.2)) * diameter
    chord = float(rng.uniform(0.6, 1.5))
    beta = [math.degrees(math.atan(pitch / (2.0 * math.pi * r * radius))) for r in _R_OVER_R]
    hub_radius = _R_OVER_R[0] * radius * float(rng.uniform(0.85, 0.97))
    design: dict[str, Any] = {
        "kind": "conventional",
        "blades": int(rng.integers(2, 7)),
        "conventional": {
            "diameter": diameter,
            "r_over_R": list(_R_OVER_R),
            "c_over_R": [c * chord for c in _C_OVER_R],
            "beta": beta,
            "thickness_ratio": list(_THICKNESS),
            "stacking": float(rng.uniform(0.2, 0.4)),
        },
        "airfoil": {"naca": "4412"},
        "resolution": {"sections": int(rng.integers(20, 41)), "points": int(rng.integers(48, 97))},
    }
    for table, values in workshop_features(seed, hub_radius).items():
        if isinstance(values, dict):
            design.setdefault(table, {}).update(values)
        else:
            design[table] = values
    design["hub"].update(
        {"radius": hub_radius, "length": float(rng.uniform(0.8, 1.6)) * hub_radius}
    )
    return design


#: Builds of one design, each after following the refusal's advice (:func:`follow_advice`).
RETRIES = 3


def follow_advice(design: dict[str, Any], refusal: str) -> bool:
    """Change ``design`` as a user would on reading ``refusal``: a trailing edge too thick for the
    blade halved, a root fillet that fails at its radius given the radius the message says works;
    False when the refusal gives no such way on."""
    works = re.search(r"hub.root_fillet_radius = ([0-9.e-]+) mm works", refusal)
    if works:
        design["hub"]["root_fillet_radius"] = float(works.group(1))
        return True
    if refusal.startswith("airfoil.trailing_edge_thickness") and "too thick" in refusal:
        design["airfoil"]["trailing_edge_thickness"] /= 2.0
        return True
    return False


def built_tally_design(seed: int, fillet_share: float = FILLET_SHARE) -> Any:
    """The propeller of ``seed`` (:func:`tally_design_dict`), built again after each refusal whose
    advice :func:`follow_advice` follows, up to RETRIES builds; the last refusal is raised."""
    from torus_cad.errors import GeometryError, KernelError, ParameterError
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    design = tally_design_dict(seed, fillet_share)
    for attempt in range(RETRIES):
        try:
            return build_propeller(PropellerParameters.from_dict(design))
        except (ParameterError, GeometryError, KernelError) as refusal:
            if attempt == RETRIES - 1 or not follow_advice(design, str(refusal)):
                raise
    raise AssertionError("unreachable")
