"""Checks on kernel results (one valid closed solid), and the shapes the checks work with; mass
properties are in :mod:`torus_cad.kernel.mass_properties`.

A boolean can "succeed" with several solids, an open shell or an invalid topology; every
result is checked here and a KernelError says what failed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, overload

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.gp import gp_Pnt
from OCP.TopoDS import TopoDS_Compound, TopoDS_Shape

from torus_cad.errors import KernelError
from torus_cad.kernel.topology import AnyShape, faces_in_order, like, occ, shells, solids

if TYPE_CHECKING:
    import cadquery as cq


@overload
def single_valid_solid(shape: cq.Shape, what: str) -> cq.Solid: ...


@overload
def single_valid_solid(shape: TopoDS_Shape, what: str) -> TopoDS_Shape: ...


def single_valid_solid(shape: AnyShape, what: str) -> TopoDS_Shape | cq.Solid:
    """The one solid of ``shape`` (of its kind: OpenCascade's or cadquery's); raise KernelError
    unless it is one solid, one closed shell, valid.

    Args:
        shape: a kernel result (OpenCascade's ``TopoDS_Shape`` or a ``cq.Shape``), mm.
        what: what made the shape, for the message (e.g. "fusing the blades with the hub").

    Returns:
        The solid, of the same kind as ``shape``: ``TopoDS_Shape`` in, ``TopoDS_Shape`` out;
        cadquery's in, ``cq.Solid`` out.

    Raises:
        KernelError: ``shape`` holds no solid or several, a solid of several shells, an open
            shell, or a solid BRepCheck_Analyzer finds invalid; the message starts with ``what``.
    """
    found = solids(occ(shape))
    if len(found) != 1:
        raise KernelError(f"{what} gave {len(found)} solids instead of 1")
    solid = found[0]
    solid_shells = shells(solid)
    if len(solid_shells) != 1:
        raise KernelError(f"{what} gave a solid with {len(solid_shells)} shells instead of 1")
    if not BRep_Tool.IsClosed_s(solid_shells[0]):
        raise KernelError(f"{what} gave an open shell (not watertight)")
    if not BRepCheck_Analyzer(solid).IsValid():
        raise KernelError(f"{what} gave a solid that BRepCheck_Analyzer finds invalid")
    return like(shape, solid)


def is_valid_closed_solid(shape: AnyShape) -> bool:
    """True when ``shape`` holds exactly one valid solid with one closed shell.

    Args:
        shape: OpenCascade's ``TopoDS_Shape`` or a ``cq.Shape``.

    Returns:
        True if :func:`single_valid_solid` accepts it, else False.
    """
    try:
        single_valid_solid(shape, "the shape")
    except KernelError:
        return False
    return True


def compound(shapes: Sequence[TopoDS_Shape]) -> TopoDS_Compound:
    """One compound of ``shapes`` (as cadquery's ``Compound.makeCompound``).

    Args:
        shapes: OpenCascade's shapes to hold; not copied.

    Returns:
        A ``TopoDS_Compound`` holding them all, in order.
    """
    builder, made = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(made)
    for shape in shapes:
        builder.Add(made, shape)
    return made


def distances_to_shape(shape: AnyShape, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance (mm) from each of ``(k, 3)`` points to the boundary of ``shape``: ``(k,)``.

    Args:
        shape: OpenCascade's ``TopoDS_Shape`` or a ``cq.Shape``, mm.
        points: ``(k, 3)`` float array, mm.

    Returns:
        ``(k,)`` float array, mm: each point's distance to the nearest face of ``shape``
        (0 on the boundary; unsigned, inside or outside).

    Raises:
        KernelError: OpenCascade could not measure a distance.
    """
    faces = compound(faces_in_order(occ(shape)))
    distances = np.empty(len(points))
    for index, point in enumerate(np.asarray(points, dtype=float)):
        vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, point))).Vertex()
        extrema = BRepExtrema_DistShapeShape(vertex, faces)
        if not extrema.IsDone():
            raise KernelError("OpenCascade could not measure a point's distance to the solid")
        distances[index] = extrema.Value()
    return distances
