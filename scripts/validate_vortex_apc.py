#!/usr/bin/env python3
"""The vortex solver (torus_cad.vortex) against UIUC's wind tunnel: the APC 10x7 Slow Flyer, static
at 4000, 5000 and 5987 rpm (the last static point measured) and the 5000 rpm sweep at J = 0.2, 0.4
and 0.6, as validate_apc_10x7sf.py does for
OpenFOAM.

    python scripts/validate_vortex_apc.py                                  # UIUC's blade, NACA 4412
    python scripts/validate_vortex_apc.py --design examples/apc_10x7sf_pe0.toml  # APC's table
    python scripts/validate_vortex_apc.py --design examples/apc_10x7sf_e63.toml
    python scripts/validate_vortex_apc.py --inviscid --chordwise 8 --spanwise 30
    python scripts/validate_vortex_apc.py --wake slipstream=true   # the wake before the rigid helix

Prints the markdown table of studies/wind_tunnel.py (CT, CP and eta measured and computed, the
errors, whether each is within the targets) and, on stderr, each point's seconds and its
lattice's inviscid power over momentum theory's ideal (below 1 no rotor can be).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from studies.wind_tunnel import Comparison, markdown_table, read_wind_tunnel  # noqa: E402
from torus_cad.simulate.settings import OperatingPoint  # noqa: E402
from torus_cad.tolerances import VORTEX_CHORDWISE_DEFAULT, VORTEX_SPANWISE_DEFAULT  # noqa: E402
from torus_cad.vortex.lattice import WakeShape  # noqa: E402
from torus_cad.vortex.solver import momentum_inflow_m_s  # noqa: E402

POINTS = ((4000.0, 0.0), (5000.0, 0.0), (5987.0, 0.0), (5000.0, 0.2), (5000.0, 0.4), (5000.0, 0.6))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--design", type=Path, default=ROOT / "examples" / "apc_10x7sf.toml")
    parser.add_argument("--chordwise", type=int, default=VORTEX_CHORDWISE_DEFAULT)
    parser.add_argument("--spanwise", type=int, default=VORTEX_SPANWISE_DEFAULT)
    parser.add_argument("--inviscid", action="store_true", help="no section polars")
    parser.add_argument(
        "--wake",
        nargs="+",
        default=[],
        metavar="FIELD=VALUE",
        help="the wake's layout changed (torus_cad.vortex.lattice.WakeShape's fields, JSON values)",
    )
    args = parser.parse_args(argv)
    wake = WakeShape(
        **{name: json.loads(value) for name, value in (t.split("=") for t in args.wake)}
    )
    from torus_cad.parameters import PropellerParameters
    from torus_cad.vortex.rotor import Discretisation
    from torus_cad.vortex.vortex_performance import vortex_performance

    params = PropellerParameters.from_toml(args.design)
    data = read_wind_tunnel()
    comparisons = []
    for rpm, advance in POINTS:
        measured = data.static_point(rpm) if advance == 0.0 else data.sweep_point(rpm, advance)
        diameter_m = 2.0 * params.conventional.diameter / 2000.0
        airspeed = advance * rpm / 60.0 * diameter_m
        start = time.perf_counter()
        result = vortex_performance(
            params,
            rpm,
            airspeed,
            Discretisation(args.chordwise, args.spanwise, wake),
            viscous=not args.inviscid,
        )
        print(
            f"{rpm:.0f} rpm, J {advance:.2f}: {time.perf_counter() - start:.1f} s; the lattice's "
            f"inviscid power {_over_momentum_ideal(result, airspeed):.3f} x momentum's ideal",
            file=sys.stderr,
            flush=True,
        )
        comparisons.append(Comparison(measured, result.report["ct"], result.report["cp"]))
    print(markdown_table(comparisons, "vortex"))
    return 0


def _over_momentum_ideal(result: Any, airspeed_m_s: float) -> float:
    """The lattice's inviscid power over momentum theory's ideal for its inviscid thrust, T (V + v)
    (v the solver's own momentum inflow, A the tip circle): at least 1 for any rotor."""
    thrust = result.report["inviscid_thrust_n"]
    induced = momentum_inflow_m_s(
        thrust,
        airspeed_m_s,
        OperatingPoint(rpm=1.0).fluid.density_kg_m3,
        math.pi * result.blade.tip_radius_m**2,
    )
    return float(result.report["inviscid_power_w"] / (thrust * (airspeed_m_s + induced)))


if __name__ == "__main__":
    sys.exit(main())
