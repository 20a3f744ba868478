#!/usr/bin/env python3
"""Which kinds of edge read back invalid from STEP, over the design space: a tally of random valid
designs.

    python scripts/step_readback_tally.py 300                 # seeds 0..299, two workers
    python scripts/step_readback_tally.py 40 --seed 1000 --freecad --gmsh
    python scripts/step_readback_tally.py --replay 17 203     # just these seeds, one line each
    python scripts/step_readback_tally.py 1100 --fillet-share 0 --freecad --gmsh   # no root fillets

Each seed is one design (:func:`studies.step_tally.tally_design_dict`): a toroidal design from the
fuzz sampler with the workshop features (bores, D-flats, set screws, chamfers, blunt flat or round
trailing edges, ccw), a root fillet on one design in four, and a conventional station-table design
on one in five. A design the build refuses is built again as a user would change it on reading the
refusal (a trailing edge too thick for the blade halved, a root fillet given the radius the message
says works); one the build still refuses (ParameterError, GeometryError, or KernelError before the
STEP file) is not a valid design and is left out of the tally; every other design's STEP file is
written without the build's own read-back check, read back by OpenCascade's STEP reader, and put
through BOPAlgo_ArgumentAnalyzer (every test but self-interference, as the build checks it; a file
the writer wrote again, self-interference too, every pair but face/face), and
each fault is classified by the kind of edge it sits on
(:func:`torus_cad.kernel.step_readback.edge_kind`), the surfaces on its two sides, and its gap
against the tolerance the reader gave it. With ``--freecad`` each file is also checked by FreeCAD's
``Part.Shape.check(True)`` (Debian's freecadcmd), and with ``--gmsh`` imported into gmsh, whose
warnings about the geometry are counted.

Prints two markdown tables of faults by edge kind (as first written; left after the writer's
second try), then one line of totals; exit status 1 if any valid design's STEP file still reads back
with a fault (or FreeCAD or gmsh finds one).
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
import tempfile
import time
from concurrent.futures import TimeoutError as FutureTimeout
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # studies/ and tests/ sit beside torus_cad, outside it


#: STEP files FreeCAD checks in one process (tests/freecad_check.py gives it 300 s).
_FREECAD_BATCH = 5


def tally_one(seed: int, folder: str, fillet_share: float) -> dict[str, Any]:
    """Build the design of ``seed``, write its STEP file into ``folder`` (readable edges made as the
    build makes them, the read-back check off) and read it back: the faults by edge kind."""
    from studies.step_tally import built_tally_design, tally_design_dict
    from torus_cad.errors import GeometryError, KernelError, ParameterError
    from torus_cad.kernel.step_readback import classified_faults, read_step_shape
    from torus_cad.kernel.writers.step import rewritten_until_readable, write_step

    design = tally_design_dict(seed, fillet_share)
    row: dict[str, Any] = {
        "seed": seed,
        "kind": design.get("kind", "toroidal"),
        "fillet": design.get("hub", {}).get("root_fillet_radius", 0.0) > 0.0,
    }
    start = time.perf_counter()
    try:
        propeller = built_tally_design(seed, fillet_share)
    except (ParameterError, GeometryError) as refusal:
        return {**row, "outcome": "refused", "reason": str(refusal)[:160]}
    except KernelError as failure:
        return {**row, "outcome": "kernel", "reason": str(failure)[:160]}
    row["build_s"] = time.perf_counter() - start
    path = Path(folder) / f"tally_{seed}.step"
    start = time.perf_counter()
    write_step(propeller.solid, path, f"tally_{seed}", check_readback=False)
    faults = classified_faults(read_step_shape(path))
    remaining: tuple[Any, ...] = ()
    left: dict[str, int] = {}
    if faults:  # what write_step does with such a file: written again with readable edges
        after = rewritten_until_readable(
            propeller.solid.wrapped,
            path,
            lambda shape: write_step(shape, path, f"tally_{seed}", check_readback=False),
        )
        remaining, left = after.on_edges, after.counts
    row["readback_s"] = time.perf_counter() - start
    outcome = "faulty" if left else "made readable" if faults else "valid"
    return {
        **row,
        "outcome": outcome,
        "path": str(path),
        "faults": [fault.as_dict() for fault in faults],
        "remaining": [fault.as_dict() for fault in remaining],
    }


def _run(
    seeds: list[int], folder: Path, workers: int, time_limit_s: float, fillet_share: float
) -> list[dict[str, Any]]:
    from pebble import ProcessPool

    rows = []
    with ProcessPool(max_workers=workers, max_tasks=20) as pool:
        futures = [
            (
                seed,
                pool.schedule(tally_one, (seed, str(folder), fillet_share), timeout=time_limit_s),
            )
            for seed in seeds
        ]
        for seed, future in futures:
            try:
                row = future.result()
            except FutureTimeout:
                row = {"seed": seed, "outcome": "timeout"}
            except Exception as error:  # a crash is counted, the tally goes on
                row = {
                    "seed": seed,
                    "outcome": "error",
                    "reason": f"{type(error).__name__}: {error}"[:160],
                }
            rows.append(row)
            faults = ", ".join(
                f"{f['status']} on {f['edge_kind']} "
                + (f"{f['gap_mm']:.2g}>{f['tolerance_mm']:.2g}" if f["gap_mm"] > 0.0 else "")
                for f in row.get("remaining", [])
            )
            print(
                f"seed {seed}: {row['outcome']} {row.get('reason', '')}{faults}",
                file=sys.stderr,
                flush=True,
            )
    return rows


def _freecad(rows: list[dict[str, Any]], folder: Path) -> None:
    from tests.freecad_check import freecad_verdicts

    paths = [Path(row["path"]) for row in rows if "path" in row]
    verdicts: dict[str, dict[str, object]] = {}
    # one freecadcmd a batch, within its time limit
    for start in range(0, len(paths), _FREECAD_BATCH):
        batch = paths[start : start + _FREECAD_BATCH]
        try:
            verdicts.update(freecad_verdicts(batch, folder / f"freecad_{start}"))
        # a loaded machine: the batch is counted, not the run lost
        except subprocess.TimeoutExpired:
            verdicts.update(
                {
                    str(path): {"solids": 0, "valid": False, "faults": "FreeCAD timed out"}
                    for path in batch
                }
            )
        print(
            f"FreeCAD: {len(verdicts)} of {len(paths)} files checked", file=sys.stderr, flush=True
        )
    for row in rows:
        if "path" in row:
            verdict = verdicts[row["path"]]
            row["freecad"] = (
                ""
                if verdict["valid"] and not verdict["faults"] and verdict["solids"] == 1
                else str(verdict["faults"] or verdict)[:160]
            )


def _gmsh(rows: list[dict[str, Any]]) -> None:
    import gmsh

    gmsh.initialize(["-noenv"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        for row in rows:
            if "path" not in row:
                continue
            gmsh.clear()
            gmsh.logger.start()
            gmsh.model.occ.importShapes(row["path"])
            gmsh.model.occ.synchronize()
            warnings = [line for line in gmsh.logger.get() if line.startswith(("Warning", "Error"))]
            gmsh.logger.stop()
            row["gmsh"] = "; ".join(warnings)[:160]
    finally:
        gmsh.finalize()


def _table(rows: list[dict[str, Any]], key: str) -> str:
    by_kind: dict[tuple[str, str], list[dict[str, Any]]] = collections.defaultdict(list)
    for row in rows:
        for fault in row.get(key, []):
            by_kind[fault["edge_kind"], fault["surfaces"]].append({**fault, "seed": row["seed"]})
    lines = [
        "| edge kind | surfaces | faults | designs | largest gap (mm) | tolerance read back (mm) |",
        "|---|---|---|---|---|---|",
    ]
    for (kind, surfaces), faults in sorted(by_kind.items(), key=lambda item: -len(item[1])):
        worst = max(faults, key=lambda fault: fault["gap_mm"])
        designs = len({fault["seed"] for fault in faults})
        lines.append(
            f"| {kind} | {surfaces} | {len(faults)} | {designs} | {worst['gap_mm']:.2g} "
            f"| {worst['tolerance_mm']:.2g} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "count", nargs="?", type=int, default=300, help="number of seeds (default 300)"
    )
    parser.add_argument("--seed", type=int, default=0, help="first seed")
    parser.add_argument(
        "--replay", type=int, nargs="+", default=None, metavar="SEED", help="only these seeds"
    )
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument(
        "--time-limit",
        type=float,
        default=120.0,
        help="seconds per design before it counts as a hang",
    )
    parser.add_argument(
        "--fillet-share",
        type=float,
        default=0.25,
        help="share of the designs drawn with a root fillet (default 0.25; 0 for none, 1 for all)",
    )
    parser.add_argument(
        "--freecad", action="store_true", help="also check each file with FreeCAD's check(True)"
    )
    parser.add_argument(
        "--gmsh", action="store_true", help="also import each file into gmsh and count its warnings"
    )
    parser.add_argument(
        "--json", type=Path, default=None, help="write every design's row to this file"
    )
    parser.add_argument(
        "--keep", type=Path, default=None, help="keep the STEP files in this folder"
    )
    args = parser.parse_args(argv)
    seeds = args.replay or list(range(args.seed, args.seed + args.count))
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as temporary:
        folder = args.keep or Path(temporary)
        folder.mkdir(parents=True, exist_ok=True)
        rows = _run(seeds, Path(folder), args.workers, args.time_limit, args.fillet_share)
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1))
        if args.freecad:
            _freecad(rows, Path(folder))
        if args.gmsh:
            _gmsh(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    outcomes = collections.Counter(row["outcome"] for row in rows)
    written = [row for row in rows if row["outcome"] in ("valid", "made readable", "faulty")]
    print("Faults of the files as first written (before the writer makes the edges readable):\n")
    print(_table(rows, "faults"))
    print("\nFaults left once the writer made the edges readable:\n")
    print(_table(rows, "remaining"))
    freecad = sum(bool(row.get("freecad")) for row in written)
    gmsh = sum(bool(row.get("gmsh")) for row in written)
    build = sorted(row["build_s"] for row in written)
    readback = sorted(row["readback_s"] for row in written)
    counts = (
        f"{outcomes['made readable'] + outcomes['faulty']} read back with faults as first "
        f"written, {outcomes['faulty']} still once made readable"
    )
    refusals = (
        f"{outcomes['refused']} refused, {outcomes['kernel']} kernel failures, "
        f"{outcomes['timeout']} timeouts, {outcomes['error']} errors"
    )
    medians = (
        f"; median build {build[len(build) // 2]:.1f} s, "
        f"write + read back {readback[len(readback) // 2]:.2f} s"
        if build
        else ""
    )
    print(
        f"\n{len(seeds)} designs in {time.perf_counter() - start:.0f} s: "
        f"{len(written)} valid built ({counts}), {refusals}; "
        f"conventional {sum(row.get('kind') == 'conventional' for row in written)}, "
        f"root fillet {sum(bool(row.get('fillet')) for row in written)}"
        + (f"; FreeCAD check(True) faults: {freecad}" if args.freecad else "")
        + (f"; gmsh warnings: {gmsh}" if args.gmsh else "")
        + medians
    )
    for row in rows:
        if row.get("freecad") or row.get("gmsh"):
            freecad_verdict, gmsh_verdict = row.get("freecad") or "ok", row.get("gmsh") or "ok"
            print(f"seed {row['seed']}: FreeCAD {freecad_verdict}; gmsh {gmsh_verdict}")
    return (
        1
        if outcomes["faulty"] or freecad or gmsh or outcomes["error"] or outcomes["timeout"]
        else 0
    )


if __name__ == "__main__":
    sys.exit(main())
