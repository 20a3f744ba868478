"""Checks on kernel results, and mass properties computed by OpenCascade.

A boolean can "succeed" with several solids, an open shell or an invalid topology; every
result is checked here and a KernelError says what failed.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp
from OCP.Bnd import Bnd_Box
from OCP.GProp import GProp_GProps
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt

import cadquery as cq

from torus_cad.errors import KernelError
from torus_cad.tolerances import MASS_PROPERTIES_RELATIVE_PRECISION


def single_valid_solid(shape: cq.Shape, what: str) -> cq.Solid:
    """The one solid of ``shape``; raise KernelError unless it is one solid, one closed shell, valid."""
    solids = shape.Solids()
    if len(solids) != 1:
        raise KernelError(f"{what} gave {len(solids)} solids instead of 1")
    solid = solids[0]
    shells = solid.Shells()
    if len(shells) != 1:
        raise KernelError(f"{what} gave a solid with {len(shells)} shells instead of 1")
    if not BRep_Tool.IsClosed_s(shells[0].wrapped):
        raise KernelError(f"{what} gave an open shell (not watertight)")
    if not BRepCheck_Analyzer(solid.wrapped).IsValid():
        raise KernelError(f"{what} gave a solid that BRepCheck_Analyzer finds invalid")
    return solid


def is_valid_closed_solid(shape: cq.Shape) -> bool:
    """True when ``shape`` holds exactly one valid solid with one closed shell."""
    try:
        single_valid_solid(shape, "the shape")
    except KernelError:
        return False
    return True


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of a solid, by OpenCascade's adaptive integration (BRepGProp).

    Attributes:
        volume_mm3: volume, mm^3.
        surface_area_mm2: area of the boundary, mm^2.
        centroid_mm: (x, y, z) centre of volume, mm.
        spin_axis_inertia_mm5: integral of r^2 dV about the z axis (the spin axis), mm^5.
        density_g_cm3: density used for the mass, g/cm^3.
        mass_g: mass, g.
        spin_axis_inertia_g_mm2: moment of inertia about the z axis, g mm^2.
        bounding_box_mm: ((xmin, ymin, zmin), (xmax, ymax, zmax)), tight box, mm.
    """

    volume_mm3: float
    surface_area_mm2: float
    centroid_mm: tuple[float, float, float]
    spin_axis_inertia_mm5: float
    density_g_cm3: float
    mass_g: float
    spin_axis_inertia_g_mm2: float
    bounding_box_mm: tuple[tuple[float, float, float], tuple[float, float, float]]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


def volume_properties(shape: cq.Shape, relative_precision: float = MASS_PROPERTIES_RELATIVE_PRECISION
                      ) -> GProp_GProps:
    """OpenCascade volume properties by adaptive integration (not cadquery's coarse default)."""
    properties = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape.wrapped, properties, relative_precision, False)
    return properties


def precise_volume(shape: cq.Shape, relative_precision: float = MASS_PROPERTIES_RELATIVE_PRECISION) -> float:
    """Volume in mm^3 by adaptive integration to ``relative_precision``."""
    return float(volume_properties(shape, relative_precision).Mass())


def mass_properties(shape: cq.Shape, density_g_cm3: float) -> MassProperties:
    """Volume, area, centroid, inertia about the z axis and mass of ``shape`` for a density in g/cm^3."""
    volume = volume_properties(shape)
    surface = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape.wrapped, surface, MASS_PROPERTIES_RELATIVE_PRECISION, False)
    centre = volume.CentreOfMass()
    inertia_mm5 = volume.MomentOfInertia(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)))
    density_g_mm3 = density_g_cm3 * 1e-3
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape.wrapped, box, False, False)
    xmin, ymin, zmin, xmax, ymax, zmax = box.Get()
    return MassProperties(
        volume_mm3=float(volume.Mass()), surface_area_mm2=float(surface.Mass()),
        centroid_mm=(centre.X(), centre.Y(), centre.Z()), spin_axis_inertia_mm5=float(inertia_mm5),
        density_g_cm3=density_g_cm3, mass_g=float(volume.Mass()) * density_g_mm3,
        spin_axis_inertia_g_mm2=float(inertia_mm5) * density_g_mm3,
        bounding_box_mm=((xmin, ymin, zmin), (xmax, ymax, zmax)))


def distances_to_shape(shape: cq.Shape, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Distance (mm) from each of ``(k, 3)`` points to the boundary of ``shape``: ``(k,)``."""
    faces = cq.Compound.makeCompound(shape.Faces()).wrapped
    distances = np.empty(len(points))
    for index, point in enumerate(np.asarray(points, dtype=float)):
        vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*map(float, point))).Vertex()
        extrema = BRepExtrema_DistShapeShape(vertex, faces)
        if not extrema.IsDone():
            raise KernelError("OpenCascade could not measure a point's distance to the solid")
        distances[index] = extrema.Value()
    return distances
