"""Blunt trailing edge of an absolute thickness in mm on every section.

Each section kind changes its own thickness law smoothly to open its trailing edge by a
gap g in chord units (``Section.with_trailing_edge_gap``; NACA: y_t + (g / 2) t^4, see
:mod:`torus_cad.geometry.section.airfoil`). The section then ends in a *base* between the ends of
its upper and lower surface, and stays closed (:mod:`torus_cad.geometry.section.section`). The base
has one of two shapes (``airfoil.trailing_edge_shape``):

* ``flat``: a straight base between two corners;
* ``round`` (the default): a round cap, the cubic Bezier curve that leaves each surface along its
  own tangent (:class:`~torus_cad.geometry.section.section.RoundTrailingEdge`), so the section is
  one smooth (G1) closed curve and the blade has no sharp trailing-edge edge. Its handles are 2/3 of
  the thickness *in mm* long (:func:`round_cap_handles`): after the section transform the cap is
  the cubic near-half-circle of that diameter (within 1.8 % of its radius; exactly tangent to
  both surfaces, and a little flatter than a half circle where the surfaces converge).

In both shapes the trailing-edge thickness is the distance between the surfaces' ends, where
the base begins: the base's length when flat, the cap's width where it meets the surfaces when
round (measured on the solid as the chord of the cap's cut in a
section plane, ``tests/test_round_trailing_edge.py``). A coordinate file whose published
trailing edge is open has a base of its own gap; with ``round`` it is capped the same way.
A base thinner than MIN_BLUNT_TRAILING_EDGE_MM on some section cannot be tessellated without
crossing triangles (its faces' chords pass through each other), so such a file's edge is closed
to the spec's sharp one (:func:`closed_if_too_thin`) and the build says so.

The sections are rotated by alpha(s), then scaled by Sx(s) along X and Sy(s) along Y (spec
§2.3), so a chord-unit gap vector d becomes S(s) R(s) d in mm: a constant thickness in mm
needs a gap in chord units that changes with s. :func:`trailing_edge_gaps` solves
|S(s) R(s) d(g)| = thickness for g at every s, where d(g), the upper trailing-edge point
minus the lower one, is affine in g for every section kind (NACA: g times the camber line's
unit normal at the trailing edge).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.transforms import SectionLaws, evaluate_quartic, rotation_matrices
from torus_cad.geometry.section.airfoil_file import AirfoilFile
from torus_cad.geometry.section.section import (
    ROUND_CAP_HANDLE_FRACTION,
    RoundTrailingEdge,
    Section,
    bezier_points,
    closed_points,
    end_derivatives,
    half_ends,
    has_base,
    round_cap_poles,
    trailing_edge_vector,
)
from torus_cad.tolerances import MIN_BLUNT_TRAILING_EDGE_MM


def section_matrices(
    angle_deg: ArrayLike, scale_x: ArrayLike, scale_y: ArrayLike
) -> NDArray[np.float64]:
    """S(s) R(s) of spec §2.3 for every s: ``(k, 2, 2)``, chord units -> mm in the section plane."""
    scales = np.stack([np.asarray(scale_x, float), np.asarray(scale_y, float)], axis=-1)
    return scales[:, :, None] * rotation_matrices(np.asarray(angle_deg, float))


def trailing_edge_gaps(
    section: Section,
    thickness_mm: float,
    angle_deg: ArrayLike,
    scale_x: ArrayLike,
    scale_y: ArrayLike,
) -> NDArray[np.float64]:
    """The chord-unit gap g(s) that makes the base ``thickness_mm`` long at every s: ``(k,)``.

    The base vector is d(g) = d0 + g e (d0 at g = 0, e its change per unit gap);
    |M (d0 + g e)| = thickness is a quadratic in g, and the larger root is the one that keeps
    the upper surface above the lower one.
    """
    matrices = section_matrices(angle_deg, scale_x, scale_y)
    start, unit = (trailing_edge_vector(opened) for opened in _opened_by_0_and_1(section))
    change = unit - start
    mapped_start, mapped_change = matrices @ start, matrices @ change
    a = np.sum(mapped_change**2, axis=-1)
    b = 2.0 * np.sum(mapped_start * mapped_change, axis=-1)
    c = np.sum(mapped_start**2, axis=-1) - thickness_mm**2
    discriminant = b * b - 4.0 * a * c
    if np.any(discriminant < 0.0):  # only when the file's own offset already exceeds the thickness
        raise ParameterError(
            f"airfoil.trailing_edge_thickness = {thickness_mm:g} mm is thinner than this airfoil's "
            "trailing edge offset along the chord; use a larger value"
        )
    return (-b + np.sqrt(discriminant)) / (2.0 * a)


def _opened_by_0_and_1(section: Section) -> tuple[Section, Section]:
    """``section`` opened by the gaps 0 and 1: every gap's section is affine between the two."""
    return section.with_trailing_edge_gap(0.0), section.with_trailing_edge_gap(1.0)


