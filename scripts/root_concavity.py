#!/usr/bin/env python3
"""The tightest concave bend of the blade's faces next to the hub, per fuzz design.

    python scripts/root_concavity.py 130 --rate fillet_rate_out/fillet_rate.json

A constant-radius (rolling-ball) fillet cannot follow a blade face that bends concavely, seen from
the fillet's side, tighter than its radius: the ball does not fit, its centre path would have a
cusp. For each valid design the fuzz sampler draws (:func:`studies.fuzz.random_design_dict`),
blade 0 is joined to the hub as the root fillet joins it, and the principal curvatures of its
blade faces are sampled (a 160 x 160 grid per face) where the face lies within ``--band`` fillet
radii of the hub's cylinder; the tightest concave radius is printed, with the design's fillet
outcome from ``scripts/fillet_rate.py`` JSON files when given. Designs refused before the
kernel are skipped.

Next to it, the same measure on the analytic blade
(:func:`torus_cad.geometry.blade.blade_surface.surface_points`, principal curvatures by finite
differences on a 1000 s x 1000 t grid, where the surface lies within the band above the hub's
cylinder and between its end planes): whether the bend is the design's or the loft's. Of the 11
failing seeds (0-129) with a bend tighter than 0.5 mm on the face, 9 bend as tightly on the analytic
blade (0.001-0.24 mm against 0.02-0.31 mm), along the section, never along s; on 2 (64, 98) it is
the section fit's wiggle next to the leading edge (analytic 10.3 and 0.86 mm).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import cadquery as cq
import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Pnt2d
from OCP.TopAbs import TopAbs_IN

from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.errors import GeometryError, KernelError, ParameterError
from torus_cad.geometry.blade.blade_surface import surface_points
from torus_cad.kernel.fillet.tight_bends import concave_bend_radius_mm
from torus_cad.kernel.fuse import fuse_pattern
from torus_cad.kernel.topology import BLADE_SURFACES
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

# studies/ sits beside torus_cad, outside it
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from studies.fuzz import random_design_dict

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
        u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face.wrapped)
        for u in np.linspace(u_min, u_max, GRID):
            for v in np.linspace(v_min, v_max, GRID):
                point = surface.Value(u, v)
                if not 0.0 < math.hypot(point.X(), point.Y()) - hub_radius_mm < band_mm:
                    continue
                if (
                    BRepClass_FaceClassifier(face.wrapped, gp_Pnt2d(u, v), 1e-6).State()
                    != TopAbs_IN
                ):
                    continue
                tightest = min(tightest, concave_bend_radius_mm(face.wrapped, surface, u, v))
    return tightest


def analytic_tightest_concave_radius_mm(
    params: PropellerParameters,
    band_mm: float,
    samples: int = 1000,
    step_s: float = 1e-3,
    step_t: float = 1e-4,
) -> float:
    """The smallest concave radius (mm, seen from outside) of blade 0's analytic surface where it
    lies within ``band_mm`` above the hub's cylinder and between the hub's end planes; inf when
    none."""
    geometry = propeller_geometry(params)
    blade, centerline = geometry.blade, geometry.centerline(0)
    s = np.linspace(step_s, 1.0 - step_s, samples)
    t = np.linspace(0.0, 2.0, samples, endpoint=False) + 1e-3 / samples
    columns = np.concatenate([t - step_t, t, t + step_t])
    rows = [
        surface_points(blade, centerline, s + shift, columns) for shift in (-step_s, 0.0, step_s)
    ]
    (s_minus, s_plus), (t_minus, at, t_plus) = (
        (rows[0][:, samples : 2 * samples], rows[2][:, samples : 2 * samples]),
        np.split(rows[1], 3, axis=1),
    )
    d_s, d_t = (s_plus - s_minus) / (2 * step_s), (t_plus - t_minus) / (2 * step_t)
    d_ss, d_tt = (s_plus - 2 * at + s_minus) / step_s**2, (t_plus - 2 * at + t_minus) / step_t**2
    d_st = (
        (rows[2][:, 2 * samples :] - rows[2][:, :samples])
        - (rows[0][:, 2 * samples :] - rows[0][:, :samples])
    ) / (4 * step_s * step_t)
    normal = np.cross(d_t, d_s)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    outward = np.sign(np.sum(normal * (at - at.mean(axis=1, keepdims=True)), axis=-1).mean(axis=1))
    normal *= outward[:, None, None]
    e, f, g = (np.sum(a * b, axis=-1) for a, b in ((d_s, d_s), (d_s, d_t), (d_t, d_t)))
    l_, m, n = (np.sum(a * normal, axis=-1) for a in (d_ss, d_st, d_tt))
    gauss, mean = (
        (l_ * n - m * m) / (e * g - f * f),
        (e * n - 2 * f * m + g * l_) / (2 * (e * g - f * f)),
    )
    concave = mean + np.sqrt(np.maximum(mean * mean - gauss, 0.0))  # the larger principal curvature
    height = np.hypot(at[..., 0], at[..., 1]) - params.hub.radius
    near = (
        (height > 0.0)
        & (height < band_mm)
        & (np.abs(at[..., 2]) < params.hub.length / 2.0)
        & (concave > 0.0)
    )
    return float(1.0 / concave[near].max()) if np.any(near) else math.inf


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "count", nargs="?", type=int, default=130, help="number of seeds (default 130)"
    )
    parser.add_argument("--seed", type=int, default=0, help="first seed")
    parser.add_argument(
        "--radius", type=float, default=0.5, help="root fillet radius, mm (default 0.5)"
    )
    parser.add_argument(
        "--band",
        type=float,
        default=2.0,
        help="height above the hub looked at, in radii (default 2)",
    )
    parser.add_argument(
        "--rate",
        type=Path,
        action="append",
        default=[],
        help="a fillet_rate.json to take outcomes from (repeatable)",
    )
    args = parser.parse_args()
    outcomes = {
        row["seed"]: row["outcome"]
        for path in args.rate
        for row in json.loads(path.read_text())["designs"]
    }
    tally: dict[tuple[str, bool], int] = {}
    for seed in range(args.seed, args.seed + args.count):
        if outcomes.get(seed) == "refused":
            continue
        try:
            propeller = build_propeller(PropellerParameters.from_dict(random_design_dict(seed)))
            joined = fuse_pattern(propeller.hub, propeller.blades[0], [0.0]).shape.Solids()[0]
        except (ParameterError, GeometryError, KernelError):
            continue
        radius = tightest_concave_radius_mm(
            propeller.parameters.hub.radius, joined, args.band * args.radius
        )
        analytic = analytic_tightest_concave_radius_mm(
            propeller.parameters, args.band * args.radius
        )
        outcome = outcomes.get(seed, "?")
        tighter = radius < args.radius
        tally[outcome, tighter] = tally.get((outcome, tighter), 0) + 1
        print(
            f"seed {seed:5d}  tightest concave radius "
            f"{radius:8.3f} mm (analytic blade {analytic:8.3f} mm)  "
            f"fillet {outcome}",
            flush=True,
        )
    for (outcome, tighter), designs in sorted(tally.items()):
        print(
            f"fillet {outcome}: {designs} designs bend "
            f"concavely {'tighter' if tighter else 'no tighter'} "
            f"than {args.radius:g} mm near the hub"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
