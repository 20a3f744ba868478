#!/usr/bin/env python3
"""Count the designs refused for their tessellation alone: built strictly valid, then their STL
refused.

    python scripts/tessellation_refusals.py          # the fuzz seeds of the notes and every example
    python scripts/tessellation_refusals.py --seeds 0 1 2 --no-examples

Each design is built (``build_propeller``); a built one has its checked STL written
(``write_checked_stl``: the build's own route) into a temporary folder. A design refused by
the build itself (bad input, geometry, the strict check) does not count: only a strictly built
solid whose STL is refused does. Fuzz seeds draw their workshop features (``studies.fuzz``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # studies/ sits beside torus_cad, outside it


def _one(label: str, load) -> str:
    from torus_cad.errors import GeometryError, KernelError, ParameterError
    from torus_cad.kernel.writers.stl import write_checked_stl
    from torus_cad.propeller import build_propeller

    start = time.perf_counter()
    try:
        propeller = build_propeller(load())
    except (ParameterError, GeometryError, KernelError) as error:
        return f"{label}: not built ({type(error).__name__}: {str(error).splitlines()[0][:120]})"
    export = propeller.parameters.export
    with tempfile.TemporaryDirectory() as folder:
        try:
            check = write_checked_stl(
                propeller.solid,
                Path(folder) / "p.stl",
                export.stl_linear_deflection,
                export.stl_angular_deflection,
            )
        except KernelError as error:
            return f"{label}: REFUSED for its tessellation: {str(error).splitlines()[0]}"
    # a checkout before the uncrossed tessellation has none
    pairs = getattr(check, "repaired_pairs", 0)
    repair = (
        f", {pairs} crossing pairs repaired ({check.repair}, "
        f"moved <= {check.repair_deviation_mm:.3f} mm)"
        if pairs
        else ""
    )
    return (
        f"{label}: written, {check.triangles} triangles{repair}, "
        f"{time.perf_counter() - start:.1f} s"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seeds", type=int, nargs="*", default=[7, 55, 106])
    parser.add_argument("--no-examples", action="store_true")
    args = parser.parse_args(argv)
    from studies.fuzz import random_design

    jobs = [
        (f"fuzz seed {seed}", lambda seed=seed: random_design(seed, workshop=True))
        for seed in args.seeds
    ]
    if not args.no_examples:
        jobs += [
            (f"example {path.name}", lambda path=path: path)
            for path in sorted((ROOT / "examples").glob("*.toml"))
            if not path.name.startswith(("optimize", "sweep"))
        ]
    refused = 0
    for label, load in jobs:
        line = _one(label, load)
        refused += "REFUSED" in line
        print(line, flush=True)
    print(f"refused for their tessellation alone: {refused} of {len(jobs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
