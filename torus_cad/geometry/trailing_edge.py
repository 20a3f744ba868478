"""Blunt trailing edge of an absolute thickness in mm on every section (issue 13, part 3).

Each section kind changes its own thickness law smoothly to open its trailing edge by a
gap g in chord units (``Section.with_trailing_edge_gap``; NACA: y_t + (g / 2) t^4, see
:mod:`torus_cad.geometry.airfoil`). The section then ends in a straight *base* between two
corners, and stays closed (:mod:`torus_cad.geometry.section`).

The sections are rotated by alpha(s), then scaled by Sx(s) along X and Sy(s) along Y (spec
§2.3), so a chord-unit gap vector d becomes S(s) R(s) d in mm: a constant thickness in mm
needs a gap in chord units that changes with s. :func:`trailing_edge_gaps` solves
|S(s) R(s) d(g)| = thickness for g at every s, where d(g), the upper trailing-edge point
minus the lower one, is affine in g for every section kind (NACA: g times the camber line's
unit normal at the trailing edge).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.errors import ParameterError
from torus_cad.geometry.section import Section, closed_points, trailing_edge_vector
from torus_cad.geometry.transforms import rotation_matrices


def section_matrices(angle_deg: ArrayLike, scale_x: ArrayLike, scale_y: ArrayLike) -> NDArray[np.float64]:
    """S(s) R(s) of spec §2.3 for every s: ``(k, 2, 2)``, chord units -> mm in the section plane."""
    scales = np.stack([np.asarray(scale_x, float), np.asarray(scale_y, float)], axis=-1)
    return scales[:, :, None] * rotation_matrices(np.asarray(angle_deg, float))


def trailing_edge_gaps(section: Section, thickness_mm: float, angle_deg: ArrayLike, scale_x: ArrayLike,
                       scale_y: ArrayLike) -> NDArray[np.float64]:
    """The chord-unit gap g(s) that makes the base ``thickness_mm`` long at every s: ``(k,)``.

    The base vector is d(g) = d0 + g e (d0 at g = 0, e its change per unit gap);
    |M (d0 + g e)| = thickness is a quadratic in g, and the larger root is the one that keeps
    the upper surface above the lower one.
    """
    matrices = section_matrices(angle_deg, scale_x, scale_y)
    start = trailing_edge_vector(section.with_trailing_edge_gap(0.0))
    change = trailing_edge_vector(section.with_trailing_edge_gap(1.0)) - start
    mapped_start, mapped_change = matrices @ start, matrices @ change
    a = np.sum(mapped_change**2, axis=-1)
    b = 2.0 * np.sum(mapped_start * mapped_change, axis=-1)
    c = np.sum(mapped_start**2, axis=-1) - thickness_mm**2
    discriminant = b * b - 4.0 * a * c
    if np.any(discriminant < 0.0):  # only when the file's own offset already exceeds the thickness
        raise ParameterError(f"airfoil.trailing_edge_thickness = {thickness_mm:g} mm is thinner than this airfoil's "
                             "trailing edge offset along the chord; use a larger value")
    return (-b + np.sqrt(discriminant)) / (2.0 * a)


class BluntSections(Sequence[Section]):
    """The sections of a blade with a blunt trailing edge: ``section`` opened by ``gaps[i]`` at the i-th s.

    Every section kind opens its trailing edge affinely in the gap (the thickness law changes by
    g times a fixed shape), so the whole family is evaluated from two sections: see :meth:`points_at`.
    """

    def __init__(self, section: Section, gaps: NDArray[np.float64]) -> None:
        self.section = section
        self.gaps = np.asarray(gaps, dtype=float)

    def __len__(self) -> int:
        return len(self.gaps)

    @overload
    def __getitem__(self, index: int) -> Section: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[Section]: ...

    def __getitem__(self, index: int | slice) -> Section | Sequence[Section]:
        if isinstance(index, slice):
            return BluntSections(self.section, self.gaps[index])
        return self.section.with_trailing_edge_gap(float(self.gaps[index]))

    def points_at(self, t: ArrayLike) -> NDArray[np.float64]:
        """Every section at the closed parameters ``t`` (with a base): ``(len(self), len(t), 2)`` chord units."""
        closed = self.section.with_trailing_edge_gap(0.0), self.section.with_trailing_edge_gap(1.0)
        start, unit = (closed_points(section, t, base=True) for section in closed)
        return start[None] + self.gaps[:, None, None] * (unit - start)[None]


def blunt_sections(section: Section, thickness_mm: float, angle_deg: ArrayLike, scale_x: ArrayLike,
                   scale_y: ArrayLike) -> BluntSections:
    """One section per s whose base is ``thickness_mm`` long once transformed (spec §2.3)."""
    return BluntSections(section, trailing_edge_gaps(section, thickness_mm, angle_deg, scale_x, scale_y))


def trailing_edge_thickness_mm(sections: Sequence[Section], angle_deg: ArrayLike, scale_x: ArrayLike,
                               scale_y: ArrayLike) -> NDArray[np.float64]:
    """Length of each transformed section's base (mm): ``(k,)``; 0 for sharp sections."""
    matrices = section_matrices(angle_deg, scale_x, scale_y)
    vectors = np.array([trailing_edge_vector(section) for section in sections])
    return np.linalg.norm(np.einsum("kij,kj->ki", matrices, vectors), axis=-1)


#: A blunt trailing edge may be at most this fraction of the section's own largest thickness
#: (thicker, the t^4 term would take over the section and the base would be its thickest part).
TRAILING_EDGE_THICKNESS_LIMIT = 0.9

#: Sections along s at which the trailing edge is checked against the section's thickness.
TRAILING_EDGE_CHECK_SECTIONS = 41


def check_trailing_edge_fits(section: Section, thickness_mm: float, angle_deg: ArrayLike, scale_x: ArrayLike,
                             scale_y: ArrayLike, s: ArrayLike, points: int = 200) -> None:
    """Refuse a blunt trailing edge thicker than TRAILING_EDGE_THICKNESS_LIMIT x a section's largest thickness.

    The thickness is the section's own (without the base), measured perpendicular to its chord
    in mm, at the s given (``angle_deg``, ``scale_x``, ``scale_y`` are the laws there).
    """
    if thickness_mm <= 0.0:
        return
    from torus_cad.errors import GeometryError
    from torus_cad.geometry.arc_length import equal_arc_length_section
    from torus_cad.geometry.blade_elements import section_thickness
    from torus_cad.geometry.transforms import transform_sections

    sharp = section.with_trailing_edge_gap(0.0)
    sampling = equal_arc_length_section(sharp, points)
    planar = transform_sections(sampling.points, angle_deg, scale_x, scale_y)
    thickest = section_thickness(planar, sampling.trailing_edge_index or 0, sampling.lower_corner_index)
    worst = int(np.argmin(thickest))
    if thickness_mm > TRAILING_EDGE_THICKNESS_LIMIT * thickest[worst]:
        raise GeometryError(
            f"airfoil.trailing_edge_thickness = {thickness_mm:g} mm is too thick for the blade: near s = "
            f"{float(np.asarray(s, dtype=float)[worst]):.3f} the section is only {thickest[worst]:.3g} mm thick "
            f"(limit {TRAILING_EDGE_THICKNESS_LIMIT:g} x that); make the edge thinner or the sections thicker")
