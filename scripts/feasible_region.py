#!/usr/bin/env python3
"""Map the default design's feasible region over two design variables with the kernel-free check.

    python scripts/feasible_region.py           # 41 x 41 designs -> docs/images/feasible_region.png
    python scripts/feasible_region.py --grid 11 --out region.png

Every point of the grid is the default propeller with the centerline's height (z_L of P2 and P3,
mm: how far the blade reaches out from the hub) and the chord law's constant term
(``transforms.scale_x[4]``, mm: the chord at the blade's two ends, which the mid-span chord
exceeds by 4 mm) set to the point's values, checked by
:func:`torus_cad.design.design_checks.check_design` (what ``torus-cad check`` and the sweep's
and study's pre-screen run; no kernel). Each point is coloured by the first check that refuses it,
the default design is marked, and the command prints the counts and the check's CPU time per design.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from torus_cad.design.design_checks import check_design
from torus_cad.errors import GeometryError, ParameterError
from torus_cad.parameters import PropellerParameters

ROOT = Path(__file__).resolve().parent.parent
X_KEY, Y_KEY = "centerline height (z_L of P2 and P3)", "transforms.scale_x[4]"

#: What refused a design, matched in the refusal's line, in the legend's order (the first is
#: "feasible").
KINDS = (
    ("feasible", "", "#4caf50"),
    ("folds over inside its bend", "folds over itself", "#e53935"),
    ("an end section leaves the hub's inset", "leaves the hub's inset", "#fb8c00"),
    ("sections too sparse for the blade", "is too few for this blade", "#8e24aa"),
    ("runs into itself or another blade", "intersect", "#3949ab"),
    ("never leaves the hub", "never leaves the hub", "#6d4c41"),
    ("other refusal", None, "#9e9e9e"),
)


def design_at(height_mm: float, chord_mm: float) -> PropellerParameters:
    """The default design with both free control points at ``height_mm`` and the chord law's
    constant term."""
    base = PropellerParameters()
    p2, p3 = base.centerline.p2, base.centerline.p3
    scale_x = list(base.transforms.scale_x)
    scale_x[4] = chord_mm
    return base.with_values(
        {
            "centerline.p2": [p2[0], p2[1], height_mm],
            "centerline.p3": [p3[0], p3[1], height_mm],
            "transforms.scale_x": scale_x,
        }
    )


def classify(point: tuple[float, float]) -> tuple[int, float]:
    """The KINDS index of the design at ``point`` and the CPU seconds its check took."""
    start = time.process_time()
    try:
        check_design(design_at(*point))
        kind = 0
    except (ParameterError, GeometryError) as error:
        message = str(error)
        kind = next(
            (
                index
                for index, (_, words, _) in enumerate(KINDS)
                if index and words and words in message
            ),
            len(KINDS) - 1,
        )
    return kind, time.process_time() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--grid", type=int, default=41, help="points along each axis (default 41)")
    parser.add_argument(
        "--heights",
        type=float,
        nargs=2,
        default=(4.0, 60.0),
        metavar=("LOW", "HIGH"),
        help="range of the centerline height, mm (default 4 60; the default design: 22)",
    )
    parser.add_argument(
        "--chords",
        type=float,
        nargs=2,
        default=(0.5, 16.0),
        metavar=("LOW", "HIGH"),
        help="range of transforms.scale_x[4], mm (default 0.5 16; the default design: 6)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=len(os.sched_getaffinity(0)),
        help="processes (default: cores)",
    )
    parser.add_argument(
        "--out", type=Path, default=ROOT / "docs" / "images" / "feasible_region.png"
    )
    args = parser.parse_args(argv)
    if args.grid < 2:
        parser.error("--grid must be at least 2")

    heights = np.linspace(*args.heights, args.grid)
    chords = np.linspace(*args.chords, args.grid)
    points = [(float(h), float(c)) for c in chords for h in heights]
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=max(1, args.workers)) as pool:
        answers = list(pool.map(classify, points, chunksize=16))
    elapsed = time.perf_counter() - start
    kinds = np.array([kind for kind, _ in answers]).reshape(len(chords), len(heights))
    cpu = [seconds for _, seconds in answers]

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    colours = ListedColormap([colour for _, _, colour in KINDS])
    figure, axis = plt.subplots(figsize=(8.0, 5.6))
    axis.pcolormesh(
        heights,
        chords,
        kinds,
        cmap=colours,
        norm=BoundaryNorm(np.arange(len(KINDS) + 1) - 0.5, len(KINDS)),
        shading="nearest",
    )
    default = PropellerParameters()
    axis.plot(
        default.centerline.p2[2],
        default.transforms.scale_x[4],
        marker="*",
        markersize=16,
        color="white",
        markeredgecolor="black",
        linestyle="none",
    )
    axis.annotate(
        "default design",
        (default.centerline.p2[2], default.transforms.scale_x[4]),
        textcoords="offset points",
        xytext=(10, 8),
        fontsize=9,
    )
    axis.set_xlabel(f"{X_KEY}, mm")
    axis.set_ylabel(f"{Y_KEY}: the chord law's constant term, mm")
    axis.set_title("The default design's feasible region (torus-cad check, no kernel)", fontsize=11)
    present = sorted(set(kinds.ravel().tolist()))
    axis.legend(
        handles=[Patch(color=KINDS[i][2], label=KINDS[i][0]) for i in present],
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        fontsize=9,
        title="first refusal",
        title_fontsize=9,
    )
    figure.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=100)
    plt.close(figure)

    print(
        f"{len(points)} designs in {elapsed:.1f} s on "
        f"{args.workers} processes; check CPU per design median "
        f"{1000 * statistics.median(cpu):.0f} ms, max {1000 * max(cpu):.0f} ms"
    )
    for index in present:
        times = [seconds for (kind, seconds) in answers if kind == index]
        print(
            f"  {len(times):5d}  {KINDS[index][0]:<40s} check "
            f"CPU median {1000 * statistics.median(times):.0f} ms"
        )
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
