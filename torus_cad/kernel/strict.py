"""The strict validity check: BRepCheck_Analyzer and BRepAlgoAPI_Check (small edges,
self-interference).

``BRepCheck_Analyzer`` checks topology and tolerances only; ``BRepAlgoAPI_Check(shape, True, True)``
(what FreeCAD's "Check geometry" runs) also intersects every pair of sub-shapes whose boxes
overlap and reports faces that cross themselves or each other. On the whole propeller that costs
several times the build, and most of it is repeated: the blades are exact copies of one blade.

So where the solid is a hub with n copies of one blade (the faces of copy k are blade 0's faces,
the same TopoDS faces, moved by a rotation about z: what the shared-intersection fuse and the
patterned root fillet build), the self-interference test runs on

* the hub's faces and blade 0's faces together (blade 0 against itself and against the hub; the
  hub against itself), plus every other copy whose box meets a hub face whose surface is not
  symmetric about the axis (a set-screw hole, a bore flat): every other copy meets the
  axisymmetric hub faces exactly as blade 0, rotated, does;
* blade 0 against each copy k = 1 .. n // 2 by their exact distance, which must exceed
  STRICT_BLADE_SEPARATION_MM (pair (i, j) is pair (0, j - i) rotated, and (0, k) is (0, n - k)).

Any other solid is checked whole.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from OCP.Bnd import Bnd_Box
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Check
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.GeomAbs import GeomAbs_Cone, GeomAbs_Cylinder, GeomAbs_Plane
from OCP.gp import gp_Dir, gp_Pnt
from OCP.TopAbs import TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedMapOfShape

from torus_cad.errors import KernelError
from torus_cad.kernel.checks import compound, single_valid_solid
from torus_cad.kernel.topology import ShapeT, occ
from torus_cad.runtime.isolation import IsolatedTimeout, run_isolated
from torus_cad.tolerances import STRICT_CHECK_TIME_LIMIT_S

#: Axis directions and positions within this of the z axis (unit vector components, mm) count as on
#: it.
STRICT_AXIS_TOLERANCE = 1e-9

#: Two blade copies closer than this (mm) count as interfering (their faces' tolerances are ~1e-7
#: mm).
STRICT_BLADE_SEPARATION_MM = 1e-4


class CheckScope(StrEnum):
    """What the self-interference test ran on (the value is what the JSON report says)."""

    PATTERN = "hub with blade 0, blade 0 against every other blade"
    WHOLE = "whole solid"


@dataclass(frozen=True)
class StrictCheck:
    """The checks a solid passed, and their cost.

    Attributes:
        scope: what the self-interference test ran on.
        blades_checked: blade copies in the self-interference test (all of them when whole).
        seconds: wall-clock seconds of the whole check.
    """

    scope: CheckScope
    blades_checked: int
    seconds: float

    def to_dict(self) -> dict[str, Any]:
        """For the JSON report's ``checks`` block: every check named is one the solid passed."""
        return {
            "brepcheck": True,
            "boolean_check_small_edges": True,
            "boolean_check_self_intersection": True,
            "scope": self.scope.value,
            "blades_checked": self.blades_checked,
            "seconds": self.seconds,
        }


@dataclass(frozen=True)
class _Pattern:
    """A solid's faces as hub faces and n copies of blade 0's faces (copy k's faces in blade 0's
    order)."""

    hub: list[TopoDS_Face]
    copies: list[list[TopoDS_Face]]


def strict_valid_solid(shape: ShapeT, what: str) -> tuple[ShapeT, StrictCheck]:
    """The one solid of ``shape`` (of its kind: OpenCascade's or cadquery's) and what it passed;
    KernelError naming the check and the face otherwise.

    :func:`torus_cad.kernel.checks.single_valid_solid` (one solid, one closed shell,
    BRepCheck_Analyzer), then BRepAlgoAPI_Check with the small-edge and self-interference tests, on
    the scope the module docstring describes.
    """
    start = time.perf_counter()
    solid = single_valid_solid(shape, what)
    occ_solid = occ(solid)
    pattern = blade_pattern(occ_solid)
    if pattern is None or len(pattern.copies) < 2:
        _raise_on_faults(occ_solid, occ_solid, pattern, what)
        return solid, StrictCheck(
            CheckScope.WHOLE, len(pattern.copies) if pattern else 0, time.perf_counter() - start
        )
    checked = [0, *_copies_near_asymmetric_hub_faces(pattern)]
    scope = compound([*pattern.hub, *(face for k in checked for face in pattern.copies[k])])
    _raise_on_faults(scope, occ_solid, pattern, what)
    _check_blade_separation(pattern, occ_solid, what)
    return solid, StrictCheck(CheckScope.PATTERN, len(checked), time.perf_counter() - start)


