"""Section polars at each strip's own Reynolds number, from NeuralFoil (a neural network trained on
XFOIL, pure numpy: it takes any coordinates and says how confident it is).

A strip's polar is the mean of its two sections' (each section's shape in its own plane, chord 1).
Where a strip's flow meets the trailing edge first (a toroidal loop's return leg), its sections are
turned round: the polar is that of the shape met from its trailing edge.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

#: Angles of attack (deg) at which each polar is tabulated.
ALPHA_DEG = np.linspace(-12.0, 20.0, 65)
#: NeuralFoil's network size ("large" is its most accurate, a few ms a polar).
MODEL_SIZE = "large"
#: The window above the zero-lift angle (deg) over which a polar's lift slope is fitted (its linear
#: range).
LINEAR_RANGE_DEG = 6.0
#: Below this confidence (NeuralFoil's analysis_confidence, 0 to 1) a strip's polar is flagged.
LOW_CONFIDENCE = 0.5


@dataclass(frozen=True)
class Polar:
    """One strip's polar at its Reynolds number.

    Attributes:
        alpha_deg: ``(A,)`` angles of attack; cl, cd, confidence: ``(A,)`` each.
    """

    alpha_deg: NDArray[np.float64]
    cl: NDArray[np.float64]
    cd: NDArray[np.float64]
    confidence: NDArray[np.float64]

    @property
    def zero_lift_deg(self) -> float:
        """The angle of zero lift (the first upward crossing of cl = 0 on the table)."""
        rising = np.flatnonzero((self.cl[:-1] <= 0.0) & (self.cl[1:] > 0.0))
        if not len(rising):
            return float(self.alpha_deg[np.argmin(np.abs(self.cl))])
        i = int(rising[0])
        return float(np.interp(0.0, self.cl[i : i + 2], self.alpha_deg[i : i + 2]))

    @property
    def stall_deg(self) -> float:
        """The angle of the polar's largest lift on the table."""
        return float(self.alpha_deg[int(np.argmax(self.cl))])

    @property
    def lift_slope_per_deg(self) -> float:
        """The slope of cl over the linear range (LINEAR_RANGE_DEG above the zero-lift angle), least
        squares through the zero-lift angle; at least a tenth of thin-airfoil theory's 2 pi per
        radian."""
        zero = self.zero_lift_deg
        window = (self.alpha_deg >= zero) & (self.alpha_deg <= zero + LINEAR_RANGE_DEG)
        offset = self.alpha_deg[window] - zero
        slope = (
            float(offset @ self.cl[window] / max(float(offset @ offset), 1e-300))
            if window.any()
            else 0.0
        )
        return max(slope, 0.1 * 2.0 * np.pi * np.pi / 180.0)


def turned_round(coordinates: NDArray[np.float64]) -> NDArray[np.float64]:
    """``coordinates`` (Selig order, chord 0..1) of the same shape met from its trailing edge."""
    nose = int(np.argmin(coordinates[:, 0]))
    upper, lower = coordinates[: nose + 1], coordinates[nose:]
    turned = np.concatenate([upper[::-1], lower[::-1][1:]])  # each side run the other way
    turned[:, 0] = 1.0 - turned[:, 0]
    return turned


def strip_polars(
    sections: tuple[NDArray[np.float64], ...],
    reynolds: NDArray[np.float64],
    turned: NDArray[np.bool_],
) -> list[Polar]:
    """The polar of each strip ``j`` (between sections ``j`` and ``j + 1``) at ``reynolds[j]``."""
    import neuralfoil

    polars = []
    for j, re in enumerate(reynolds.tolist()):
        tables = []
        for shape in (sections[j], sections[j + 1]):
            coordinates = turned_round(shape) if turned[j] else shape
            aero = neuralfoil.get_aero_from_coordinates(
                coordinates,
                alpha=ALPHA_DEG,
                Re=np.full(len(ALPHA_DEG), max(re, 1e3)),
                model_size=MODEL_SIZE,
            )
            tables.append(
                (
                    np.asarray(aero["CL"]),
                    np.asarray(aero["CD"]),
                    np.asarray(aero["analysis_confidence"]),
                )
            )
        cl, cd, confidence = (0.5 * (tables[0][k] + tables[1][k]) for k in range(3))
        polars.append(Polar(ALPHA_DEG, cl, cd, confidence))
    return polars
