#!/usr/bin/env python3
"""Benchmark reading an airfoil coordinate file: parse + crossing checks, against the point count.

    python scripts/bench_airfoil_file.py        # 200 ... 20,000 points, and the all-pairs reference
    python scripts/bench_airfoil_file.py --points 94000
                                                # one size (above the limit: refused, timed)

Each file is a NACA 2412 in Selig order with cosine-spaced stations, written to a temp folder and
read with :func:`torus_cad.geometry.section.airfoil_file.read_airfoil_file`. The reference column
times the all-pairs segment test (every segment against every other, blocks of 256 rows) that the
sort-and-sweep search replaced, on the same loop; the ratio is reference / sweep. Never part of the
test suite.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from torus_cad.errors import ParameterError
from torus_cad.geometry.section.airfoil import NacaAirfoil
from torus_cad.geometry.section.airfoil_file import (
    first_crossing,
    read_airfoil_file,
    write_selig_file,
)


def _loop(points: int) -> np.ndarray:
    stations = points // 2 + 1
    u = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, stations)))
    section = NacaAirfoil(0.02, 0.4, 0.12)
    upper, lower = section.points_on_half(u, True), section.points_on_half(u, False)
    return np.concatenate([upper[::-1], lower[1:]])


def _all_pairs_crossing(polygon: np.ndarray, rows: int = 256) -> tuple[int, int] | None:
    start, end = polygon, np.roll(polygon, -1, axis=0)
    count = len(start)

    def orientation(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        return np.sign(
            (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        )

    index = np.arange(count)
    for first in range(0, count, rows):
        block = index[first : first + rows]
        p, q = start[block][:, None], end[block][:, None]
        r, s = start[None, :], end[None, :]
        crossing = (orientation(p, q, r) * orientation(p, q, s) < 0) & (
            orientation(r, s, p) * orientation(r, s, q) < 0
        )
        gap = np.abs(block[:, None] - index[None, :])
        pairs = np.argwhere(
            crossing & ~((gap <= 1) | (gap == count - 1)) & (block[:, None] < index[None, :])
        )
        if len(pairs):
            return int(block[pairs[0, 0]]), int(pairs[0, 1])
    return None


def _time(function, *args) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    function(*args)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, nargs="*", default=[200, 1000, 5000, 20000])
    parser.add_argument(
        "--reference-max", type=int, default=20000, help="largest size timed all-pairs"
    )
    args = parser.parse_args()
    print(f"{'points':>8} {'read s':>9} {'sweep s':>10} {'all-pairs s':>12} {'ratio':>7}  result")
    with tempfile.TemporaryDirectory() as folder:
        for points in args.points:
            loop = _loop(points)
            path = write_selig_file(Path(folder) / f"n{points}.dat", f"naca2412 {points}", loop)
            start = time.perf_counter()
            try:
                read_airfoil_file(path)
                result = "read"
            except ParameterError as error:
                result = f"refused: {error}"
            read_s = time.perf_counter() - start
            kd_s = _time(first_crossing, loop, True)
            reference = (
                _time(_all_pairs_crossing, loop) if points <= args.reference_max else float("nan")
            )
            print(
                f"{len(loop):>8} {read_s:>9.3f} {kd_s:>10.4f}"
                f" {reference:>12.3f} {reference / kd_s:>7.0f}  {result}"
            )


if __name__ == "__main__":
    main()
