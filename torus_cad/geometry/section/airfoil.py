"""NACA sections (spec §1): 4-digit (the spec's), and the 5-digit 230-series kind; closed f(t).

All lengths are fractions of the chord; ``t`` is the chord position in [0, 1] for the
camber line and thickness, and the closed-curve parameter in [0, 2] for :func:`airfoil_points`
(upper surface leading edge -> trailing edge on [0, 1], lower surface trailing edge -> leading
edge on [1, 2], spec §1.3; see :mod:`torus_cad.geometry.section.section` for sections with a blunt
trailing edge). Both kinds implement :class:`torus_cad.geometry.section.section.Section`.

Blunt trailing edge: ``trailing_edge_gap`` g (chord units) changes the
thickness law to y_t(t) + (g / 2) t^4, i.e. the last coefficient of the NACA thickness
polynomial -0.1036 becomes -0.1036 + g / (10 thickness). This is the classical "open
trailing edge" variant of the four-digit thickness (-0.1015 gives g = 0.0021 x 10 thickness):
y_t is unchanged at the leading edge with its derivatives up to the third, and changes by
g / 2 t^4 elsewhere (the half-thickness by 0.004 g at 30 % of the chord, by g / 2 at the trailing
edge), so the section keeps its shape and gets a base of thickness g, normal to the camber line at
the trailing edge (along y when camber_normal is False).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from torus_cad.errors import ParameterError, shown

if TYPE_CHECKING:
    from torus_cad.geometry.section.section import Section

#: Coefficients of the NACA thickness polynomial (spec §1.1): sqrt(t), t, t^2, t^3, t^4.
THICKNESS_COEFFICIENTS = (0.2969, -0.1260, -0.3516, 0.2843, -0.1036)


class _ThicknessOnCamberLine:
    """The NACA construction (spec §1.2): the thickness y_t laid off the camber line y_c.

    Subclasses define ``_mean_line`` (the camber line and its derivatives) and ``kinks``, and
    the fields ``thickness``, ``camber_normal`` and ``trailing_edge_gap``.
    """

    thickness: float
    camber_normal: bool
    trailing_edge_gap: float

    def _mean_line(
        self, t: NDArray[np.float64], order: int
    ) -> NDArray[np.float64]:  # pragma: no cover - abstract
        """The ``order``-th t derivative (0, 1 or 2) of the mean camber line y_c at ``t``, shape of
        ``t``."""
        raise NotImplementedError

    def camber(self, t: ArrayLike) -> NDArray[np.float64]:
        """Mean camber line y_c(t), shape of ``t``."""
        return self._mean_line(np.asarray(t, dtype=float), 0)

    def camber_slope(self, t: ArrayLike) -> NDArray[np.float64]:
        """dy_c/dt, shape of ``t``."""
        return self._mean_line(np.asarray(t, dtype=float), 1)

    def camber_curvature(self, t: ArrayLike) -> NDArray[np.float64]:
        """d^2 y_c/dt^2, shape of ``t``."""
        return self._mean_line(np.asarray(t, dtype=float), 2)

    def half_thickness(self, t: ArrayLike) -> NDArray[np.float64]:
        """y_t(t) = 5 thickness [0.2969 sqrt(t) - 0.1260 t - ...] + g/2 t^4, shape of ``t``; zero at
        t = 0."""
        t = np.asarray(t, dtype=float)
        a0, a1, a2, a3, a4 = THICKNESS_COEFFICIENTS
        base = 5 * self.thickness * (a0 * np.sqrt(t) + t * (a1 + t * (a2 + t * (a3 + t * a4))))
        return base + 0.5 * self.trailing_edge_gap * t**4

    def with_trailing_edge_gap(self, gap: float) -> Self:
        """The same section with a base of ``gap`` (chord units) at the trailing edge (module
        docstring)."""
        # subclasses are dataclasses
        changed: Self = dataclasses.replace(cast(Any, self), trailing_edge_gap=float(gap))
        return changed

    def fold_ratio(self, samples: int = 2001) -> tuple[float, float]:
        """Largest y_t(t) * kappa_c(t) on the chord and where: ``(ratio, t)``.

        With the thickness normal to the camber line, the lower surface is an offset of the
        camber line; where the offset y_t exceeds the camber line's radius of curvature
        1 / kappa_c (ratio >= 1) that surface folds over itself (a swallowtail).
        """
        t = np.linspace(0.0, 1.0, samples)
        if not self.camber_normal or not np.any(self.camber_curvature(t)):
            return 0.0, 0.0
        kappa = np.abs(self.camber_curvature(t)) / (1 + self.camber_slope(t) ** 2) ** 1.5
        ratio = self.half_thickness(t) * kappa
        worst = int(np.argmax(ratio))
        return float(ratio[worst]), float(t[worst])

    def surfaces(
        self, chord_position: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Upper and lower surface points at chord positions ``t``, each ``(len(t), 2)`` (spec
        §1.2)."""
        t = np.asarray(chord_position, dtype=float)
        y_c = self.camber(t)
        y_t = self.half_thickness(t)
        theta = np.arctan(self.camber_slope(t)) if self.camber_normal else np.zeros_like(t)
        offset = np.stack([-y_t * np.sin(theta), y_t * np.cos(theta)], axis=-1)
        camber_point = np.stack([t, y_c], axis=-1)
        return camber_point + offset, camber_point - offset

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """Surface points at chord t = u^2 for u in [0, 1], shape ``(len(u), 2)``.

        The substitution t = u^2 removes the sqrt(t) singularity of the thickness at the
        leading edge, so a curve in u has a bounded derivative everywhere.
        """
        u = np.asarray(root_chord, dtype=float)
        upper_points, lower_points = self.surfaces(u * u)
        return upper_points if upper else lower_points

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """|d f / du| for the surface point at t = u^2, shape of ``u`` (finite at u = 0)."""
        u = np.asarray(root_chord, dtype=float)
        t = u * u
        a0, a1, a2, a3, a4 = THICKNESS_COEFFICIENTS
        # d y_t / du = 2u * d y_t / dt; the sqrt term gives 0.2969 * 5 * thickness exactly.
        dyt_du = (
            5 * self.thickness * (a0 + 2 * u * (a1 + t * (2 * a2 + t * (3 * a3 + t * 4 * a4))))
            + 4.0 * self.trailing_edge_gap * u**7
        )
        slope = self.camber_slope(t)
        dyc_du = 2 * u * slope
        y_t = self.half_thickness(t)
        sign = 1.0 if upper else -1.0
        if self.camber_normal:
            theta = np.arctan(slope)
            dtheta_du = 2 * u * self.camber_curvature(t) / (1 + slope**2)
            dx = 2 * u - sign * (dyt_du * np.sin(theta) + y_t * np.cos(theta) * dtheta_du)
            dy = dyc_du + sign * (dyt_du * np.cos(theta) - y_t * np.sin(theta) * dtheta_du)
        else:
            dx = 2 * u
            dy = dyc_du + sign * dyt_du
        return np.hypot(dx, dy)


