"""Hub (spec §6.2): a cylinder of radius R and length L on the z axis, centred at the origin."""

from __future__ import annotations

import cadquery as cq


def hub_solid(radius: float, length: float) -> cq.Solid:
    """Cylinder r <= radius, |z| <= length / 2 (mm)."""
    return cq.Solid.makeCylinder(radius, length, cq.Vector(0.0, 0.0, -length / 2.0), cq.Vector(0.0, 0.0, 1.0))
