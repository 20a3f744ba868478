"""Measure every test and write the test tiers to ``tests/tiers.json``.

    python3 scripts/test_tiers.py
        # run the suite (pytest -n 2), then the fast tier alone
    python3 scripts/test_tiers.py --junit run.xml   # take the suite's durations from an earlier run

Tiers (``tests/conftest.py`` marks them):

- ``fast``: the quickest tests of every module, chosen so that ``pytest -m fast`` on its own stays
  under FAST_TIER_SECONDS; the script runs that tier to measure it, with the fixtures it pays for.
- ``long``: tests that took LONG_TEST_SECONDS or more in the suite run (simulations, studies,
  fillet sweeps over every example), and long tests of the file before that did not finish in
  it (a run stopped by hand); ``pytest -m long`` runs them, CI runs everything else.
- every other test, and any test not measured yet, is in neither and runs in CI; so do the
  modules of ALWAYS_IN_CI, whatever they take.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ElementTree
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TIERS_FILE = ROOT / "tests" / "tiers.json"
#: A test slower than this in the suite run goes to the long tier.
LONG_TEST_SECONDS = 30.0
#: The fast tier, run alone, must finish within this (wall clock, collection included).
FAST_TIER_SECONDS = 30.0
#: Only tests quicker than this in the suite run are candidates for the fast tier.
FAST_CANDIDATE_SECONDS = 2.0
#: Modules whose tests share one stateful page, in file order (each starts where the one before left
#: it): only a run of tests at the end of such a module may go to the long tier.
CHAINED_MODULES = ("tests/test_studio_browser.py",)
#: Modules that CI runs whole however long they take: the simulation's physics checks (coarse
#: level).
ALWAYS_IN_CI = ("tests/test_simulate.py",)
#: The sum of the fast tier's test times is kept under this share of FAST_TIER_SECONDS (the rest is
#: start-up).
FAST_SUM_SHARE = 0.25


def _durations(junit: Path) -> dict[str, float]:
    """Seconds per test node id (setup + call + teardown) of a pytest ``--junitxml`` file."""
    durations: dict[str, float] = {}
    for case in ElementTree.parse(junit).getroot().iter("testcase"):
        if case.find("skipped") is not None:
            continue
        module, _, klass = case.get("classname", "").partition(".test_")
        path = module.replace(".", "/") + "/test_" + klass.split(".")[0] + ".py"
        durations[f"{path}::{case.get('name')}"] = float(case.get("time", 0.0))
    return durations


def _run_pytest(arguments: list[str]) -> tuple[dict[str, float], float]:
    """Durations of one pytest run with ``arguments`` and its wall-clock seconds."""
    with tempfile.TemporaryDirectory() as folder:
        junit = Path(folder) / "run.xml"
        start = time.monotonic()
        subprocess.run(
            [
                sys.executable,
                "-m",
                "pytest",
                "-q",
                "-p",
                "no:cacheprovider",
                f"--junitxml={junit}",
                *arguments,
            ],
            cwd=ROOT,
            check=False,
        )
        return _durations(junit), time.monotonic() - start


def _collected() -> list[str]:
    """Every test's node id, in collection order."""
    listing = subprocess.run(
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider"],
        cwd=ROOT,
        check=False,
        capture_output=True,
        text=True,
    ).stdout
    return [line.strip() for line in listing.splitlines() if "::" in line]


def _long_tier(durations: dict[str, float], unfinished: set[str]) -> list[str]:
    """Tests of LONG_TEST_SECONDS or more (and the unfinished ones); in a chained module only its
    tail."""
    long = {
        node for node, seconds in durations.items() if seconds >= LONG_TEST_SECONDS
    } | unfinished
    long = {node for node in long if _module(node) not in ALWAYS_IN_CI}
    for module in CHAINED_MODULES:
        in_order = [node for node in _collected() if _module(node) == module]
        tail: set[str] = set()
        for node in reversed(in_order):
            if node not in long:
                break
            tail.add(node)
        long = {node for node in long if _module(node) != module} | tail
    return sorted(long)


def _module(node_id: str) -> str:
    return node_id.partition("::")[0]


def _fast_candidates(durations: dict[str, float]) -> list[str]:
    """Per module, its tests quicker than FAST_CANDIDATE_SECONDS, quickest first, within the time
    share."""
    by_module: dict[str, list[str]] = defaultdict(list)
    for node, seconds in sorted(durations.items(), key=lambda item: item[1]):
        if seconds < FAST_CANDIDATE_SECONDS:
            by_module[_module(node)].append(node)
    return _within_budget(by_module, durations)


def _within_budget(by_module: dict[str, list[str]], durations: dict[str, float]) -> list[str]:
    """Round-robin over the modules (one test each, then a second ...) until the time share is
    spent."""
    budget, chosen, spent = FAST_SUM_SHARE * FAST_TIER_SECONDS, [], 0.0
    for rank in range(max((len(nodes) for nodes in by_module.values()), default=0)):
        for nodes in by_module.values():
            if rank < len(nodes) and (rank == 0 or spent + durations[nodes[rank]] <= budget):
                chosen.append(nodes[rank])
                spent += durations[nodes[rank]]
    return sorted(chosen)


def _prune(fast: list[str], measured: dict[str, float]) -> list[str]:
    """The fast tier again, with the times it took when run alone (module fixtures included)."""
    by_module: dict[str, list[str]] = defaultdict(list)
    for node in sorted(fast, key=lambda node: measured.get(node, 0.0)):
        by_module[_module(node)].append(node)
    return _within_budget(by_module, {node: measured.get(node, 0.0) for node in fast})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--junit", type=Path, help="a junit XML of a whole-suite run to take the durations from"
    )
    args = parser.parse_args()
    durations = _durations(args.junit) if args.junit else _run_pytest(["-n", "2", "-m", ""])[0]
    unfinished = (
        set(json.loads(TIERS_FILE.read_text())["long"]) - durations.keys()
        if TIERS_FILE.exists()
        else set()
    )
    long = _long_tier(durations, unfinished)
    fast = _fast_candidates(durations)
    TIERS_FILE.write_text(json.dumps({"fast": fast, "long": long}, indent=1) + "\n")
    measured, _ = _run_pytest(["-m", "fast"])
    fast = _prune(fast, measured)
    TIERS_FILE.write_text(json.dumps({"fast": fast, "long": long}, indent=1) + "\n")
    _, wall = _run_pytest(["-m", "fast"])
    modules = {_module(node) for node in durations}
    print(
        f"fast tier: {len(fast)} tests of "
        f"{len({_module(node) for node in fast})}/{len(modules)} modules, "
        f"{wall:.1f} s wall (limit {FAST_TIER_SECONDS:g} s)"
    )
    print(
        f"long tier: {len(long)} tests, "
        f"{sum(durations.get(node, 0.0) for node in long):.0f} s of test time in the "
        f"suite run ({len(unfinished)} more that did not finish in it)"
    )
    rest = sum(seconds for node, seconds in durations.items() if node not in long)
    print(
        f"the rest (CI): {len(durations) - len(long)} tests, "
        f"{rest:.0f} s of test time in the suite run"
    )


if __name__ == "__main__":
    main()
