"""Measure how equal the arc-length spacing of spec §5 is, and what it costs.

    python scripts/arc_length_spacing.py [--points 200] [--repeats 5]

Prints, for the spec's procedure (one spacing around the whole section) and for the anchored
sampling the solid uses (trailing edge kept as a point), the largest relative deviation of
consecutive arc lengths and of consecutive chord lengths, and the median time per airfoil.
"""

from __future__ import annotations

import argparse
import statistics
import time
from itertools import pairwise

import numpy as np

from torus_cad.geometry.section.airfoil import NacaAirfoil, airfoil_points
from torus_cad.geometry.section.arc_length import equal_arc_length_section, spacing_deviation


def arc_gaps(airfoil: NacaAirfoil, t: np.ndarray, fine: int = 2000) -> np.ndarray:
    """Arc length between consecutive parameters of the closed section, from fine polylines."""
    closed = np.append(t, 2.0)
    return np.array(
        [
            np.linalg.norm(
                np.diff(airfoil_points(airfoil, np.linspace(a, b, fine)), axis=0), axis=1
            ).sum()
            for a, b in pairwise(closed)
        ]
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    airfoil = NacaAirfoil()
    for anchor, label in ((False, "spec procedure"), (True, "anchored (solid, mesh)")):
        times = []
        for _ in range(args.repeats):
            equal_arc_length_section.cache_clear()
            start = time.perf_counter()
            sampling = equal_arc_length_section(airfoil, args.points, anchor)
            times.append(time.perf_counter() - start)
        gaps = arc_gaps(airfoil, sampling.t)
        chords = np.linalg.norm(np.roll(sampling.points, -1, axis=0) - sampling.points, axis=1)
        line = (
            f"{label:<24} n = {args.points}: arc-length spacing max |d/mean - 1| = "
            f"{np.abs(gaps / gaps.mean() - 1).max():.2e}, "
            f"chord-length {spacing_deviation(sampling.points):.2e}"
        )
        if not anchor:  # one chord cuts the sharp trailing-edge corner: report the rest too
            keep = np.ones(len(chords), dtype=bool)
            keep[np.searchsorted(sampling.t, 1.0) - 1] = False
            line += (
                f" ({np.abs(chords[keep] / chords[keep].mean() - 1).max():.2e}"
                " without the corner chord)"
            )
        print(line + f"; {statistics.median(times) * 1000:.1f} ms per airfoil")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
