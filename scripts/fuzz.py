#!/usr/bin/env python3
"""Fuzz the generator: build N random in-range designs and tally what happened.

    python scripts/fuzz.py 1000               # seeds 0..999, 2 workers, files written and read back
    python scripts/fuzz.py 200 --seed 5000    # seeds 5000..5199
    python scripts/fuzz.py --replay fuzz_out/fuzz_17.toml [more.toml ...]
    python scripts/fuzz.py 30 --build-all   # build even what the pre-screen refuses: do they agree?

Every design comes from :func:`studies.fuzz.random_design_dict` (the same sampler the
hypothesis tests use) and runs on the batch runner that sweeps use (:mod:`torus_cad.batch`):
a worker process per core, a time limit per design, so a hang or a crash is counted rather
than stopping the run. Outcomes (:class:`torus_cad.batch.Outcome`): valid solid / clear
refusal (ParameterError, GeometryError) / anything else (``failed``: KernelError on an
in-range design, ``error``: any other exception, ``bad_file``, ``timeout``, ``crash``). The
parameters of every "anything else" design are saved as ``<out>/<name>.toml`` (with the
outcome in a comment on top) to replay with ``--replay`` or ``torus-cad build <file>``.
A progress bar shows on a terminal. Exit status: 0 when "anything else" is 0.

As a sweep does, the run first checks each design in its own process without the kernel
(:func:`torus_cad.batch.job.prescreen`): a design the checks refuse is counted as a pre-screened
refusal and never built; the summary gives the check's CPU time per design. With ``--build-all``
every design is built anyway, and the summary says whether the build agreed: every design the
check refused refused by the build with the same line, none it passed refused by the build.
"""

from __future__ import annotations

import argparse
import collections
import json
import statistics
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from torus_cad.batch.job import DesignTask, prescreen
from torus_cad.batch.outcome import RUN_OUTCOMES, DesignResult, Outcome, tally
from torus_cad.batch.runner import LocalPool, capped_workers, default_workers, run_tasks
from torus_cad.parameters import PropellerParameters
from torus_cad.runtime.progress import BatchProgress

# studies/ sits beside torus_cad, outside it
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from studies.fuzz import fuzz_range, fuzz_tasks, random_design_dict


def _save_failure(out_dir: Path, params: PropellerParameters, result: DesignResult) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{params.name}.toml"
    header = [
        f"# fuzz failure: {result.outcome}: {result.reason}".replace("\n", " "),
        f"# replay: python scripts/fuzz.py --replay {path}",
    ]
    header += ["# " + line for line in result.detail.strip().splitlines()[-6:]]
    path.write_text("\n".join(header) + "\n" + params.to_toml(comments=False))
    return path


def _reason(result: DesignResult) -> str:
    """A short key for grouping refusals by their reason."""
    text = result.reason
    for marker in (";", "(", " near ", " at s ", ":"):
        text = text.split(marker)[0]
    return text.strip()[:90]