def own_gap(section: Section) -> float:
    """The gap g (chord units) with ``section.with_trailing_edge_gap(g)`` the section itself
    (a coordinate file's published gap); exact, the trailing-edge vector being affine in g."""
    start, unit = (trailing_edge_vector(opened) for opened in _opened_by_0_and_1(section))
    change = unit - start
    return float((trailing_edge_vector(section) - start) @ change / (change @ change))


def round_cap_handles(
    ends: NDArray[np.float64], derivatives: NDArray[np.float64], matrices: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Handle lengths h_u, h_l (chord units) of round caps that are near half circles in mm: ``(k,
    2)``.

    Args:
        ends: ``(k, 2, 2)`` the surfaces' ends U, L of each section, chord units.
        derivatives: ``(k, 2, 2)`` the surfaces' end derivatives there (any length, pointing aft).
        matrices: ``(k, 2, 2)`` S(s) R(s), chord units -> mm.

    Each handle, mapped to mm, is ROUND_CAP_HANDLE_FRACTION x the mapped |U - L| long.
    """
    tangents = derivatives / np.linalg.norm(derivatives, axis=-1, keepdims=True)
    thickness_mm = np.linalg.norm(
        np.einsum("kij,kj->ki", matrices, ends[:, 0] - ends[:, 1]), axis=-1
    )
    mapped_tangent_mm = np.linalg.norm(np.einsum("kij,ksj->ksi", matrices, tangents), axis=-1)
    return ROUND_CAP_HANDLE_FRACTION * thickness_mm[:, None] / mapped_tangent_mm


@lru_cache(maxsize=16)
def _family_ends(
    section: Section,
) -> tuple[
    tuple[NDArray[np.float64], NDArray[np.float64]], tuple[NDArray[np.float64], NDArray[np.float64]]
]:
    """:func:`half_ends` and :func:`end_derivatives` of ``section`` opened by 0 and by 1, remembered
    (every call of :func:`torus_cad.geometry.blade.blade_surface.sections_along` makes a new
    family)."""
    family = _opened_by_0_and_1(section)
    return (
        (half_ends(family[0]), half_ends(family[1])),
        (end_derivatives(family[0]), end_derivatives(family[1])),
    )


class BluntSections(Sequence[Section]):
    """The sections of a blade with a blunt trailing edge: ``section`` opened by ``gaps[i]`` at the
    i-th s, flat, or, given the section matrices S(s) R(s) ``(k, 2, 2)`` as ``round_cap_matrices``,
    with a round cap whose handles (:attr:`handles`) are made in mm by :func:`round_cap_handles`.

    Every section kind opens its trailing edge affinely in the gap (the thickness law changes by
    g times a fixed shape), so the whole family is evaluated from two sections: see
    :meth:`points_at`.
    """

    def __init__(
        self,
        section: Section,
        gaps: NDArray[np.float64],
        round_cap_matrices: NDArray[np.float64] | None = None,
    ) -> None:
        self.section = section
        self.gaps = np.asarray(gaps, dtype=float)
        self.round_cap_matrices = round_cap_matrices
        self._handles: NDArray[np.float64] | None = None

    @property
    def handles(self) -> NDArray[np.float64] | None:
        """The round caps' handle lengths h_u, h_l, chord units: ``(k, 2)``; None when flat. Made
        when first asked for (the surfaces alone, e.g. for the printability report, do not need
        them)."""
        if self.round_cap_matrices is None:
            return None
        if self._handles is None:
            self._handles = round_cap_handles(
                self.ends(), self.end_derivatives(), self.round_cap_matrices
            )
        return self._handles

    def ends(self) -> NDArray[np.float64]:
        """The surfaces' ends U, L of every section: ``(k, 2, 2)`` chord units."""
        start, unit = _family_ends(self.section)[0]
        return start[None] + self.gaps[:, None, None] * (unit - start)[None]

    def end_derivatives(self) -> NDArray[np.float64]:
        """The surfaces' end derivatives d f / du of every section: ``(k, 2, 2)`` (affine in the gap
        too)."""
        start, unit = _family_ends(self.section)[1]
        return start[None] + self.gaps[:, None, None] * (unit - start)[None]

    def cap_poles(self) -> NDArray[np.float64]:
        """Every section's round-cap poles (:meth:`RoundTrailingEdge.cap_poles`): ``(k, 4, 2)``."""
        lengths = self.handles
        if lengths is None:
            raise ValueError("these sections have a flat trailing edge")
        derivatives = self.end_derivatives()
        return round_cap_poles(
            self.ends(), derivatives / np.linalg.norm(derivatives, axis=-1, keepdims=True), lengths
        )

    def __len__(self) -> int:
        return len(self.gaps)

    @overload
    def __getitem__(self, index: int) -> Section: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[Section]: ...

    def __getitem__(self, index: int | slice) -> Section | Sequence[Section]:
        if isinstance(index, slice):
            matrices = self.round_cap_matrices
            return BluntSections(
                self.section, self.gaps[index], None if matrices is None else matrices[index]
            )
        opened = self.section.with_trailing_edge_gap(float(self.gaps[index]))
        lengths = self.handles
        if lengths is None:
            return opened
        return RoundTrailingEdge(opened, float(lengths[index, 0]), float(lengths[index, 1]))

    def points_at(self, t: ArrayLike) -> NDArray[np.float64]:
        """Every section at the closed parameters ``t`` (with a base): ``(len(self), len(t), 2)``
        chord units."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        start, unit = (
            closed_points(section, t, base=True) for section in _opened_by_0_and_1(self.section)
        )
        points = start[None] + self.gaps[:, None, None] * (unit - start)[None]
        on_cap = (t > 1.0) & (t < 2.0)
        # the cap is not affine in the gap
        if self.round_cap_matrices is not None and np.any(on_cap):
            points[:, on_cap] = bezier_points(self.cap_poles(), t[on_cap] - 1.0)
        return points


def blunt_sections(
    section: Section,
    thickness_mm: float | None,
    angle_deg: ArrayLike,
    scale_x: ArrayLike,
    scale_y: ArrayLike,
    round_cap: bool = False,
) -> BluntSections:
    """One section per s whose trailing edge is ``thickness_mm`` thick once transformed (spec §2.3),
    or, with None, ``section``'s own (a coordinate file's open edge); flat, or round with
    ``round_cap``."""
    count = len(np.atleast_1d(np.asarray(angle_deg, dtype=float)))
    gaps = (
        np.full(count, own_gap(section))
        if thickness_mm is None
        else trailing_edge_gaps(section, thickness_mm, angle_deg, scale_x, scale_y)
    )
    return BluntSections(
        section, gaps, section_matrices(angle_deg, scale_x, scale_y) if round_cap else None
    )


def trailing_edge_thickness_mm(
    sections: Sequence[Section], angle_deg: ArrayLike, scale_x: ArrayLike, scale_y: ArrayLike
) -> NDArray[np.float64]:
    """Length of each transformed section's base (mm): ``(k,)``; 0 for sharp sections."""
    matrices = section_matrices(angle_deg, scale_x, scale_y)
    vectors = np.array([trailing_edge_vector(section) for section in sections])
    return np.linalg.norm(np.einsum("kij,kj->ki", matrices, vectors), axis=-1)


