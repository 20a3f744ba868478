#!/usr/bin/env python3
"""Faults of every shipped design's STEP file read back, by BOPAlgo_ArgumentAnalyzer with every
test.

    python scripts/step_readback_check.py             # the default and every examples/*.toml design
    python scripts/step_readback_check.py examples/workshop_fillet.toml
    python scripts/step_readback_check.py --fillet 0.5 --fast
        # each with a 0.5 mm root fillet, as the build checks

For each design: the build's wall time, the faults of the solid in memory and of its STEP file as
OpenCascade's STEP reader gives it back (torus_cad.kernel.step_readback: every test on, as FreeCAD's
"Check geometry" with BOP check), by status, and the seconds each analysis took. Prints a table.
``--fillet R`` builds each design with ``hub.root_fillet_radius = R`` (and, where the fillet's
spread refuses the hub's chamfer, without the chamfer); ``--fast`` leaves out the self-interference
test (the build's own read-back check does: its strict check ran it on the solid) and the analysis
in memory.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from torus_cad.propeller import Propeller

ROOT = Path(__file__).resolve().parent.parent


def _designs() -> list[str]:
    import tomllib

    shipped = [
        path
        for path in sorted((ROOT / "examples").glob("*.toml"))
        if not ({"sweep", "study"} & tomllib.loads(path.read_text(encoding="utf-8")).keys())
    ]
    return ["default", *(str(path.relative_to(ROOT)) for path in shipped)]


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{count} {status}" for status, count in counts.items()) or "0"


def _build(design: str, fillet_mm: float | None) -> Propeller:
    """The design (the default for ``default``) built, with a root fillet of ``fillet_mm`` if given:
    without the hub's chamfer when the fillet's spread refuses it (as tests/test_fillet_examples.py
    does)."""
    from torus_cad.errors import GeometryError, ParameterError
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    params = (
        PropellerParameters()
        if design == "default"
        else PropellerParameters.from_toml(design if Path(design).exists() else ROOT / design)
    )
    if fillet_mm is None:
        return build_propeller(params)
    params = params.with_values({"hub.root_fillet_radius": fillet_mm})
    try:
        return build_propeller(params)
    except (ParameterError, GeometryError) as refusal:
        if "hub.chamfer" not in str(refusal):
            raise
        return build_propeller(params.with_values({"hub.chamfer": 0.0}))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "designs", nargs="*", help="design files (default: the default and every shipped example)"
    )
    parser.add_argument(
        "--fillet",
        type=float,
        default=None,
        metavar="R",
        help=(
            "build each design with a root fillet of R mm (without its chamfer if that is refused)"
        ),
    )
    parser.add_argument(
        "--fast",
        action="store_true",
        help="no self-interference test and no analysis in memory (what the build checks)",
    )
    args = parser.parse_args(argv)
    from torus_cad.errors import TorusCadError
    from torus_cad.kernel.step_readback import ArgumentFaults, argument_faults, step_readback_faults
    from torus_cad.kernel.writers.step import write_step

    rows = []
    for design in args.designs or _designs():
        start = time.perf_counter()
        try:
            propeller = _build(design, args.fillet)
        except TorusCadError as error:  # the table goes on; the line says why
            print(f"{design}: not built: {error}", file=sys.stderr)
            continue
        build_s = time.perf_counter() - start
        memory = ArgumentFaults() if args.fast else argument_faults(propeller.solid.wrapped)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "design.step"
            write_step(
                propeller.solid,
                path,
                propeller.parameters.name,
                propeller.parameters.export.step_schema,
                check_readback=False,
            )
            readback = step_readback_faults(path, self_interference=not args.fast)
        rows.append((design, build_s, memory, readback))
        print(
            f"{design}: build {build_s:.1f} s; in memory "
            f"{_counts(memory.counts)} ({memory.seconds:.1f} s); "
            f"read back {_counts(readback.counts)} ({readback.seconds:.1f} s)",
            file=sys.stderr,
            flush=True,
        )
    print("| design | build s | faults in memory | faults read back | analysis s (read back) |")
    print("|---|---|---|---|---|")
    for design, build_s, memory, readback in rows:
        print(
            f"| {design} | {build_s:.1f} | {_counts(memory.counts)} | {_counts(readback.counts)} "
            f"| {readback.seconds:.1f} |"
        )
    return 1 if any(readback.counts for *_, readback in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
