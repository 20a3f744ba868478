"""Root fillet: a constant-radius fillet along every blade-hub junction (BRepFilletAPI_MakeFillet).

What makes OpenCascade's rolling-ball fillet work on these blades (measured, see the README):

* The lofted blade's side is one B-spline face, closed in u with its seam on the sharp
  trailing edge. A fillet along a junction that runs round such a face fails; the face is
  therefore split into three (u in thirds, ShapeUpgrade_ShapeDivideClosed) before the fuse, so
  the trailing edge is a true edge between two faces, where the fillet's two ends meet.
  A split vertex near the leading edge (u = 1/2), where the section turns tightly, makes the
  fillet fail again, so it is not split in halves.
* The junction edges are the edges between a blade face (B-spline) and a hub face (the hub is
  made of planes, cylinders and cones only).
* When that fails, further tries (:data:`_TRIES`): the side face split in quarters, thirds with
  ten times tighter approximation (SetParams), fifths, sixths. Each saves designs the others do
  not; the first try is the common case and the others cost time only where it fails (each
  stops at FILLET_RETRY_TIME_LIMIT_S, all of them together at FILLET_TRIES_TIME_LIMIT_S).
* Where a blade root comes within about a radius of the hub's end face (the blade ends sit 1 mm
  below it, spec §3.1) so that the fillet would have to roll over the hub's edge, the same tries
  are made on a hub longer at both ends and the result cut back to the hub's length (see
  :func:`fillet_pattern`); where the blade itself passes the hub's end, the cut-back spares the
  blades.
* OpenCascade sometimes builds the fillet and reports success but leaves a flawed solid
  (BRepCheck_Analyzer rejects it); ShapeFix_Shape mends some. A mended solid must pass the same
  checks (one valid closed solid, no less volume) and add no more volume than a fillet's
  cross-section along the junction (REPAIRED_FILLET_MAX_AREA_RADII2 x r^2 per mm).
* OpenCascade's fillet can crash the process on some inputs (a segmentation fault in a few
  per cent of random designs), so it runs in a forked child process with a time limit; the
  result comes back as a BRep string.

* The pattern trick of the fuse applies (:func:`fillet_pattern`): blade 0 alone is joined to
  the hub and filleted, once; its blade and fillet faces are rotated to every blade angle, the
  fillet's contact curves on the hub's cylinder shifted in u, and the shell is assembled from
  known faces. The cost is one blade's fillet for any blade count, and one blade's success is
  every blade's. If that assembly fails its checks, the whole propeller is filleted instead.

When the fillet fails, smaller radii are tried to name one that works in the error message.

Where a blade face bends concavely, seen from outside, tighter than the radius along a junction
edge, a rolling ball of that radius cannot stay in contact with it along the whole bend (its
centre path would have a cusp), and no try above helps. On fuzz designs this happens where the blade's sections are a
millimetre or two long at the hub: a cambered section's own concave stretch, scaled that small,
bends with radii of 0.001-0.9 mm. The bend is the design's (the analytic surface,
:func:`torus_cad.geometry.surface.surface_points`, bends tighter than 0.5 mm too, where the face does:
``scripts/root_concavity.py``), not the loft's, on 9 of the 11 fuzz designs (seeds 0-129) where the
face bends tighter than 0.5 mm. Such a bend is where OpenCascade fails, not a strict bound: a short
enough concave stretch is bridged (seed 128 takes a 0.5 mm fillet with a 0.20 mm analytic bend), and
the other fillet shapes (:data:`FILLET_SHAPE`) save none of these designs. When every try fails and blade 0 has such an edge, the error says so; with
``hub.root_fillet_tight_bends = 'reduce'`` the tries are made once more
with those edges' radius reduced to REDUCED_FILLET_FRACTION of the bend's radius
(:func:`reduced_edge_radii`; OpenCascade blends it with the requested radius along the rest of
that junction loop). The result says so (:class:`RootFillet`: ``constant_radius`` False, the
smallest radius, the length of junction along which the radius varies), and so do the JSON
report and the CLI.

Measured on the fuzz sampler's valid designs (seeds 0-129, 0.5 mm, ``scripts/fillet_rate.py``):
70 of 83 get the requested radius everywhere; see the README for the reduced ones.
"""

from __future__ import annotations

