"""Moving frames along the centerline (spec §4): Frenet-Serret, and a rotation-minimising opt-in.

The section plane is spanned by N (the section's X) and B (its Y); T is normal to it.
The Frenet normal N = T'/|T'| is undefined where the curvature vanishes and flips at an
inflection, so :func:`frenet_frames` checks the whole curve and raises a GeometryError
naming the s where that happens. :func:`rotation_minimizing_frames` (double reflection,
Wang et al. 2008) is defined on any regular curve; it is beyond the spec and opt-in.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.errors import GeometryError
from torus_cad.geometry.blade.centerline import Centerline

#: Samples on s in [0, 1] used to scan the centerline for vanishing curvature, flips of N,
#: and to step the rotation-minimising frame.
FRAME_SCAN_SAMPLES = 401

#: Curvature |T'(s)| / |C'(s)| below which the Frenet normal counts as undefined (1/mm).
FRENET_MIN_CURVATURE = 1e-6


class FrameKind(StrEnum):
    """The moving frame the sections sit on."""

    FRENET = "frenet"
    """Frenet-Serret (spec §4); undefined where the curvature vanishes."""
    ROTATION_MINIMIZING = "rotation_minimizing"
    """Double-reflection rotation-minimising frame (beyond the spec);
    defined on any regular curve."""


@dataclass(frozen=True)
class Frames:
    """Orthonormal frames at parameters s.

    Attributes:
        s: ``(k,)`` curve parameters in [0, 1].
        origin: ``(k, 3)`` mm, C(s).
        tangent: ``(k, 3)`` unit T.
        normal: ``(k, 3)`` unit N, the section's X direction.
        binormal: ``(k, 3)`` unit B = T x N, the section's Y direction.
    """

    s: NDArray[np.float64]
    origin: NDArray[np.float64]
    tangent: NDArray[np.float64]
    normal: NDArray[np.float64]
    binormal: NDArray[np.float64]

    def take(self, rows: NDArray[np.int64]) -> Frames:
        """The frames at the given row indices.

        Args:
            rows: ``(m,)`` int array of indices into the k frames.

        Returns:
            The m frames at those rows (``s`` ``(m,)``, the vectors ``(m, 3)``).
        """
        return Frames(
            self.s[rows],
            self.origin[rows],
            self.tangent[rows],
            self.normal[rows],
            self.binormal[rows],
        )


def _unit(vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def curvature(first: NDArray[np.float64], second: NDArray[np.float64]) -> NDArray[np.float64]:
    """kappa = |C' x C''| / |C'|^3 (1/mm) from ``(k, 3)`` derivatives.

    Args:
        first: ``(k, 3)`` float array, C'(s), mm per unit s.
        second: ``(k, 3)`` float array, C''(s), mm per unit s squared.

    Returns:
        ``(k,)`` float array, the curvature, 1/mm.
    """
    return np.linalg.norm(np.cross(first, second), axis=-1) / np.linalg.norm(first, axis=-1) ** 3


def frenet_from_derivatives(
    first: NDArray[np.float64], second: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Unit T, N, B ``(k, 3)`` from C' and C'' ``(k, 3)`` (spec §4.1).

    Args:
        first: ``(k, 3)`` float array, C'(s), mm per unit s.
        second: ``(k, 3)`` float array, C''(s), mm per unit s squared.

    Returns:
        The unit tangent T, normal N and binormal B = T x N, each a ``(k, 3)`` float array (NaN
        where C'' is parallel to C').
    """
    tangent = _unit(first)
    # T' is parallel to the part of C'' normal to T; B = T x N.
    along = np.sum(second * tangent, axis=-1, keepdims=True)
    normal = _unit(second - along * tangent)
    return tangent, normal, np.cross(tangent, normal)


def check_frenet_defined(centerline: Centerline, samples: int = FRAME_SCAN_SAMPLES) -> None:
    """Raise GeometryError if the curvature vanishes or N flips anywhere on s in [0, 1].

    Args:
        centerline: the blade's centerline, mm.
        samples: number of equally spaced s in [0, 1] scanned.

    Raises:
        GeometryError: the centerline stops (C'(s) = 0), its curvature is below
            FRENET_MIN_CURVATURE (1/mm), or its Frenet normal flips at an inflection; the
            message names the s.
    """
    s = np.linspace(0.0, 1.0, samples)
    derivatives = centerline.derivatives(s, order=2)
    if np.any(np.linalg.norm(derivatives[:, 1], axis=-1) < 1e-9):
        where = s[np.argmin(np.linalg.norm(derivatives[:, 1], axis=-1))]
        raise GeometryError(
            f"the centerline stops (C'(s) = 0) near s = {where:.3f}; move its control points apart"
        )
    kappa = curvature(derivatives[:, 1], derivatives[:, 2])
    weakest = int(np.argmin(kappa))
    if kappa[weakest] < FRENET_MIN_CURVATURE:
        raise GeometryError(
            "the Frenet frame is undefined: the centerline's "
            f"curvature vanishes near s = {s[weakest]:.3f} "
            f"(kappa = {kappa[weakest]:.2e} 1/mm); bend the centerline or set centerline.frame = "
            "'rotation_minimizing'"
        )
    _, normal, _ = frenet_from_derivatives(derivatives[:, 1], derivatives[:, 2])
    flips = np.nonzero(np.sum(normal[:-1] * normal[1:], axis=-1) < 0.0)[0]
    if flips.size:
        where = 0.5 * (s[flips[0]] + s[flips[0] + 1])
        raise GeometryError(
            f"the Frenet normal flips at an inflection of the centerline near s = {where:.3f}; "
            "change the control points or set centerline.frame = 'rotation_minimizing'"
        )


