#!/usr/bin/env python3
"""How often the root fillet works on random valid designs (aim: >= 90 % at 0.5 mm).

    python scripts/fillet_rate.py 160                # seeds 0..159, radius 0.5 mm
    python scripts/fillet_rate.py 160 --radius 1.0 --seed 1000
    python scripts/fillet_rate.py --seeds 32 55 --fillet-shape polynomial
        # another cross-section law

Each design comes from the fuzz sampler (:func:`studies.fuzz.random_design_dict`, the
designs ``scripts/fuzz.py`` draws) with ``hub.root_fillet_radius`` set. Designs refused before
the kernel, or whose fuse fails, are not counted; the others either get their fillet (one
valid solid: ``ok`` with the requested radius everywhere, ``reduced`` with a smaller one along
junction edges where the blade bends too tightly for it, see
torus_cad.kernel.fillet.root_fillet.RootFillet) or fail with "root fillet failed". The fillet runs
in a forked child process, so a crash in OpenCascade counts as a failure. Prints one line per design
and the rate; writes ``fillet_rate_out/fillet_rate.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from OCP.ChFi3d import ChFi3d_Polynomial, ChFi3d_QuasiAngular, ChFi3d_Rational

import torus_cad.kernel.fillet.one_fillet as fillet_edges
import torus_cad.kernel.fillet.root_fillet as fillet
from torus_cad.errors import GeometryError, KernelError, ParameterError
from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

# studies/ sits beside torus_cad, outside it
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from studies.fuzz import random_design_dict

#: BRepFilletAPI_MakeFillet's cross-section laws, by name.
FILLET_SHAPES = {
    "rational": ChFi3d_Rational,
    "quasi-angular": ChFi3d_QuasiAngular,
    "polynomial": ChFi3d_Polynomial,
}


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "count", nargs="?", type=int, default=160, help="number of seeds (default 160)"
    )
    parser.add_argument("--seed", type=int, default=0, help="first seed")
    parser.add_argument(
        "--radius", type=float, default=0.5, help="root fillet radius, mm (default 0.5)"
    )
    parser.add_argument("--seeds", type=int, nargs="+", help="these seeds instead of a range")
    parser.add_argument(
        "--fillet-shape",
        choices=sorted(FILLET_SHAPES),
        default="rational",
        help="the fillet's cross-section law (default rational, as torus_cad builds it)",
    )
    parser.add_argument("--out", type=Path, default=Path("fillet_rate_out"))
    args = parser.parse_args()
    # measure the requested radius only; no search for one that works
    fillet._FALLBACK_FRACTIONS = ()
    # the fillet's forked child inherits it
    fillet_edges.FILLET_SHAPE = FILLET_SHAPES[args.fillet_shape]
    rows = []
    for seed in args.seeds or range(args.seed, args.seed + args.count):
        design = random_design_dict(seed)
        design["hub"]["root_fillet_radius"] = args.radius
        # 'ok' is the requested radius everywhere
        design["hub"]["root_fillet_tight_bends"] = "reduce"
        start = time.perf_counter()
        try:
            propeller = build_propeller(PropellerParameters.from_dict(design))
            made = propeller.root_fillet
            outcome = (
                "failed"
                if made is None or not is_valid_closed_solid(propeller.solid)
                else "ok"
                if made.constant_radius
                else "reduced"
            )
        except (ParameterError, GeometryError):
            outcome = "refused"
        except KernelError as error:
            outcome = "failed" if "root fillet failed" in str(error) else "fuse_failed"
        seconds = time.perf_counter() - start
        rows.append(
            {
                "seed": seed,
                "blades": design["blades"],
                "outcome": outcome,
                "seconds": round(seconds, 3),
                **(
                    {
                        "smallest_radius_mm": made.smallest_radius_mm,
                        "varying_junction_mm": made.varying_junction_mm,
                    }
                    if outcome == "reduced" and made is not None
                    else {}
                ),
            }
        )
        if outcome != "refused":
            print(
                f"seed {seed:5d}  blades {design['blades']}  {outcome:<8} {seconds:6.2f} s",
                flush=True,
            )
    ok = sum(row["outcome"] == "ok" for row in rows)
    reduced = sum(row["outcome"] == "reduced" for row in rows)
    counted = sum(row["outcome"] in ("ok", "reduced", "failed") for row in rows)
    rate = ok / counted if counted else float("nan")
    print(
        f"root fillet {args.radius:g} mm: {ok} of {counted} valid "
        f"designs ({100 * rate:.1f} %) at that radius everywhere, "
        f"{ok + reduced} ({100 * (ok + reduced) / max(counted, 1):.1f} %) "
        f"with {reduced} reduced where the blade bends too "
        "tightly; "
        f"{sum(row['outcome'] == 'refused' for row in rows)} refused, "
        f"{sum(row['outcome'] == 'fuse_failed' for row in rows)} fuse failures not counted"
    )
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "fillet_rate.json").write_text(
        json.dumps(
            {
                "radius_mm": args.radius,
                "ok": ok,
                "reduced": reduced,
                "counted": counted,
                "rate": rate,
                "designs": rows,
            },
            indent=1,
        )
        + "\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
