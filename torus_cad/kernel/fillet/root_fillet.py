"""Root fillet: a constant-radius fillet along every blade-hub junction (BRepFilletAPI_MakeFillet).

The tries (:data:`FILLET_TRIES`) and the result type. The lofted blade's side is one B-spline face
closed in u with its seam on the trailing edge; a fillet along a junction that runs round such a
face fails, so the face is split (ShapeUpgrade_ShapeDivideClosed, in thirds first) before the fuse.
Further tries split it otherwise or tighten the approximation; each stops at
FILLET_RETRY_TIME_LIMIT_S, all together at FILLET_TRIES_TIME_LIMIT_S. When every try fails, smaller
radii are tried to name one that works in the error. Beside this module: one fillet in a child
process and its repair (``one_fillet``), the blade bends too tight for the ball
(``tight_bends``) and the pattern trick that fillets one blade for all (``pattern``).
Why each step is there: docs/explanation/how-the-solid-is-built.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cadquery as cq
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideClosed
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS, TopoDS_Edge
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel.fillet.continuity import c1_fillet
from torus_cad.kernel.fillet.one_fillet import FilletParams, fillet_in_child
from torus_cad.kernel.fillet.tight_bends import reduced_edge_radii, varying_junction_mm
from torus_cad.kernel.readable_edges import readable_edges
from torus_cad.kernel.topology import BLADE_SURFACES

#: Pieces the blade's closed side face is split into (see the module docstring): thirds work
#: best; quarters (a split vertex at the leading edge), fifths and sixths each save some designs
#: the others do not.
SIDE_FACE_PIECES = (3, 4, 5, 6)


#: BRepFilletAPI_MakeFillet.SetParams (Tang, Tesp, T2d, TApp3d, TolApp2d, Fleche) for a last try:
#: ten times tighter approximation than OpenCascade's defaults; saves some fillets the defaults
#: lose (``scripts/fillet_rate.py`` counts them).
TIGHT_FILLET_PARAMS = (1e-3, 1e-5, 1e-6, 1e-5, 1e-6, 1e-4)


#: The tries, in order: (index into SIDE_FACE_PIECES, fillet parameters or None for the defaults).
#: The first is the common case; the others cost time only where it fails.
FILLET_TRIES = ((0, None), (1, None), (0, TIGHT_FILLET_PARAMS), (2, None), (3, None))


#: A fillet whose solid has a tolerance over this (mm) counts as failed, so the next try is made:
#: OpenCascade can return a fillet whose surfaces part from the blade by up to 0.07 mm (an 8-blade
#: design with 45 % thick sections and a 0.5 mm fillet), valid in memory but not once a STEP reader
#: gives its edges what it samples (edges shorter than that, curves parting more); good fillets stay
#: under 2e-3 mm.
FILLET_TOLERANCE_MAX_MM = 0.01

#: Radii tried, as fractions of the requested one, to suggest a radius that works.
_FALLBACK_FRACTIONS = (0.5, 0.25, 0.1)


def prepare_blade_for_fillet(blade: cq.Solid, pieces: int = SIDE_FACE_PIECES[0]) -> cq.Solid:
    """The same blade with its closed side face split into ``pieces`` equal parts in u (the trailing
    edge becomes an edge)."""
    divide = ShapeUpgrade_ShapeDivideClosed(blade.wrapped)
    divide.SetNbSplitPoints(pieces - 1)
    divide.Perform()
    solids = cq.Shape.cast(divide.Result()).Solids()
    if len(solids) != 1:
        raise KernelError(
            "splitting the blade's side face for the root fillet did not give one solid"
        )
    return solids[0]


def junction_edges(solid: cq.Solid) -> list[TopoDS_Edge]:
    """Edges of ``solid`` between a blade face and a hub face (module docstring)."""
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    edges = []
    for index in range(1, ancestors.Extent() + 1):
        kinds = {
            BRepAdaptor_Surface(TopoDS.Face_s(face)).GetType() in BLADE_SURFACES
            for face in ancestors.FindFromIndex(index)
        }
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
        face_parts: the part each face of ``solid`` came from, in the order of ``solid.Faces()``
            (:mod:`torus_cad.kernel.face_provenance`; a fillet face is its blade's).
    """

    solid: cq.Solid
    radius_mm: float
    smallest_radius_mm: float
    varying_junction_mm: float = 0.0
    face_parts: tuple[int, ...] = ()

    @property
    def constant_radius(self) -> bool:
        """Whether the fillet has the requested radius along the whole junction."""
        return self.varying_junction_mm == 0.0

    def to_dict(self) -> dict[str, float | bool]:
        """For the JSON report."""
        return {
            "radius_mm": self.radius_mm,
            "constant_radius": self.constant_radius,
            "smallest_radius_mm": self.smallest_radius_mm,
            "varying_junction_per_blade_mm": self.varying_junction_mm,
        }


