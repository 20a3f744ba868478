"""The VTK scene of a propeller, shared by the preview picture and the studio: numpy triangles and
polylines as vtkPolyData, the shaded surface actor and the lights.

The preview renders these actors off-screen (:mod:`torus_cad.preview.picture`); the studio puts
the same actors in a render window that trame serialises to the browser
(:mod:`torus_cad.studio.view`), so both show a design with one material, one normal rule and one
set of lights. Only VTK's data, filter and core rendering modules are imported here (no OpenGL
and no CAD kernel): the studio's server never renders.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals
from vtkmodules.vtkRenderingCore import vtkActor, vtkLightKit, vtkPolyDataMapper, vtkRenderer

__all__ = [
    "FEATURE_ANGLE_DEG",
    "add_lights",
    "polyline_polydata",
    "surface_actor",
    "triangle_polydata",
]

#: Smooth shading across edges where triangles meet at less than this angle (degrees); sharper
#: edges (the trailing edge, the hub's rims) stay sharp.
FEATURE_ANGLE_DEG = 35.0


def _points(vertices: NDArray[np.float64]) -> vtkPoints:
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(vertices, dtype=float), deep=True))  # type: ignore[no-untyped-call]
    return points


def _cells(connectivity: NDArray[np.int64], sizes: NDArray[np.int64]) -> vtkCellArray:
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cells = vtkCellArray()
    cells.SetData(
        numpy_to_vtkIdTypeArray(offsets, deep=True),  # type: ignore[no-untyped-call]
        numpy_to_vtkIdTypeArray(  # type: ignore[no-untyped-call]
            np.ascontiguousarray(connectivity, dtype=np.int64), deep=True
        ),
    )
    return cells


def _cell_colors(polydata: vtkPolyData, rgb: NDArray[np.float64]) -> None:
    """``rgb`` ``(cells, 3)`` in 0..1 as the polydata's cell colours."""
    colors = numpy_to_vtk(
        np.ascontiguousarray(np.round(np.asarray(rgb) * 255.0), dtype=np.uint8), deep=True
    )  # type: ignore[no-untyped-call]
    colors.SetName("colors")
    polydata.GetCellData().SetScalars(colors)


def triangle_polydata(
    vertices: NDArray[np.float64],
    triangles: NDArray[np.int64],
    cell_rgb: NDArray[np.float64] | None = None,
    smooth: bool = True,
) -> vtkPolyData:
    """Triangles as a vtkPolyData, with smooth vertex normals split at sharp edges.

    Args:
        vertices: ``(k, 3)`` points, mm.
        triangles: ``(m, 3)`` vertex indices, counter-clockwise seen from outside (kept as they
            are).
        cell_rgb: optional ``(m, 3)`` colour per triangle, RGB 0..1.
        smooth: compute the vertex normals (off: flat facets).
    """
    polydata = vtkPolyData()
    polydata.SetPoints(_points(vertices))
    triangles = np.asarray(triangles, dtype=np.int64)
    polydata.SetPolys(_cells(triangles.ravel(), np.full(len(triangles), 3, dtype=np.int64)))
    if cell_rgb is not None:
        _cell_colors(polydata, cell_rgb)
    if not smooth:
        return polydata
    normals = vtkPolyDataNormals()
    normals.SetInputData(polydata)
    normals.SetFeatureAngle(FEATURE_ANGLE_DEG)
    normals.SplittingOn()
    normals.ConsistencyOff()  # the meshes are already oriented outward
    normals.AutoOrientNormalsOff()
    normals.ComputeCellNormalsOff()
    normals.Update()
    output: vtkPolyData = normals.GetOutput()
    return output


def polyline_polydata(
    curves: Sequence[NDArray[np.float64]], cell_rgb: NDArray[np.float64] | None = None
) -> vtkPolyData:
    """Closed polylines, one per ``(p, 3)`` curve (mm), with an optional ``(curves, 3)`` RGB 0..1
    colour each."""
    polydata = vtkPolyData()
    if not curves:
        return polydata
    vertices = np.concatenate(curves)
    starts = np.cumsum([0] + [len(curve) for curve in curves[:-1]])
    connectivity = np.concatenate(
        [np.r_[np.arange(len(curve)), 0] + start for curve, start in zip(curves, starts)]
    )
    polydata.SetPoints(_points(vertices))
    polydata.SetLines(
        _cells(connectivity.astype(np.int64), np.array([len(curve) + 1 for curve in curves]))
    )
    if cell_rgb is not None:
        _cell_colors(polydata, cell_rgb)
    return polydata


def surface_actor(polydata: vtkPolyData, rgb: tuple[float, float, float] | None = None) -> vtkActor:
    """The propeller's material on ``polydata``: one colour ``rgb`` (0..1), else its cell
    colours."""
    mapper = vtkPolyDataMapper()
    mapper.SetInputData(polydata)
    if rgb is None:
        mapper.SetScalarModeToUseCellData()
        mapper.SetColorModeToDirectScalars()
    else:
        mapper.ScalarVisibilityOff()
    actor = vtkActor()
    actor.SetMapper(mapper)
    surface = actor.GetProperty()
    if rgb is not None:
        surface.SetColor(*rgb)
    surface.SetInterpolationToPhong()
    surface.SetAmbient(0.15)
    surface.SetDiffuse(0.82)
    surface.SetSpecular(0.25)
    surface.SetSpecularPower(40.0)
    return actor


def add_lights(renderer: vtkRenderer) -> None:
    """VTK's light kit: a key light above and left of the camera, a fill, back and head light (faces
    seen edge-on stay readable)."""
    kit = vtkLightKit()
    kit.SetKeyLightIntensity(0.85)
    kit.SetKeyToFillRatio(1.6)
    kit.SetKeyToHeadRatio(1.7)
    kit.AddLightsToRenderer(renderer)
