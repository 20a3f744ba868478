"""``torus-cad defaults``: the default design as commented TOML, or a design's resolved spec
parameters."""

from __future__ import annotations

import argparse
import sys

from torus_cad.cli.design_input import load_parameters
from torus_cad.cli.exits import EXIT_OK
from torus_cad.design.design_targets import resolve_design_targets
from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters


def run(args: argparse.Namespace) -> int:
    if not args.resolved:
        if args.config or args.overrides:
            raise ParameterError(
                "torus-cad defaults takes a design file or --set only with --resolved"
            )
        sys.stdout.write(
            "# torus_cad design file: every key is optional and defaults to the value below.\n"
        )
        sys.stdout.write(PropellerParameters().to_toml(comments=True))
        return EXIT_OK
    params = load_parameters(args.config, args.overrides)
    targets = resolve_design_targets(params)
    sys.stdout.write(
        "# torus_cad design file: the spec's parameters "
        "that the design's airfoil.naca, diameter and\n"
        "# pitch resolved to ("
        + (
            ", ".join(f"{key} = {value!r}" for key, value in targets.requested.items())
            or "none set"
        )
        + "); it builds the same propeller.\n"
    )
    if targets.tip_diameter_mm is not None:
        sys.stdout.write(f"# tip diameter {targets.tip_diameter_mm:.3f} mm")
        if targets.pitch_fit is not None:
            achieved = ", ".join(f"{value:.2f}" for value in targets.pitch_fit.pitch_at_75_mm)
            sys.stdout.write(f"; geometric pitch at 75 % of the tip radius {achieved} mm")
        sys.stdout.write("\n")
    sys.stdout.write(targets.parameters.to_toml(comments=True))
    return EXIT_OK
