"""Hub (spec §6.2): where the blades meet the cylinder r = R_hub, and where its seam may go.

A B-rep cylinder has a seam: the line u = 0 of its lateral face, at some angle about the
axis. The hub is rotationally symmetric, so that angle is free, and the kernel puts it where
no blade meets the hub: the holes the blades cut into the lateral face then never straddle
the seam, so no seam edge runs through a blade root in the STEP file, and blade i's hole is
blade 0's shifted by 360 i / n degrees in u, in one piece.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from torus_cad.tolerances import HUB_FOOTPRINT_MARGIN_DEG

#: Sections whose nearest point is within this fraction of the hub radius count as meeting
#: the hub when the kernel looks for a place for the hub's seam (geometry.hub).
HUB_FOOTPRINT_NEAR_RELATIVE = 0.02


#: Resolution of the angular scan for a free seam angle (bins around the axis).
_SEAM_SCAN_BINS = 3600


def footprint_arcs_deg(
    blade_points: NDArray[np.float64], hub_radius: float
) -> list[tuple[float, float]]:
    """Angular arcs (start, end) in degrees, start < end, that cover where blade 0 meets the hub.

    ``blade_points`` is the sampled blade surface, ``(sections, points, 3)`` float, mm, blade 0.
    A run of consecutive sections that comes within ``HUB_FOOTPRINT_NEAR_RELATIVE`` of the hub
    radius, widened by one section at each side (the hub's surface crosses the blade between
    an inside and an outside section), gives one arc: the angular hull of its points plus
    ``HUB_FOOTPRINT_MARGIN_DEG`` at each side. An arc of half a turn or more means the
    footprint is too wide to place a seam beside it; the arc (0, 360) is returned then.
    """
    points = np.asarray(blade_points, dtype=float)
    radius = np.hypot(points[..., 0], points[..., 1])
    near = radius.min(axis=1) < hub_radius * (1.0 + HUB_FOOTPRINT_NEAR_RELATIVE)
    widened = near.copy()
    widened[1:] |= near[:-1]
    widened[:-1] |= near[1:]
    arcs = []
    for start, stop in _true_runs(widened):
        angles = np.arctan2(points[start:stop, :, 1], points[start:stop, :, 0]).ravel()
        reference = np.angle(np.exp(1j * angles).mean())
        relative = np.angle(np.exp(1j * (angles - reference)))
        low = np.degrees(reference + relative.min()) - HUB_FOOTPRINT_MARGIN_DEG
        high = np.degrees(reference + relative.max()) + HUB_FOOTPRINT_MARGIN_DEG
        if high - low >= 180.0:
            return [(0.0, 360.0)]
        arcs.append((float(low), float(high)))
    return arcs


def seam_angle_deg(
    blade_points: NDArray[np.float64],
    hub_radius: float,
    blades: int,
    reserved_arcs_deg: Sequence[tuple[float, float]] = (),
) -> float | None:
    """An angle (degrees about +z, from +x) where the hub's seam meets no blade, or None.

    Blade i's footprint is blade 0's rotated by 360 i / n (spec §6.1). The seam goes to the
    middle of the widest free gap between the footprints of all ``blades`` blades and the
    ``reserved_arcs_deg`` (start, end) (e.g. a set-screw hole); None when they cover the whole
    circle.
    """
    occupied = np.zeros(_SEAM_SCAN_BINS, dtype=bool)
    bin_deg = 360.0 / _SEAM_SCAN_BINS
    arcs = [
        (low + 360.0 * blade / blades, high + 360.0 * blade / blades)
        for low, high in footprint_arcs_deg(blade_points, hub_radius)
        for blade in range(blades)
    ]
    for low, high in [*arcs, *reserved_arcs_deg]:
        first = int(np.floor(low / bin_deg))
        last = int(np.ceil(high / bin_deg))
        occupied[np.arange(first, last + 1) % _SEAM_SCAN_BINS] = True
    if occupied.all():
        return None
    # Unroll the circle at an occupied bin so that no free gap wraps around the end.
    shift = int(np.argmax(occupied))
    start, stop = max(_true_runs(np.roll(~occupied, -shift)), key=lambda run: run[1] - run[0])
    middle_bin = (start + stop - 1) / 2.0 + shift
    return float(((middle_bin + 0.5) * bin_deg) % 360.0)


def _true_runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(start, stop) index pairs of the runs of True in a 1-D boolean array."""
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))