def fillet_blade_roots(
    solid: cq.Solid,
    face_parts: Sequence[int],
    radius_mm: float,
    suggest: bool = True,
    params: FilletParams | None = None,
    deadline: float | None = None,
    reduce: bool = False,
    readable: bool = True,
) -> RootFillet:
    """``solid`` (its faces' parts ``face_parts``) with a fillet of ``radius_mm`` along every
    blade-hub junction; one valid solid, with its faces' parts.

    With ``reduce``, junction edges along which a blade face bends too tightly for the ball get a
    smaller radius (:func:`reduced_edge_radii`); without, the fillet has ``radius_mm`` everywhere.
    Raises KernelError ("root fillet failed ...", with a radius that works when one of the
    smaller radii tried does) when OpenCascade cannot make it. ``deadline`` (time.monotonic()
    seconds) cuts the child's time limit short. With ``readable`` (unless a boolean still changes
    the solid), its edges are made to read back from STEP as they are (:func:`made_readable`).
    """
    edges = junction_edges(solid)
    if not edges:
        raise KernelError("root fillet failed: no blade-hub junction edges found")
    radii = reduced_edge_radii(solid, edges, radius_mm) if reduce else [radius_mm] * len(edges)
    filleted = fillet_in_child(
        solid, edges, radius_mm, params, deadline, radii if reduce else None, face_parts
    )
    if filleted is not None:
        try:  # no C0 face or edge (kernel.fillet_continuity)
            smooth, parts = c1_fillet(filleted.solid, filleted.face_parts)
        # the split would not give a valid solid: the fillet as OpenCascade made it
        except KernelError:
            smooth, parts = filleted.solid, tuple(filleted.face_parts)
        if readable:
            smooth, parts = made_readable(smooth, parts)
        _check_tolerance(smooth, radius_mm)
        return RootFillet(
            smooth,
            radius_mm,
            min(radii),
            varying_junction_mm(solid, edges, radii, radius_mm),
            parts,
        )
    if not suggest:
        raise KernelError(f"root fillet failed at hub.root_fillet_radius = {radius_mm:g} mm")
    raise fillet_failure(solid, radius_mm)


def _check_tolerance(solid: cq.Solid, radius_mm: float) -> None:
    """KernelError when ``solid``'s greatest tolerance is over FILLET_TOLERANCE_MAX_MM (the fillet
    of ``radius_mm`` is then only near its blade and hub: the module's FILLET_TOLERANCE_MAX_MM)."""
    greatest = ShapeAnalysis_ShapeTolerance().Tolerance(solid.wrapped, 1)
    if greatest > FILLET_TOLERANCE_MAX_MM:
        raise KernelError(
            "root fillet failed at hub.root_fillet_radius "
            f"= {radius_mm:g} mm: OpenCascade's fillet "
            "parts from the blade or hub by up to "
            f"{greatest:.2g} mm (over {FILLET_TOLERANCE_MAX_MM:g} mm)"
        )


def made_readable(solid: cq.Solid, face_parts: Sequence[int]) -> tuple[cq.Solid, tuple[int, ...]]:
    """``solid`` with edges that read back from STEP as they are, and its faces' parts
    (:mod:`torus_cad.kernel.readable_edges`); ``solid`` with its p-curves squared but no edge split
    if the split would not give a valid solid (the build's read-back check then names what is
    left)."""
    try:
        readable = readable_edges(solid, face_parts)
    except KernelError:
        return solid, tuple(face_parts)
    return readable.solid, readable.face_parts


def fillet_failure(
    solid: cq.Solid, radius_mm: float, tight_bend_mm: float | None = None
) -> KernelError:
    """The error for a fillet of ``radius_mm`` that failed on ``solid``; it names a smaller radius
    that works on ``solid`` if one of :data:`_FALLBACK_FRACTIONS` of it does, and, with
    ``tight_bend_mm`` (the tightest concave bend of a blade face along the junction, mm), says that
    the blade bends too tightly for a ball of ``radius_mm`` and how to get a reduced fillet."""
    edges = junction_edges(solid)
    works = next(
        (
            radius_mm * fraction
            for fraction in _FALLBACK_FRACTIONS
            if fillet_in_child(solid, edges, radius_mm * fraction) is not None
        ),
        None,
    )
    smallest = radius_mm * min(_FALLBACK_FRACTIONS, default=1.0)
    hint = (
        f"; hub.root_fillet_radius = {works:.3g} mm works"
        if works is not None
        else f"; {smallest:.3g} mm fails as well"
    )
    if tight_bend_mm is not None:
        hint += (
            f"; a blade bends concavely with a {tight_bend_mm:.3g} mm "
            "radius at the hub, too tight for the ball: "
            f"hub.root_fillet_tight_bends = 'reduce' makes the fillet smaller there"
        )
    return KernelError(
        f"root fillet failed: OpenCascade could not fillet the blade roots at "
        f"hub.root_fillet_radius = {radius_mm:g} mm{hint}"
    )
