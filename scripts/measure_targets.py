"""Measure the design targets on the built solids of the examples (run from the repo root).

For every example with a ``diameter`` or ``pitch``: the tip diameter of the B-rep (BRepExtrema
against a coaxial cylinder) and the geometric pitch of the B-rep's sections where the blade
passes 75 % of the tip radius (a plane cuts the solid there; the chord is read off the contour),
next to what was asked and what the fit reported.

    python scripts/measure_targets.py [designs.toml ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

from torus_cad.kernel.measure import max_radius_mm
from torus_cad.outputs.measured_targets import pitch_on_solid, radius_crossings
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller


def main(paths: list[Path]) -> int:
    print(
        "| design | diameter asked | B-rep diameter | pitch "
        "asked | reported at 0.75 R | B-rep at 0.75 R |"
    )
    print("| --- | --- | --- | --- | --- | --- |")
    for path in paths:
        asked = PropellerParameters.from_toml(path)
        if not (asked.diameter or asked.pitch):
            continue
        propeller = build_propeller(asked)
        targets = propeller.design_targets
        diameter = 2.0 * max_radius_mm(propeller.solid)
        reported = measured = "-"
        if targets is not None and targets.pitch_fit is not None:
            reported = " / ".join(f"{value:.1f}" for value in targets.pitch_fit.pitch_at_75_mm)
            crossings = radius_crossings(
                propeller.parameters, 0.375 * (targets.tip_diameter_mm or diameter)
            )
            measured = " / ".join(f"{pitch_on_solid(propeller, s):.1f}" for s, _ in crossings)
        print(
            f"| {asked.name} | {asked.diameter:g} | {diameter:.3f} | "
            f"{asked.pitch:g} | {reported} | {measured} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    arguments = [Path(arg) for arg in sys.argv[1:]]
    raise SystemExit(
        main(
            arguments
            or sorted(
                path
                for path in Path("examples").glob("*.toml")
                if not path.name.startswith(("sweep", "workshop"))
            )
        )
    )