import dataclasses
import io
import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import cadquery as cq
from OCP.BRep import BRep_Builder, BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools
from OCP.ChFi3d import ChFi3d_FilletShape, ChFi3d_Rational
from OCP.GeomAbs import GeomAbs_BezierSurface, GeomAbs_BSplineSurface, GeomAbs_Cylinder, GeomAbs_OffsetSurface
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec2d
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.ShapeFix import ShapeFix_Shape
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideClosed
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_WIRE
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape, TopoDS_Shell, TopoDS_Solid, TopoDS_Wire
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape, TopTools_IndexedMapOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel.checks import precise_volume, single_valid_solid
from torus_cad.kernel.fuse import fuse_pattern, pattern_blades
from torus_cad.kernel.isolation import IsolatedCrash, IsolatedTimeout, run_isolated
from torus_cad.kernel.topology import cut, explore
from torus_cad.tolerances import (
    FILLET_RETRY_TIME_LIMIT_S,
    FILLET_TIME_LIMIT_S,
    FILLET_TRIES_TIME_LIMIT_S,
    REDUCED_FILLET_FRACTION,
    REDUCED_FILLET_SAMPLES,
    REPAIRED_FILLET_MAX_AREA_RADII2,
    VOLUME_CHECK_RELATIVE_PRECISION,
)

#: Faces of these surface types belong to a blade; every other face (plane, cylinder, cone) to the hub.
BLADE_SURFACES = (GeomAbs_BSplineSurface, GeomAbs_BezierSurface, GeomAbs_OffsetSurface)

#: Pieces the blade's closed side face is split into (see the module docstring): thirds work
#: best; quarters (a split vertex at the leading edge), fifths and sixths each save some designs
#: the others do not.
SIDE_FACE_PIECES = (3, 4, 5, 6)

#: BRepFilletAPI_MakeFillet.SetParams (Tang, Tesp, T2d, TApp3d, TolApp2d, Fleche) for a last try:
#: ten times tighter approximation than OpenCascade's defaults; saves some fillets the defaults
#: lose (measured: 3 of 13 failing fuzz designs).
TIGHT_FILLET_PARAMS = (1e-3, 1e-5, 1e-6, 1e-5, 1e-6, 1e-4)

#: The fillet's cross-section law (BRepFilletAPI_MakeFillet's FShape): OpenCascade's default, the
#: rational one, a true circular arc of the radius. The quasi-angular and polynomial laws save none
#: of the 13 fuzz designs (seeds 0-129) the tries leave at 0.5 mm (``scripts/fillet_rate.py --fillet-shape``).
FILLET_SHAPE: ChFi3d_FilletShape = ChFi3d_Rational

#: The tries, in order: (index into SIDE_FACE_PIECES, fillet parameters or None for the defaults).
#: The first is the common case; the others cost time only where it fails.
_TRIES = ((0, None), (1, None), (0, TIGHT_FILLET_PARAMS), (2, None), (3, None))

_FULL_TURN = 2.0 * math.pi

#: Radii tried, as fractions of the requested one, to suggest a radius that works.
_FALLBACK_FRACTIONS = (0.5, 0.25, 0.1)


def prepare_blade_for_fillet(blade: cq.Solid, pieces: int = SIDE_FACE_PIECES[0]) -> cq.Solid:
    """The same blade with its closed side face split into ``pieces`` equal parts in u (the trailing edge becomes an edge)."""
    divide = ShapeUpgrade_ShapeDivideClosed(blade.wrapped)
    divide.SetNbSplitPoints(pieces - 1)
    divide.Perform()
    solids = cq.Shape.cast(divide.Result()).Solids()
    if len(solids) != 1:
        raise KernelError("splitting the blade's side face for the root fillet did not give one solid")
    return solids[0]