def _whole_range(key: str) -> tuple[int, int]:
    low, high = fuzz_range(key)
    return int(low), int(high)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "count", nargs="?", type=int, default=100, help="number of random designs (default 100)"
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="first seed (designs use seeds seed..seed+N-1)"
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=default_workers(),
        help="worker processes (default: the available cores; more are capped at them)",
    )
    parser.add_argument(
        "--oversubscribe", action="store_true", help="start --workers even beyond the cores"
    )
    parser.add_argument(
        "--time-limit",
        type=float,
        default=60.0,
        help="seconds per design before it counts as a hang",
    )
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("fuzz_out"),
        help="folder for failing designs and the summary",
    )
    parser.add_argument(
        "--no-write", action="store_true", help="build only; do not write and re-read the files"
    )
    parser.add_argument("--no-stl", action="store_true", help="write STEP and JSON only")
    parser.add_argument(
        "--replay", nargs="+", type=Path, metavar="TOML", help="run these saved designs instead"
    )
    parser.add_argument(
        "--sections",
        type=int,
        nargs=2,
        default=_whole_range("resolution.sections"),
        metavar=("LOW", "HIGH"),
        help="range of resolution.sections to sample "
        "(default: the schema's fuzz range, %(default)s)",
    )
    parser.add_argument(
        "--points",
        type=int,
        nargs=2,
        default=_whole_range("resolution.points"),
        metavar=("LOW", "HIGH"),
        help="range of resolution.points to sample "
        "(default: the schema's fuzz range, %(default)s: low, for speed)",
    )
    parser.add_argument(
        "--workshop",
        action="store_true",
        help="also draw bore, flat, set screw, chamfer, blunt trailing edge and handedness",
    )
    parser.add_argument(
        "--record", type=Path, metavar="JSONL", help="append every outcome to this JSON-lines file"
    )
    parser.add_argument(
        "--build-all",
        action="store_true",
        help="build the designs the kernel-free pre-screen refuses too, and report the agreement",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="print every design's outcome")
    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error(f"--workers must be a whole number >= 1, got {args.workers}")

    if args.replay:
        designs = [PropellerParameters.from_toml(path).to_dict() for path in args.replay]
    else:
        designs = [
            random_design_dict(
                seed,
                workshop=args.workshop,
                sections=tuple(args.sections),
                points=tuple(args.points),
            )
            for seed in range(args.seed, args.seed + args.count)
        ]

    tasks = fuzz_tasks(designs, write=not args.no_write, stl=not args.no_stl)
    screened: dict[str, DesignResult] = {}  # design id -> the pre-screen's refusal
    check_cpu: list[float] = []  # CPU seconds of the pre-screen per design

    def prescreened(all_tasks: list[DesignTask]) -> Iterator[DesignTask]:
        """The tasks the pre-screen passes (all of them with --build-all), checked as workers free
        up."""
        for task in all_tasks:
            cpu = time.process_time()
            refusal = prescreen(task)
            check_cpu.append(time.process_time() - cpu)
            if refusal is not None:
                screened[task.design_id] = refusal
                if not args.build_all:
                    on_result(task, refusal)
                    continue
            yield task

    start = time.perf_counter()
    results: list[DesignResult] = []
    # design id -> its outcome (the pre-screen's for a design not built)
    built: dict[str, DesignResult] = {}
    failures: list[DesignResult] = []
    bar = BatchProgress(len(tasks), label="fuzz")

    def say(text: str) -> None:  # above the bar on a terminal; plain lines in a log
        if bar.enabled:
            bar.message(text)
        else:
            print(text, flush=True)

    def on_result(task: DesignTask, result: DesignResult) -> None:
        results.append(result)
        built[task.design_id] = result
        bar.update(result.outcome)
        if not bar.enabled and len(results) % 50 == 0:
            say(f"  ... {len(results)}/{len(tasks)} in {time.perf_counter() - start:.0f} s")
        if args.record:
            with args.record.open("a") as handle:
                handle.write(
                    json.dumps(
                        {
                            "name": task.design_id,
                            "kind": result.outcome.value,
                            "message": result.reason,
                            "seconds": round(result.seconds, 3),
                            "prescreened": result.prescreened,
                        }
                    )
                    + "\n"
                )
        if not result.outcome.acceptable:
            failures.append(result)
            if not args.replay:
                saved = _save_failure(
                    args.out, PropellerParameters.from_dict(task.parameters), result
                )
                say(f"  {result.outcome:<9} {task.design_id}: {result.reason[:150]} -> {saved}")
            else:
                say(f"  {result.outcome:<9} {task.design_id}: {result.reason}\n{result.detail}")
        elif args.verbose or args.replay:
            say(
                f"  {result.outcome:<9} {task.design_id} ("
                f"{result.seconds:.2f} s) {result.reason[:150]}"
            )

    args.workers = capped_workers(
        args.workers, len(tasks), args.oversubscribe, lambda line: print(line, file=sys.stderr)
    )
    with bar:
        run_tasks(
            prescreened(tasks),
            on_result,
            lambda: LocalPool(args.workers, args.time_limit),
            window=2 * args.workers,
        )
    elapsed = time.perf_counter() - start
    counts = tally(results)
    anything_else = sum(counts[outcome] for outcome in RUN_OUTCOMES if not outcome.acceptable)

    print()
    print(
        f"{len(results)} designs in {elapsed:.1f} s on {args.workers} workers "
        f"({'build only' if args.no_write else 'build, write, read back'})"
    )
    kernel_refusals = sum(1 for r in results if r.outcome is Outcome.REFUSED and not r.prescreened)
    print(f"  valid solid     {counts[Outcome.VALID]:6d}")
    print(
        f"  clear refusal   {counts[Outcome.REFUSED]:6d}  "
        f"({counts[Outcome.REFUSED] - kernel_refusals} pre-screened "
        f"without the kernel, {kernel_refusals} by the build)"
        if not args.build_all
        else (
            f"  clear refusal   {counts[Outcome.REFUSED]:6d}  (by "
            f"the build; the pre-screen refused {len(screened)})"
        )
    )
    others = [
        f"{outcome} {counts[outcome]}"
        for outcome in RUN_OUTCOMES
        if not outcome.acceptable and counts[outcome]
    ]
    print(f"  anything else   {anything_else:6d}" + (f"  ({', '.join(others)})" if others else ""))
    if check_cpu:
        print(
            f"pre-screen: {len(screened)} of "
            f"{len(check_cpu)} designs refused; CPU per design median "
            f"{1000 * statistics.median(check_cpu):.0f} ms, max {1000 * max(check_cpu):.0f} ms"
        )
    if args.build_all:
        same = sum(1 for name, refusal in screened.items() if built[name].reason == refusal.reason)
        missed = [
            name
            for name, result in built.items()
            if name not in screened and result.outcome is Outcome.REFUSED
        ]
        print(
            f"agreement: {same} of the {len(screened)} pre-screened "
            "refused by the build with the same line; "
            f"{len(missed)} the pre-screen passed refused by the build"
            + (f" ({', '.join(missed)})" if missed else "")
        )
    failed = collections.Counter(_reason(r) for r in results if r.outcome is Outcome.FAILED)
    if failed:
        print("kernel failure reasons:")
        for reason, count in failed.most_common():
            print(f"  {count:5d}  {reason}")
    reasons = collections.Counter(_reason(r) for r in results if r.outcome is Outcome.REFUSED)
    if reasons:
        print("refusal reasons:")
        for reason, count in reasons.most_common():
            print(f"  {count:5d}  {reason}")
    if not args.replay:
        args.out.mkdir(parents=True, exist_ok=True)
        summary = {
            "count": len(results),
            "first_seed": args.seed,
            "sections": list(args.sections),
            "points": list(args.points),
            "seconds": elapsed,
            "workers": args.workers,
            "write": not args.no_write,
            "tally": {outcome.value: counts[outcome] for outcome in RUN_OUTCOMES},
            "anything_else": anything_else,
            "refusal_reasons": dict(reasons.most_common()),
            "prescreened": len(screened),
            "build_all": args.build_all,
            "prescreen_cpu_s": {
                "median": statistics.median(check_cpu) if check_cpu else None,
                "max": max(check_cpu) if check_cpu else None,
            },
            "failures": [
                {"name": r.design_id, "kind": r.outcome.value, "message": r.reason}
                for r in failures
            ],
        }
        (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        print(f"summary: {args.out / 'summary.json'}")
    return 0 if anything_else == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
