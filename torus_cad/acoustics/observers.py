"""Where the noise is heard: observers at a distance from the hub and an angle from the spin axis.

The angle is measured from +z, the direction the thrust pushes the propeller (ahead of it; 90
degrees is the rotor's plane, 180 behind it), in the plane x-z (for a steady rotor the azimuth
changes only the phase).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from torus_cad.errors import ParameterError

if TYPE_CHECKING:
    import numpy as np

#: simulate --observer: an observer's distance from the hub, m (open below, closed above). It must
#: also lie outside the blade tips' circle (torus_cad.acoustics.observers.check_observers).
NOISE_OBSERVER_DISTANCE_M = (0.0, 1.0e4)


#: The option that names an observer on the command line.
OPTION = "--observer"
ANGLE_RANGE_DEG = (0.0, 180.0)


@dataclass(frozen=True)
class Observer:
    """An observer ``distance_m`` (m) from the hub at ``angle_deg`` (degrees) from the +z axis."""

    distance_m: float
    angle_deg: float

    @property
    def position_m(self) -> np.ndarray:
        """(x, y, z) in m, in the plane x-z."""
        import numpy as np  # here, not at the top: the CLI's parser reads this module's option type

        angle = math.radians(self.angle_deg)
        return np.array([self.distance_m * math.sin(angle), 0.0, self.distance_m * math.cos(angle)])

    def to_dict(self) -> dict[str, float]:
        return {"distance_m": self.distance_m, "angle_deg": self.angle_deg}


#: 1 m from the hub at 0, 30, 60 and 90 degrees from the axis.
DEFAULT_OBSERVERS = tuple(Observer(1.0, angle) for angle in (0.0, 30.0, 60.0, 90.0))


def observer_ranges() -> str:
    """The allowed form and ranges of ``--observer``, as its help and its refusal say them."""
    low, high = NOISE_OBSERVER_DISTANCE_M
    return (
        f"DIST_M:ANGLE_DEG with DIST_M in ({low:g}, {high:g}] m and ANGLE_DEG in "
        f"[{ANGLE_RANGE_DEG[0]:g}, {ANGLE_RANGE_DEG[1]:g}] degrees from the +z axis"
    )


def parse_observer(text: str) -> Observer:
    """``DIST_M:ANGLE_DEG`` (e.g. ``2:45``) as an Observer; ParameterError naming the option, the
    value and the allowed ranges (distance in ``NOISE_OBSERVER_DISTANCE_M``, angle in [0, 180]
    degrees)."""
    low, high = NOISE_OBSERVER_DISTANCE_M
    shown = text if len(text) <= 40 else text[:37] + "..."
    parts = text.split(":")
    try:
        distance, angle = (
            (float(part) for part in parts) if len(parts) == 2 else (math.nan, math.nan)
        )
    except ValueError:
        distance = angle = math.nan
    if not (
        math.isfinite(distance)
        and math.isfinite(angle)
        and low < distance <= high
        and ANGLE_RANGE_DEG[0] <= angle <= ANGLE_RANGE_DEG[1]
    ):
        raise ParameterError(
            f"{OPTION} = {shown!r} is out of range or malformed; allowed {observer_ranges()}"
        )
    return Observer(distance, angle)


class ObserverOption:
    """The argparse ``type`` of ``--observer``: :func:`parse_observer`, its refusal as argparse's
    error (exit 2).

    A value of two numbers has two ranges, so it carries them as text (``ranges``, in its help) and
    values outside them (``outside``, for the tests) instead of the one-number options'
    ``bounds``."""

    __name__ = "observer"
    ranges = observer_ranges()
    outside = ("0:45", "1:181", "1:-1", "20000:0", "nan:0", "1e999:30", "1:2:3", "x" * 100_000)

    def __call__(self, text: str) -> Observer:
        try:
            return parse_observer(text)
        except ParameterError as error:
            raise argparse.ArgumentTypeError(str(error)) from None


observer_option = ObserverOption()


def check_observers(observers: tuple[Observer, ...], tip_radius_m: float) -> None:
    """ParameterError for an observer inside the sphere the blade tips sweep (the formula holds
    outside it)."""
    for observer in observers:
        if observer.distance_m <= tip_radius_m:
            raise ParameterError(
                f"{OPTION} = {observer.distance_m:g}:{observer.angle_deg:g} is inside the rotor; "
                f"allowed a distance above the tip radius {tip_radius_m:g} m"
            )