def junction_edges(solid: cq.Solid) -> list[TopoDS_Edge]:
    """Edges of ``solid`` between a blade face and a hub face (module docstring)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    edges = []
    for index in range(1, ancestors.Extent() + 1):
        kinds = {BRepAdaptor_Surface(TopoDS.Face_s(face)).GetType() in BLADE_SURFACES
                 for face in ancestors.FindFromIndex(index)}
        if kinds == {True, False}:
            edges.append(TopoDS.Edge_s(ancestors.FindKey(index)))
    return edges


@dataclass(frozen=True)
class RootFillet:
    """A filleted solid and the radii its fillet has (mm).

    Attributes:
        solid: one valid closed solid.
        radius_mm: the requested radius (``hub.root_fillet_radius``).
        smallest_radius_mm: the smallest radius on any junction edge; ``radius_mm`` when the fillet
            has the requested radius everywhere.
        varying_junction_mm: length (mm) of blade 0's junction along which the fillet's radius is
            not constant: the whole junction loops (blade 0 has one where each end meets the hub)
            that hold an edge of reduced radius (:func:`reduced_edge_radii`), as OpenCascade blends
            the radius between that edge and its neighbours; 0 for a constant-radius fillet.
    """

    solid: cq.Solid
    radius_mm: float
    smallest_radius_mm: float
    varying_junction_mm: float = 0.0

    @property
    def constant_radius(self) -> bool:
        """Whether the fillet has the requested radius along the whole junction."""
        return self.varying_junction_mm == 0.0

    def to_dict(self) -> dict[str, float | bool]:
        """For the JSON report."""
        return {"radius_mm": self.radius_mm, "constant_radius": self.constant_radius,
                "smallest_radius_mm": self.smallest_radius_mm,
                "varying_junction_per_blade_mm": self.varying_junction_mm}


def fillet_blade_roots(solid: cq.Solid, radius_mm: float, suggest: bool = True,
                       params: FilletParams | None = None, deadline: float | None = None,
                       reduce: bool = False) -> RootFillet:
    """``solid`` with a fillet of ``radius_mm`` along every blade-hub junction; one valid solid.

    With ``reduce``, junction edges along which a blade face bends too tightly for the ball get a
    smaller radius (:func:`reduced_edge_radii`); without, the fillet has ``radius_mm`` everywhere.
    Raises KernelError ("root fillet failed ...", with a radius that works when one of the
    smaller radii tried does) when OpenCascade cannot make it. ``deadline`` (time.monotonic()
    seconds) cuts the child's time limit short.
    """
    edges = junction_edges(solid)
    if not edges:
        raise KernelError("root fillet failed: no blade-hub junction edges found")
    radii = reduced_edge_radii(solid, edges, radius_mm) if reduce else [radius_mm] * len(edges)
    filleted = _fillet_in_child(solid, edges, radius_mm, params, deadline, radii if reduce else None)
    if filleted is not None:
        return RootFillet(filleted, radius_mm, min(radii), _varying_junction_mm(solid, edges, radii, radius_mm))
    if not suggest:
        raise KernelError(f"root fillet failed at hub.root_fillet_radius = {radius_mm:g} mm")
    raise fillet_failure(solid, radius_mm)


def reduced_edge_radii(solid: cq.Solid, edges: Sequence[TopoDS_Edge], radius_mm: float) -> list[float]:
    """A fillet radius per junction edge (mm): ``radius_mm``, or, where the edge's blade face bends
    concavely (seen from outside) tighter than ``radius_mm`` / REDUCED_FILLET_FRACTION along the
    edge, REDUCED_FILLET_FRACTION x the tightest bend's radius there.

    A rolling ball of radius r cannot stay in contact along a face that bends concavely tighter
    than r (its centre path would have a cusp; a short enough bend is bridged). On fuzz designs whose blade sections are a
    millimetre or two long where they meet the hub, a cambered section's own concave stretch is
    that tight (the analytic surface, not the loft's fit, bends so: measured against
    :func:`torus_cad.geometry.surface.surface_points`)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    radii = []
    for edge in edges:
        faces = [TopoDS.Face_s(face) for face in ancestors.FindFromKey(edge)]
        blade_face = next(face for face in faces if BRepAdaptor_Surface(face).GetType() in BLADE_SURFACES)
        bend_mm = _tightest_concave_radius_along(edge, blade_face)
        radii.append(min(radius_mm, REDUCED_FILLET_FRACTION * bend_mm))
    return radii


def _varying_junction_mm(solid: cq.Solid, edges: Sequence[TopoDS_Edge], radii: Sequence[float], radius_mm: float
                         ) -> float:
    """Length (mm) of the fillet contours (chains of tangent junction edges, as OpenCascade forms
    them) that hold an edge whose radius is below ``radius_mm``."""
    if min(radii, default=radius_mm) >= radius_mm:
        return 0.0
    contours = BRepFilletAPI_MakeFillet(solid.wrapped)
    for edge in edges:
        contours.Add(radius_mm, edge)
    varying = {contours.Contour(edge) for edge, radius in zip(edges, radii) if radius < radius_mm}
    return sum(cq.Edge(edge).Length() for edge in edges if contours.Contour(edge) in varying)


