"""One root fillet on given junction edges: BRepFilletAPI_MakeFillet, the repair of a flawed result,
and the forked child (torus_cad.runtime.isolation) it runs in, since OpenCascade's fillet can crash
the process or hang on some inputs; the result comes back as a BRep string.

OpenCascade sometimes builds the fillet, reports success and leaves a solid BRepCheck rejects;
ShapeFix_Shape mends some. A mended solid must pass the same checks (one valid closed solid, no
less volume) and add no more volume than a fillet's cross-section along the junction
(REPAIRED_FILLET_MAX_AREA_RADII2 x r^2 per mm).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import NamedTuple

import cadquery as cq
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.ChFi3d import ChFi3d_FilletShape, ChFi3d_Rational
from OCP.ShapeFix import ShapeFix_Shape
from OCP.TopoDS import TopoDS_Edge

from torus_cad.errors import KernelError
from torus_cad.kernel import face_provenance
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.kernel.topology import shape_bytes, shape_from_bytes
from torus_cad.runtime.isolation import IsolatedCrash, IsolatedTimeout, run_isolated
from torus_cad.tolerances import VOLUME_CHECK_RELATIVE_PRECISION

#: Seconds the root fillet may take (in its child process) before it counts as failed.
FILLET_TIME_LIMIT_S = 60.0

#: A repaired root fillet (ShapeFix) is accepted only if it adds at most this many r^2 of volume
#: per mm of junction: a rolling-ball fillet between faces meeting at 30 degrees adds 2.4 r^2,
#: at 90 degrees 0.21 r^2 (what repaired fillets add: the docs' measurements page).
REPAIRED_FILLET_MAX_AREA_RADII2 = 4.0


#: The fillet's cross-section law (BRepFilletAPI_MakeFillet's FShape): OpenCascade's default, the
#: rational one, a true circular arc of the radius; the quasi-angular and polynomial laws save no
#: design the tries lose (``scripts/fillet_rate.py --fillet-shape`` compares them).
FILLET_SHAPE: ChFi3d_FilletShape = ChFi3d_Rational


#: BRepFilletAPI_MakeFillet.SetParams arguments: Tang, Tesp, T2d, TApp3d, TolApp2d, Fleche.
FilletParams = tuple[float, float, float, float, float, float]


class Filleted(NamedTuple):
    """A filleted solid and the part of each of its faces (:mod:`torus_cad.kernel.face_provenance`;
    empty when the input's were not given)."""

    solid: cq.Solid
    face_parts: tuple[int, ...]


def fillet_edges(
    solid: cq.Solid,
    edges: list[TopoDS_Edge],
    radius_mm: float,
    params: FilletParams | None = None,
    edge_radii: Sequence[float] | None = None,
    face_parts: Sequence[int] | None = None,
) -> Filleted | None:
    """The fillet in this process: the checked solid, or None when OpenCascade fails or the result
    is unsound.

    ``params``: BRepFilletAPI_MakeFillet.SetParams values (default: OpenCascade's). ``edge_radii``:
    a radius per edge (mm) instead of ``radius_mm`` on all; OpenCascade blends the radius between
    edges of one contour that differ. ``face_parts``: the part of each face of ``solid``; the
    result's are then found through the fillet's history (KernelError if a face has none)."""
    fillet = BRepFilletAPI_MakeFillet(solid.wrapped, FILLET_SHAPE)
    if params is not None:
        fillet.SetParams(*params)
    for edge in edges:
        fillet.Add(radius_mm, edge)
    for edge, radius in zip(edges, edge_radii or ()):
        if radius < radius_mm:
            contour = fillet.Contour(edge)
            index = next(
                i
                for i in range(1, fillet.NbEdges(contour) + 1)
                if fillet.Edge(contour, i).IsSame(edge)
            )
            fillet.SetRadius(radius, contour, index)
    try:
        fillet.Build()
    except Exception:  # OCCT raises Standard_Failure subclasses through OCP
        return None
    if not fillet.IsDone():
        return None
    fix: ShapeFix_Shape | None = None
    try:
        result = single_valid_solid(cq.Shape.cast(fillet.Shape()), "the root fillet")
    except KernelError:  # OpenCascade sometimes builds the fillet but leaves flaws ShapeFix mends
        fix = ShapeFix_Shape(fillet.Shape())
        fix.Perform()
        try:
            result = single_valid_solid(cq.Shape.cast(fix.Shape()), "the repaired root fillet")
        except KernelError:
            return None
    added_mm3 = precise_volume(result, VOLUME_CHECK_RELATIVE_PRECISION) - precise_volume(
        solid, VOLUME_CHECK_RELATIVE_PRECISION
    )
    # A concave fillet only adds material: a smaller volume means a wrong result. A repaired one
    # must also add no more than a fillet's cross-section along the junction.
    if added_mm3 < 0.0:
        return None
    if fix is not None and added_mm3 > REPAIRED_FILLET_MAX_AREA_RADII2 * radius_mm**2 * sum(
        cq.Edge(edge).Length() for edge in edges
    ):
        return None
    if face_parts is None:
        return Filleted(result, ())
    return Filleted(result, _filleted_face_parts(fillet, fix, solid, face_parts, result))


def _filleted_face_parts(
    fillet: BRepFilletAPI_MakeFillet,
    fix: ShapeFix_Shape | None,
    solid: cq.Solid,
    face_parts: Sequence[int],
    result: cq.Solid,
) -> tuple[int, ...]:
    """The part of each face of ``result`` through the fillet's history (and ShapeFix's, if it
    mended it)."""
    origins = face_provenance.through_history(
        fillet, face_provenance.labelled_faces(solid.wrapped, face_parts)
    ) + face_provenance.fillet_faces(fillet, solid.wrapped, face_parts)
    if fix is not None:
        origins = face_provenance.through_reshape(fix.Context(), origins, result.wrapped)
    return face_provenance.face_parts(result.wrapped, origins)


def fillet_in_child(
    solid: cq.Solid,
    edges: list[TopoDS_Edge],
    radius_mm: float,
    params: FilletParams | None = None,
    deadline: float | None = None,
    edge_radii: Sequence[float] | None = None,
    face_parts: Sequence[int] | None = None,
) -> Filleted | None:
    """:func:`fillet_edges` in a forked child (torus_cad.runtime.isolation): a crash or a hang there
    is a failed fillet, not a dead process. The child sends the solid as a BRep string, with its
    face parts.

    The child gets FILLET_TIME_LIMIT_S, or what is left until ``deadline`` (time.monotonic()) if
    less."""
    limit_s = (
        FILLET_TIME_LIMIT_S
        if deadline is None
        else min(FILLET_TIME_LIMIT_S, deadline - time.monotonic())
    )
    if limit_s <= 0.0:
        return None

    def fillet_as_brep() -> tuple[bytes, tuple[int, ...]] | None:
        try:
            result = fillet_edges(solid, edges, radius_mm, params, edge_radii, face_parts)
        except Exception:  # OpenCascade's failures (Standard_Failure and others): a failed fillet
            return None
        return None if result is None else (shape_bytes(result.solid.wrapped), result.face_parts)

    try:
        data = run_isolated(fillet_as_brep, timeout_s=limit_s, what="the root fillet")
    except (IsolatedTimeout, IsolatedCrash):
        return None
    if not data:
        return None
    brep, parts = data
    return Filleted(
        single_valid_solid(cq.Shape.cast(shape_from_bytes(brep)), "the root fillet"), parts
    )
