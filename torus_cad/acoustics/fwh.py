"""Farassat's formulation 1A of the Ffowcs Williams-Hawkings equation on an impermeable surface
turning about +z.

Written here: no maintained Python FW-H code exists (PyPI has none; the maintained solvers are
Julia, Fortran or OpenFOAM libraries that the v1912 build here lacks), and the steady rotating case
is a hundred lines of numpy.

The surface is a set of flat faces (centroid, unit normal into the fluid, area), each a compact
source that turns with the rotor on its circle about the +z axis through the origin at the signed
angular velocity ``omega`` (rad/s; positive counter-clockwise seen from +z). Its gauge pressure is
steady in the rotating frame (a frozen-rotor solution), so the signal repeats every revolution. For
each observer time ``t`` on a uniform grid over one revolution and each face, Newton's method solves
the retarded-time equation ``t = tau + |x - y(tau)| / c`` (its derivative ``1 - M_r`` is near 1 for
a subsonic source, so it converges in a few steps); the thickness (monopole, from the normal
velocity ``v . n`` of the moving surface) and loading (dipole, ``p n``) terms are then evaluated
with every time derivative in closed form (the motion is a rotation) and summed over the faces. The
medium is at rest relative to the hub (hover, or an observer flying with the rotor with the flight
speed's convection neglected); viscous stresses are left out of the loading.

Farassat, F. (2007), Derivation of Formulations 1 and 1A of Farassat, NASA/TM-2007-214853, eqs. 36
and 37.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Newton's method on the retarded-time equation stops when every residual is below this fraction of
#: a period.
RETARDED_TIME_TOLERANCE = 1e-12
RETARDED_TIME_MAX_STEPS = 50
#: Faces evaluated at once (bounds the memory: a few arrays of FACE_CHUNK x samples floats).
FACE_CHUNK = 2048


@dataclass(frozen=True)
class RotatingSurface:
    """Flat faces at rotor angle 0: centroids (N, 3) m, unit normals (N, 3) pointing into the fluid,
    areas (N,) m^2, gauge pressure (N,) Pa (steady in the rotating frame); ``blade_copies``: the
    faces are one blade's of that many identical blades evenly spaced about +z (1: the faces are the
    whole rotor's). Blade k's signal is blade 0's a k-th of a blade passage later, so the rotor's is
    blade 0's with every harmonic of the rotation that is not a blade-passing one removed, times the
    blade count: the FW-H sum over one blade's faces instead of every blade's."""

    centroids_m: Array
    normals: Array
    areas_m2: Array
    pressure_pa: Array
    blade_copies: int = 1

    def __post_init__(self) -> None:
        count = len(self.areas_m2)
        if (
            self.centroids_m.shape != (count, 3)
            or self.normals.shape != (count, 3)
            or self.pressure_pa.shape != (count,)
        ):
            raise ValueError("centroids and normals must be (N, 3), areas and pressure (N,)")
        if self.blade_copies < 1:
            raise ValueError(f"blade_copies = {self.blade_copies}: at least 1")

    @property
    def pressure_force_n(self) -> Array:
        """The force the surface's pressure exerts on the body (N, 3): minus the sum of p n A (over
        every copy: evenly spaced copies' side forces cancel)."""
        force = np.asarray(-(self.pressure_pa * self.areas_m2) @ self.normals, dtype=float)
        if self.blade_copies == 1:
            return force
        return np.array([0.0, 0.0, self.blade_copies * force[2]])

    @property
    def face_count(self) -> int:
        """The rotor's faces, every copy's."""
        return len(self.areas_m2) * self.blade_copies


@dataclass(frozen=True)
class Medium:
    """The undisturbed fluid: density kg/m^3 and speed of sound m/s."""

    density_kg_m3: float
    speed_of_sound_m_s: float


@dataclass(frozen=True)
class ObserverSignal:
    """The acoustic pressure at one observer over one revolution: observer times (S,) s from 0
    (uniform, one period ``2 pi / |omega|``), thickness and loading parts (S,) Pa."""

    time_s: Array
    thickness_pa: Array
    loading_pa: Array

    @property
    def total_pa(self) -> Array:
        return np.asarray(self.thickness_pa + self.loading_pa)


def _rotate(vectors: Array, angle: Array) -> tuple[Array, Array, Array]:
    """Components x, y, z of ``vectors`` (n, 3) turned by ``angle`` (n, S) rad about +z: each (n,
    S)."""
    cos, sin = np.cos(angle), np.sin(angle)
    x, y = vectors[:, 0:1], vectors[:, 1:2]
    return x * cos - y * sin, x * sin + y * cos, np.broadcast_to(vectors[:, 2:3], angle.shape)


