#!/usr/bin/env python3
"""What the STEP read-back validity costs, in process CPU seconds (the machine may be shared).

    python scripts/bench_step_readback.py                      # the default
    python scripts/bench_step_readback.py examples/cooling_fan_7blade.toml
    python scripts/bench_step_readback.py examples/workshop_motor_mount.toml --set blades=5

After a warm-up build: the build (its strict check runs in a child and is not counted), the rebuilt
intersection edges within it (torus_cad.kernel.edge_curves), the STEP write, the read-back alone,
the read-back check the build runs (every test but self-interference) and the self-interference
test on the file read back; then what the writer adds only when a file reads back faulty: the edges
made readable on a copy of the solid, and its file written and checked again.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any


def _cpu(work: Callable[[], Any]) -> tuple[Any, float]:
    start = time.process_time()
    result = work()
    return result, time.process_time() - start


def _timed(module: Any) -> list[float]:
    """Wrap ``module.refit_intersection_edges`` so that each call's CPU seconds land in the list
    returned."""
    seconds: list[float] = []
    refit = module.refit_intersection_edges

    def timed(*arguments: Any) -> Any:
        result, spent = _cpu(lambda: refit(*arguments))
        seconds.append(spent)
        return result

    module.refit_intersection_edges = timed
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("design", nargs="?", help="design file (default: the default design)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change a parameter (TOML value), e.g. --set blades=5; may be repeated",
    )
    args = parser.parse_args()
    import tomllib

    import torus_cad.kernel.fuse as fuse
    import torus_cad.kernel.hub as hub
    from torus_cad.kernel.readable_edges import readable_copy
    from torus_cad.kernel.step_readback import check_step_readback, read_step, step_readback_faults
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    refit_seconds = _timed(fuse)
    hub_seconds = _timed(hub)
    params = (
        PropellerParameters() if args.design is None else PropellerParameters.from_toml(args.design)
    )
    params = params.with_values(
        {
            key: tomllib.loads(f"v = {value}")["v"]
            for key, value in (item.split("=", 1) for item in args.set)
        }
    )
    build_propeller(params)  # warm-up: imports, caches
    refit_seconds.clear()
    hub_seconds.clear()
    propeller, build_s = _cpu(lambda: build_propeller(params))
    rows = {
        "build (strict check in a child, not counted)": build_s,
        "  of which rebuilt edges": sum(refit_seconds),
        "  of which the hub's rebuilt edges (bore, set screw)": sum(hub_seconds),
    }
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "design.step"
        rows["STEP write"] = _cpu(
            lambda: write_step(
                propeller.solid, path, propeller.parameters.name, check_readback=False
            )
        )[1]
        rows["read back alone"] = _cpu(lambda: read_step(path))[1]
        rows["read-back check (the build's: all but self-interference)"] = _cpu(
            lambda: check_step_readback(path, "the design", self_interference=False)
        )[1]
        rows["read back, every test (self-interference included)"] = _cpu(
            lambda: step_readback_faults(path)
        )[1]
        copy, rows["edges made readable (the writer's second try, on a faulty file only)"] = _cpu(
            lambda: readable_copy(propeller.solid.wrapped)
        )
        rows["  its file written and checked again"] = _cpu(
            lambda: (
                write_step(copy, path, propeller.parameters.name, check_readback=False),
                check_step_readback(path, "the design", self_interference=False),
            )
        )[1]
    for name, seconds in rows.items():
        print(f"{seconds:7.3f} s  {name}")


if __name__ == "__main__":
    main()