@dataclass(frozen=True)
class NacaAirfoil(_ThicknessOnCamberLine):
    """A NACA 4-digit section (spec §1).

    Attributes:
        max_camber: m, fraction of chord, >= 0.
        camber_position: p, fraction of chord in (0, 1) (ignored when m = 0).
        thickness: maximum thickness, fraction of chord.
        camber_normal: apply thickness normal to the camber line (True) or along y (theta_c = 0).
        trailing_edge_gap: thickness of a blunt trailing edge, fraction of chord (0 = the spec's
            sharp edge).
    """

    max_camber: float = 0.02
    camber_position: float = 0.4
    thickness: float = 0.5
    camber_normal: bool = True
    trailing_edge_gap: float = 0.0

    @classmethod
    def from_designation(cls, designation: str, camber_normal: bool = True) -> NacaAirfoil:
        """The section of a 4-digit designation "MPTT": m = M/100, p = P/10, thickness = TT/100."""
        m, p, thickness = naca4_numbers(designation)
        return cls(m, p, thickness, camber_normal)

    @property
    def kinks(self) -> tuple[float, ...]:
        """u = sqrt(p): the camber line's curvature jumps at p."""
        if self.max_camber > 0.0 and 0.0 < self.camber_position < 1.0:
            return (float(np.sqrt(self.camber_position)),)
        return ()

    def _mean_line(self, t: NDArray[np.float64], order: int) -> NDArray[np.float64]:
        """Two parabolas meeting at p with zero slope: m/p^2 (2pt - t^2) before, m/(1-p)^2 ((1-2p) +
        2pt - t^2) after; the curvature is piecewise constant."""
        m, p = self.max_camber, self.camber_position
        if m == 0.0:
            return np.zeros_like(t)
        front = [2 * p * t - t**2, 2 * (p - t), np.full_like(t, -2.0)][order]
        back = [(1 - 2 * p) + 2 * p * t - t**2, 2 * (p - t), np.full_like(t, -2.0)][order]
        return np.where(t <= p, m / p**2 * front, m / (1 - p) ** 2 * back)


