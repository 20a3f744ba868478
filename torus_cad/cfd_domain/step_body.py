"""A user's own propeller from a STEP file, as a :class:`~torus_cad.cfd_domain.domain.PropellerBody`
(``simulate --step``).

The file is untrusted input: it is read by
:func:`torus_cad.runtime.input_files.read_untrusted_bytes` (a regular file, at most
``STEP_FILE_MAX_BYTES``), must start with the STEP header ``ISO-10303-21;``, must hold exactly one
solid, and that solid must pass OpenCascade's ``BRepCheck_Analyzer`` with one closed shell
(:func:`torus_cad.kernel.checks.single_valid_solid`). Every refusal is a ParameterError (exit 2)
naming the path as given, never the content.

The solid is placed so that its spin axis is +z: the axis is the line along ``axis`` (one of
``+z -z +x -x +y -y`` in the file's coordinates) through the solid's centroid (a balanced
propeller's centroid is on its axis); the solid is rotated so that this direction becomes +z and
moved so the line is the z axis (its axial position is kept). ``turning`` is the sense of rotation
seen from the + end of the axis (``cw`` like the built designs: the air is pushed toward −axis, the
thrust points along +axis).

Measures, from the placed solid:

* tip diameter D: twice the largest distance of the solid from the axis (the bounding cylinder):
  an enclosing cylinder's radius less its distance to the solid (OpenCascade's BRepExtrema);
* hub: the central cylinder. Rings of ``HUB_RING_POINTS`` points about the axis, in the plane
  through the centroid, are classified against the solid: the hub radius is the largest ring radius
  whose points all lie inside the solid (beyond it the ring passes between the blades; found in
  ``HUB_RADIAL_STEPS`` steps up to D/2, then ``HUB_BISECTIONS`` halvings); the hub length is the
  axial extent, up and down from the centroid's plane, over which the ring halfway between the
  innermost such radius and the hub radius (inside the hub's wall, clear of a bore) stays all
  inside (halvings too). No ring all inside: no hub (0, 0);
* the smallest chord, which sets the element size on the propeller, is not measured: it is taken
  as ``CHORD_PER_DIAMETER`` x D (the built default design's ratio, 6.0 mm at D = 45.1 mm);
* the trailing edges, for their size field (the levels turn curvature sizing off): the knife edges,
  where the two faces' normals differ by more than ``KNIFE_EDGE_NORMAL_ANGLE_DEG`` (a wedge under
  45 degrees; a blunt or round trailing edge is not found, and its surface mesh is then refined only
  where its triangles cross).
"""

from __future__ import annotations

import math
import os
import re
import tempfile
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.cfd_domain.domain import PropellerBody
from torus_cad.cfd_domain.sizes import TrailingEdges
from torus_cad.errors import KernelError, ParameterError
from torus_cad.parameters.design import Handedness
from torus_cad.runtime.input_files import read_untrusted_bytes
from torus_cad.tolerances import STEP_FILE_MAX_BYTES

#: The first bytes of every STEP file (ISO 10303-21), after optional whitespace.
STEP_MAGIC = b"ISO-10303-21;"
#: Hub rings: points around, radial steps up to D/2, then halvings of the last step (radius, and the
#: axial extent from the centroid's plane up and down).
HUB_RING_POINTS = 16
HUB_RADIAL_STEPS = 24
HUB_BISECTIONS = 8
#: An edge whose two faces' normals differ by more than this (degrees) is a knife (trailing) edge;
#: samples along it.
KNIFE_EDGE_NORMAL_ANGLE_DEG = 135.0
KNIFE_EDGE_SAMPLES = 41
#: The smallest chord of a STEP propeller as a fraction of its tip diameter (the default design's
#: 6.0 / 45.1).
CHORD_PER_DIAMETER = 0.133
#: What a STEP propeller's name is made of; everything else becomes '_'.
_NAME_CHARACTERS = re.compile(r"[^A-Za-z0-9_.-]")
_WHAT = "STEP file"


class Axis(StrEnum):
    """The spin axis of a STEP propeller in its file's coordinates."""

    PLUS_Z = "+z"
    MINUS_Z = "-z"
    PLUS_X = "+x"
    MINUS_X = "-x"
    PLUS_Y = "+y"
    MINUS_Y = "-y"


#: The rotation (about a coordinate axis, degrees) that turns each axis into +z.
_ROTATIONS: dict[Axis, tuple[tuple[float, float, float], float]] = {
    Axis.PLUS_Z: ((1.0, 0.0, 0.0), 0.0),
    Axis.MINUS_Z: ((1.0, 0.0, 0.0), 180.0),
    Axis.PLUS_X: ((0.0, 1.0, 0.0), -90.0),
    Axis.MINUS_X: ((0.0, 1.0, 0.0), 90.0),
    Axis.PLUS_Y: ((1.0, 0.0, 0.0), 90.0),
    Axis.MINUS_Y: ((1.0, 0.0, 0.0), -90.0),
}


