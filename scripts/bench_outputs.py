#!/usr/bin/env python3
"""What publishing a build as one output set costs: the transaction against plain writes.

    python scripts/bench_outputs.py            # 15 alternating runs of each, default propeller
    python scripts/bench_outputs.py --runs 5

Builds the default propeller once, then alternates, into fresh folders:

* **plain**: what ``write_outputs`` did before output sets: STEP, STL, the blade-element table
  (CSV, PNG) and the JSON report, each written to a temp file and renamed onto its final name;
* **set**: ``write_output_set`` as ``torus-cad build`` runs it now: the mesh budget estimate, a
  staging folder, the same writers, SHA-256 of every file in the report, the locked publish.

Prints the median of each, the difference, and the difference as a share of the whole default
build (build + write, medians). The JSON report's mass properties are part of both.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path


def _plain_write(propeller, out_dir: Path, density_g_cm3: float) -> None:
    from torus_cad import __version__
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.kernel.writers.stl import write_stl
    from torus_cad.outputs.build_report import build_report
    from torus_cad.outputs.sections_table import write_sections_table
    from torus_cad.runtime.files import atomic_path

    params = propeller.parameters
    write_step(
        propeller.solid,
        out_dir / f"{params.name}.step",
        params.name,
        params.export.step_schema,
        program=f"torus_cad {__version__}",
    )
    write_stl(
        propeller.solid,
        out_dir / f"{params.name}.stl",
        params.export.stl_linear_deflection,
        params.export.stl_angular_deflection,
    )
    write_sections_table(propeller.surface, params, out_dir)
    with atomic_path(out_dir / f"{params.name}.json") as temp:
        temp.write_text(json.dumps(build_report(propeller, density_g_cm3), indent=2) + "\n")


def _set_write(propeller, out_dir: Path, density_g_cm3: float) -> None:
    from torus_cad.outputs.output_set import write_output_set

    write_output_set(propeller, out_dir, density_g_cm3, sections_table=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=15, help="runs of each (alternating)")
    args = parser.parse_args()
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    build_seconds = []
    for _ in range(3):
        start = time.perf_counter()
        propeller = build_propeller(PropellerParameters())
        build_seconds.append(time.perf_counter() - start)
    times: dict[str, list[float]] = {"plain": [], "set": []}
    with tempfile.TemporaryDirectory() as scratch:
        for run in range(args.runs + 1):  # run 0 warms both up
            for kind, write in (("plain", _plain_write), ("set", _set_write)):
                out_dir = Path(scratch) / f"{kind}_{run}"
                out_dir.mkdir()
                start = time.perf_counter()
                write(propeller, out_dir, 1.24)
                if run:
                    times[kind].append(time.perf_counter() - start)
    build_s = statistics.median(build_seconds)
    plain_s, set_s = statistics.median(times["plain"]), statistics.median(times["set"])
    print(f"build (median of 3)              {build_s * 1000:8.1f} ms")
    print(f"plain writes (median of {args.runs})      {plain_s * 1000:8.1f} ms")
    print(f"output set (median of {args.runs})        {set_s * 1000:8.1f} ms")
    print(
        f"difference                       {(set_s - plain_s) * 1000:8.1f} ms = "
        f"{(set_s - plain_s) / (build_s + plain_s) * 100:+.1f} % of build + write "
        f"({(build_s + plain_s) * 1000:.0f} -> {(build_s + set_s) * 1000:.0f} ms)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