def concave_bend_radius_mm(face: TopoDS_Face, surface: BRepAdaptor_Surface, u: float, v: float) -> float:
    """Radius (mm) of ``face``'s tightest concave bend (seen from outside, from the material's
    outward side) at surface parameters (u, v); inf where it bends only convexly there or its
    curvature is not defined. ``surface`` is ``BRepAdaptor_Surface(face)``."""
    props = BRepLProp_SLProps(surface, u, v, 2, 1e-7)
    if not props.IsCurvatureDefined():
        return math.inf
    outward = -1.0 if face.Orientation() == TopAbs_REVERSED else 1.0  # concave: positive curvature
    concave = max(outward * props.MaxCurvature(), outward * props.MinCurvature())
    return 1.0 / concave if concave > 0.0 else math.inf


def _tightest_concave_radius_along(edge: TopoDS_Edge, face: TopoDS_Face) -> float:
    """The smallest radius (mm) of a concave bend (seen from outside) of ``face`` at REDUCED_FILLET_SAMPLES
    points along ``edge``; inf where it bends only convexly."""
    surface = BRepAdaptor_Surface(face)
    projector = ShapeAnalysis_Surface(BRep_Tool.Surface_s(face))
    curve = BRepAdaptor_Curve(edge)
    first, last = curve.FirstParameter(), curve.LastParameter()
    uvs = (projector.ValueOfUV(curve.Value(first + (last - first) * index / (REDUCED_FILLET_SAMPLES - 1)), 1e-7)
           for index in range(REDUCED_FILLET_SAMPLES))
    return min((concave_bend_radius_mm(face, surface, uv.X(), uv.Y()) for uv in uvs), default=math.inf)


def fillet_failure(solid: cq.Solid, radius_mm: float, tight_bend_mm: float | None = None) -> KernelError:
    """The error for a fillet of ``radius_mm`` that failed on ``solid``; it names a smaller radius
    that works on ``solid`` if one of :data:`_FALLBACK_FRACTIONS` of it does, and, with
    ``tight_bend_mm`` (the tightest concave bend of a blade face along the junction, mm), says that
    the blade bends too tightly for a ball of ``radius_mm`` and how to get a reduced fillet."""
    edges = junction_edges(solid)
    works = next((radius_mm * fraction for fraction in _FALLBACK_FRACTIONS
                  if _fillet_in_child(solid, edges, radius_mm * fraction) is not None), None)
    smallest = radius_mm * min(_FALLBACK_FRACTIONS, default=1.0)
    hint = f"; hub.root_fillet_radius = {works:.3g} mm works" if works is not None else f"; {smallest:.3g} mm fails as well"
    if tight_bend_mm is not None:
        hint += (f"; a blade bends concavely with a {tight_bend_mm:.3g} mm radius at the hub, too tight for the ball: "
                 f"hub.root_fillet_tight_bends = 'reduce' makes the fillet smaller there")
    return KernelError(f"root fillet failed: OpenCascade could not fillet the blade roots at "
                       f"hub.root_fillet_radius = {radius_mm:g} mm{hint}")


#: BRepFilletAPI_MakeFillet.SetParams arguments: Tang, Tesp, T2d, TApp3d, TolApp2d, Fleche.
FilletParams = tuple[float, float, float, float, float, float]

#: Builds the run-out hub for a given extension (mm): a plain hub that much longer at each end,
#: and the tools that cut it back to the real hub afterwards (see :func:`fillet_pattern`).
RunOutHub = Callable[[float], tuple[cq.Solid, list[TopoDS_Shape]]]

#: The run-out hub's extension at each end, in fillet radii.
_RUN_OUT_RADII = 3.0


