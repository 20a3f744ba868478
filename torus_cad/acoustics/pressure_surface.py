"""A finished simulation's blade surface pressure as a
:class:`~torus_cad.acoustics.fwh.RotatingSurface`.

The case's ``surfaces`` function object (torus_cad.simulate.case.BLADE_PRESSURE) writes the
propeller patch at the last time as VTK XML PolyData (m; face values of simpleFoam's kinematic
pressure p / rho, m^2/s^2), read here with VTK's own reader. OpenFOAM orders a boundary face's
points so that its normal points out of the fluid domain (into the blade); the acoustic surface's
normal points into the fluid, so it is reversed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.acoustics.fwh import RotatingSurface
from torus_cad.errors import TorusCadError

SURFACE_FILE_SUFFIX = ".vtp"


class SurfacePressureError(TorusCadError):
    """The case has no readable blade surface pressure."""


def _time_value(folder: Path) -> float:
    try:
        return float(folder.name)
    except ValueError:
        return -1.0


def surface_pressure_file(case: Path, function_object: str, patch: str) -> Path:
    """``postProcessing/<function_object>/<latest time>/<patch>.vtp`` of ``case``;
    SurfacePressureError if none."""
    root = Path(case) / "postProcessing" / function_object
    times = sorted(
        (folder for folder in root.glob("*") if _time_value(folder) >= 0.0), key=_time_value
    )
    for folder in reversed(times):
        path = folder / f"{patch}{SURFACE_FILE_SUFFIX}"
        if path.is_file():
            return path
    raise SurfacePressureError(
        f"no blade surface pressure in {str(root)!r} (the case's {function_object!r} "
        f"function object wrote no {patch}{SURFACE_FILE_SUFFIX})"
    )


def read_surface(path: Path, density_kg_m3: float, field: str = "p") -> RotatingSurface:
    """The faces of the VTK PolyData file ``path`` (points in m) with the gauge pressure
    ``density_kg_m3`` times the face field ``field`` (kinematic, m^2/s^2), normals reversed into the
    fluid. Polygons are split into fans for their area vector and centroid."""
    from vtkmodules.util.numpy_support import vtk_to_numpy as untyped_vtk_to_numpy

    def vtk_to_numpy(array: Any) -> np.ndarray:
        return np.asarray(untyped_vtk_to_numpy(array))  # type: ignore[no-untyped-call]

    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    data = reader.GetOutput()
    values = data.GetCellData().GetArray(field) if data is not None else None
    if values is None or data.GetNumberOfPolys() == 0:
        raise SurfacePressureError(f"{str(path)!r} has no polygons with a face field {field!r}")
    points = vtk_to_numpy(data.GetPoints().GetData()).astype(float)
    polys = data.GetPolys()
    offsets = vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    connectivity = vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    counts = np.diff(offsets)
    # one fan triangle per polygon vertex beyond two
    first = np.repeat(offsets[:-1], counts - 2)
    within = np.arange(len(first)) - np.repeat(np.cumsum(counts - 2) - (counts - 2), counts - 2)
    corner0 = points[connectivity[first]]
    corner1 = points[connectivity[first + within + 1]]
    corner2 = points[connectivity[first + within + 2]]
    owner = np.repeat(np.arange(len(counts)), counts - 2)
    triangle_area = 0.5 * np.cross(corner1 - corner0, corner2 - corner0)
    triangle_centre = (corner0 + corner1 + corner2) / 3.0
    area_vector = np.zeros((len(counts), 3))
    np.add.at(area_vector, owner, triangle_area)
    weight = np.linalg.norm(triangle_area, axis=1)
    centre = np.zeros((len(counts), 3))
    np.add.at(centre, owner, triangle_centre * weight[:, None])
    areas = np.linalg.norm(area_vector, axis=1)
    keep = areas > 0.0
    weights = np.zeros(len(counts))
    np.add.at(weights, owner, weight)
    kinematic = vtk_to_numpy(values).astype(float).reshape(len(counts), -1)[:, 0]
    return RotatingSurface(
        centre[keep] / weights[keep, None],
        -area_vector[keep] / areas[keep, None],
        areas[keep],
        density_kg_m3 * kinematic[keep],
    )