#: A blunt trailing edge may be at most this fraction of the section's own largest thickness
#: (thicker, the t^4 term would take over the section and the base would be its thickest part).
TRAILING_EDGE_THICKNESS_LIMIT = 0.9

#: Sections along s at which the trailing edge is checked against the section's thickness.
TRAILING_EDGE_CHECK_SECTIONS = 41


def check_trailing_edge_fits(
    section: Section,
    thickness_mm: float,
    angle_deg: ArrayLike,
    scale_x: ArrayLike,
    scale_y: ArrayLike,
    s: ArrayLike,
    points: int = 200,
) -> None:
    """Refuse a blunt trailing edge thicker than TRAILING_EDGE_THICKNESS_LIMIT x a section's largest
    thickness.

    The thickness is the section's own (without the base), measured perpendicular to its chord
    in mm, at the s given (``angle_deg``, ``scale_x``, ``scale_y`` are the laws there).
    """
    if thickness_mm <= 0.0:
        return
    from torus_cad.errors import GeometryError
    from torus_cad.geometry.blade.transforms import transform_sections
    from torus_cad.geometry.section.arc_length import equal_arc_length_section
    from torus_cad.geometry.section.section import section_thickness

    sharp = section.with_trailing_edge_gap(0.0)
    sampling = equal_arc_length_section(sharp, points)
    planar = transform_sections(sampling.points, angle_deg, scale_x, scale_y)
    thickest = section_thickness(
        planar, sampling.trailing_edge_index or 0, sampling.lower_corner_index
    )
    worst = int(np.argmin(thickest))
    if thickness_mm > TRAILING_EDGE_THICKNESS_LIMIT * thickest[worst]:
        raise GeometryError(
            f"airfoil.trailing_edge_thickness = {thickness_mm:g} mm "
            "is too thick for the blade: near s = "
            f"{float(np.asarray(s, dtype=float)[worst]):.3f} the "
            f"section is only {thickest[worst]:.3g} mm thick "
            f"(limit {TRAILING_EDGE_THICKNESS_LIMIT:g} x that); "
            "make the edge thinner or the sections thicker"
        )


def closed_if_too_thin(
    section: Section, laws: SectionLaws, s: ArrayLike
) -> tuple[Section, tuple[float, float] | None]:
    """``section`` itself, or, when its own base (a coordinate file's open trailing edge) is thinner
    than MIN_BLUNT_TRAILING_EDGE_MM at one of the ``s`` given (the sections outside the hub), the
    section closed to a sharp edge and the (thinnest, thickest) base it had there, mm (module
    docstring)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    # only a file has its own
    if not isinstance(section, AirfoilFile) or not has_base(section) or not len(s):
        return section, None
    angle, scale_x, scale_y = (
        evaluate_quartic(law, s)
        for law in (laws.angle_of_attack_deg, laws.scale_x_mm, laws.scale_y_mm)
    )
    base_mm = trailing_edge_thickness_mm([section] * len(s), angle, scale_x, scale_y)
    if base_mm.min() >= MIN_BLUNT_TRAILING_EDGE_MM:
        return section, None
    return section.sharpened(), (float(base_mm.min()), float(base_mm.max()))
