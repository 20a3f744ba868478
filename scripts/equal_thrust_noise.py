#!/usr/bin/env python3
"""The tonal noise of the runs of an earlier ``scripts/equal_thrust.py --out OUT``, made before
simulate's cases wrote their blade surface pressure.

    python scripts/equal_thrust_noise.py OUT SCRATCH

For each ``OUT/*/<name>_performance.json``: copies its case's mesh, dictionaries and last time into
``SCRATCH/<name>_case``, adds the ``blade_pressure`` function object of today's cases to its
controlDict, has ``simpleFoam -postProcess -latestTime`` write the propeller's surface pressure (a
second, no solver iteration), and prints the noise at simulate's default observers
(torus_cad.acoustics). A run of ``equal_thrust.py`` with today's simulate has these numbers in its
reports already. Never part of the test suite (needs the cases).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
from pathlib import Path

from foamlib import FoamFile

from torus_cad.acoustics.fwh import Medium
from torus_cad.acoustics.noise_report import evaluate_noise
from torus_cad.acoustics.observers import DEFAULT_OBSERVERS
from torus_cad.acoustics.pressure_surface import read_surface, surface_pressure_file
from torus_cad.parameters.design import Handedness
from torus_cad.simulate import case as foam_case
from torus_cad.simulate.settings import AIR_15C, OperatingPoint


def case_noise(report_path: Path, scratch: Path, blades: int) -> None:
    """Write the surface pressure of the run of ``report_path`` into a copy of its case; print its
    noise."""
    report = json.loads(report_path.read_text(encoding="utf-8"))
    source, case = report_path.parent / report["case"], scratch / report["case"]
    shutil.rmtree(case, ignore_errors=True)
    case.mkdir(parents=True)
    for name in ("constant", "system", "0", str(report["iterations"])):
        shutil.copytree(source / name, case / name)
    spec = foam_case.CaseSpec(
        OperatingPoint(report["rpm"]),
        Handedness(report["handedness"]),
        report["tip_diameter_m"],
        1.0,
        report["iterations"],
        1,
        "",
    )
    with FoamFile(case / "system" / "controlDict") as control:
        control["functions"] = {
            foam_case.BLADE_PRESSURE: foam_case.control_dict(spec)["functions"][
                foam_case.BLADE_PRESSURE
            ]
        }
    env = {**os.environ, "WM_PROJECT_DIR": os.environ.get("WM_PROJECT_DIR", "/usr/share/openfoam")}
    subprocess.run(
        ["simpleFoam", "-postProcess", "-latestTime"],
        cwd=case,
        env=env,
        check=True,
        capture_output=True,
    )
    density = report["fluid"]["density_kg_m3"]
    surface = read_surface(
        surface_pressure_file(case, foam_case.BLADE_PRESSURE, foam_case.WALL), density
    )
    noise = evaluate_noise(
        surface,
        report["omega_rad_s"],
        blades,
        Medium(density, AIR_15C.speed_of_sound_m_s),
        DEFAULT_OBSERVERS,
        directivity=False,
    )
    print(
        f"{report['name']}: {report['rpm']:.0f} rpm, "
        f"{report['thrust_n']:.4g} N, {report['power_w']:.4g} W; surface "
        f"pressure thrust {noise.report['surface_pressure_thrust_n']:.4g} N; "
        f"noise {noise.report['seconds']:.1f} s"
    )
    for entry in noise.report["observers"]:
        print(
            f"  {entry['distance_m']:g} m {entry['angle_deg']:g} deg: {entry['oaspl_db']:.1f} dB, "
            f"{entry['oaspl_dba']:.1f} dB(A), other harmonics "
            f"{entry['other_harmonics_spl_db']:.1f} dB, "
            f"BPF {entry['harmonics'][0]['frequency_hz']:.0f} Hz"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "out", type=Path, help="the --out folder of an earlier scripts/equal_thrust.py run"
    )
    parser.add_argument("scratch", type=Path, help="where the case copies go")
    parser.add_argument(
        "--blades", type=int, default=3, help="blade count of both designs (default 3)"
    )
    args = parser.parse_args()
    for report_path in sorted(args.out.glob("*/*_performance.json")):
        case_noise(report_path, args.scratch, args.blades)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
