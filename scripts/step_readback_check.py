#!/usr/bin/env python3
"""Faults of every shipped design's STEP file read back, by BOPAlgo_ArgumentAnalyzer with every test.

    python scripts/step_readback_check.py                       # the default and every examples/*.toml design
    python scripts/step_readback_check.py examples/workshop_fillet.toml

For each design: the build's wall time, the faults of the solid in memory and of its STEP file as
OpenCascade's STEP reader gives it back (torus_cad.kernel.step_readback: every test on, as FreeCAD's
"Check geometry" with BOP check), by status, and the seconds each analysis took. Prints a table.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _designs() -> list[str]:
    import tomllib

    shipped = [path for path in sorted((ROOT / "examples").glob("*.toml"))
               if not ({"sweep", "study"} & tomllib.loads(path.read_text(encoding="utf-8")).keys())]
    return ["default", *(str(path.relative_to(ROOT)) for path in shipped)]


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{count} {status}" for status, count in counts.items()) or "0"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("designs", nargs="*", help="design files (default: the default and every shipped example)")
    args = parser.parse_args(argv)
    from torus_cad.errors import TorusCadError
    from torus_cad.kernel.step_readback import argument_faults, step_readback_faults
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.propeller import build_propeller

    rows = []
    for design in args.designs or _designs():
        start = time.perf_counter()
        try:
            propeller = build_propeller(None if design == "default" else design if Path(design).exists()
                                        else ROOT / design)
        except TorusCadError as error:  # the table goes on; the line says why
            print(f"{design}: not built: {error}", file=sys.stderr)
            continue
        build_s = time.perf_counter() - start
        memory = argument_faults(propeller.solid.wrapped)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "design.step"
            write_step(propeller.solid, path, propeller.parameters.name, propeller.parameters.export.step_schema)
            readback = step_readback_faults(path)
        rows.append((design, build_s, memory, readback))
        print(f"{design}: build {build_s:.1f} s; in memory {_counts(memory.counts)} ({memory.seconds:.1f} s); "
              f"read back {_counts(readback.counts)} ({readback.seconds:.1f} s)", file=sys.stderr, flush=True)
    print("| design | build s | faults in memory | faults read back | analysis s (read back) |")
    print("|---|---|---|---|---|")
    for design, build_s, memory, readback in rows:
        print(f"| {design} | {build_s:.1f} | {_counts(memory.counts)} | {_counts(readback.counts)} "
              f"| {readback.seconds:.1f} |")
    return 1 if any(readback.counts for *_, readback in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
