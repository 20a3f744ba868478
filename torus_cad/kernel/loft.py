"""Loft: compatible section wires -> one closed blade solid (poles interpolated in s; ThruSections
fallback)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepBuilderAPI import (
    BRepBuilderAPI_MakeFace,
    BRepBuilderAPI_MakeSolid,
    BRepBuilderAPI_Sewing,
)
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
from OCP.BRepTools import BRepTools_WireExplorer
from OCP.Geom import Geom_BSplineCurve, Geom_BSplineSurface
from OCP.gp import gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.ShapeFix import ShapeFix_Solid
from OCP.TColgp import TColgp_Array2OfPnt
from OCP.TopAbs import TopAbs_SHELL
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from scipy.interpolate import make_interp_spline

from torus_cad.errors import KernelError
from torus_cad.kernel.topology import ShapeT, like, occ, solids
from torus_cad.kernel.wires import knot_arrays

#: Precision of the loft (BRepOffsetAPI_ThruSections pres3d), mm.
LOFT_PRECISION = 1e-6


#: Sewing tolerance of the blade's side face and end caps (mm); their shared edges are the same
#: curves (the side surface interpolates the end sections exactly), so a tight value suffices.
LOFT_SEWING_TOLERANCE = 1e-6


def loft_solid(
    wires: Sequence[ShapeT], parameters: Sequence[float] | NDArray[np.float64] | None = None
) -> ShapeT:
    """A smooth closed solid through ``wires``, capped by planar end faces (OpenCascade's wires give
    OpenCascade's solid, cadquery's a ``cq.Solid``).

    The wires must be compatible B-splines (same edges, each with the same degree, knots and
    pole count, starting at the trailing edge), as :func:`torus_cad.kernel.wires.section_curves`
    makes them; each edge position gets its own side face (a blunt trailing edge's base and
    the airfoil). The side surface interpolates every pole across the sections with a cubic
    (not-a-knot) spline in the sections' own parameters ``parameters`` (default: uniform in
    [0, 1], the s of :func:`torus_cad.geometry.blade.blade_surface.blade_surface`), so it follows
    the design between sections. BRepOffsetAPI_ThruSections, used before and kept as a fallback,
    chooses its own chord-length parametrisation; on sparse, strongly changing blades it missed
    the design by up to ~40 % of the chord next to the hub and the fuse then failed or hung
    (found by scripts/fuzz.py).
    """
    if len(wires) < 2:
        raise KernelError(f"a loft needs at least 2 section wires, got {len(wires)}")
    if len(wires) >= 4:
        try:
            return like(wires[0], _loft_through_poles([occ(wire) for wire in wires], parameters))
        except (KernelError, ValueError, RuntimeError):
            pass  # incompatible wires or a sewing failure: let ThruSections try
    return thru_sections_solid(wires)


def _bsplines_of(wire: TopoDS_Shape) -> list[Geom_BSplineCurve]:
    """The wire's edges' B-spline curves, in the wire's order."""
    curves = []
    explorer = BRepTools_WireExplorer(TopoDS.Wire_s(wire))
    while explorer.More():
        curve = BRep_Tool.Curve_s(explorer.Current(), 0.0, 1.0)
        if not isinstance(curve, Geom_BSplineCurve):
            raise KernelError("a section wire must be made of B-spline edges")
        curves.append(curve)
        explorer.Next()
    return curves


def _loft_through_poles(
    wires: Sequence[TopoDS_Shape], parameters: Sequence[float] | NDArray[np.float64] | None
) -> TopoDS_Shape:
    """One side face per edge position (one for a sharp trailing edge; base and airfoil for a blunt
    one)."""
    edges = [_bsplines_of(wire) for wire in wires]
    if len({len(curves) for curves in edges}) != 1:
        raise KernelError("the section wires have different numbers of edges")
    s = (
        np.linspace(0.0, 1.0, len(wires))
        if parameters is None
        else np.asarray(parameters, dtype=float)
    )
    faces = [_side_face([curves[index] for curves in edges], s) for index in range(len(edges[0]))]
    return _closed_solid(faces, wires)


