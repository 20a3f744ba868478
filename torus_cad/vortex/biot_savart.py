"""Velocity induced by straight vortex segments of unit strength (Biot-Savart), vectorised over
points and segments. Hand-written: a few lines of numpy, where a vortex-method package would bring a
whole solver whose wake and rotor model are not this one's."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Points closer to a segment's line than this fraction of its length get no velocity from it (the
#: segment's own midpoint, where its velocity is singular and, by symmetry, has no part in its
#: force).
CORE_FRACTION = 1e-6
#: Point-segment pairs computed at once: small enough for the temporaries to stay in the cache.
CHUNK_PAIRS = 1 << 16


def _kernel(
    points: NDArray[np.float64],
    starts: NDArray[np.float64],
    ends: NDArray[np.float64],
    core_m: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], ...]:
    """The three components ``(P, S)`` of r1 x r2 and the factor ``(P, S)`` that scales them into
    the velocity of unit segments (zero on a segment's line; with ``core_m`` ``(S,)``, a vortex core
    of that
    radius: |r1 x r2|^2 + core^2 |r0|^2 in the denominator, so a line passing through a point
    induces a finite velocity there)."""
    r1 = [points[:, k, None] - starts[None, :, k] for k in range(3)]
    r2 = [points[:, k, None] - ends[None, :, k] for k in range(3)]
    r0 = ends - starts
    cx = r1[1] * r2[2] - r1[2] * r2[1]
    cy = r1[2] * r2[0] - r1[0] * r2[2]
    cz = r1[0] * r2[1] - r1[1] * r2[0]
    cross_squared = cx * cx + cy * cy + cz * cz
    n1 = np.sqrt(r1[0] ** 2 + r1[1] ** 2 + r1[2] ** 2)
    n2 = np.sqrt(r2[0] ** 2 + r2[1] ** 2 + r2[2] ** 2)
    dot1 = r0[None, :, 0] * r1[0] + r0[None, :, 1] * r1[1] + r0[None, :, 2] * r1[2]
    dot2 = r0[None, :, 0] * r2[0] + r0[None, :, 1] * r2[1] + r0[None, :, 2] * r2[2]
    length_squared = np.einsum("sk,sk->s", r0, r0)[None, :]
    near = cross_squared <= (CORE_FRACTION**2) * length_squared**2
    if core_m is not None:
        cross_squared = cross_squared + (core_m**2)[None, :] * length_squared
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(near, 0.0, (dot1 / n1 - dot2 / n2) / (4.0 * np.pi * cross_squared))
    return cx, cy, cz, factor


def segment_velocities(
    points: NDArray[np.float64], starts: NDArray[np.float64], ends: NDArray[np.float64]
) -> NDArray[np.float64]:
    """``(P, S, 3)``: the velocity at each of ``points`` ``(P, 3)`` induced by each segment from
    ``starts`` to ``ends`` (``(S, 3)`` each) carrying a unit circulation (right-hand rule about the
    segment's direction), in the units of the points per unit circulation (1/length)."""
    cx, cy, cz, factor = _kernel(points, starts, ends)
    return np.stack([cx * factor, cy * factor, cz * factor], axis=2)


def normal_influence(
    points: NDArray[np.float64],
    normals: NDArray[np.float64],
    starts: NDArray[np.float64],
    ends: NDArray[np.float64],
    core_m: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """``(P, S)``: the velocity each unit segment induces at each point along that point's
    normal."""
    out = np.empty((len(points), len(starts)))
    size = _chunk(len(points))
    for first in range(0, len(starts), size):
        chunk = slice(first, first + size)
        cx, cy, cz, factor = _kernel(
            points, starts[chunk], ends[chunk], None if core_m is None else core_m[chunk]
        )
        out[:, chunk] = (
            cx * normals[:, 0, None] + cy * normals[:, 1, None] + cz * normals[:, 2, None]
        ) * factor
    return out


def induced_velocity(
    points: NDArray[np.float64],
    starts: NDArray[np.float64],
    ends: NDArray[np.float64],
    circulation: NDArray[np.float64],
    core_m: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """``(P, 3)``: the velocity at ``points`` induced by segments carrying ``circulation``
    ``(S,)``."""
    out = np.zeros((len(points), 3))
    size = _chunk(len(points))
    for first in range(0, len(starts), size):
        chunk = slice(first, first + size)
        cx, cy, cz, factor = _kernel(
            points, starts[chunk], ends[chunk], None if core_m is None else core_m[chunk]
        )
        weighted = factor * circulation[None, chunk]
        out[:, 0] += (cx * weighted).sum(axis=1)
        out[:, 1] += (cy * weighted).sum(axis=1)
        out[:, 2] += (cz * weighted).sum(axis=1)
    return out


def _chunk(points: int) -> int:
    """Segments a chunk for ``points`` points (at least 64)."""
    return max(64, CHUNK_PAIRS // max(points, 1))