def boolean_check_faults(shape: TopoDS_Shape) -> list[tuple[str, list[TopoDS_Shape]]]:
    """BRepAlgoAPI_Check(shape, small edges, self-interference): (status name, faulty shapes) per
    fault.

    Without OpenCascade's thread pool: the check runs in a forked child, where the parent's pool
    threads are not, and a parallel check waits for them forever."""
    check = BRepAlgoAPI_Check()
    check.SetData(shape, True, True)
    check.SetRunParallel(False)
    check.Perform()
    if check.IsValid():
        return []
    return [
        (
            str(fault.GetCheckStatus()).rsplit(".", 1)[-1].removeprefix("BOPAlgo_"),
            [*fault.GetFaultyShapes1(), *fault.GetFaultyShapes2()],
        )
        for fault in check.Result()
    ]


#: A faulty sub-shape as the child reports it: the index of a face in the solid's faces, or a shape
#: type's name.
_Where = int | str


def _indexed_faults(shape: TopoDS_Shape, solid: TopoDS_Shape) -> list[tuple[str, list[_Where]]]:
    """:func:`boolean_check_faults` as plain data (what a child process can send back)."""
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(solid, TopAbs_FACE, faces)
    return [
        (
            status,
            [
                faces.FindIndex(found) - 1
                if found.ShapeType() == TopAbs_FACE
                else str(found.ShapeType()).rsplit(".", 1)[-1].removeprefix("TopAbs_").lower()
                for found in shapes
            ],
        )
        for status, shapes in boolean_check_faults(shape)
    ]


def _raise_on_faults(
    shape: TopoDS_Shape, solid: TopoDS_Shape, pattern: _Pattern | None, what: str
) -> None:
    try:
        faults = run_isolated(
            _indexed_faults,
            shape,
            solid,
            timeout_s=STRICT_CHECK_TIME_LIMIT_S,
            what=f"{what}: BRepAlgoAPI_Check (self-interference / small-edge test)",
        )
    except IsolatedTimeout as error:
        raise KernelError(
            f"{error} (the limit); the solid is not known to be free of self-intersections, so "
            "nothing is written: a simpler design (fewer sections, no root fillet) checks faster"
        ) from None
    if faults:
        status, found = faults[0]
        where = ", ".join(_describe(item, solid, pattern) for item in found) or "the shape"
        raise KernelError(
            f"{what}: BRepAlgoAPI_Check finds {len(faults)} fault(s), first {status} "
            f"(self-interference / small-edge test) on {where}"
        )


def _describe(where: _Where, solid: TopoDS_Shape, pattern: _Pattern | None) -> str:
    """'face 7 of solid.Faces() (blade 0, BSplineSurface)' for a face index; the shape type
    otherwise."""
    if isinstance(where, str) or where < 0:
        return str(where) if isinstance(where, str) else "a face of the checked shape"
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(solid, TopAbs_FACE, faces)
    face = TopoDS.Face_s(faces.FindKey(where + 1))
    part = "hub or blade"
    if pattern is not None:
        blades = [
            k for k, copy in enumerate(pattern.copies) if any(face.IsSame(other) for other in copy)
        ]
        part = f"blade {blades[0]}" if blades else "hub"
    kind = str(BRepAdaptor_Surface(face).GetType()).rsplit(".", 1)[-1].removeprefix("GeomAbs_")
    return f"face {where} of solid.Faces() ({part}, {kind})"


def blade_pattern(solid: TopoDS_Shape) -> _Pattern | None:
    """The solid's faces as hub and blade copies, or None when they are not such a pattern.

    Copies share their faces' geometry (the same TShape) and differ by a location, a rotation
    about z; a face whose TShape is used once is a hub face. Copy k is the one whose faces are
    placed as the first shared face's k-th use.
    """
    faces = [TopoDS.Face_s(face) for face in _face_list(solid)]
    groups: list[list[TopoDS_Face]] = []
    for face in faces:
        group = next((group for group in groups if group[0].IsPartner(face)), None)
        if group is None:
            groups.append([face])
        else:
            group.append(face)
    shared = [group for group in groups if len(group) > 1]
    if not shared or len({len(group) for group in shared}) != 1:
        return None
    locations = [face.Location() for face in shared[0]]
    if not all(_is_rotation_about_z(location.Transformation()) for location in locations):
        return None
    copies: list[list[TopoDS_Face]] = [[] for _ in locations]
    for group in shared:
        indices = [
            next(
                (
                    k
                    for k, location in enumerate(locations)
                    if _same_placement(face.Location(), location)
                ),
                -1,
            )
            for face in group
        ]
        if sorted(indices) != list(range(len(locations))):
            return None  # not one face per copy
        for face, index in zip(group, indices, strict=True):
            copies[index].append(face)
    return _Pattern([group[0] for group in groups if len(group) == 1], copies)


