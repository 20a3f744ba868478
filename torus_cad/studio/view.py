"""The studio's 3D scene in VTK: one actor per part (hub grey, each blade its own colour) and the
blades' section curves.

The scene is rendered in the browser (trame's VtkLocalView serializes it to vtk.js, WebGL): orbit,
zoom and pan need no round trip, and the server never renders: its render window is VTK's
plain, OpenGL-free ``vtkRenderWindow`` (vtkRenderingOpenGL2 is never imported), which only holds
the scene for serialization (rendering on the server, in software, is much slower: the measurements
page of the docs).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow

from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.preview.vtk_scene import (
    add_lights,
    polyline_polydata,
    surface_actor,
    triangle_polydata,
)
from torus_cad.studio.scene import PartMesh

#: Background of the view, RGB 0..1.
BACKGROUND = (0.90, 0.92, 0.95)

#: Section curves are drawn darker than their blade's colour, by this factor.
SECTION_SHADE = 0.45


def part_color(part: int, blades: int) -> tuple[float, float, float]:
    """RGB 0..1 of a part: the hub grey, blade i its own colour."""
    return HUB_COLOR if part == HUB_PART else blade_color(part, blades)


class PropellerView:
    """A render window, never rendered on the server, holding the propeller's parts and section
    curves."""

    def __init__(self) -> None:
        self.renderer = vtkRenderer()
        self.renderer.SetBackground(*BACKGROUND)
        add_lights(self.renderer)
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
            actor = surface_actor(
                triangle_polydata(mesh.vertices, mesh.triangles), part_color(mesh.part, blades)
            )
            self.renderer.AddActor(actor)
            self._part_actors.append(actor)
        if not self._framed:
            self.reset_camera()
            self._framed = True

    def show_sections(self, sections: Sequence[NDArray[np.float64]], blades: int) -> None:
        """Replace the section curves: ``sections[i]`` is blade i's ``(sections, points, 3)``
        array."""
        curves = [ring for blade in sections for ring in blade]
        counts = [len(blade) for blade in sections]
        colors = (
            np.concatenate(
                [
                    np.tile(np.array(blade_color(index, blades)) * SECTION_SHADE, (count, 1))
                    for index, count in enumerate(counts)
                ]
            )
            if counts
            else np.zeros((0, 3))
        )
        polydata = polyline_polydata(curves, colors)
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
