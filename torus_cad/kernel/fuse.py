"""Pattern and fuse: n blades around the axis, joined with the hub.

Two routes give the same solid:

* :func:`fuse_pattern` intersects one blade with the hub, once, and reuses that intersection
  for every blade: the blade's part outside the hub is cut free, rotated to each blade angle,
  and joined to the hub. Its cost barely grows with the blade count.
* :func:`fuse_all` fuses the hub and all n blades in one general boolean: the fallback for
  whenever the first route raises or its result fails the checks.

Both report which part every face of the result came from (:attr:`Fused.face_parts`): the
assembled shell is put together from faces whose part is known; a boolean's history
(``Modified`` / ``IsDeleted`` of each argument's faces) says where each input face went.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING, Generic

from OCP.BOPAlgo import BOPAlgo_GlueShift
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_BooleanOperation, BRepAlgoAPI_Cut, BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_Cylinder
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec2d
from OCP.Precision import Precision
from OCP.TopAbs import TopAbs_FACE, TopAbs_WIRE
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape, TopoDS_Shell, TopoDS_Solid

from torus_cad.build_stages import Stage
from torus_cad.errors import KernelError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.edge_curves import refit_intersection_edges
from torus_cad.kernel.face_provenance import Origins, face_parts, through_history
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.kernel.topology import (
    AnyShape,
    ShapeT,
    boolean,
    count,
    edges,
    explore,
    faces,
    faces_in_order,
    like,
    occ,
    result,
    transformed,
)
from torus_cad.runtime.stage_timer import StageTimer
from torus_cad.tolerances import VOLUME_CHECK_RELATIVE_PRECISION

if TYPE_CHECKING:
    import cadquery as cq  # noqa: F401 (the shapes' other kind, in annotations)

_FULL_TURN = 2.0 * math.pi


def pattern_blades(blade: ShapeT, angles_deg: Sequence[float]) -> list[ShapeT]:
    """Copies of ``blade`` (built for angle ``angles_deg[0]``) rotated about z to every angle (of
    the kind ``blade`` is: OpenCascade's shape or cadquery's).

    Blade i's centerline is blade 0's rotated by theta_i - theta_0 (spec §3.3 and §6.1), so
    rotating the solid gives exactly the solid built from blade i's own control points.
    """
    first = angles_deg[0]
    return [
        blade if angle == first else like(blade, transformed(occ(blade), _turn(angle - first)))
        for angle in angles_deg
    ]


def _turn(angle_deg: float) -> gp_Trsf:
    """The rotation by ``angle_deg`` about +z."""
    rotation = gp_Trsf()
    rotation.SetRotation(
        gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), math.radians(angle_deg)
    )
    return rotation


def fuse_all(hub: ShapeT, blades: Sequence[AnyShape]) -> Fused[ShapeT]:
    """Hub and all blades fused in one BRepAlgoAPI_Fuse call (parallel, oriented bounding boxes);
    the result of the kind ``hub`` is."""
    fuse = boolean(BRepAlgoAPI_Fuse(), [occ(hub)], [occ(blade) for blade in blades])
    shape = result(fuse, "fuse the blades with the hub")
    parts = [(occ(hub), HUB_PART), *((occ(blade), index) for index, blade in enumerate(blades))]
    labels = face_parts(shape, _history(fuse, parts))
    # As on the shared route: the intersection edges rebuilt to 4e-8 mm, for the STEP file
    # (kernel.edge_curves).
    refit_intersection_edges(
        shape,
        [
            face
            for face, part in zip(faces_in_order(shape), labels, strict=True)
            if part == HUB_PART
        ],
    )
    return Fused(like(hub, shape), FuseRoute.GENERAL, labels)


class FuseRoute(StrEnum):
    """How the blades were joined to the hub (the value is the code the JSON report gives)."""

    ASSEMBLED = "assembled"
    """One blade-hub intersection reused for every blade;
    the shell put together from known faces."""
    GLUED = "glued"
    """One blade-hub intersection reused; the copies glued to the hub (a blade cuts an end face)."""
    GENERAL = "general"
    """The fallback: one general boolean of the hub and all blades."""

    @property
    def description(self) -> str:
        """The route in words, for people (the studio's readout)."""
        return {
            FuseRoute.ASSEMBLED: "shared intersection, assembled",
            FuseRoute.GLUED: "shared intersection, glued",
            FuseRoute.GENERAL: "one general fuse",
        }[self]


@dataclass(frozen=True)
class Fused(Generic[ShapeT]):
    """The hub and blades joined into one shape.

    Attributes:
        shape: the result (to be checked: one valid closed solid is expected).
        route: how it was joined.
        face_parts: which part each face of ``shape`` came from, in the order of
            ``shape.Faces()`` (TopExp's indexed map of faces): HUB_PART or the blade's index.
    """

    shape: ShapeT
    route: FuseRoute
    face_parts: tuple[int, ...]


def fuse_pattern(
    hub: ShapeT, blade: AnyShape, angles_deg: Sequence[float], refit_edges: bool = True
) -> Fused[ShapeT]:
    """Hub and copies of ``blade`` at every angle, with one blade-hub intersection for all of them.

    1. Cut the blade (built at ``angles_deg[0]``) by the hub: its part outside the hub, whose
       faces on the hub's lateral cylinder ("patches") are bounded by the intersection curves.
    2. Rotate that part to every angle. A rotation about the axis maps the hub's cylinder onto
       itself with u shifted by the angle, so each copy's curves on the cylinder are blade 0's
       shifted in u; they are attached to the hub's lateral face as such, instead of being
       projected again.
    3. Join the copies to the hub. Usually the hub only loses one hole per patch, and the
       shell is put together from known faces (:func:`_assemble`). When a blade also cuts an
       end face, or a patch straddles the hub's seam, the copies are glued to the hub with a
       fuse that needs no surface-surface intersection (:func:`_glue`).

    ``refit_edges=False`` keeps the boolean's own intersection curves: the root fillet's route,
    whose rolling ball fails on the refitted curves (prop_10x5_2blade at 0.5 mm) and whose STEP file
    is not read back (its fillet faces carry their own curve-on-surface gaps).

    Returns the shape, how it was joined (ASSEMBLED or GLUED) and each face's part. The caller
    checks the result (validity covers each edge's curve on the hub against its 3D curve) and falls
    back to :func:`fuse_all` on a KernelError or an invalid solid. The propeller's hub has its seam
    beside every footprint, see
    :func:`torus_cad.geometry.hub.seam.seam_angle_deg`.
    """
    hub_shape = occ(hub)
    lateral = _lateral_face(hub_shape)
    cut = boolean(BRepAlgoAPI_Cut(), [occ(blade)], [hub_shape])
    outside = result(cut, "cut the blade free of the hub")
    patches = _modified_faces(cut, lateral)
    if not patches:
        raise KernelError("the blade does not meet the hub's lateral face")
    hub_pieces = _modified_faces_of_shape(cut, hub_shape)
    if refit_edges:  # to 4e-8 mm: a STEP file keeps no edge tolerance (kernel.edge_curves)
        refit_intersection_edges(outside, hub_pieces)
    copies = [
        _rotated_with_hub_curves(outside, patches, lateral, math.radians(angle - angles_deg[0]))
        for angle in angles_deg
    ]
    whole_patches = len(hub_pieces) == len(patches) and not any(
        BRep_Tool.IsClosed_s(edge, patch) for patch in patches for edge in edges(patch)
    )
    if whole_patches:
        solid, origins = _assemble(hub_shape, lateral, copies, patches)
        return Fused(like(hub, solid), FuseRoute.ASSEMBLED, face_parts(solid, origins))
    blade_faces = count(outside, TopAbs_FACE) - len(hub_pieces)
    glued, origins = _glue(
        hub_shape, copies, count(hub_shape, TopAbs_FACE) + len(copies) * blade_faces
    )
    return Fused(like(hub, glued), FuseRoute.GLUED, face_parts(glued, origins))


def _assemble(
    hub: TopoDS_Shape,
    lateral: TopoDS_Face,
    copies: Sequence[TopoDS_Shape],
    patches: Sequence[TopoDS_Face],
) -> tuple[TopoDS_Solid, Origins]:
    """The propeller's solid put together from known faces, with no boolean, and each face's part.

    Its shell: the hub's end faces, a new lateral face (the hub's surface and outer wire) with
    each copy's patch boundaries as holes, and each copy's faces off the hub. A patch lies on
    the hub's cylinder with its normal flipped (its material is outside the hub), and the hole
    keeps the material on the other side of the same curve; the two flips cancel, so the
    patch's wires, oriented as the patch uses them, are the holes as the lateral face uses them.
    """
    outer_wire = BRepTools.OuterWire_s(lateral)
    lateral_with_holes = BRepBuilderAPI_MakeFace(BRep_Tool.Surface_s(lateral), outer_wire, True)
    for wire in explore(lateral, TopAbs_WIRE):  # holes the hub already has (a set-screw hole)
        if not wire.IsSame(outer_wire):
            lateral_with_holes.Add(TopoDS.Wire_s(wire))
    origins: Origins = []
    for index, copy in enumerate(copies):
        for face in faces(copy):
            if any(face.IsPartner(patch) for patch in patches):
                for wire in explore(face, TopAbs_WIRE):
                    lateral_with_holes.Add(TopoDS.Wire_s(wire))
            else:
                origins.append((face, index))
    if not lateral_with_holes.IsDone():
        raise KernelError("OpenCascade could not cut the blade roots out of the hub's lateral face")
    hub_faces = [
        lateral_with_holes.Face(),
        *(face for face in faces(hub) if not face.IsSame(lateral)),
    ]
    origins.extend((face, HUB_PART) for face in hub_faces)
    return solid_of_faces(origins), origins


def solid_of_faces(origins: Origins) -> TopoDS_Solid:
    """The solid bounded by one shell of the faces of ``origins`` (each face with its part), in that
    order, sewn by their shared edges (no boolean): the assembled routes' last step."""
    builder = BRep_Builder()
    shell = TopoDS_Shell()
    builder.MakeShell(shell)
    for face, _ in origins:
        builder.Add(shell, face)
    shell.Closed(BRep_Tool.IsClosed_s(shell))
    solid = TopoDS_Solid()
    builder.MakeSolid(solid)
    builder.Add(solid, shell)
    return solid


def _glue(
    hub: TopoDS_Shape, copies: Sequence[TopoDS_Shape], expected_faces: int
) -> tuple[TopoDS_Shape, Origins]:
    """Hub and copies fused with BOPAlgo_GlueShift (they only touch along faces of the hub's
    surfaces), and where each of their faces went."""
    glue = BRepAlgoAPI_Fuse()
    glue.SetGlue(BOPAlgo_GlueShift)
    fused = result(boolean(glue, [hub], copies), "glue the blades to the hub")
    faces = count(fused, TopAbs_FACE)
    if faces != expected_faces:
        raise KernelError(
            f"gluing the blades to the hub gave {faces} faces instead of {expected_faces}"
        )
    return fused, _history(
        glue, [(hub, HUB_PART), *((copy, index) for index, copy in enumerate(copies))]
    )


def _history(
    operation: BRepAlgoAPI_BooleanOperation, arguments: Iterable[tuple[TopoDS_Shape, int]]
) -> Origins:
    """(result face, part) for every face of every (argument, part), through the boolean's
    history."""
    return through_history(
        operation, [(face, part) for argument, part in arguments for face in faces(argument)]
    )


def _rotated_with_hub_curves(
    outside: TopoDS_Shape, patches: list[TopoDS_Face], lateral: TopoDS_Face, angle_rad: float
) -> TopoDS_Shape:
    """``outside`` rotated by ``angle_rad`` about +z, its patch edges given curves on ``lateral``.

    The copy shares its edges with ``outside`` (only the location differs); each edge keeps one
    curve on ``lateral`` per location, so the copies' curves do not disturb each other.
    """
    rotation = gp_Trsf()
    rotation.SetRotation(gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), angle_rad)
    location = TopLoc_Location(rotation)
    builder = BRep_Builder()
    for patch in patches:
        u_min, u_max, _, _ = BRepTools.UVBounds_s(patch)
        # a patch starting at the seam may start a parametric hair before it (u = -1e-13 after
        # kernel.edge_curves)
        shift = angle_rad - _FULL_TURN * math.floor(
            (u_min + angle_rad + Precision.PConfusion_s()) / _FULL_TURN
        )
        if u_max + shift > _FULL_TURN:
            raise KernelError("a blade's footprint on the hub crosses the hub's seam")
        for edge in edges(patch):
            curve = BRep_Tool.CurveOnSurface_s(edge, patch, 0.0, 0.0)
            if curve is None:
                raise KernelError("an intersection edge has no curve on the hub")
            moved = TopoDS.Edge_s(edge.Moved(location))
            builder.UpdateEdge(
                moved, curve.Translated(gp_Vec2d(shift, 0.0)), lateral, BRep_Tool.Tolerance_s(edge)
            )
    return outside.Moved(location)


