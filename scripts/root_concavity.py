#!/usr/bin/env python3
"""The tightest concave bend of the blade's faces next to the hub, per fuzz design (issue 13).

    python scripts/root_concavity.py 130 --rate fillet_rate_out/fillet_rate.json

A constant-radius (rolling-ball) fillet cannot follow a blade face that bends concavely, seen from
the fillet's side, tighter than its radius: the ball does not fit, its centre path would have a
cusp. For each valid design the fuzz sampler draws (:func:`torus_cad.studies.fuzz.random_design_dict`),
blade 0 is joined to the hub as the root fillet joins it, and the principal curvatures of its
blade faces are sampled (a 160 x 160 grid per face) where the face lies within ``--band`` fillet
radii of the hub's cylinder; the tightest concave radius is printed, with the design's fillet
outcome from ``scripts/fillet_rate.py`` JSON files when given. Designs refused before the
kernel are skipped.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import cadquery as cq
import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Pnt2d
from OCP.TopAbs import TopAbs_IN, TopAbs_REVERSED

from torus_cad.errors import GeometryError, KernelError, ParameterError
from torus_cad.kernel.fillet import BLADE_SURFACES
from torus_cad.kernel.fuse import fuse_pattern
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller
from torus_cad.studies.fuzz import random_design_dict

#: Samples per face direction.
GRID = 160


def tightest_concave_radius_mm(hub_radius_mm: float, solid: cq.Solid, band_mm: float) -> float:
    """Smallest radius (mm) of a concave bend (seen from outside) of ``solid``'s blade faces within
    ``band_mm`` of the hub's cylinder (radius ``hub_radius_mm`` about z); inf when there is none."""
    tightest = math.inf
    for face in solid.Faces():
        surface = BRepAdaptor_Surface(face.wrapped)
        if surface.GetType() not in BLADE_SURFACES:
            continue
        outward = -1.0 if face.wrapped.Orientation() == TopAbs_REVERSED else 1.0
        u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face.wrapped)
        for u in np.linspace(u_min, u_max, GRID):
            for v in np.linspace(v_min, v_max, GRID):
                point = surface.Value(u, v)
                if not 0.0 < math.hypot(point.X(), point.Y()) - hub_radius_mm < band_mm:
                    continue
                if BRepClass_FaceClassifier(face.wrapped, gp_Pnt2d(u, v), 1e-6).State() != TopAbs_IN:
                    continue
                props = BRepLProp_SLProps(surface, u, v, 2, 1e-7)
                if not props.IsCurvatureDefined():
                    continue
                # With the outward normal, a concave bend has a positive curvature.
                concave = max(outward * props.MaxCurvature(), outward * props.MinCurvature())
                if concave > 0.0:
                    tightest = min(tightest, 1.0 / concave)
    return tightest


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("count", nargs="?", type=int, default=130, help="number of seeds (default 130)")
    parser.add_argument("--seed", type=int, default=0, help="first seed")
    parser.add_argument("--radius", type=float, default=0.5, help="root fillet radius, mm (default 0.5)")
    parser.add_argument("--band", type=float, default=2.0, help="height above the hub looked at, in radii (default 2)")
    parser.add_argument("--rate", type=Path, action="append", default=[],
                        help="a fillet_rate.json to take outcomes from (repeatable)")
    args = parser.parse_args()
    outcomes = {row["seed"]: row["outcome"] for path in args.rate
                for row in json.loads(path.read_text())["designs"]}
    tally: dict[tuple[str, bool], int] = {}
    for seed in range(args.seed, args.seed + args.count):
        if outcomes.get(seed) == "refused":
            continue
        try:
            propeller = build_propeller(PropellerParameters.from_dict(random_design_dict(seed)))
            joined = fuse_pattern(propeller.hub, propeller.blades[0], [0.0]).shape.Solids()[0]
        except (ParameterError, GeometryError, KernelError):
            continue
        radius = tightest_concave_radius_mm(propeller.parameters.hub.radius, joined, args.band * args.radius)
        outcome = outcomes.get(seed, "?")
        tighter = radius < args.radius
        tally[outcome, tighter] = tally.get((outcome, tighter), 0) + 1
        print(f"seed {seed:5d}  tightest concave radius {radius:8.3f} mm  fillet {outcome}", flush=True)
    for (outcome, tighter), designs in sorted(tally.items()):
        print(f"fillet {outcome}: {designs} designs bend concavely {'tighter' if tighter else 'no tighter'} "
              f"than {args.radius:g} mm near the hub")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