@dataclass(frozen=True)
class StepPropeller:
    """A STEP propeller placed with its axis on +z.

    Attributes:
        source: the path as given.
        axis: its spin axis in the file's coordinates; turning: its sense of rotation seen from + of
            the axis.
        body: the placed solid, its tip diameter (mm) and chord (mm) for the domain.
        hub_radius_mm, hub_length_mm: the central cylinder (see the module doc); 0 when none is
            found.
        centroid_mm: the solid's centroid in the file's coordinates, mm.
    """

    source: str
    axis: Axis
    turning: Handedness
    body: PropellerBody
    hub_radius_mm: float
    hub_length_mm: float
    centroid_mm: tuple[float, float, float]

    def report(self) -> dict[str, Any]:
        """The report's ``step`` entry (lengths in mm)."""
        return {
            "file": self.source,
            "axis": self.axis.value,
            "turning": self.turning.value,
            "tip_diameter_mm": self.body.tip_diameter_mm,
            "hub_radius_mm": self.hub_radius_mm,
            "hub_length_mm": self.hub_length_mm,
            "chord_mm": self.body.chord_mm,
            "centroid_mm": list(self.centroid_mm),
            "measures": "D: twice the largest distance from the "
            "axis (BRepExtrema); hub: the largest ring about "
            "the axis through the centroid lying wholly "
            "inside the solid, and the axial extent of a "
            "ring inside its wall; chord: CHORD_PER_DIAMETER x D",
        }


def step_name(path: str | Path) -> str:
    """The output name from the file's stem: characters other than letters, digits, '_', '-' and '.'
    become '_', leading ones other than a letter or digit are dropped (a name starts with one), at
    most 64 characters ('step_propeller' when nothing is left)."""
    name = _NAME_CHARACTERS.sub("_", Path(path).stem).lstrip("_.-")[:64].rstrip(".")
    return name or "step_propeller"


def read_step_solid(path: str | Path) -> Any:
    """The one valid solid of the STEP file ``path`` (a cadquery Solid), or ParameterError naming
    the path."""
    from torus_cad.kernel.checks import single_valid_solid
    from torus_cad.kernel.step_readback import read_step

    source = str(path)
    raw = read_untrusted_bytes(path, _WHAT, STEP_FILE_MAX_BYTES)
    if not raw.lstrip().startswith(STEP_MAGIC):
        raise ParameterError(
            f"{_WHAT} {source!r} is not a STEP file (it does not start with {STEP_MAGIC.decode()})"
        )
    with tempfile.TemporaryDirectory(prefix="torus_cad_step_") as folder:
        copy = Path(folder) / "input.step"  # the bytes checked above, not the path again
        copy.write_bytes(raw)
        try:
            with _quiet_stdout():
                shape = read_step(copy)
        except KernelError as error:
            what = "holds no shape" if "holds no shape" in str(error) else "does not read as STEP"
            raise ParameterError(f"{_WHAT} {source!r} {what}") from None
    solids = shape.Solids() if shape is not None and not shape.wrapped.IsNull() else []
    if len(solids) != 1:
        raise ParameterError(
            f"{_WHAT} {source!r} holds {len(solids)} solids; "
            "it must hold exactly one (the propeller)"
        )
    try:
        return single_valid_solid(solids[0], f"{_WHAT} {source!r}")
    except KernelError as error:
        raise ParameterError(
            f"{error} (OpenCascade's checks); repair it in the CAD program"
        ) from None


class _quiet_stdout:
    """OpenCascade's STEP reader prints its parse errors on the C-level stdout: send them to
    /dev/null."""

    def __enter__(self) -> None:
        import sys

        sys.stdout.flush()
        self._saved = os.dup(1)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.close(null)

    def __exit__(self, *exc_info: object) -> None:
        os.dup2(self._saved, 1)
        os.close(self._saved)


def place_on_z(solid: Any, axis: Axis) -> tuple[Any, tuple[float, float, float]]:
    """``solid`` turned so ``axis`` is +z and moved so the line along it through the centroid is the
    z axis; and the centroid in the file's coordinates (mm)."""
    import cadquery as cq

    centre = solid.Center()
    direction, angle = _ROTATIONS[axis]
    turned = solid.rotate(cq.Vector(0, 0, 0), cq.Vector(*direction), angle) if angle else solid
    moved = turned.Center()
    return turned.translate(cq.Vector(-moved.x, -moved.y, 0.0)), (centre.x, centre.y, centre.z)


