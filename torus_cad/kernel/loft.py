"""Loft: compatible section wires -> one closed blade solid (BRepOffsetAPI_ThruSections)."""

from __future__ import annotations

from collections.abc import Sequence

from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections

import cadquery as cq

from torus_cad.errors import KernelError
from torus_cad.tolerances import LOFT_PRECISION


def loft_solid(wires: Sequence[cq.Wire]) -> cq.Solid:
    """A smooth (non-ruled) closed solid through ``wires``, capped by planar end faces.

    The wires must already be compatible (same knots, same start at the trailing edge),
    as :func:`torus_cad.kernel.wires.fit_section_curves` makes them; the compatibility
    search of ThruSections is therefore switched off (it would only re-align start points).
    """
    if len(wires) < 2:
        raise KernelError(f"a loft needs at least 2 section wires, got {len(wires)}")
    builder = BRepOffsetAPI_ThruSections(True, False, LOFT_PRECISION)
    builder.CheckCompatibility(False)
    for wire in wires:
        builder.AddWire(wire.wrapped)
    builder.Build()
    if not builder.IsDone():
        raise KernelError("the loft of the blade sections failed in OpenCascade (BRepOffsetAPI_ThruSections)")
    shape = cq.Shape.cast(builder.Shape())
    solids = shape.Solids()
    if len(solids) != 1:
        raise KernelError(f"the loft of the blade sections gave {len(solids)} solids instead of 1")
    return solids[0]
