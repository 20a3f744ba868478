"""Calibrate and check the CFD budget's estimate (torus_cad/cfd/estimate.py) against real runs.

    python scripts/cfd_budget.py                 # the default design at a few [cfd] settings (~10-20 min)
    python scripts/cfd_budget.py --quick         # the two coarsest settings only

For each setting: the size integrals (∫ dV / h³ and the surface triangles), the estimate, and a
real ``torus-cad cfd`` run's tetrahedra, wall time and peak resident memory (its own process);
then the least-squares constants (tetrahedra per volume unit and per triangle, memory base and per
tetrahedron) that the estimate module's constants were set from, and the estimate's time.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: [cfd] settings measured (command-line options), coarsest first.
SETTINGS: list[list[str]] = [
    ["--cells-per-chord", "4", "--curvature-cells", "0", "--growth-rate", "1.6", "--domain-radius", "2",
     "--upstream", "1.5", "--downstream", "2"],  # the README example
    ["--cells-per-chord", "4", "--growth-rate", "1.6"],
    ["--cells-per-chord", "6", "--growth-rate", "1.4"],
    [],  # the defaults
]


def _options_to_values(options: list[str]) -> dict[str, float]:
    return {f"cfd.{options[i][2:].replace('-', '_')}": float(options[i + 1]) for i in range(0, len(options), 2)}


def measure(options: list[str]) -> dict[str, float]:
    """One ``torus-cad cfd`` run in its own process: tetrahedra, wall seconds, peak RSS (MB)."""
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        process = subprocess.Popen([sys.executable, "-m", "torus_cad", "cfd", *options, "--out", folder, "-q"])
        _, status, usage = os.wait4(process.pid, 0)
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            raise SystemExit(f"torus-cad cfd {' '.join(options)} exited {process.returncode}")
        report = json.loads((Path(folder) / "torus_propeller_cfd.json").read_text())
        return {"tetrahedra": report["tetrahedra_total"], "wall_s": time.perf_counter() - start,
                "peak_mb": usage.ru_maxrss / 1024.0, "estimate": report["estimate"]["tetrahedra"]}


def main() -> None:
    from torus_cad.cfd.estimate import estimate_cfd_mesh, size_integrals
    from torus_cad.parameters import PropellerParameters

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the two coarsest settings only")
    args = parser.parse_args()
    rows = []
    for options in SETTINGS[:2] if args.quick else SETTINGS:
        params = PropellerParameters().with_values(_options_to_values(options))
        start = time.perf_counter()
        estimate = estimate_cfd_mesh(params)
        estimate_s = time.perf_counter() - start
        volume_units, triangles = size_integrals(params)
        real = measure(options)
        rows.append((volume_units, triangles, real))
        print(f"{' '.join(options) or '(defaults)'}: integrals {volume_units:,.0f} / {triangles:,} triangles; "
              f"estimate {estimate.tetrahedra:,} tets, {estimate.memory_mb:,.0f} MB ({estimate_s:.2f} s); real "
              f"{real['tetrahedra']:,} tets ({estimate.tetrahedra / real['tetrahedra']:.2f}x), {real['peak_mb']:,.0f} MB "
              f"peak, {real['wall_s']:.1f} s", flush=True)
    design = np.array([[volume, triangles] for volume, triangles, _ in rows])
    tets = np.array([real["tetrahedra"] for _, _, real in rows])
    per_volume, per_triangle = np.linalg.lstsq(design, tets, rcond=None)[0]
    memory = np.polyfit(tets, [real["peak_mb"] for _, _, real in rows], 1)
    print(f"fit: TETS_PER_VOLUME_UNIT = {per_volume:.2f}, TETS_PER_TRIANGLE = {per_triangle:.2f}; "
          f"MEMORY_BASE_MB = {memory[1]:.0f}, MEMORY_PER_TET_KB = {memory[0] * 1000.0:.2f}")


if __name__ == "__main__":
    main()
