"""The pattern trick for the root fillet: blade 0 alone is joined to the hub and filleted, once; its
blade and fillet faces are rotated to every blade angle, the fillet's contact curves on the hub's
cylinder shifted in u, and the shell is assembled from known faces. One blade's fillet then costs
the same for any blade count. If the assembly fails its checks, the whole propeller is filleted.

Where a blade root comes within about a radius of the hub's end face, so that the fillet would
roll over the hub's edge, the tries are made on a hub longer at both ends (the run-out hub) and
the result is cut back to the hub's length, sparing a blade that itself passes the hub's end.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Iterator, Sequence

import cadquery as cq
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_Cylinder
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec2d
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_WIRE
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape, TopoDS_Solid, TopoDS_Wire
from OCP.TopTools import TopTools_IndexedMapOfShape

from torus_cad.errors import KernelError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel import face_provenance
from torus_cad.kernel.checks import single_valid_solid
from torus_cad.kernel.face_provenance import Origins
from torus_cad.kernel.fillet.one_fillet import FilletParams
from torus_cad.kernel.fillet.root_fillet import (
    FILLET_TRIES,
    SIDE_FACE_PIECES,
    RootFillet,
    fillet_blade_roots,
    fillet_failure,
    junction_edges,
    made_readable,
    prepare_blade_for_fillet,
)
from torus_cad.kernel.fillet.tight_bends import reduced_edge_radii
from torus_cad.kernel.fuse import fuse_pattern, pattern_blades, solid_of_faces
from torus_cad.kernel.topology import BLADE_SURFACES, boolean, explore, faces, result
from torus_cad.tolerances import REDUCED_FILLET_FRACTION

#: Seconds each of the root fillet's further tries (after the first, which has
#: FILLET_TIME_LIMIT_S) may take in its child: the tries that save a design take under a second,
#: the ones that fail either fail as fast or hang until their limit (``scripts/fillet_rate.py``).
FILLET_RETRY_TIME_LIMIT_S = 15.0
#: Seconds the root fillet's further tries together may take (counted from the end of the first);
#: when it runs out, the remaining tries are skipped and the fillet fails. With the first try and
#: the search for a smaller radius to suggest (up to 3 children of FILLET_TIME_LIMIT_S), a failing
#: fillet takes at most about 60 + 60 + 3 x 60 s.
FILLET_TRIES_TIME_LIMIT_S = 60.0

#: Builds the run-out hub for a given extension (mm): a plain hub that much longer at each end,
#: and the tools that cut it back to the real hub afterwards (see :func:`fillet_pattern`).
RunOutHub = Callable[[float], tuple[cq.Solid, list[TopoDS_Shape]]]


#: The run-out hub's extension at each end, in fillet radii.
_RUN_OUT_RADII = 3.0


def fillet_pattern(
    hub: cq.Solid,
    blade: cq.Solid,
    angles_deg: Sequence[float],
    radius_mm: float,
    run_out: RunOutHub | None = None,
    reduce_where_tight: bool = False,
) -> RootFillet:
    """The filleted propeller from one filleted blade: blade 0 joined to ``hub``, filleted,
    patterned.

    ``blade`` is built at ``angles_deg[0]``; its side face is split as
    :func:`prepare_blade_for_fillet` does, and the fillet made as each of :data:`FILLET_TRIES` says
    until it works. Where a blade root comes within about a radius of the hub's end face, the
    fillet would have to roll over the hub's edge and fails. With ``run_out``, the tries are then
    made on a hub longer at both ends (the fillet runs out past the end), and the result is cut
    back to the hub's length (the fillet ends in the end face, as it would when a longer filleted
    hub is faced) with the bore and set-screw hole cut at the same time. Where the blade itself
    passes the hub's end plane, the cut-back's end slabs have the blades cut out of them, so the
    blades' parts past the end stay as they are (the fillet still ends flush with the end face).
    The first try stops at FILLET_TIME_LIMIT_S; each further one at FILLET_RETRY_TIME_LIMIT_S, and
    all of them together at FILLET_TRIES_TIME_LIMIT_S.

    When every try fails and a blade face bends too tightly for the ball along some junction edge
    (:func:`reduced_edge_radii`): with ``reduce_where_tight``, the same tries are made once more
    with those edges' radii reduced, and the result says so (:attr:`RootFillet.constant_radius` is
    False); without, the error says that the blade bends too tightly there for the ball.

    Raises KernelError as :func:`fillet_blade_roots` does when the fillet fails; returns a
    checked single valid solid.
    """
    split = _LazySplits(blade)
    try:  # the common case; the child stops at FILLET_TIME_LIMIT_S, as ever
        return _fillet_and_pattern(hub, split[0], angles_deg, radius_mm, suggest=False)
    except KernelError:
        pass
    deadline = time.monotonic() + FILLET_TRIES_TIME_LIMIT_S  # the further tries' shared time
    attempt = _RunOut(blade, angles_deg, radius_mm, run_out)
    filleted = _first_that_works(
        hub, split, angles_deg, radius_mm, FILLET_TRIES[1:], deadline, reduce=False
    )
    if filleted is None:
        filleted = attempt.tries(split, deadline, reduce=False)
    if filleted is not None:
        return filleted
    joined = single_valid_solid(
        fuse_pattern(hub, split[0], angles_deg[:1], refit_edges=False).shape,
        "joining blade 0 to the hub",
    )
    smallest_mm = min(reduced_edge_radii(joined, junction_edges(joined), radius_mm))
    if smallest_mm < radius_mm and not reduce_where_tight:
        raise fillet_failure(joined, radius_mm, tight_bend_mm=smallest_mm / REDUCED_FILLET_FRACTION)
    if smallest_mm < radius_mm:
        # the reduced tries get the same time again
        deadline = time.monotonic() + FILLET_TRIES_TIME_LIMIT_S
        filleted = _first_that_works(
            hub, split, angles_deg, radius_mm, FILLET_TRIES, deadline, reduce=True
        )
        if filleted is None:
            filleted = attempt.tries(split, deadline, reduce=True)
        if filleted is not None:
            return filleted
    # Every try failed: the error names a smaller radius that works on blade 0, if one does.
    raise fillet_failure(joined, radius_mm)


def _first_that_works(
    hub: cq.Solid,
    split: _LazySplits,
    angles_deg: Sequence[float],
    radius_mm: float,
    tries: Sequence[tuple[int, FilletParams | None]],
    deadline: float,
    reduce: bool,
    finish: Callable[[RootFillet], RootFillet] | None = None,
) -> RootFillet | None:
    """The first of ``tries`` (as :data:`FILLET_TRIES`) that works on ``hub``, passed through
    ``finish`` (a KernelError there counts as a failed try; the edges are made readable from STEP
    after it, not before); None if none does. Each try stops at FILLET_RETRY_TIME_LIMIT_S (one that
    saves a design does so in under a second), all by ``deadline``."""
    for index, params in tries:
        try:
            made = _fillet_and_pattern(
                hub,
                split[index],
                angles_deg,
                radius_mm,
                suggest=False,
                params=params,
                deadline=min(deadline, time.monotonic() + FILLET_RETRY_TIME_LIMIT_S),
                reduce=reduce,
                readable=finish is None,
            )
            return made if finish is None else finish(made)
        except KernelError:
            pass
    return None


class _RunOut:
    """The tries on the run-out hub (see :func:`fillet_pattern`), made when first needed."""

    def __init__(
        self,
        blade: cq.Solid,
        angles_deg: Sequence[float],
        radius_mm: float,
        run_out: RunOutHub | None,
    ) -> None:
        self.blade, self.angles_deg, self.radius_mm, self.run_out = (
            blade,
            angles_deg,
            radius_mm,
            run_out,
        )
        self.made: tuple[cq.Solid, list[TopoDS_Shape], Origins] | None = None

    def _hub_and_tools(self) -> tuple[cq.Solid, list[TopoDS_Shape], Origins]:
        """The run-out hub, the tools that cut it back and their faces' parts (the hub's, or where a
        slab had a blade cut out of it, that blade's)."""
        if self.made is None:
            assert self.run_out is not None
            extended, tools = self.run_out(_RUN_OUT_RADII * self.radius_mm)
            slabs, others = tools[:2], tools[2:]
            origins: Origins = [(face, HUB_PART) for tool in others for face in faces(tool)]
            # the blade itself reaches past a hub end: the cut-back keeps it there
            if _touches(self.blade, slabs):
                blades = [copy.wrapped for copy in pattern_blades(self.blade, self.angles_deg)]
                blade_faces = [
                    (face, index) for index, copy in enumerate(blades) for face in faces(copy)
                ]
                cut_slabs = []
                for slab in slabs:
                    operation = boolean(BRepAlgoAPI_Cut(), [slab], blades)
                    cut_slabs.append(
                        result(operation, "keep the blades out of the run-out's cut-back")
                    )
                    origins += face_provenance.through_history(
                        operation, [(f, HUB_PART) for f in faces(slab)] + blade_faces
                    )
                slabs = cut_slabs
            else:
                origins += [(face, HUB_PART) for slab in slabs for face in faces(slab)]
            self.made = extended, [*slabs, *others], origins
        return self.made

    def tries(self, split: _LazySplits, deadline: float, reduce: bool) -> RootFillet | None:
        """The first of :data:`FILLET_TRIES` that works on the run-out hub, cut back; None if none
        does by ``deadline``."""
        if self.run_out is None or time.monotonic() >= deadline:
            return None
        extended, tools, tool_faces = self._hub_and_tools()

        def cut_back(made: RootFillet) -> RootFillet:
            operation = boolean(BRepAlgoAPI_Cut(), [made.solid.wrapped], tools)
            shape = result(operation, "cut the run-out hub back to the hub's length")
            solid = single_valid_solid(cq.Shape.cast(shape), "cutting the run-out hub back")
            origins = (
                face_provenance.labelled_faces(made.solid.wrapped, made.face_parts) + tool_faces
            )
            parts = face_provenance.face_parts(
                solid.wrapped, face_provenance.through_history(operation, origins)
            )
            solid, parts = made_readable(solid, parts)  # the cut's new edges too
            return dataclasses.replace(made, solid=solid, face_parts=parts)

        return _first_that_works(
            extended,
            split,
            self.angles_deg,
            self.radius_mm,
            FILLET_TRIES,
            deadline,
            reduce,
            cut_back,
        )


