"""Fuzz designs through the build and the strict validity check (the property test and
``scripts/bench_strict_check.py --fuzz`` use it).

Each design of :func:`studies.fuzz.random_design` (``workshop`` features included) is
built; a build that succeeds has its whole solid checked again by BRepAlgoAPI_Check (not the
build's blade-pattern shortcut: that is what is being tested) and its STL written and read back
by meshlib.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path

from pebble import ProcessPool


@dataclass(frozen=True)
class FuzzOutcome:
    """One design: ``status`` 'built', 'refused' (bad input, exit 2) or 'failed' (KernelError: the
    build, its strict check or its STL's; or a worker that died); whether the whole solid passes
    BRepCheck and BRepAlgoAPI_Check (also for a solid whose STL failed) and, when built, its STL's
    crossing triangle pairs (meshlib)."""

    seed: int
    status: str
    reason: str = ""
    strict_valid: bool = False
    stl_pairs: int = -1
    build_s: float = 0.0
    check_s: float = 0.0


def fuzz_one(seed: int, workshop: bool = True) -> FuzzOutcome:
    """Build the fuzz design of ``seed`` and check what it published."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Check
    from OCP.BRepCheck import BRepCheck_Analyzer

    from studies.fuzz import random_design
    from torus_cad.errors import GeometryError, KernelError, ParameterError
    from torus_cad.kernel.mesh_check import intersecting_pairs_in_file
    from torus_cad.kernel.writers.stl import write_checked_stl
    from torus_cad.propeller import build_propeller

    start = time.perf_counter()
    try:
        propeller = build_propeller(random_design(seed, workshop=workshop))
    except (ParameterError, GeometryError) as error:
        return FuzzOutcome(seed, "refused", str(error).splitlines()[0][:200])
    except KernelError as error:
        return FuzzOutcome(seed, "failed", str(error).splitlines()[0][:300])
    built = time.perf_counter()
    solid = propeller.solid.wrapped
    valid = BRepCheck_Analyzer(solid).IsValid() and BRepAlgoAPI_Check(solid, True, True).IsValid()
    checked = time.perf_counter()
    export = propeller.parameters.export
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "fuzz.stl"
        try:
            write_checked_stl(
                propeller.solid, path, export.stl_linear_deflection, export.stl_angular_deflection
            )
        except KernelError as error:  # the build refuses to publish such an STL (exit 1)
            return FuzzOutcome(seed, "failed", str(error).splitlines()[0][:300], valid)
        pairs = intersecting_pairs_in_file(path)[0]
    return FuzzOutcome(seed, "built", "", valid, pairs, built - start, checked - built)


#: Seconds one fuzz design may take in its worker before it counts as failed.
FUZZ_DESIGN_TIME_LIMIT_S = 600.0


def fuzz_many(seeds: Sequence[int], workers: int = 2, workshop: bool = True) -> list[FuzzOutcome]:
    """:func:`fuzz_one` of every seed in ``workers`` spawned processes (OpenCascade's threads do not
    survive a fork); a worker that crashes or overruns FUZZ_DESIGN_TIME_LIMIT_S is a 'failed'
    design."""
    with ProcessPool(max_workers=workers, context=get_context("spawn")) as pool:
        futures = [
            (seed, pool.schedule(fuzz_one, (seed, workshop), timeout=FUZZ_DESIGN_TIME_LIMIT_S))
            for seed in seeds
        ]
        outcomes = []
        for seed, future in futures:
            try:
                outcomes.append(future.result())
            except Exception as error:  # the worker died (a crash in OpenCascade) or timed out
                outcomes.append(
                    FuzzOutcome(seed, "failed", f"worker: {type(error).__name__}: {error}"[:300])
                )
        return outcomes
