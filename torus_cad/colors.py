"""Colours of the parts in assemblies, previews and the studio (RGB, 0..1)."""

from __future__ import annotations

import colorsys

#: Colour of the hub in assemblies and previews (RGB, 0..1).
HUB_COLOR: tuple[float, float, float] = (0.62, 0.64, 0.68)

_BLADE_PALETTE: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71),  # blue
    (0.95, 0.50, 0.09),  # orange
    (0.17, 0.63, 0.17),  # green
    (0.84, 0.15, 0.16),  # red
    (0.58, 0.40, 0.74),  # purple
    (0.09, 0.75, 0.81),  # cyan
    (0.89, 0.47, 0.76),  # pink
    (0.74, 0.74, 0.13),  # olive
)


def blade_color(index: int, blades: int) -> tuple[float, float, float]:
    """A distinct RGB colour (0..1) for blade ``index`` of ``blades``; neighbours always differ."""
    if blades <= len(_BLADE_PALETTE):
        return _BLADE_PALETTE[index]
    hue = (0.58 + index / blades) % 1.0  # evenly spaced hues, starting at blue
    return colorsys.hsv_to_rgb(hue, 0.75, 0.85 if index % 2 == 0 else 0.70)