class _LazySplits:
    """``blade`` split into each number of :data:`SIDE_FACE_PIECES`, made when first asked for."""

    def __init__(self, blade: cq.Solid) -> None:
        self.blade = blade
        self.made: dict[int, cq.Solid] = {}

    def __getitem__(self, index: int) -> cq.Solid:
        pieces = SIDE_FACE_PIECES[index]
        if pieces not in self.made:
            self.made[pieces] = prepare_blade_for_fillet(self.blade, pieces)
        return self.made[pieces]

    def __iter__(self) -> Iterator[cq.Solid]:
        return (self[index] for index in range(len(SIDE_FACE_PIECES)))


def _fillet_and_pattern(
    hub: cq.Solid,
    blade: cq.Solid,
    angles_deg: Sequence[float],
    radius_mm: float,
    suggest: bool = True,
    params: FilletParams | None = None,
    deadline: float | None = None,
    reduce: bool = False,
    readable: bool = True,
) -> RootFillet:
    single = fuse_pattern(hub, blade, angles_deg[:1], refit_edges=False)
    filleted = fillet_blade_roots(
        single_valid_solid(single.shape, "joining blade 0 to the hub"),
        single.face_parts,
        radius_mm,
        suggest,
        params,
        deadline,
        reduce,
        readable,
    )
    if len(angles_deg) == 1:
        return filleted
    try:
        assembled, origins = _assemble_filleted(filleted.solid.wrapped, angles_deg)
        solid = single_valid_solid(cq.Shape.cast(assembled), "patterning the filleted blade")
        return dataclasses.replace(
            filleted, solid=solid, face_parts=face_provenance.face_parts(solid.wrapped, origins)
        )
    except KernelError:
        whole = fuse_pattern(hub, blade, angles_deg, refit_edges=False)
        everywhere = fillet_blade_roots(
            single_valid_solid(whole.shape, "joining the blades to the hub"),
            whole.face_parts,
            radius_mm,
            suggest,
            params,
            deadline,
            reduce,
            readable,
        )
        # every blade's junction is the same: report blade 0's share
        return dataclasses.replace(
            everywhere, varying_junction_mm=everywhere.varying_junction_mm / len(angles_deg)
        )