def tip_diameter_mm(solid: Any) -> float:
    """Twice the largest distance of ``solid`` from the z axis, mm: a cylinder about z enclosing the
    solid, less its shortest distance to the solid (OpenCascade's BRepExtrema, exact on the
    B-rep)."""
    import cadquery as cq
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape

    box = solid.BoundingBox()
    radius = 2.0 * max(abs(box.xmin), abs(box.xmax), abs(box.ymin), abs(box.ymax)) + 1.0
    height = box.zmax - box.zmin + 2.0
    cylinder = cq.Solid.makeCylinder(radius, height, cq.Vector(0.0, 0.0, box.zmin - 1.0))
    lateral = next(face for face in cylinder.Faces() if face.geomType() == "CYLINDER")
    distance = BRepExtrema_DistShapeShape(lateral.wrapped, solid.wrapped)
    if not distance.IsDone():
        raise KernelError("OpenCascade could not measure the STEP solid's distance from its axis")
    return float(2.0 * (radius - distance.Value()))


def hub_measures(solid: Any, diameter_mm: float) -> tuple[float, float]:
    """(hub radius, hub length) in mm of ``solid`` about the z axis (see the module doc); (0, 0)
    without a hub."""
    from OCP.BRepClass3d import BRepClass3d_SolidClassifier
    from OCP.gp import gp_Pnt
    from OCP.TopAbs import TopAbs_IN

    classifier = BRepClass3d_SolidClassifier(solid.wrapped)
    box = solid.BoundingBox()
    z_centre = solid.Center().z
    angles = np.linspace(0.0, 2.0 * math.pi, HUB_RING_POINTS, endpoint=False)
    tolerance = 1e-6 * box.DiagonalLength

    def ring_inside(radius: float, z: float) -> bool:
        for angle in angles:
            classifier.Perform(
                gp_Pnt(radius * math.cos(angle), radius * math.sin(angle), z), tolerance
            )
            if classifier.State() != TopAbs_IN:
                return False
        return True

    step = diameter_mm / 2.0 / HUB_RADIAL_STEPS
    full = [index for index in range(1, HUB_RADIAL_STEPS) if ring_inside(index * step, z_centre)]
    if not full:
        return 0.0, 0.0
    hub_radius = _bisect(
        lambda radius: ring_inside(radius, z_centre), max(full) * step, (max(full) + 1) * step
    )
    wall = 0.5 * (min(full) * step + hub_radius)
    if not ring_inside(wall, z_centre):
        return hub_radius, 0.0
    top = _bisect(lambda z: ring_inside(wall, z), z_centre, box.zmax)
    bottom = _bisect(lambda z: ring_inside(wall, z), z_centre, box.zmin)
    return hub_radius, top - bottom


def _bisect(inside: Any, good: float, bad: float) -> float:
    """The boundary between ``good`` (where ``inside`` holds) and ``bad``, to ``HUB_BISECTIONS``
    halvings."""
    for _ in range(HUB_BISECTIONS):
        middle = 0.5 * (good + bad)
        good, bad = (middle, bad) if inside(middle) else (good, middle)
    return good


def knife_edges(solid: Any) -> TrailingEdges | None:
    """The solid's knife edges (edges between two faces whose normals, at the edge's middle, differ
    by more than ``KNIFE_EDGE_NORMAL_ANGLE_DEG``: a sharp trailing edge), each sampled at
    ``KNIFE_EDGE_SAMPLES`` points, as trailing edges of thickness 0 mm for the size field; None when
    there are none."""
    import cadquery as cq
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    limit = math.cos(math.radians(KNIFE_EDGE_NORMAL_ANGLE_DEG))
    curves = []
    for index in range(1, ancestors.Extent() + 1):
        faces = list(ancestors.FindFromIndex(index))
        if len(faces) != 2:
            continue
        edge = cq.Edge(TopoDS.Edge_s(ancestors.FindKey(index)))
        middle = edge.positionAt(0.5)
        normals = [cq.Face(TopoDS.Face_s(face)).normalAt(middle) for face in faces]
        if normals[0].dot(normals[1]) < limit:
            curves.append(
                np.array(
                    [
                        edge.positionAt(t).toTuple()
                        for t in np.linspace(0.0, 1.0, KNIFE_EDGE_SAMPLES)
                    ]
                )
            )
    return TrailingEdges(tuple(curves), 0.0) if curves else None


def load_step_propeller(
    path: str | Path, axis: Axis = Axis.PLUS_Z, turning: Handedness = Handedness.CW
) -> StepPropeller:
    """Read, check, place and measure the STEP propeller at ``path`` (ParameterError for a bad
    file)."""
    solid = read_step_solid(path)
    placed, centroid = place_on_z(solid, axis)
    diameter = tip_diameter_mm(placed)
    hub_radius, hub_length = hub_measures(placed, diameter)
    body = PropellerBody(
        placed, step_name(path), diameter, CHORD_PER_DIAMETER * diameter, knife_edges(placed)
    )
    return StepPropeller(str(path), axis, turning, body, hub_radius, hub_length, centroid)
