#!/usr/bin/env python3
"""Check the shared-intersection fuse against the general fuse on N random designs.

    python scripts/fuse_routes.py 200              # seeds 0..199, 2 worker processes
    python scripts/fuse_routes.py 50 --seed 1000

For every design that builds, the propeller made by ``build_propeller`` (normally by the
shared-intersection route, :func:`torus_cad.kernel.fuse.fuse_pattern`) is compared with one
general ``BRepAlgoAPI_Fuse`` of the same hub and blades (:func:`torus_cad.kernel.fuse.fuse_all`):
volume (adaptive integration, relative precision 1e-7) and face count, plus the time of each
route's fuse. Prints how often each route was taken, the largest volume difference and the
median times; designs whose volumes differ by more than ``--tolerance`` are listed (exit 1).
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from torus_cad.errors import GeometryError, ParameterError
from torus_cad.kernel.fuse import FuseRoute

# studies/ sits beside torus_cad, outside it
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from studies.fuzz import random_design

VOLUME_PRECISION = 1e-7


def compare(seed: int) -> dict[str, Any]:
    """Build design ``seed`` and fuse it again the general way; volumes, faces and times of both."""
    from torus_cad.kernel.checks import single_valid_solid
    from torus_cad.kernel.fuse import fuse_all
    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.propeller import build_propeller

    try:
        propeller = build_propeller(random_design(seed))
    except (ParameterError, GeometryError) as refusal:
        return {"seed": seed, "outcome": "refused", "message": str(refusal)}
    except Exception as error:
        return {"seed": seed, "outcome": "error", "message": f"{type(error).__name__}: {error}"}
    start = time.perf_counter()
    general = single_valid_solid(
        fuse_all(propeller.hub, propeller.blades).shape, "the general fuse"
    )
    general_s = time.perf_counter() - start
    built_volume = precise_volume(propeller.solid, VOLUME_PRECISION)
    general_volume = precise_volume(general, VOLUME_PRECISION)
    return {
        "seed": seed,
        "outcome": "valid",
        "route": propeller.fuse_route,
        "blades": propeller.parameters.blades,
        "route_fuse_s": propeller.stage_seconds["fuse"],
        "general_fuse_s": general_s,
        "relative_volume_difference": abs(built_volume - general_volume) / general_volume,
        "faces": (len(propeller.solid.Faces()), len(general.Faces())),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("count", type=int, help="number of random designs")
    parser.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument(
        "--tolerance", type=float, default=1e-6, help="largest accepted relative volume difference"
    )
    args = parser.parse_args(argv)

    started = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(compare, range(args.seed, args.seed + args.count)))
    valid = [row for row in rows if row["outcome"] == "valid"]
    shared = [row for row in valid if row["route"] != FuseRoute.GENERAL]
    print(
        f"{args.count} designs: {len(valid)} built, "
        f"{sum(r['outcome'] == 'refused' for r in rows)} refused, "
        f"{sum(r['outcome'] == 'error' for r in rows)} errors "
        f"({time.perf_counter() - started:.0f} s)"
    )
    routes = collections.Counter(row["route"] for row in valid)
    print("routes: " + ", ".join(f"{route} {count}" for route, count in sorted(routes.items())))
    for route in sorted(routes):
        if route != FuseRoute.ASSEMBLED:
            print(
                f"  {route}: seeds "
                f"{', '.join(str(row['seed']) for row in valid if row['route'] == route)}"
            )
    bad = [
        row
        for row in valid
        if row["relative_volume_difference"] > args.tolerance or row["faces"][0] != row["faces"][1]
    ]
    if valid:
        worst = max(valid, key=lambda row: row["relative_volume_difference"])
        print(
            "largest relative volume difference: "
            f"{worst['relative_volume_difference']:.2e} (seed {worst['seed']})"
        )
    if shared:
        route_s = statistics.median(row["route_fuse_s"] for row in shared)
        general_s = statistics.median(row["general_fuse_s"] for row in shared)
        print(
            f"median fuse time where the shared route was taken: {route_s * 1e3:.0f} ms shared, "
            f"{general_s * 1e3:.0f} ms general ({general_s / route_s:.2f}x)"
        )
    for row in rows:
        if row["outcome"] == "error" or row in bad:
            print(f"  seed {row['seed']}: {row}")
    return 1 if bad or any(row["outcome"] == "error" for row in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