#: Standard NACA 5-digit mean lines for a design lift coefficient of 0.3, by the P digit:
#: (r, k1) for Q = 0 and (r, k1, k2/k1) for the reflexed Q = 1 (Abbott & von Doenhoff,
#: "Theory of Wing Sections", 1959, §6.5; NASA TM X-3284).
NACA5_STANDARD = {
    1: (0.0580, 361.40),
    2: (0.1260, 51.640),
    3: (0.2025, 15.957),
    4: (0.2900, 6.643),
    5: (0.3910, 3.230),
}
NACA5_REFLEXED = {
    2: (0.1300, 51.990, 0.000764),
    3: (0.2170, 15.793, 0.00677),
    4: (0.3180, 6.520, 0.0303),
    5: (0.4410, 3.191, 0.1355),
}


@dataclass(frozen=True)
class Naca5Airfoil(_ThicknessOnCamberLine):
    """A NACA 5-digit section "LPQTT": the 4-digit thickness on the 5-digit mean line.

    Mean line (x = chord position, r and k1 from :data:`NACA5_STANDARD`, scaled by the
    design lift coefficient 0.15 L / 0.3): y_c = k1/6 (x^3 - 3 r x^2 + r^2 (3 - r) x) for
    x < r, k1 r^3 / 6 (1 - x) beyond; reflexed (Q = 1) lines add the k2/k1 terms.

    Attributes:
        r: end of the cubic part of the mean line (chord fraction).
        k1: the mean line's scale factor.
        k2_over_k1: reflex factor (0 = the standard, unreflexed line).
        thickness, camber_normal, trailing_edge_gap: as :class:`NacaAirfoil`.
    """

    r: float = 0.2025
    k1: float = 15.957
    k2_over_k1: float = 0.0
    thickness: float = 0.12
    camber_normal: bool = True
    trailing_edge_gap: float = 0.0

    @classmethod
    def from_designation(cls, designation: str, camber_normal: bool = True) -> Naca5Airfoil:
        """The section of a 5-digit designation such as "23012" (L = 2, P = 3, Q = 0, TT = 12)."""
        digits = _digits(designation, 5)
        lift, position, reflex, thickness = (
            digits[0],
            digits[1],
            digits[2],
            int(designation.strip()[-2:]),
        )
        table = NACA5_REFLEXED if reflex else NACA5_STANDARD
        if reflex > 1 or position not in table or lift == 0 or thickness == 0:
            raise ParameterError(
                f"airfoil.naca = {designation!r} is not a known 5-digit section; allowed: L 1-9, P "
                f"{min(table)}-{max(table)} ({'reflexed' if reflex else 'standard'}"
                " mean line), Q 0 or 1, TT 01-99"
            )
        r, k1, *ratio = table[position]
        return cls(
            r,
            k1 * (0.15 * lift) / 0.3,
            ratio[0] if ratio else 0.0,
            thickness / 100.0,
            camber_normal,
        )

    @property
    def kinks(self) -> tuple[float, ...]:
        """u = sqrt(r): the mean line's third derivative jumps there (its curvature is
        continuous)."""
        return (float(np.sqrt(self.r)),)

    def _mean_line(self, t: NDArray[np.float64], order: int) -> NDArray[np.float64]:
        """The cubic (then linear) mean line of the class docstring."""
        r, k1, ratio = self.r, self.k1, self.k2_over_k1
        if ratio == 0.0:
            front = [
                (t**3 - 3 * r * t**2 + r**2 * (3 - r) * t),
                (3 * t**2 - 6 * r * t + r**2 * (3 - r)),
                (6 * t - 6 * r),
            ][order]
            back = [r**3 * (1 - t), -(r**3) * np.ones_like(t), np.zeros_like(t)][order]
            return k1 / 6 * np.where(t < r, front, back)
        linear = ratio * (1 - r) ** 3 + r**3
        front = [(t - r) ** 3 - linear * t + r**3, 3 * (t - r) ** 2 - linear, 6 * (t - r)][order]
        back = [
            ratio * (t - r) ** 3 - linear * t + r**3,
            3 * ratio * (t - r) ** 2 - linear,
            6 * ratio * (t - r),
        ][order]
        return k1 / 6 * np.where(t < r, front, back)