def _same_placement(first: TopLoc_Location, second: TopLoc_Location) -> bool:
    """Whether two locations move points the same way (a chain with a zero rotation in it is not
    IsEqual to the chain without, and places the face the same)."""
    a, b = first.Transformation(), second.Transformation()
    return all(
        abs(a.Value(row, column) - b.Value(row, column)) <= STRICT_AXIS_TOLERANCE
        for row in range(1, 4)
        for column in range(1, 5)
    )


def _face_list(shape: TopoDS_Shape) -> list[TopoDS_Shape]:
    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(shape, TopAbs_FACE, faces)
    return [faces.FindKey(index) for index in range(1, faces.Extent() + 1)]


def _is_rotation_about_z(transformation: Any) -> bool:
    axis = gp_Dir(0.0, 0.0, 1.0).Transformed(transformation)
    origin = gp_Pnt(0.0, 0.0, 0.0).Transformed(transformation)
    return (
        axis.Z() > 1.0 - STRICT_AXIS_TOLERANCE
        and origin.Distance(gp_Pnt(0.0, 0.0, 0.0)) < STRICT_AXIS_TOLERANCE
        and not transformation.IsNegative()
    )


def _axisymmetric_surface(face: TopoDS_Face) -> bool:
    """Whether ``face``'s surface is symmetric about the z axis: a plane normal to it, a cylinder or
    cone about it."""
    surface = BRepAdaptor_Surface(face)
    kind = surface.GetType()
    if kind == GeomAbs_Plane:
        return abs(surface.Plane().Axis().Direction().Z()) > 1.0 - STRICT_AXIS_TOLERANCE
    if kind not in (GeomAbs_Cylinder, GeomAbs_Cone):
        return False
    axis = surface.Cylinder().Axis() if kind == GeomAbs_Cylinder else surface.Cone().Axis()
    location = axis.Location()
    return (
        abs(axis.Direction().Z()) > 1.0 - STRICT_AXIS_TOLERANCE
        and abs(location.X()) < STRICT_AXIS_TOLERANCE
        and abs(location.Y()) < STRICT_AXIS_TOLERANCE
    )


def _box(shapes: Sequence[TopoDS_Shape]) -> Bnd_Box:
    box = Bnd_Box()
    for shape in shapes:
        BRepBndLib.Add_s(shape, box)
    box.Enlarge(STRICT_BLADE_SEPARATION_MM)
    return box


def _copies_near_asymmetric_hub_faces(pattern: _Pattern) -> list[int]:
    """Copies other than blade 0 whose box meets the box of a hub face that is not symmetric about
    z."""
    asymmetric = [face for face in pattern.hub if not _axisymmetric_surface(face)]
    if not asymmetric:
        return []
    boxes = [_box([face]) for face in asymmetric]
    return [
        k
        for k in range(1, len(pattern.copies))
        if any(not _box(pattern.copies[k]).IsOut(box) for box in boxes)
    ]


def _check_blade_separation(pattern: _Pattern, solid: TopoDS_Shape, what: str) -> None:
    first = compound(pattern.copies[0])
    for k in range(1, len(pattern.copies) // 2 + 1):
        other = compound(pattern.copies[k])
        if _box(pattern.copies[0]).IsOut(_box(pattern.copies[k])):
            continue
        distance = BRepExtrema_DistShapeShape(first, other)
        if not distance.IsDone():
            raise KernelError(
                f"{what}: OpenCascade could not measure the distance between blade 0 and blade {k}"
            )
        if distance.Value() <= STRICT_BLADE_SEPARATION_MM:
            raise KernelError(
                f"{what}: blade 0 and blade {k} touch or "
                f"cross (distance {distance.Value():.2g} mm, "
                f"at least {STRICT_BLADE_SEPARATION_MM:g} mm required; self-interference test)"
            )


def strict_valid_propeller(
    solid: TopoDS_Shape, fillet_on_sharp_edge: bool
) -> tuple[TopoDS_Shape, StrictCheck]:
    """:func:`strict_valid_solid` on the propeller; its error says the way out when a root fillet
    (``fillet_on_sharp_edge``) runs round a knife trailing edge."""
    try:
        return strict_valid_solid(solid, "the propeller")
    except KernelError as error:
        if not fillet_on_sharp_edge:
            raise
        # OpenCascade's rolling ball turns round the zero-thickness edge in one degenerate corner
        # face.
        raise KernelError(
            f"{error}; a root fillet round a sharp trailing edge can leave a self-intersecting "
            "corner face there: airfoil.trailing_edge_thickness > 0 with "
            "airfoil.trailing_edge_shape = 'round' takes it"
        ) from None
