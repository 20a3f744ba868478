"""Off-screen preview picture of a propeller: an isometric view and a view along the spin axis.

Rendered by VTK off-screen (EGL or OSMesa: no window, no display needed) with a depth buffer and
smooth normals, from OpenCascade's tessellation of the fused solid. Each face is coloured by the
part it came from (the hub grey, every blade its own colour)::

    from torus_cad.propeller import build_propeller
    from torus_cad.preview import write_preview
    write_preview(build_propeller(), "propeller.png", size=(1200, 600))

VTK is imported only when a picture is made.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import cadquery as cq
import numpy as np
from numpy.typing import NDArray

from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.errors import ParameterError
from torus_cad.kernel.checks import distances_to_shape, precise_volume
from torus_cad.kernel.export import atomic_path
from torus_cad.parameters import PropellerParameters

#: Default picture size in pixels (width, height): two square views side by side.
DEFAULT_SIZE: tuple[int, int] = (1200, 600)

#: Smallest and largest accepted picture edge, pixels.
MIN_EDGE, MAX_EDGE = 64, 8000

#: Along the spin axis: looking down the z axis from +z, x to the right, y up.
AXIAL_DIRECTION = (0.0, 0.0, 1.0)

_HUB_PART = -1


class _HasParts(Protocol):
    parameters: PropellerParameters
    solid: cq.Solid
    hub: cq.Solid
    blades: list[cq.Solid]


@dataclass(frozen=True)
class PreviewMesh:
    """A triangle mesh of the fused solid with each triangle's part.

    Attributes:
        vertices: ``(k, 3)`` points, mm.
        triangles: ``(m, 3)`` vertex indices, counter-clockwise seen from outside.
        parts: ``(m,)`` part of each triangle: -1 the hub, i >= 0 blade i.
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    parts: NDArray[np.int64]


@dataclass(frozen=True)
class View:
    """An orthographic camera: the unit direction from the scene toward the camera, and the screen's up."""

    toward_camera: tuple[float, float, float]
    up: tuple[float, float, float]
    label: str = ""