def fillet_pattern(hub: cq.Solid, blade: cq.Solid, angles_deg: Sequence[float], radius_mm: float,
                   run_out: RunOutHub | None = None, reduce_where_tight: bool = False) -> RootFillet:
    """The filleted propeller from one filleted blade: blade 0 joined to ``hub``, filleted, patterned.

    ``blade`` is built at ``angles_deg[0]``; its side face is split as
    :func:`prepare_blade_for_fillet` does, and the fillet made as each of :data:`_TRIES` says
    until it works. Where a blade root comes within about a radius of the hub's end face, the
    fillet would have to roll over the hub's edge and fails. With ``run_out``, the tries are then
    made on a hub longer at both ends (the fillet runs out past the end), and the result is cut
    back to the hub's length (the fillet ends in the end face, as it would when a longer filleted
    hub is faced) with the bore and set-screw hole cut at the same time. Where the blade itself
    passes the hub's end plane, the cut-back's end slabs have the blades cut out of them, so the
    blades' parts past the end stay as they are (the fillet still ends flush with the end face).
    The first try stops at FILLET_TIME_LIMIT_S; each further one at FILLET_RETRY_TIME_LIMIT_S, and all
    of them together at FILLET_TRIES_TIME_LIMIT_S.

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
    filleted = _first_that_works(hub, split, angles_deg, radius_mm, _TRIES[1:], deadline, reduce=False)
    if filleted is None:
        filleted = attempt.tries(split, deadline, reduce=False)
    if filleted is not None:
        return filleted
    joined = single_valid_solid(fuse_pattern(hub, split[0], angles_deg[:1]).shape, "joining blade 0 to the hub")
    smallest_mm = min(reduced_edge_radii(joined, junction_edges(joined), radius_mm))
    if smallest_mm < radius_mm and not reduce_where_tight:
        raise fillet_failure(joined, radius_mm, tight_bend_mm=smallest_mm / REDUCED_FILLET_FRACTION)
    if smallest_mm < radius_mm:
        deadline = time.monotonic() + FILLET_TRIES_TIME_LIMIT_S  # the reduced tries get the same time again
        filleted = _first_that_works(hub, split, angles_deg, radius_mm, _TRIES, deadline, reduce=True)
        if filleted is None:
            filleted = attempt.tries(split, deadline, reduce=True)
        if filleted is not None:
            return filleted
    # Every try failed: the error names a smaller radius that works on blade 0, if one does.
    raise fillet_failure(joined, radius_mm)


def _first_that_works(hub: cq.Solid, split: _LazySplits, angles_deg: Sequence[float], radius_mm: float,
                      tries: Sequence[tuple[int, FilletParams | None]], deadline: float, reduce: bool,
                      finish: Callable[[RootFillet], RootFillet] = lambda made: made) -> RootFillet | None:
    """The first of ``tries`` (as :data:`_TRIES`) that works on ``hub``, passed through ``finish``
    (a KernelError there counts as a failed try); None if none does. Each try stops at
    FILLET_RETRY_TIME_LIMIT_S (one that saves a design does so in under a second), all by ``deadline``."""
    for index, params in tries:
        try:
            return finish(_fillet_and_pattern(hub, split[index], angles_deg, radius_mm, suggest=False, params=params,
                                              deadline=min(deadline, time.monotonic() + FILLET_RETRY_TIME_LIMIT_S),
                                              reduce=reduce))
        except KernelError:
            pass
    return None


class _RunOut:
    """The tries on the run-out hub (see :func:`fillet_pattern`), made when first needed."""

    def __init__(self, blade: cq.Solid, angles_deg: Sequence[float], radius_mm: float, run_out: RunOutHub | None) -> None:
        self.blade, self.angles_deg, self.radius_mm, self.run_out = blade, angles_deg, radius_mm, run_out
        self.made: tuple[cq.Solid, list[TopoDS_Shape]] | None = None

    def _hub_and_tools(self) -> tuple[cq.Solid, list[TopoDS_Shape]]:
        if self.made is None:
            assert self.run_out is not None
            extended, tools = self.run_out(_RUN_OUT_RADII * self.radius_mm)
            if _touches(self.blade, tools[:2]):  # the blade itself reaches past a hub end: the cut-back keeps it there
                blades = [copy.wrapped for copy in pattern_blades(self.blade, self.angles_deg)]
                tools = [cut(slab, blades, "keep the blades out of the run-out's cut-back") for slab in tools[:2]] + tools[2:]
            self.made = extended, tools
        return self.made

    def tries(self, split: _LazySplits, deadline: float, reduce: bool) -> RootFillet | None:
        """The first of :data:`_TRIES` that works on the run-out hub, cut back; None if none does by ``deadline``."""
        if self.run_out is None or time.monotonic() >= deadline:
            return None
        extended, tools = self._hub_and_tools()

        def cut_back(made: RootFillet) -> RootFillet:
            solid = single_valid_solid(cq.Shape.cast(cut(made.solid.wrapped, tools,
                                                         "cut the run-out hub back to the hub's length")),
                                       "cutting the run-out hub back")
            return dataclasses.replace(made, solid=solid)

        return _first_that_works(extended, split, self.angles_deg, self.radius_mm, _TRIES, deadline, reduce, cut_back)


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


def _fillet_and_pattern(hub: cq.Solid, blade: cq.Solid, angles_deg: Sequence[float], radius_mm: float,
                        suggest: bool = True, params: FilletParams | None = None,
                        deadline: float | None = None, reduce: bool = False) -> RootFillet:
    single = fuse_pattern(hub, blade, angles_deg[:1]).shape
    filleted = fillet_blade_roots(single_valid_solid(single, "joining blade 0 to the hub"), radius_mm, suggest, params,
                                  deadline, reduce)
    if len(angles_deg) == 1:
        return filleted
    try:
        solid = single_valid_solid(cq.Shape.cast(_assemble_filleted(filleted.solid.wrapped, angles_deg)),
                                   "patterning the filleted blade")
        return dataclasses.replace(filleted, solid=solid)
    except KernelError:
        whole = fuse_pattern(hub, blade, angles_deg).shape
        everywhere = fillet_blade_roots(single_valid_solid(whole, "joining the blades to the hub"), radius_mm, suggest,
                                        params, deadline, reduce)
        # every blade's junction is the same: report blade 0's share
        return dataclasses.replace(everywhere, varying_junction_mm=everywhere.varying_junction_mm / len(angles_deg))


def _touches(shape: cq.Solid, tools: Sequence[TopoDS_Shape]) -> bool:
    """Whether ``shape`` comes within 1e-6 mm of any of ``tools``."""
    for tool in tools:
        distance = BRepExtrema_DistShapeShape(shape.wrapped, tool)
        if not distance.IsDone() or distance.Value() < 1e-6:
            return True
    return False




def _assemble_filleted(filleted: TopoDS_Shape, angles_deg: Sequence[float]) -> TopoDS_Solid:
    """The shell of the hub with every blade: blade 0's blade and fillet faces rotated to each angle.

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
    inner_wires = [TopoDS.Wire_s(wire) for wire in explore(lateral, TopAbs_WIRE) if not wire.IsSame(outer_wire)]
    blade_holes = [wire for wire in inner_wires if blade_edges.Contains(explore(wire, TopAbs_EDGE)[0])]
    lateral_with_holes = BRepBuilderAPI_MakeFace(BRep_Tool.Surface_s(lateral), outer_wire, True)
    for wire in inner_wires:
        if not any(wire.IsSame(hole) for hole in blade_holes):
            lateral_with_holes.Add(wire)
    builder, shell = BRep_Builder(), TopoDS_Shell()
    builder.MakeShell(shell)
    for angle in angles_deg:
        location = _shift_hole_curves(blade_holes, lateral, math.radians(angle - angles_deg[0]))
        for wire in blade_holes:
            lateral_with_holes.Add(TopoDS.Wire_s(wire.Moved(location)))
        for face in blade_faces:
            builder.Add(shell, face.Moved(location))
    if not lateral_with_holes.IsDone():
        raise KernelError("OpenCascade could not cut the filleted blade roots out of the hub's lateral face")
    new_lateral = lateral_with_holes.Face()
    new_lateral.Orientation(lateral.Orientation())
    builder.Add(shell, new_lateral)
    for face in faces:
        if not face.IsSame(lateral) and BRepAdaptor_Surface(face).GetType() not in BLADE_SURFACES:
            builder.Add(shell, face)
    shell.Closed(BRep_Tool.IsClosed_s(shell))
    solid = TopoDS_Solid()
    builder.MakeSolid(solid)
    builder.Add(solid, shell)
    return solid


