"""The vortex run's files beside its report: the loading along the blade (CSV and picture) and the
wake (picture)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from torus_cad.vortex.lattice import Lattice
from torus_cad.vortex.rotor import RotorBlade
from torus_cad.vortex.vortex_performance import StripLoads

#: The CSV's columns (SI units; s is the centerline parameter, 0..1).
LOADING_COLUMNS = (
    "s",
    "radius_m",
    "circulation_m2_s",
    "thrust_n_per_m",
    "torque_nm_per_m",
    "reynolds",
    "cl",
    "cd",
    "polar_confidence",
)
#: Wake segments drawn at most (every n-th, evenly), so that the picture stays light.
WAKE_SEGMENTS_DRAWN = 20000


def write_loading_csv(strips: StripLoads, path: Path) -> Path:
    """One row a strip of blade 0, columns LOADING_COLUMNS; return ``path``."""
    columns = (
        strips.s,
        strips.radius_m,
        strips.circulation_m2_s,
        strips.thrust_n_per_m,
        strips.torque_nm_per_m,
        strips.reynolds,
        strips.cl,
        strips.cd,
        strips.confidence,
    )
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(LOADING_COLUMNS)
        for row in zip(*columns):
            writer.writerow([f"{value:.9g}" for value in row])
    return path


def write_loading_plot(strips: StripLoads, path: Path, title: str) -> Path:
    """Circulation (above) and thrust and torque per unit length (below) against s (matplotlib,
    Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (upper, lower) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    try:
        upper.plot(strips.s, strips.circulation_m2_s, "o-", ms=3, color="tab:purple")
        upper.set_ylabel("circulation, m^2/s")
        upper.set_title(title)
        lower.plot(
            strips.s, strips.thrust_n_per_m, "o-", ms=3, color="tab:blue", label="thrust, N/m"
        )
        lower.plot(
            strips.s,
            strips.torque_nm_per_m * 1000.0,
            "s-",
            ms=3,
            color="tab:red",
            label="torque, N mm/m",
        )
        lower.set_xlabel("centerline parameter s")
        lower.legend(loc="best")
        for axes in (upper, lower):
            axes.grid(True, alpha=0.3)
        figure.tight_layout()
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return path


def write_wake_plot(blade: RotorBlade, lattice: Lattice, path: Path, title: str) -> Path:
    """Every blade's wake lines in 3D and blade 0's camber surface, mm (matplotlib, Agg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    wake = slice(lattice.bound_segments, None)
    starts, ends = lattice.starts[wake] * 1000.0, lattice.ends[wake] * 1000.0
    step = max(1, len(starts) // WAKE_SEGMENTS_DRAWN)
    figure = plt.figure(figsize=(8, 8))
    try:
        axes = figure.add_subplot(projection="3d")
        axes.add_collection3d(
            Line3DCollection(
                np.stack([starts[::step], ends[::step]], axis=1),
                linewidths=0.3,
                colors="tab:blue",
                alpha=0.5,
            )
        )
        camber = blade.camber_m * 1000.0
        axes.plot_surface(camber[..., 0], camber[..., 1], camber[..., 2], color="tab:orange")
        every = np.concatenate([starts, ends, camber.reshape(-1, 3)])
        low, high = every.min(axis=0), every.max(axis=0)
        centre, half = 0.5 * (low + high), 0.5 * float((high - low).max())
        axes.set_xlim(centre[0] - half, centre[0] + half)
        axes.set_ylim(centre[1] - half, centre[1] + half)
        axes.set_zlim(centre[2] - half, centre[2] + half)
        axes.set_xlabel("x, mm")
        axes.set_ylabel("y, mm")
        axes.set_zlabel("z, mm")
        axes.set_title(title)
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return path