def _touches(shape: cq.Solid, tools: Sequence[TopoDS_Shape]) -> bool:
    """Whether ``shape`` comes within 1e-6 mm of any of ``tools``."""
    for tool in tools:
        distance = BRepExtrema_DistShapeShape(shape.wrapped, tool)
        if not distance.IsDone() or distance.Value() < 1e-6:
            return True
    return False


def _assemble_filleted(
    filleted: TopoDS_Shape, angles_deg: Sequence[float]
) -> tuple[TopoDS_Solid, Origins]:
    """The shell of the hub with every blade: blade 0's blade and fillet faces rotated to each
    angle (blade i's by construction, as each face's part), the hub's faces the hub's.

    The hub's lateral face keeps its own surface and outer wire, its holes that no blade made
    (a set-screw hole), and gets, for each copy, blade 0's fillet-contact wires rotated, their
    curves on the cylinder shifted in u by the copy's angle (as :mod:`torus_cad.kernel.fuse` does
    for the bare intersection curves).
    """
    faces = [TopoDS.Face_s(face) for face in explore(filleted, TopAbs_FACE)]
    lateral = _outer_cylinder(faces)
    blade_faces = [face for face in faces if BRepAdaptor_Surface(face).GetType() in BLADE_SURFACES]
    blade_edges = TopTools_IndexedMapOfShape()
    for face in blade_faces:
        TopExp.MapShapes_s(face, TopAbs_EDGE, blade_edges)
    outer_wire = BRepTools.OuterWire_s(lateral)
    inner_wires = [
        TopoDS.Wire_s(wire) for wire in explore(lateral, TopAbs_WIRE) if not wire.IsSame(outer_wire)
    ]
    blade_holes = [
        wire for wire in inner_wires if blade_edges.Contains(explore(wire, TopAbs_EDGE)[0])
    ]
    lateral_with_holes = BRepBuilderAPI_MakeFace(BRep_Tool.Surface_s(lateral), outer_wire, True)
    for wire in inner_wires:
        if not any(wire.IsSame(hole) for hole in blade_holes):
            lateral_with_holes.Add(wire)
    origins: Origins = []
    for index, angle in enumerate(angles_deg):
        location = _shift_hole_curves(blade_holes, lateral, math.radians(angle - angles_deg[0]))
        for wire in blade_holes:
            lateral_with_holes.Add(TopoDS.Wire_s(wire.Moved(location)))
        origins.extend((face.Moved(location), index) for face in blade_faces)
    if not lateral_with_holes.IsDone():
        raise KernelError(
            "OpenCascade could not cut the filleted blade roots out of the hub's lateral face"
        )
    new_lateral = lateral_with_holes.Face()
    new_lateral.Orientation(lateral.Orientation())
    hub_faces = [
        new_lateral,
        *(
            face
            for face in faces
            if not face.IsSame(lateral)
            and BRepAdaptor_Surface(face).GetType() not in BLADE_SURFACES
        ),
    ]
    origins.extend((face, HUB_PART) for face in hub_faces)
    return solid_of_faces(origins), origins