def _shift_hole_curves(holes: Sequence[TopoDS_Wire], lateral: TopoDS_Face, angle_rad: float) -> TopLoc_Location:
    """The rotation by ``angle_rad`` about +z; the rotated hole edges get their curves on ``lateral`` shifted in u."""
    rotation = gp_Trsf()
    rotation.SetRotation(gp_Ax1(gp_Pnt(0.0, 0.0, 0.0), gp_Dir(0.0, 0.0, 1.0)), angle_rad)
    location = TopLoc_Location(rotation)  # not the empty location even at 0: every copy gets its curves
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
            builder.UpdateEdge(moved, curve.Translated(gp_Vec2d(shift, 0.0)), lateral, BRep_Tool.Tolerance_s(edge))
    return location


def _outer_cylinder(faces: Sequence[TopoDS_Face]) -> TopoDS_Face:
    cylinders = [(BRepAdaptor_Surface(face).Cylinder().Radius(), index, face) for index, face in enumerate(faces)
                 if BRepAdaptor_Surface(face).GetType() == GeomAbs_Cylinder]
    if not cylinders:
        raise KernelError("the filleted hub has no cylindrical face")
    return max(cylinders, key=lambda item: item[:2])[2]




def fillet_edges(solid: cq.Solid, edges: list[TopoDS_Edge], radius_mm: float,
                 params: FilletParams | None = None, edge_radii: Sequence[float] | None = None) -> cq.Solid | None:
    """The fillet in this process: the checked solid, or None when OpenCascade fails or the result is unsound.

    ``params``: BRepFilletAPI_MakeFillet.SetParams values (default: OpenCascade's). ``edge_radii``:
    a radius per edge (mm) instead of ``radius_mm`` on all; OpenCascade blends the radius between
    edges of one contour that differ."""
    fillet = BRepFilletAPI_MakeFillet(solid.wrapped, FILLET_SHAPE)
    if params is not None:
        fillet.SetParams(*params)
    for edge in edges:
        fillet.Add(radius_mm, edge)
    for edge, radius in zip(edges, edge_radii or ()):
        if radius < radius_mm:
            contour = fillet.Contour(edge)
            index = next(i for i in range(1, fillet.NbEdges(contour) + 1) if fillet.Edge(contour, i).IsSame(edge))
            fillet.SetRadius(radius, contour, index)
    try:
        fillet.Build()
    except Exception:  # OCCT raises Standard_Failure subclasses through OCP
        return None
    if not fillet.IsDone():
        return None
    repaired = False
    try:
        result = single_valid_solid(cq.Shape.cast(fillet.Shape()), "the root fillet")
    except KernelError:  # OpenCascade sometimes builds the fillet but leaves flaws ShapeFix mends
        fix = ShapeFix_Shape(fillet.Shape())
        fix.Perform()
        try:
            result = single_valid_solid(cq.Shape.cast(fix.Shape()), "the repaired root fillet")
        except KernelError:
            return None
        repaired = True
    added_mm3 = (precise_volume(result, VOLUME_CHECK_RELATIVE_PRECISION)
                 - precise_volume(solid, VOLUME_CHECK_RELATIVE_PRECISION))
    # A concave fillet only adds material: a smaller volume means a wrong result. A repaired one
    # must also add no more than a fillet's cross-section along the junction.
    if added_mm3 < 0.0:
        return None
    if repaired and added_mm3 > REPAIRED_FILLET_MAX_AREA_RADII2 * radius_mm ** 2 * sum(cq.Edge(edge).Length()
                                                                                         for edge in edges):
        return None
    return result