def retarded_times(
    centroids_m: Array,
    omega_rad_s: float,
    observer_m: Array,
    time_s: Array,
    speed_of_sound_m_s: float,
) -> Array:
    """Emission times tau (n, S) s at which sound from each source (rotating with ``omega``, at
    ``centroids_m`` at tau = 0) reaches ``observer_m`` at ``time_s``: Newton's method on
    ``tau + |x - y(tau)| / c - t = 0``."""
    c = speed_of_sound_m_s
    period = 2.0 * math.pi / abs(omega_rad_s)
    x0 = np.linalg.norm(observer_m[None, :] - centroids_m, axis=1)[:, None]
    tau = np.broadcast_to(time_s[None, :] - x0 / c, (len(centroids_m), len(time_s))).copy()
    for _ in range(RETARDED_TIME_MAX_STEPS):
        yx, yy, yz = _rotate(centroids_m, omega_rad_s * tau)
        rx, ry, rz = observer_m[0] - yx, observer_m[1] - yy, observer_m[2] - yz
        r = np.sqrt(rx * rx + ry * ry + rz * rz)
        residual = tau + r / c - time_s[None, :]
        mach_r = omega_rad_s * (-yy * rx + yx * ry) / (c * r)  # v . r_hat / c with v = omega z x y
        tau -= residual / (1.0 - mach_r)
        if float(np.max(np.abs(residual))) < RETARDED_TIME_TOLERANCE * period:
            return tau
    raise ArithmeticError("the retarded-time equation did not converge (a supersonic source?)")


def observer_signal(
    surface: RotatingSurface,
    omega_rad_s: float,
    observer_m: Array | tuple[float, float, float],
    medium: Medium,
    samples: int,
) -> ObserverSignal:
    """The thickness and loading noise of ``surface`` turning at ``omega_rad_s`` (rad/s about +z,
    nonzero) at ``observer_m`` (m, at rest relative to the hub), on ``samples`` uniform observer
    times over one revolution."""
    if omega_rad_s == 0.0 or not math.isfinite(omega_rad_s):
        raise ValueError(
            f"omega = {omega_rad_s!r} rad/s: a steady rotor's tones need a nonzero, finite rotation"
        )
    observer = np.asarray(observer_m, dtype=float)
    c, rho = medium.speed_of_sound_m_s, medium.density_kg_m3
    period = 2.0 * math.pi / abs(omega_rad_s)
    time_s: Array = np.arange(samples, dtype=np.float64) * (period / samples)
    thickness, loading = np.zeros(samples), np.zeros(samples)
    for start in range(0, len(surface.areas_m2), FACE_CHUNK):
        part = slice(start, start + FACE_CHUNK)
        centroids, normals = surface.centroids_m[part], surface.normals[part]
        areas, pressure = surface.areas_m2[part][:, None], surface.pressure_pa[part][:, None]
        tau = retarded_times(centroids, omega_rad_s, observer, time_s, c)
        angle = omega_rad_s * tau
        yx, yy, yz = _rotate(centroids, angle)
        nx, ny, nz = _rotate(normals, angle)
        vx, vy = -omega_rad_s * yy, omega_rad_s * yx  # v = omega z x y
        ax, ay = -omega_rad_s * vy, omega_rad_s * vx  # dv/dtau = omega z x v
        ndx, ndy = -omega_rad_s * ny, omega_rad_s * nx  # dn/dtau = omega z x n
        rx, ry, rz = observer[0] - yx, observer[1] - yy, observer[2] - yz
        r = np.sqrt(rx * rx + ry * ry + rz * rz)
        ux, uy, uz = rx / r, ry / r, rz / r
        mach_r = (vx * ux + vy * uy) / c
        mach_sq = (vx * vx + vy * vy) / (c * c)
        mach_r_dot = (ax * ux + ay * uy) / c
        doppler = 1.0 - mach_r
        # thickness: rho0 [U_n_dot / (r D^2) + U_n (r Mr_dot + c (Mr - M^2)) / (r^2 D^3)], U_n = v .
        # n
        u_n = vx * nx + vy * ny
        u_n_dot = ax * nx + ay * ny + vx * ndx + vy * ndy
        common = r * mach_r_dot + c * (mach_r - mach_sq)
        thickness_terms = rho * (u_n_dot / (r * doppler**2) + u_n * common / (r * r * doppler**3))
        # loading: L = p n, L_r = L . r_hat, L_M = L . M, L_dot = p dn/dtau (p steady in the
        # rotating frame)
        l_r = pressure * (nx * ux + ny * uy + nz * uz)
        l_r_dot = pressure * (ndx * ux + ndy * uy)
        l_m = pressure * (nx * vx + ny * vy) / c
        loading_terms = (
            l_r_dot / (c * r * doppler**2)
            + (l_r - l_m) / (r * r * doppler**2)
            + l_r * common / (c * r * r * doppler**3)
        )
        thickness += np.sum(thickness_terms * areas, axis=0)
        loading += np.sum(loading_terms * areas, axis=0)
    scale = 1.0 / (4.0 * math.pi)
    copies = surface.blade_copies
    return ObserverSignal(
        time_s, _every_blade(thickness, copies) * scale, _every_blade(loading, copies) * scale
    )


def _every_blade(signal: Array, copies: int) -> Array:
    """The rotor's signal from one blade's ``signal`` over a revolution, ``copies`` identical
    blades evenly spaced (:class:`RotatingSurface`): its blade-passing harmonics (and the mean)
    times ``copies``, the others removed."""
    if copies == 1:
        return signal
    spectrum = np.fft.rfft(signal)
    spectrum[np.arange(len(spectrum)) % copies != 0] = 0.0
    return np.fft.irfft(copies * spectrum, n=len(signal))