def _digits(designation: str, count: int) -> list[int]:
    text = designation.strip() if isinstance(designation, str) else ""
    if not re.fullmatch(rf"\d{{{count}}}", text):
        raise ParameterError(f"airfoil.naca = {shown(designation)} must be {count} digits")
    return [int(character) for character in text]


def naca4_numbers(designation: str) -> tuple[float, float, float]:
    """(m, p, thickness) of a 4-digit designation "MPTT"; ParameterError if it is not one."""
    digits = _digits(designation, 4)
    m, p, thickness = digits[0] / 100.0, digits[1] / 10.0, int(designation.strip()[2:]) / 100.0
    if thickness == 0.0:
        raise ParameterError(f"airfoil.naca = {designation!r} has zero thickness; TT must be 01-99")
    if (m == 0.0) != (p == 0.0):
        raise ParameterError(
            f"airfoil.naca = {designation!r}: M and P must both be 0 (symmetric) or both non-zero"
        )
    return m, p, thickness


def naca_section(designation: str, camber_normal: bool = True) -> NacaAirfoil | Naca5Airfoil:
    """The section of a 4- or 5-digit NACA designation ("2412", "0012", "23012")."""
    text = designation.strip() if isinstance(designation, str) else ""
    if len(text) == 5:
        return Naca5Airfoil.from_designation(text, camber_normal)
    if len(text) == 4:
        return NacaAirfoil.from_designation(text, camber_normal)
    raise ParameterError(
        f'airfoil.naca = {shown(designation)} must be a 4-digit (e.g. "2412") or '
        '5-digit (e.g. "23012") NACA designation'
    )


def airfoil_points(airfoil: Section, t: ArrayLike) -> NDArray[np.float64]:
    """The closed section f(t) of spec §1.3 for t in [0, 2], shape ``(len(t), 2)``.

    t in [0, 1]: upper surface at chord t (leading edge -> trailing edge);
    t in (1, 2]: lower surface at chord 2 - t (trailing edge -> leading edge).
    Any :class:`~torus_cad.geometry.section.section.Section` works (a blunt one with the extended
    parameter of :func:`torus_cad.geometry.section.section.closed_points`).

    Args:
        airfoil: the section, in chord units.
        t: ``(n,)`` float array of closed-curve parameters, in [0, 2] (in [0, 3] for a blunt
            section).

    Returns:
        ``(n, 2)`` float array, chord units: x along the chord from the leading edge, y normal
        to it.
    """
    from torus_cad.geometry.section.section import closed_points

    return closed_points(airfoil, t)