def _side_face(curves: Sequence[Geom_BSplineCurve], s: NDArray[np.float64]) -> TopoDS_Face:
    """A B-spline face through compatible curves: every pole column interpolated by a cubic in s."""
    first = curves[0]
    degree, count = first.Degree(), first.NbPoles()
    knots = np.concatenate(
        [[first.Knot(i)] * first.Multiplicity(i) for i in range(1, first.NbKnots() + 1)]
    )
    for curve in curves[1:]:
        if curve.Degree() != degree or curve.NbPoles() != count or curve.IsRational():
            raise KernelError("the section B-splines are not compatible")
    poles = np.array(
        [
            [(p.X(), p.Y(), p.Z()) for p in (curve.Pole(i) for i in range(1, count + 1))]
            for curve in curves
        ]
    )
    along = make_interp_spline(s, poles, k=3)  # not-a-knot cubic through every pole column
    surface_poles = TColgp_Array2OfPnt(1, count, 1, along.c.shape[0])
    for j, column in enumerate(along.c, start=1):
        for i, (x, y, z) in enumerate(column, start=1):
            surface_poles.SetValue(i, j, gp_Pnt(float(x), float(y), float(z)))
    u_knots, u_multiplicities = knot_arrays(knots)
    v_knots, v_multiplicities = knot_arrays(along.t)
    surface = Geom_BSplineSurface(
        surface_poles, u_knots, v_knots, u_multiplicities, v_multiplicities, degree, 3
    )
    face = BRepBuilderAPI_MakeFace(surface, LOFT_PRECISION)
    if not face.IsDone():
        raise KernelError("OpenCascade could not make the blade's side face")
    return face.Face()


def _closed_solid(faces: Sequence[TopoDS_Face], wires: Sequence[TopoDS_Shape]) -> TopoDS_Shape:
    """The side faces and planar caps on the first and last wires, sewn into one checked solid."""
    sewing = BRepBuilderAPI_Sewing(LOFT_SEWING_TOLERANCE)
    for face in faces:
        sewing.Add(face)
    for wire in (wires[0], wires[-1]):
        cap = BRepBuilderAPI_MakeFace(TopoDS.Wire_s(wire), True)
        if not cap.IsDone():
            raise KernelError("OpenCascade could not cap the blade with a planar end face")
        sewing.Add(cap.Face())
    sewing.Perform()
    sewn = sewing.SewedShape()
    if sewn.ShapeType() != TopAbs_SHELL:
        raise KernelError("sewing the blade's faces did not give one shell")
    solid = BRepBuilderAPI_MakeSolid(TopoDS.Shell_s(sewn))
    if not solid.IsDone():
        raise KernelError("OpenCascade could not make a solid from the blade's shell")
    fix = ShapeFix_Solid(solid.Solid())
    fix.Perform()  # orients the shell outward
    result = solids(fix.Solid())
    if len(result) != 1 or not BRepCheck_Analyzer(result[0]).IsValid() or _volume(result[0]) <= 0.0:
        raise KernelError("the lofted blade is not one valid solid")
    return result[0]


def thru_sections_solid(wires: Sequence[ShapeT]) -> ShapeT:
    """The loft by BRepOffsetAPI_ThruSections (smooth, not ruled); the fallback of
    :func:`loft_solid`.

    The compatibility search of ThruSections is switched off (the wires are already
    compatible; it would only re-align start points).
    """
    if len(wires) < 2:
        raise KernelError(f"a loft needs at least 2 section wires, got {len(wires)}")
    builder = BRepOffsetAPI_ThruSections(True, False, LOFT_PRECISION)
    builder.CheckCompatibility(False)
    for wire in wires:
        builder.AddWire(TopoDS.Wire_s(occ(wire)))
    builder.Build()
    if not builder.IsDone():
        raise KernelError(
            "the loft of the blade sections failed in OpenCascade (BRepOffsetAPI_ThruSections)"
        )
    made = solids(builder.Shape())
    if len(made) != 1:
        raise KernelError(f"the loft of the blade sections gave {len(made)} solids instead of 1")
    return like(wires[0], made[0])


def _volume(shape: TopoDS_Shape) -> float:
    """OpenCascade's volume of ``shape`` at its default precision (mm^3), as cadquery's
    ``Shape.Volume()``."""
    properties = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, properties)
    return float(properties.Mass())
