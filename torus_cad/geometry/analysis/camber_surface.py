"""The blade's camber surface and its sections' own shapes, from the sampled blade (kernel-free).

Each section of a :class:`~torus_cad.geometry.blade.blade_surface.BladeSurface` is a closed curve
that starts at the leading edge, runs along the upper surface to the trailing edge and back along
the lower one. Its **chord line** runs from the leading edge to the trailing edge (the middle of a
blunt edge's base, as :func:`torus_cad.geometry.analysis.blade_elements.chord_lines`). The **camber
point** at chord fraction x is the mean of the upper and lower surfaces' points at the same fraction
of the chord (each surface interpolated in its projection on the chord line). The vortex solver
(:mod:`torus_cad.vortex`) lays its lattice on these points; its section polars take each section's
shape in its own plane, normalised by the chord (:func:`section_coordinates`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from torus_cad.geometry.analysis.blade_elements import chord_lines
from torus_cad.geometry.blade.blade_surface import BladeSurface


@dataclass(frozen=True)
class CamberSurface:
    """The camber surface of one blade at given chord fractions.

    Attributes:
        points: ``(sections, fractions, 3)`` mm: the camber point of each section at each chord
            fraction.
        fractions: ``(fractions,)`` chord fractions, 0 (leading edge) to 1 (trailing edge).
        chord_mm: ``(sections,)`` chord lengths.
        s: ``(sections,)`` the sections' centerline parameters.
    """

    points: NDArray[np.float64]
    fractions: NDArray[np.float64]
    chord_mm: NDArray[np.float64]
    s: NDArray[np.float64]


def cosine_fractions(count: int) -> NDArray[np.float64]:
    """``(count + 1,)`` chord fractions 0..1, closer together at both edges (x = (1 - cos(pi k /
    count)) / 2)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.arange(count + 1) / count))


def camber_surface(surface: BladeSurface, fractions: NDArray[np.float64]) -> CamberSurface:
    """The camber points of every section of ``surface`` at the chord ``fractions`` (module doc)."""
    te = surface.trailing_edge_column
    leading, chord = chord_lines(surface.points, te, surface.lower_corner_index)
    length = np.linalg.norm(chord, axis=1)
    points = np.empty((len(surface.points), len(fractions), 3))
    for k, section in enumerate(surface.points):
        upper, lower = _sides(section, te, surface.lower_corner_index)
        points[k] = 0.5 * (
            _at_fractions(upper, leading[k], chord[k], fractions)
            + _at_fractions(lower, leading[k], chord[k], fractions)
        )
    return CamberSurface(points, np.asarray(fractions, dtype=float), length, surface.s)


def section_coordinates(surface: BladeSurface, k: int) -> NDArray[np.float64]:
    """``(p, 2)`` the shape of section ``k`` in its plane, the chord from (0, 0) to (1, 0), in Selig
    order (upper trailing edge -> leading edge -> lower trailing edge), the upper surface at y >
    0."""
    te = surface.trailing_edge_column
    leading, chord = chord_lines(surface.points, te, surface.lower_corner_index)
    length = float(np.linalg.norm(chord[k]))
    along = chord[k] / length
    binormal = surface.frames.binormal[k] - np.dot(surface.frames.binormal[k], along) * along
    across = binormal / np.linalg.norm(binormal)
    upper, lower = _sides(surface.points[k], te, surface.lower_corner_index)
    ordered = np.concatenate([upper[::-1], lower[1:]]) - leading[k]
    xy = np.stack([ordered @ along, ordered @ across], axis=1) / length
    if np.mean(upper @ across) < np.mean(lower @ across):  # the upper surface up
        xy[:, 1] = -xy[:, 1]
    return xy


def _sides(
    section: NDArray[np.float64], te: int, lower_corner: int | None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The upper and the lower surface of a closed section, each from the leading edge to the
    trailing edge."""
    upper = section[: te + 1]
    lower = np.concatenate(
        [section[(lower_corner if lower_corner is not None else te) :], section[:1]]
    )[::-1]
    return upper, lower


def _at_fractions(
    side: NDArray[np.float64],
    leading: NDArray[np.float64],
    chord: NDArray[np.float64],
    fractions: NDArray[np.float64],
) -> NDArray[np.float64]:
    """``side``'s points (``(p, 3)``, leading to trailing edge) at ``fractions`` of the chord, each
    coordinate interpolated linearly in the points' projection on the chord line."""
    along = np.maximum.accumulate(
        np.clip((side - leading) @ chord / np.dot(chord, chord), 0.0, 1.0)
    )
    return np.stack([np.interp(fractions, along, side[:, axis]) for axis in range(3)], axis=1)