def _fillet_in_child(solid: cq.Solid, edges: list[TopoDS_Edge], radius_mm: float,
                     params: FilletParams | None = None, deadline: float | None = None,
                     edge_radii: Sequence[float] | None = None) -> cq.Solid | None:
    """:func:`fillet_edges` in a forked child (torus_cad.kernel.isolation): a crash or a hang there is
    a failed fillet, not a dead process.

    The child gets FILLET_TIME_LIMIT_S, or what is left until ``deadline`` (time.monotonic()) if less."""
    limit_s = FILLET_TIME_LIMIT_S if deadline is None else min(FILLET_TIME_LIMIT_S, deadline - time.monotonic())
    if limit_s <= 0.0:
        return None

    def fillet_as_brep() -> bytes | None:
        try:
            result = fillet_edges(solid, edges, radius_mm, params, edge_radii)
        except Exception:  # OpenCascade's failures (Standard_Failure and others): a failed fillet
            return None
        return None if result is None else _to_brep(result.wrapped)

    try:
        data = run_isolated(fillet_as_brep, timeout_s=limit_s, what="the root fillet")
    except (IsolatedTimeout, IsolatedCrash):
        return None
    if not data:
        return None
    return single_valid_solid(cq.Shape.cast(_from_brep(data)), "the root fillet")


def _to_brep(shape: TopoDS_Shape) -> bytes:
    stream = io.BytesIO()
    BRepTools.Write_s(shape, stream)
    return stream.getvalue()


def _from_brep(data: bytes) -> TopoDS_Shape:
    shape = TopoDS_Shape()
    BRepTools.Read_s(shape, io.BytesIO(data), BRep_Builder())
    return shape