def parse_size(text: str, option: str = "--size") -> tuple[int, int]:
    """``"1200x600"`` -> ``(1200, 600)``; raise ParameterError (naming ``option``) for anything else."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not match:
        raise ParameterError(f"{option} {text!r} must look like WIDTHxHEIGHT in pixels, e.g. 1200x600")
    return _checked_size((int(match.group(1)), int(match.group(2))), f"{option} {text.strip()}")


def _checked_size(size: Sequence[int], what: str = "preview size") -> tuple[int, int]:
    width, height = (int(value) for value in size)
    for label, value in (("width", width), ("height", height)):
        if not MIN_EDGE <= value <= MAX_EDGE:
            raise ParameterError(f"{what}: {label} {value} px is out of range; allowed [{MIN_EDGE}, {MAX_EDGE}]")
    return width, height


# -- tessellation --------------------------------------------------------------------------------

def preview_mesh(solid: cq.Shape, hub: cq.Shape, blades: Sequence[cq.Shape],
                 tolerance: float | None = None, angular_tolerance: float = 0.2) -> PreviewMesh:
    """Tessellate ``solid`` (a copy: the caller's triangulation is left alone) and tag each face
    with the part (hub or blade i) it lies on.

    ``tolerance`` is the chordal deviation in mm (default: 1/3000 of the bounding-box diagonal).
    """
    shape = solid.copy()
    diagonal = shape.BoundingBox().DiagonalLength
    tolerance = max(diagonal / 3000.0, 1e-3) if tolerance is None else tolerance
    parts: list[cq.Shape] = [hub, *blades]
    boxes = [_box(part) for part in parts]
    vertices: list[NDArray[np.float64]] = []
    triangles: list[NDArray[np.int64]] = []
    labels: list[NDArray[np.int64]] = []
    offset = 0
    shape.mesh(tolerance, angular_tolerance)
    for face in shape.Faces():
        points, indices = face.tessellate(tolerance, angular_tolerance)  # reuses the solid's mesh
        if not indices:
            continue
        face_vertices = np.array([point.toTuple() for point in points], dtype=float)
        face_triangles = np.asarray(indices, dtype=np.int64)
        part = _face_part(face_vertices, face_triangles, parts, boxes, 10.0 * tolerance)
        vertices.append(face_vertices)
        triangles.append(face_triangles + offset)
        labels.append(np.full(len(face_triangles), part, dtype=np.int64))
        offset += len(face_vertices)
    if not triangles:
        raise ValueError("the solid has no triangulated faces to draw")
    return PreviewMesh(np.concatenate(vertices), np.concatenate(triangles), np.concatenate(labels))


def _face_part(vertices: NDArray[np.float64], triangles: NDArray[np.int64], parts: Sequence[cq.Shape],
               boxes: Sequence[tuple[NDArray[np.float64], NDArray[np.float64]]], slack: float) -> int:
    """-1 for the hub, i for blade i: the part whose boundary passes nearest a few of the face's facets."""
    centroids = vertices[triangles].mean(axis=1)
    samples = centroids[np.linspace(0, len(centroids) - 1, min(5, len(centroids))).astype(int)]
    candidates = [index for index, (low, high) in enumerate(boxes)
                  if np.all(samples >= low - slack) and np.all(samples <= high + slack)] or list(range(len(parts)))
    if len(candidates) == 1:
        return candidates[0] - 1  # parts[0] is the hub
    medians = [float(np.median(distances_to_shape(parts[index], samples))) for index in candidates]
    return candidates[int(np.argmin(medians))] - 1


def _box(shape: cq.Shape) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    box = shape.BoundingBox()
    return np.array([box.xmin, box.ymin, box.zmin]), np.array([box.xmax, box.ymax, box.zmax])


# -- the camera ----------------------------------------------------------------------------------

def loop_area_vectors(loops: Sequence[NDArray[np.float64]]) -> NDArray[np.float64]:
    """The vector area (1/2 of the sum of r x dr, mm^2) of each closed polyline ``(k, 3)``: ``(n, 3)``.

    A loop blade's centerline, closed through the hub, bounds the blade's "window"; a camera
    perpendicular to this vector sees that window as a line, the blade edge-on."""
    areas = []
    for loop in loops:
        points = np.asarray(loop, dtype=float)
        areas.append(0.5 * np.cross(points, np.roll(points, -1, axis=0)).sum(axis=0))
    return np.array(areas)


def isometric_direction(area_vectors: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit direction toward an isometric-like camera (elevation 35-45 degrees) that keeps
    every blade as far from edge-on as it can: it maximises the smallest projected window area,
    |view . A_i|, over the blades (0 would show that blade as a line)."""
    azimuth, elevation = np.meshgrid(np.radians(np.arange(0.0, 360.0, 2.0)), np.radians(np.arange(35.0, 46.0, 5.0)))
    directions = np.stack([np.cos(elevation) * np.cos(azimuth), np.cos(elevation) * np.sin(azimuth),
                           np.sin(elevation)], axis=-1).reshape(-1, 3)
    worst = np.abs(directions @ np.asarray(area_vectors, dtype=float).T).min(axis=1)
    return directions[int(np.argmax(worst))]


def propeller_views(propeller: _HasParts) -> tuple[View, View]:
    """The isometric view (no blade edge-on) and the view along the spin axis."""
    geometry = propeller.parameters.geometry()
    s = np.linspace(0.0, 1.0, 64)
    loops = [geometry.centerline(index).points(s) for index in range(geometry.blades)]
    iso = isometric_direction(loop_area_vectors(loops))
    return (View((float(iso[0]), float(iso[1]), float(iso[2])), (0.0, 0.0, 1.0), "isometric"),
            View(AXIAL_DIRECTION, (0.0, 1.0, 0.0), "along the spin axis (+z toward you)"))


# -- rendering -----------------------------------------------------------------------------------

def _import_vtk() -> Any:
    if not os.environ.get("DISPLAY"):
        # Without an X server, VTK's default window tries X first and warns; go straight to EGL.
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 - registers the OpenGL back end
    from vtkmodules import (
        vtkCommonCore,
        vtkCommonDataModel,
        vtkFiltersCore,
        vtkRenderingCore,
        vtkRenderingFreeType,  # noqa: F401 - text rendering
    )
    from vtkmodules.util import numpy_support

    return vtkCommonCore, vtkCommonDataModel, vtkFiltersCore, vtkRenderingCore, numpy_support


def _actor(vertices: NDArray[np.float64], triangles: NDArray[np.int64], colors: NDArray[np.float64]) -> Any:
    """A VTK actor of a triangle mesh with one RGB (0..1) colour per triangle and smooth normals."""
    core, data, filters, rendering, numpy_support = _import_vtk()
    points = core.vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(vertices, dtype=np.float64), deep=True))
    cells = data.vtkCellArray()
    connectivity = np.ascontiguousarray(triangles, dtype=np.int64).ravel()
    offsets = np.arange(0, len(connectivity) + 1, 3, dtype=np.int64)
    cells.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
                  numpy_support.numpy_to_vtkIdTypeArray(connectivity, deep=True))
    poly = data.vtkPolyData()
    poly.SetPoints(points)
    poly.SetPolys(cells)
    rgb = numpy_support.numpy_to_vtk(np.ascontiguousarray(np.clip(colors, 0, 1) * 255, dtype=np.uint8), deep=True)
    rgb.SetName("colors")
    poly.GetCellData().SetScalars(rgb)
    normals = filters.vtkPolyDataNormals()  # smooth shading; edges sharper than 40 degrees stay sharp
    normals.SetInputData(poly)
    normals.SetFeatureAngle(40.0)
    normals.SplittingOn()
    normals.ConsistencyOff()  # OpenCascade's triangles are already oriented outward
    normals.ComputeCellNormalsOff()
    mapper = rendering.vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    mapper.SetScalarModeToUseCellData()
    mapper.SetColorModeToDirectScalars()
    actor = rendering.vtkActor()
    actor.SetMapper(mapper)
    properties = actor.GetProperty()
    properties.SetInterpolationToPhong()
    properties.SetAmbient(0.25)
    properties.SetDiffuse(0.75)
    properties.SetSpecular(0.25)
    properties.SetSpecularPower(40.0)
    return actor


def _text(text: str, x: float, y: float, size: int, gray: float, centred: bool = True) -> Any:
    rendering = _import_vtk()[3]
    actor = rendering.vtkTextActor()
    actor.SetInput(text)
    properties = actor.GetTextProperty()
    properties.SetFontSize(size)
    properties.SetColor(gray, gray, gray)
    properties.SetJustificationToCentered() if centred else properties.SetJustificationToLeft()
    properties.SetVerticalJustificationToTop()
    actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    actor.GetPositionCoordinate().SetValue(x, y)
    return actor


def render_views(actors_of: Callable[[], list[Any]], views: Sequence[View], size: Sequence[int],
                 title: str = "") -> NDArray[np.uint8]:
    """Render the views side by side, each with its own actors (``actors_of()`` is called per view):
    an ``(height, width, 3)`` uint8 RGB picture of exactly ``size`` = (width, height) pixels."""
    width, height = _checked_size(size)
    _, _, _, rendering, numpy_support = _import_vtk()
    window = rendering.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(8)
    window.SetSize(width, height)
    title_px = max(12, int(height * 0.035)) if title else 0
    top = 1.0 - (2.2 * title_px / height if title else 0.0)
    for column, view in enumerate(views):
        renderer = rendering.vtkRenderer()
        renderer.SetBackground(1.0, 1.0, 1.0)
        renderer.SetViewport(column / len(views), 0.0, (column + 1) / len(views), top)
        for actor in actors_of():
            renderer.AddActor(actor)
        camera = renderer.GetActiveCamera()
        camera.ParallelProjectionOn()
        camera.SetFocalPoint(0.0, 0.0, 0.0)
        camera.SetPosition(*view.toward_camera)
        camera.SetViewUp(*view.up)
        renderer.ResetCamera()
        camera.SetParallelScale(camera.GetParallelScale() * 0.88)
        renderer.ResetCameraClippingRange()
        if view.label:
            renderer.AddViewProp(_text(view.label, 0.5, 0.06, max(10, int(height * 0.022)), 0.35))
        window.AddRenderer(renderer)
    if title:
        overlay = rendering.vtkRenderer()
        overlay.SetViewport(0.0, top, 1.0, 1.0)
        overlay.SetBackground(1.0, 1.0, 1.0)
        overlay.AddViewProp(_text(title, 0.5, 0.85, title_px, 0.15))
        window.AddRenderer(overlay)
    window.Render()
    grabber = rendering.vtkWindowToImageFilter()
    grabber.SetInput(window)
    grabber.ReadFrontBufferOff()
    grabber.Update()
    image = grabber.GetOutput()
    pixels = numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
    picture = pixels.reshape(height, width, -1)[::-1, :, :3].copy()  # VTK's rows run bottom to top
    window.Finalize()
    return picture


def part_colors(parts: NDArray[np.int64], blades: int) -> NDArray[np.float64]:
    """RGB (0..1) for every triangle from its part: the hub grey, blade i its own colour."""
    palette = np.array([HUB_COLOR] + [blade_color(index, blades) for index in range(blades)])
    return palette[np.asarray(parts) + 1]


def render_preview(propeller: _HasParts, size: Sequence[int] = DEFAULT_SIZE, title: str | None = None,
                   progress: Callable[[str], None] | None = None) -> NDArray[np.uint8]:
    """The preview picture as an ``(height, width, 3)`` RGB uint8 array of exactly ``size`` pixels.

    Args:
        propeller: a built propeller (:class:`torus_cad.propeller.Propeller`): its ``solid``, ``hub``
            and ``blades``.
        size: (width, height) in pixels, each 64..8000.
        title: text above the views (default: the name, blade count and volume in mm^3).
        progress: optional callback, called with ``"tessellate"`` and ``"render"``.
    """
    width, height = _checked_size(size)
    if progress:
        progress("tessellate")
    blades = len(propeller.blades)
    # Tessellate about as finely as the picture can show: the chordal deviation is ~1/5 px of a view.
    diagonal = propeller.solid.BoundingBox().DiagonalLength
    mesh = preview_mesh(propeller.solid, propeller.hub, propeller.blades,
                        tolerance=max(diagonal / (5.0 * min(width / 2.0, height)), 1e-3))
    if title is None:
        volume = precise_volume(propeller.solid, 1e-5)  # shown to 4-5 digits: a coarser integral will do
        title = (f"{propeller.parameters.name}: {blades} blade{'s' if blades != 1 else ''}, "
                 f"volume {volume:,.0f} mm³")
    if progress:
        progress("render")
    colors = part_colors(mesh.parts, blades)
    return render_views(lambda: [_actor(mesh.vertices, mesh.triangles, colors)], propeller_views(propeller),
                        (width, height), title)


def write_png(image: NDArray[np.uint8], path: str | Path) -> Path:
    """Write an ``(height, width, 3 or 4)`` uint8 picture as PNG, atomically; return the path."""
    _, data, _, _, numpy_support = _import_vtk()
    from vtkmodules.vtkIOImage import vtkPNGWriter

    height, width, channels = image.shape
    vtk_image = data.vtkImageData()
    vtk_image.SetDimensions(width, height, 1)
    scalars = numpy_support.numpy_to_vtk(np.ascontiguousarray(image[::-1].reshape(-1, channels)), deep=True)
    vtk_image.GetPointData().SetScalars(scalars)
    path = Path(path)
    with atomic_path(path) as temp:
        writer = vtkPNGWriter()
        writer.SetFileName(str(temp))
        writer.SetInputData(vtk_image)
        writer.Write()
    return path


def write_preview(propeller: _HasParts, path: str | Path, size: Sequence[int] = DEFAULT_SIZE,
                  title: str | None = None, progress: Callable[[str], None] | None = None) -> Path:
    """Render the preview (see :func:`render_preview`) and write it as a PNG, atomically; return the path."""
    return write_png(render_preview(propeller, size, title, progress), path)
