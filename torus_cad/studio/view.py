"""The studio's 3D scene in VTK: one actor per part (hub grey, each blade its own colour) and the
blades' section curves.

The scene is rendered in the browser (trame's VtkLocalView serializes it to vtk.js, WebGL): orbit,
zoom and pan need no round trip, and the server never renders: its render window is VTK's
plain, OpenGL-free ``vtkRenderWindow`` (vtkRenderingOpenGL2 is never imported), which only holds
the scene for serialization. Rendering on the server instead (llvmpipe, no GPU) took 0.3-1.2 s a
frame on the 2-core project machine.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersCore import vtkPolyDataNormals
from vtkmodules.vtkRenderingCore import (
    vtkActor,
    vtkLightKit,
    vtkPolyDataMapper,
    vtkRenderer,
    vtkRenderWindow,
)

from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.studio.scene import HUB_PART, PartMesh

#: Background of the view, RGB 0..1.
BACKGROUND = (0.90, 0.92, 0.95)

#: Section curves are drawn darker than their blade's colour, by this factor.
SECTION_SHADE = 0.45

#: Smooth shading between triangles meeting at less than this angle (degrees); sharper edges stay sharp.
FEATURE_ANGLE_DEG = 40.0


def _cells(connectivity: NDArray[np.int64], sizes: NDArray[np.int64]) -> vtkCellArray:
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cells = vtkCellArray()
    cells.SetData(numpy_to_vtkIdTypeArray(offsets, deep=True),  # type: ignore[no-untyped-call]
                  numpy_to_vtkIdTypeArray(connectivity, deep=True))  # type: ignore[no-untyped-call]
    return cells


def _points(vertices: NDArray[np.float64]) -> vtkPoints:
    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.ascontiguousarray(vertices, dtype=float), deep=True))  # type: ignore[no-untyped-call]
    return points


def triangle_polydata(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> vtkPolyData:
    """A vtkPolyData of triangles with smooth normals (sharp edges kept)."""
    polydata = vtkPolyData()
    polydata.SetPoints(_points(vertices))
    triangles = np.asarray(triangles, dtype=np.int64)
    polydata.SetPolys(_cells(triangles.ravel(), np.full(len(triangles), 3)))
    normals = vtkPolyDataNormals()
    normals.SetInputData(polydata)
    normals.SetFeatureAngle(FEATURE_ANGLE_DEG)
    normals.ConsistencyOff()  # the meshes are already oriented outward
    normals.AutoOrientNormalsOff()
    normals.Update()
    return normals.GetOutput()


def polyline_polydata(curves: Sequence[NDArray[np.float64]]) -> vtkPolyData:
    """Closed polylines, one per ``(p, 3)`` curve."""
    polydata = vtkPolyData()
    if not curves:
        return polydata
    vertices = np.concatenate(curves)
    starts = np.cumsum([0] + [len(curve) for curve in curves[:-1]])
    connectivity = np.concatenate([np.r_[np.arange(len(curve)), 0] + start for curve, start in zip(curves, starts)])
    polydata.SetPoints(_points(vertices))
    polydata.SetLines(_cells(connectivity.astype(np.int64), np.array([len(curve) + 1 for curve in curves])))
    return polydata


def part_color(part: int, blades: int) -> tuple[float, float, float]:
    """RGB 0..1 of a part: the hub grey, blade i its own colour."""
    return HUB_COLOR if part == HUB_PART else blade_color(part, blades)


class PropellerView:
    """A render window, never rendered on the server, holding the propeller's parts and section curves."""

    def __init__(self) -> None:
        self.renderer = vtkRenderer()
        self.renderer.SetBackground(*BACKGROUND)
        lights = vtkLightKit()  # key, fill and back lights: faces seen edge-on stay readable
        lights.AddLightsToRenderer(self.renderer)
        self.window = vtkRenderWindow()
        self.window.AddRenderer(self.renderer)
        self._part_actors: list[vtkActor] = []
        self._section_actor = vtkActor()
        self._section_mapper = vtkPolyDataMapper()
        self._section_actor.SetMapper(self._section_mapper)
        self._section_actor.GetProperty().SetLineWidth(1.5)
        self._section_actor.GetProperty().SetLighting(False)
        self.renderer.AddActor(self._section_actor)
        self._framed = False

    def show_parts(self, parts: Sequence[PartMesh], blades: int) -> None:
        """Replace the drawn parts (the hub and every blade)."""
        for actor in self._part_actors:
            self.renderer.RemoveActor(actor)
        self._part_actors = []
        for mesh in parts:
            if not len(mesh.triangles):
                continue
            mapper = vtkPolyDataMapper()
            mapper.SetInputData(triangle_polydata(mesh.vertices, mesh.triangles))
            actor = vtkActor()
            actor.SetMapper(mapper)
            surface = actor.GetProperty()
            surface.SetColor(*part_color(mesh.part, blades))
            surface.SetSpecular(0.25)
            surface.SetSpecularPower(30.0)
            self.renderer.AddActor(actor)
            self._part_actors.append(actor)
        if not self._framed:
            self.reset_camera()
            self._framed = True

    def show_sections(self, sections: Sequence[NDArray[np.float64]], blades: int) -> None:
        """Replace the section curves: ``sections[i]`` is blade i's ``(sections, points, 3)`` array."""
        curves = [ring for blade in sections for ring in blade]
        polydata = polyline_polydata(curves)
        counts = [len(blade) for blade in sections]
        colors = np.concatenate([np.tile(np.array(blade_color(index, blades)) * SECTION_SHADE, (count, 1))
                                 for index, count in enumerate(counts)]) if counts else np.zeros((0, 3))
        scalars = numpy_to_vtk((colors * 255).astype(np.uint8), deep=True)  # type: ignore[no-untyped-call]
        scalars.SetName("colors")
        polydata.GetCellData().SetScalars(scalars)
        mapper = self._section_mapper
        mapper.SetInputData(polydata)
        mapper.SetColorModeToDirectScalars()
        mapper.SetScalarModeToUseCellData()

    def set_sections_visible(self, visible: bool) -> None:
        """Show or hide the section curves."""
        self._section_actor.SetVisibility(bool(visible))

    def reset_camera(self) -> None:
        """A view of the whole propeller from above its side, spin axis up."""
        camera = self.renderer.GetActiveCamera()
        camera.SetFocalPoint(0.0, 0.0, 0.0)
        camera.SetPosition(0.55, -1.0, 1.25)  # from above: the blades behind the hub stay in sight
        camera.SetViewUp(0.0, 0.0, 1.0)
        self.renderer.ResetCamera()
        camera.Zoom(1.05)
