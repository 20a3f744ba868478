#!/usr/bin/env python3
"""What the strict validity check costs against the build, per design.

    python scripts/bench_strict_check.py            # default, workshop_motor_mount, workshop_fillet
    python scripts/bench_strict_check.py examples/cooling_fan_7blade.toml --runs 3
    python scripts/bench_strict_check.py --fuzz 100
        # fuzz counts: tried / built / refused / strict-valid

For each design (median of ``--runs`` builds): the build's stages without the strict check, the
strict check as the build runs it (BRepCheck, then BRepAlgoAPI_Check with small edges and
self-interference on the hub with blade 0 plus blade 0 against the other copies), the same
BRepAlgoAPI_Check on the whole solid and on blade 0 alone for comparison, and the STL write with
its meshlib check. Prints wall-clock seconds and process CPU seconds (all threads; the machine may
be shared), and the ratios check / build. ``--fuzz N`` runs N fuzz designs (workshop features
included) in 2 worker processes and prints the counts.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

DEFAULT_DESIGNS = ("default", "examples/workshop_motor_mount.toml", "examples/workshop_fillet.toml")


def _timed(work: Callable[[], Any]) -> tuple[Any, float, float]:
    wall, cpu = time.perf_counter(), time.process_time()
    result = work()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def _one_run(design: str) -> dict[str, tuple[float, float]]:
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Check

    from torus_cad.kernel.strict import strict_valid_solid
    from torus_cad.kernel.writers.stl import write_checked_stl
    from torus_cad.propeller import build_propeller

    propeller, wall, cpu = _timed(lambda: build_propeller(None if design == "default" else design))
    strict = propeller.stage_seconds.get("strict_check", 0.0)
    times = {"build without strict check": (wall - strict, float("nan")), "build": (wall, cpu)}
    if propeller.parameters.handedness.value == "ccw":
        print(
            "  (ccw: the build checks the solid before "
            "its mirror; timed here on the mirrored solid)"
        )
    _, wall, cpu = _timed(lambda: strict_valid_solid(propeller.solid, "the propeller"))
    times["strict check (build's scope)"] = (wall, cpu)
    valid, wall, cpu = _timed(
        lambda: BRepAlgoAPI_Check(propeller.solid.wrapped, True, True).IsValid()
    )
    times[f"BRepAlgoAPI_Check whole solid ({'valid' if valid else 'FAULTS'})"] = (wall, cpu)
    valid, wall, cpu = _timed(
        lambda: BRepAlgoAPI_Check(propeller.blades[0].wrapped, True, True).IsValid()
    )
    times[f"BRepAlgoAPI_Check blade 0 ({'valid' if valid else 'FAULTS'})"] = (wall, cpu)
    export = propeller.parameters.export
    with tempfile.TemporaryDirectory() as folder:
        _, wall, cpu = _timed(
            lambda: write_checked_stl(
                propeller.solid.copy(),
                Path(folder) / "p.stl",
                export.stl_linear_deflection,
                export.stl_angular_deflection,
            )
        )
    times["STL write + meshlib check"] = (wall, cpu)
    return times


def bench(design: str, runs: int) -> None:
    results = [_one_run(design) for _ in range(runs)]
    print(f"{design} (median of {runs}):")
    medians = {
        key: (
            statistics.median(r[key][0] for r in results),
            statistics.median(r[key][1] for r in results),
        )
        for key in results[0]
    }
    build_wall = medians["build without strict check"][0]
    for key, (wall, cpu) in medians.items():
        print(f"  {key:42s} {wall:7.2f} s wall {cpu:7.2f} s cpu   {wall / build_wall:5.2f} x build")


def fuzz(count: int) -> None:
    from collections import Counter

    # studies/ sits beside torus_cad, outside it
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from studies.strict_fuzz import fuzz_many

    start = time.perf_counter()
    outcomes = fuzz_many(range(count), workers=2)
    built = [outcome for outcome in outcomes if outcome.status == "built"]
    print(
        f"fuzz seeds 0-{count - 1}: "
        f"{dict(Counter(outcome.status for outcome in outcomes))}; built and "
        "strict-valid (whole-solid BRepAlgoAPI_Check): "
        f"{sum(outcome.strict_valid for outcome in built)} of "
        f"{len(built)}; STL with 0 crossing pairs: "
        f"{sum(outcome.stl_pairs == 0 for outcome in built)}; "
        f"{time.perf_counter() - start:.0f} s"
    )
    for outcome in outcomes:
        if outcome.status == "failed":
            print(f"  seed {outcome.seed} failed: {outcome.reason}")
    if built:
        print(
            f"  median build {statistics.median(o.build_s for o in built):.2f}"
            " s, median whole-solid check "
            f"{statistics.median(o.check_s for o in built):.2f} s"
        )


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("designs", nargs="*", default=list(DEFAULT_DESIGNS))
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--fuzz", type=int, default=0, help="run this many fuzz designs instead")
    args = parser.parse_args(argv)
    if args.fuzz:
        fuzz(args.fuzz)
        return 0
    for design in args.designs:
        bench(design, args.runs)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