def frenet_frames(centerline: Centerline, s: ArrayLike) -> Frames:
    """Frenet-Serret frames at ``s`` (spec §4.1), after checking they exist on the whole curve.

    Args:
        centerline: the blade's centerline, mm.
        s: ``(k,)`` float array (or a scalar) of curve parameters in [0, 1].

    Returns:
        The k frames: origins C(s) ``(k, 3)`` mm and unit T, N, B ``(k, 3)``.

    Raises:
        GeometryError: the Frenet frame is undefined somewhere on the curve
            (:func:`check_frenet_defined`).
    """
    check_frenet_defined(centerline)
    s = np.atleast_1d(np.asarray(s, dtype=float))
    derivatives = centerline.derivatives(s, order=2)
    tangent, normal, binormal = frenet_from_derivatives(derivatives[:, 1], derivatives[:, 2])
    return Frames(s, derivatives[:, 0], tangent, normal, binormal)


def rotation_minimizing_frames(
    centerline: Centerline, s: ArrayLike, substeps: int = FRAME_SCAN_SAMPLES
) -> Frames:
    """Rotation-minimising frames at ``s`` by double reflection (beyond the spec).

    The first frame equals the Frenet frame at s = 0 where that exists (so a curve with
    curvature everywhere starts like the spec), otherwise any normal perpendicular to T.
    The reflection is stepped on a grid of at least ``substeps`` points that contains ``s``.

    Args:
        centerline: the blade's centerline, mm.
        s: ``(k,)`` float array (or a scalar) of curve parameters in [0, 1], non-decreasing.
        substeps: number of equally spaced s in [0, 1] the reflection steps through,
            besides ``s``.

    Returns:
        The k frames: origins C(s) ``(k, 3)`` mm and unit T, N, B ``(k, 3)``.

    Raises:
        ValueError: ``s`` decreases somewhere.
    """
    s = np.atleast_1d(np.asarray(s, dtype=float))
    if np.any(np.diff(s) < 0):
        raise ValueError("s must be increasing")
    dense = np.linspace(0.0, 1.0, substeps)
    # Drop dense points that nearly coincide with a requested s: a near-zero step breaks the
    # reflection.
    distance = np.abs(dense[:, None] - s[None, :]).min(axis=1)
    grid = np.union1d(dense[distance > 1e-9], s)
    derivatives = centerline.derivatives(grid, order=2)
    points, tangents = derivatives[:, 0], _unit(derivatives[:, 1])
    normal = _initial_normal(tangents[0], derivatives[0, 2])
    normals = np.empty_like(tangents)
    normals[0] = normal
    for i in range(len(grid) - 1):
        step = points[i + 1] - points[i]
        reflected_normal = normals[i] - 2 * np.dot(step, normals[i]) / np.dot(step, step) * step
        reflected_tangent = tangents[i] - 2 * np.dot(step, tangents[i]) / np.dot(step, step) * step
        second_axis = tangents[i + 1] - reflected_tangent
        norm2 = np.dot(second_axis, second_axis)
        if norm2 > 0.0:
            reflected_normal = (
                reflected_normal - 2 * np.dot(second_axis, reflected_normal) / norm2 * second_axis
            )
        # Re-orthonormalise against drift.
        reflected_normal -= np.dot(reflected_normal, tangents[i + 1]) * tangents[i + 1]
        normals[i + 1] = reflected_normal / np.linalg.norm(reflected_normal)
    pick = np.searchsorted(grid, s)
    tangent, normal = tangents[pick], normals[pick]
    return Frames(s, points[pick], tangent, normal, np.cross(tangent, normal))


def _initial_normal(
    tangent: NDArray[np.float64], second: NDArray[np.float64]
) -> NDArray[np.float64]:
    candidate = second - np.dot(second, tangent) * tangent
    if np.linalg.norm(candidate) < 1e-9 * max(1.0, float(np.linalg.norm(second))):
        helper = np.eye(3)[int(np.argmin(np.abs(tangent)))]
        candidate = helper - np.dot(helper, tangent) * tangent
    return candidate / np.linalg.norm(candidate)


def section_frames(centerline: Centerline, s: ArrayLike, frame: FrameKind) -> Frames:
    """Frames of the given kind at ``s``.

    Args:
        centerline: the blade's centerline, mm.
        s: ``(k,)`` float array (or a scalar) of curve parameters in [0, 1] (non-decreasing for
            the rotation-minimising frame).
        frame: Frenet-Serret (the spec's) or rotation-minimising.

    Returns:
        The k frames: origins C(s) ``(k, 3)`` mm and unit T, N, B ``(k, 3)``.

    Raises:
        GeometryError: a Frenet frame is undefined somewhere on the curve.
        ValueError: ``s`` decreases somewhere (rotation-minimising frame).
    """
    if frame is FrameKind.FRENET:
        return frenet_frames(centerline, s)
    return rotation_minimizing_frames(centerline, s)
