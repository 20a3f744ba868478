"""The rotor as the FW-H code (torus_cad.acoustics) hears it, from the vortex solution: the blade's
surface for the thickness noise (its faces carry no pressure) and every lattice ring for the loading
noise, on blade 0, the others identical copies of it.

A lifting surface has no thickness and carries a pressure jump, not a pressure: each ring becomes
two faces on the same spot, normals opposite, with pressures -dp/2 and +dp/2 so that the pair pushes
the blade with the ring's force across the ring (dp = F . n / A, F the ring's Kutta-Joukowski force,
viscous-corrected; its part along the surface, leading-edge suction, is left out). Their thickness
terms cancel, so the thickness noise is the blade surface's alone.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from torus_cad.acoustics.fwh import RotatingSurface
from torus_cad.vortex.lattice import Lattice
from torus_cad.vortex.rotor import RotorBlade

#: Every this many of a section's points make the thickness noise's faces: a face stays far smaller
#: than the wavelength of the highest harmonic reported, and the noise's cost goes with the faces.
THICKNESS_POINT_STRIDE = 4


def rotor_surface(
    blade: RotorBlade, lattice: Lattice, ring_force_n: NDArray[np.float64]
) -> RotatingSurface:
    """Blade 0's surface and lattice (``ring_force_n`` ``(K - 1, C, 3)`` N on its rings) as FW-H
    faces, the other blades its copies (:class:`~torus_cad.acoustics.fwh.RotatingSurface`); module
    doc."""
    centroids, normals, areas, pressure = _blade_faces(blade.surface_m[:, ::THICKNESS_POINT_STRIDE])
    ring_centroids, ring_normals, ring_areas = _ring_faces(lattice.grid)
    jump = np.einsum("ik,ik->i", ring_force_n.reshape(-1, 3), ring_normals) / np.maximum(
        ring_areas, 1e-300
    )
    one_blade = (
        np.concatenate([centroids, ring_centroids, ring_centroids]),
        np.concatenate([normals, ring_normals, -ring_normals]),
        np.concatenate([areas, ring_areas, ring_areas]),
        np.concatenate([pressure, -0.5 * jump, 0.5 * jump]),
    )
    return RotatingSurface(*one_blade, blade_copies=blade.blades)


def _blade_faces(surface_m: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """The quads between neighbouring sections and points of ``surface_m`` ``(K, P, 3)``: centroids,
    unit normals out of the blade (into the air), areas, zero pressure."""
    a, b = surface_m[:-1], surface_m[1:]
    c, d = np.roll(b, -1, axis=1), np.roll(a, -1, axis=1)
    area_vector = 0.5 * np.cross(c - a, d - b)
    centroid = 0.25 * (a + b + c + d)
    middle = 0.5 * (a.mean(axis=1, keepdims=True) + b.mean(axis=1, keepdims=True))
    # the faces' normals point into the blade
    if np.einsum("jik,jik->", area_vector, centroid - middle) < 0.0:
        area_vector = -area_vector
    area = np.linalg.norm(area_vector, axis=2).ravel()
    keep = area > 0.0
    normal = area_vector.reshape(-1, 3)[keep] / area[keep, None]
    return centroid.reshape(-1, 3)[keep], normal, area[keep], np.zeros(int(keep.sum()))


def _ring_faces(grid: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """Each ring of ``grid`` ``(K - 1, 2, C + 1, 3)``: centroid, unit normal and area ``((K - 1) C,
    ...)``."""
    a, b = grid[:, 0, :-1], grid[:, 1, :-1]
    c, d = grid[:, 1, 1:], grid[:, 0, 1:]
    area_vector = (0.5 * np.cross(c - a, d - b)).reshape(-1, 3)
    area = np.linalg.norm(area_vector, axis=1)
    return (
        (0.25 * (a + b + c + d)).reshape(-1, 3),
        area_vector / np.maximum(area, 1e-300)[:, None],
        area,
    )
