#!/usr/bin/env python3
"""Whether the root fillet works on the default and every shipped example, at 0.5 and 1.0 mm.

    python scripts/fillet_examples.py                  # radii 0.5 and 1.0 mm
    python scripts/fillet_examples.py --radius 0.25

Prints one line per design and radius: ``ok``, ``reduced`` (made, but with a smaller radius
along junction edges where the blade bends too tightly for it:
torus_cad.kernel.fillet.root_fillet.RootFillet), ``refused`` (exit-2 input, e.g. a chamfer the
fillet's spread would cut into) or ``failed`` (OpenCascade could not make the fillet), and the build
time. Only the requested radius is tried (no search for a smaller one that works).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torus_cad.kernel.fillet.root_fillet as fillet
from torus_cad.errors import GeometryError, KernelError, ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def outcome(params: PropellerParameters) -> str:
    """``ok``, ``reduced: <radii>``, ``refused: <reason>`` or ``failed: <reason>`` of one build."""
    try:
        made = build_propeller(params).root_fillet
    except (ParameterError, GeometryError) as error:
        return f"refused: {error}"
    except KernelError as error:
        return f"failed: {error}"
    if made is not None and not made.constant_radius:
        return (
            f"reduced: down to {made.smallest_radius_mm:.3g} mm "
            f"along {made.varying_junction_mm:.2f} mm "
            "of each blade's junction"
        )
    return "ok"


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--radius", type=float, action="append", help="fillet radius, mm (default 0.5 and 1.0)"
    )
    args = parser.parse_args()
    fillet._FALLBACK_FRACTIONS = ()  # the requested radius only
    designs = {"default": PropellerParameters()}
    for path in sorted(EXAMPLES.glob("*.toml")):
        if "sweep" not in path.name:  # a sweep file is not a design
            designs[path.stem] = PropellerParameters.from_toml(path)
    for name, params in designs.items():
        for radius in args.radius or [0.5, 1.0]:
            start = time.perf_counter()
            result = outcome(params.with_values({"hub.root_fillet_radius": radius}))
            print(
                f"{name:<28} {radius:4.2f} mm  {result[:110]}  "
                f"({time.perf_counter() - start:.1f} s)",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