def _shift_hole_curves(
    holes: Sequence[TopoDS_Wire], lateral: TopoDS_Face, angle_rad: float
) -> TopLoc_Location:
    """The rotation by ``angle_rad`` about +z; the rotated hole edges get their curves on
    ``lateral`` shifted in u."""
    rotation = gp_Trsf()
    rotation.SetRotation(gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), angle_rad)
    # not the empty location even at 0: every copy gets its curves
    location = TopLoc_Location(rotation)
    builder = BRep_Builder()
    for wire in holes:
        u_min, u_max, _, _ = BRepTools.UVBounds_s(lateral, wire)
        shift = angle_rad - _FULL_TURN * math.floor((u_min + angle_rad) / _FULL_TURN)
        if u_max + shift > _FULL_TURN:
            raise KernelError("a filleted blade root crosses the hub's seam")
        for edge in explore(wire, TopAbs_EDGE):
            edge = TopoDS.Edge_s(edge)
            curve = BRep_Tool.CurveOnSurface_s(edge, lateral, 0.0, 0.0)
            if curve is None:
                raise KernelError("a fillet contact edge has no curve on the hub")
            moved = TopoDS.Edge_s(edge.Moved(location))
            builder.UpdateEdge(
                moved, curve.Translated(gp_Vec2d(shift, 0.0)), lateral, BRep_Tool.Tolerance_s(edge)
            )
    return location


def _outer_cylinder(faces: Sequence[TopoDS_Face]) -> TopoDS_Face:
    cylinders = [
        (BRepAdaptor_Surface(face).Cylinder().Radius(), index, face)
        for index, face in enumerate(faces)
        if BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder
    ]
    if not cylinders:
        raise KernelError("the filleted hub has no cylindrical face")
    return max(cylinders, key=lambda item: item[:2])[2]


_FULL_TURN = 2.0 * math.pi
