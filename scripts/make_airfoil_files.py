"""Write the example coordinate files in examples/airfoils/ (run from the repo root).

* ``naca2412.dat`` (Selig layout) and ``naca2412_lednicer.dat`` (Lednicer layout): the NACA 2412
  from the spec's §1 formulas (thickness normal to the camber line), 81 cosine-spaced chord
  stations per surface, 7 decimals. The same points in both layouts.
* ``clarky.dat`` (Selig layout): the Clark Y from its published ordinate table (percent chord,
  17 stations, measured from the flat lower surface; 11.7 % thick, trailing edge 0.12 % open),
  typed in for torus_cad. torus_cad normalises it (leading edge to the origin, chord to 1).

    python scripts/make_airfoil_files.py [OUT_DIR]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from torus_cad.geometry.section.airfoil import NacaAirfoil
from torus_cad.geometry.section.airfoil_file import write_lednicer_file, write_selig_file

#: Clark Y: chord stations, upper and lower ordinates, all in percent chord.
CLARK_Y_STATIONS = (
    0.0,
    1.25,
    2.5,
    5.0,
    7.5,
    10.0,
    15.0,
    20.0,
    30.0,
    40.0,
    50.0,
    60.0,
    70.0,
    80.0,
    90.0,
    95.0,
    100.0,
)
CLARK_Y_UPPER = (
    3.50,
    5.45,
    6.50,
    7.90,
    8.85,
    9.60,
    10.69,
    11.36,
    11.70,
    11.40,
    10.52,
    9.15,
    7.35,
    5.22,
    2.80,
    1.49,
    0.12,
)
CLARK_Y_LOWER = (
    3.50,
    1.93,
    1.47,
    0.93,
    0.63,
    0.42,
    0.15,
    0.03,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
)


def naca_surfaces(airfoil: NacaAirfoil, stations: int = 81) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower surfaces ``(stations, 2)`` at cosine-spaced chord positions, leading edge
    first."""
    chord = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, stations)))
    return airfoil.surfaces(chord)


def main(out_dir: Path) -> None:
    out_dir.mkdir(parents=True, exist_ok=True)
    upper, lower = naca_surfaces(NacaAirfoil.from_designation("2412"))
    write_selig_file(
        out_dir / "naca2412.dat",
        "NACA 2412 (torus_cad, spec 1 formulas, 81 cosine stations)",
        np.concatenate([upper[::-1], lower[1:]]),
    )
    write_lednicer_file(
        out_dir / "naca2412_lednicer.dat",
        "NACA 2412 (torus_cad, spec 1 formulas, 81 cosine stations)",
        upper,
        lower,
    )
    x = np.array(CLARK_Y_STATIONS) / 100.0
    clark_upper = np.stack([x, np.array(CLARK_Y_UPPER) / 100.0], axis=1)
    clark_lower = np.stack([x, np.array(CLARK_Y_LOWER) / 100.0], axis=1)
    write_selig_file(
        out_dir / "clarky.dat",
        "CLARK Y (published ordinates, percent chord / 100)",
        np.concatenate([clark_upper[::-1], clark_lower[1:]]),
        digits=5,
    )


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("examples/airfoils"))
