#!/usr/bin/env python3
"""Fuzz the generator: build N random in-range designs and tally what happened.

    python scripts/fuzz.py 1000                 # seeds 0..999, 2 workers, files written and read back
    python scripts/fuzz.py 200 --seed 5000      # seeds 5000..5199
    python scripts/fuzz.py --replay fuzz_out/fuzz_17.toml [more.toml ...]

Every design comes from :func:`torus_cad.fuzzing.random_design` (the same sampler the
hypothesis tests use) and runs in a worker process with a time limit, so a hang or a crash
is counted rather than stopping the run. Outcomes: valid solid / clear refusal
(ParameterError, GeometryError) / anything else (KernelError on an in-range design, any
other exception, a bad file, a time-out, a crash). The parameters of every "anything else"
design are saved as ``<out>/<name>.toml`` (with the outcome in a comment on top) to replay
with ``--replay`` or ``torus-cad build <file>``. Exit status: 0 when "anything else" is 0.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

from torus_cad.fuzzing import (ACCEPTABLE, OUTCOMES, Outcome, SupervisedPool, default_workers,
                               random_design_dict, tally)
from torus_cad.parameters import PropellerParameters


def _save_failure(out_dir: Path, params: PropellerParameters, outcome: Outcome) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{params.name}.toml"
    header = [f"# fuzz failure: {outcome.kind}: {outcome.message}".replace("\n", " "),
              f"# replay: python scripts/fuzz.py --replay {path}"]
    header += ["# " + line for line in outcome.detail.strip().splitlines()[-6:]]
    path.write_text("\n".join(header) + "\n" + params.to_toml(comments=False))
    return path


def _reason(outcome: Outcome) -> str:
    """A short key for grouping refusals by their reason."""
    text = outcome.message
    for marker in (";", "(", " near ", " at s ", ":"):
        text = text.split(marker)[0]
    return text.strip()[:90]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("count", nargs="?", type=int, default=100, help="number of random designs (default 100)")
    parser.add_argument("--seed", type=int, default=0, help="first seed (designs use seeds seed..seed+N-1)")
    parser.add_argument("--workers", type=int, default=default_workers(), help="worker processes (default: cores)")
    parser.add_argument("--time-limit", type=float, default=60.0, help="seconds per design before it counts as a hang")
    parser.add_argument("--out", type=Path, default=Path("fuzz_out"), help="folder for failing designs and the summary")
    parser.add_argument("--no-write", action="store_true", help="build only; do not write and re-read the files")
    parser.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    parser.add_argument("--replay", nargs="+", type=Path, metavar="TOML", help="run these saved designs instead")
    parser.add_argument("--sections", type=int, nargs=2, default=(16, 36), metavar=("LOW", "HIGH"),
                        help="range of resolution.sections to sample (default 16 36)")
    parser.add_argument("--points", type=int, nargs=2, default=(24, 48), metavar=("LOW", "HIGH"),
                        help="range of resolution.points to sample (default 24 48: low, for speed)")
    parser.add_argument("--record", type=Path, metavar="JSONL", help="append every outcome to this JSON-lines file")
    parser.add_argument("-v", "--verbose", action="store_true", help="print every design's outcome")
    args = parser.parse_args(argv)

    if args.replay:
        designs = [PropellerParameters.from_toml(path).to_dict() for path in args.replay]
    else:
        designs = [random_design_dict(seed, sections=tuple(args.sections), points=tuple(args.points))
                   for seed in range(args.seed, args.seed + args.count)]

    pool = SupervisedPool(workers=args.workers, time_limit=args.time_limit, write=not args.no_write,
                          stl=not args.no_stl)
    start = time.perf_counter()
    done = 0
    failures: list[tuple[str, Outcome]] = []

    def on_result(index: int, outcome: Outcome) -> None:
        nonlocal done
        done += 1
        design = designs[index]
        name = design["name"]
        if args.record:
            with args.record.open("a") as handle:
                handle.write(json.dumps({"name": name, "kind": outcome.kind, "message": outcome.message,
                                         "seconds": round(outcome.seconds, 3)}) + "\n")
        if not outcome.acceptable:
            failures.append((name, outcome))
            if not args.replay:
                saved = _save_failure(args.out, PropellerParameters.from_dict(design), outcome)
                print(f"  {outcome.kind:<9} {name}: {outcome.message[:150]} -> {saved}", flush=True)
            else:
                print(f"  {outcome.kind:<9} {name}: {outcome.message}\n{outcome.detail}", flush=True)
        elif args.verbose or args.replay:
            print(f"  {outcome.kind:<9} {name} ({outcome.seconds:.2f} s) {outcome.message[:150]}", flush=True)
        if done % 50 == 0:
            print(f"  ... {done}/{len(designs)} in {time.perf_counter() - start:.0f} s", flush=True)

    outcomes = pool.run(designs, on_result)
    elapsed = time.perf_counter() - start
    counts = tally(outcomes)
    anything_else = sum(counts[kind] for kind in OUTCOMES if kind not in ACCEPTABLE)

    print()
    print(f"{len(outcomes)} designs in {elapsed:.1f} s on {args.workers} workers "
          f"({'build only' if args.no_write else 'build, write, read back'})")
    print(f"  valid solid     {counts['valid']:6d}")
    print(f"  clear refusal   {counts['refused']:6d}")
    print(f"  anything else   {anything_else:6d}"
          + (f"  ({', '.join(f'{kind} {counts[kind]}' for kind in OUTCOMES if kind not in ACCEPTABLE and counts[kind])})"
             if anything_else else ""))
    reasons = collections.Counter(_reason(o) for o in outcomes if o.kind == "refused")
    if reasons:
        print("refusal reasons:")
        for reason, count in reasons.most_common():
            print(f"  {count:5d}  {reason}")
    if not args.replay:
        args.out.mkdir(parents=True, exist_ok=True)
        summary = {"count": len(outcomes), "first_seed": args.seed, "sections": list(args.sections),
                   "points": list(args.points), "seconds": elapsed, "workers": args.workers,
                   "write": not args.no_write, "tally": counts, "anything_else": anything_else,
                   "refusal_reasons": dict(reasons.most_common()),
                   "failures": [{"name": n, "kind": o.kind, "message": o.message} for n, o in failures]}
        (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        print(f"summary: {args.out / 'summary.json'}")
    return 0 if anything_else == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