def _lateral_face(hub: TopoDS_Shape) -> TopoDS_Face:
    """The hub's outer cylindrical face (a bore or a set-screw hole is a smaller cylinder)."""
    cylinders = [
        (BRepAdaptor_Surface(face).Cylinder().Radius(), index, face)
        for index, face in enumerate(faces_in_order(hub))
        if BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder
    ]
    if not cylinders:
        raise KernelError("the hub has no cylindrical face")
    return max(cylinders, key=lambda item: item[:2])[2]


def _modified_faces(
    operation: BRepAlgoAPI_BooleanOperation, face: TopoDS_Face
) -> list[TopoDS_Face]:
    """The pieces of an argument's ``face`` that bound the result (from the operation's history)."""
    return [TopoDS.Face_s(piece) for piece in operation.Modified(face)]


def _modified_faces_of_shape(
    operation: BRepAlgoAPI_BooleanOperation, shape: TopoDS_Shape
) -> list[TopoDS_Face]:
    return [piece for face in faces(shape) for piece in _modified_faces(operation, face)]


def joined_propeller(
    hub: TopoDS_Shape,
    blade: TopoDS_Shape,
    blades: list[TopoDS_Shape],
    angles_deg: list[float],
    timer: StageTimer[Stage],
) -> tuple[TopoDS_Shape, Fused[TopoDS_Shape]]:
    """The fused, checked propeller of ``hub`` and ``blades`` (``blade`` turned to ``angles_deg``),
    and how it was made (route, each face's part), each step timed as a build stage.

    The shared-intersection route's result is checked for validity, which includes every
    edge's curve on the hub against its 3D curve. Where that route fails, one general fuse
    is used and its volume is checked as well (:func:`check_fused_volume`).

    Args:
        hub: the hub solid, mm.
        blade: blade 0, mm.
        blades: every blade, ``blade`` turned to each of ``angles_deg``.
        angles_deg: the blades' angles about +z, degrees.
        timer: times the FUSE and CHECK stages.

    Returns:
        The single valid solid and the fuse that made it.

    Raises:
        KernelError: neither route gives one valid solid, or the general fuse lost or doubled
            material.
    """
    try:
        with timer.stage(Stage.FUSE):
            fused = fuse_pattern(hub, blade, angles_deg)
        with timer.stage(Stage.CHECK):
            return single_valid_solid(fused.shape, "joining the blades to the hub"), fused
    except KernelError:
        pass  # the general fuse below decides
    with timer.stage(Stage.FUSE):
        fused = fuse_all(hub, blades)
    with timer.stage(Stage.CHECK):
        solid = single_valid_solid(fused.shape, "fusing the blades with the hub")
        check_fused_volume(solid, hub, blade, len(blades))
    return solid, fused


def check_fused_volume(
    solid: TopoDS_Shape, hub: TopoDS_Shape, blade: TopoDS_Shape, blades: int
) -> None:
    """hub < fused <= hub + n x blade: a fuse that lost or doubled material is an error.

    Args:
        solid: the fused propeller, mm.
        hub: the hub, mm.
        blade: one blade, mm.
        blades: how many blades were fused.

    Raises:
        KernelError: the fused volume lies outside that interval (naming the three volumes).
    """
    volume, hub_volume, blade_volume = (
        precise_volume(shape, VOLUME_CHECK_RELATIVE_PRECISION) for shape in (solid, hub, blade)
    )
    if (
        not hub_volume
        < volume
        <= (hub_volume + blades * blade_volume) * (1 + 10 * VOLUME_CHECK_RELATIVE_PRECISION)
    ):
        raise KernelError(
            f"the fused volume {volume:.3f} mm^3 is outside (hub {hub_volume:.3f}, "
            f"hub + {blades} blades {hub_volume + blades * blade_volume:.3f}] mm^3"
        )
