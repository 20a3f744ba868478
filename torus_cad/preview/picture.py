"""Off-screen preview picture of a propeller: a view from above that shows every blade (none
edge-on, see :func:`oblique_view`) and a view along the spin axis.

Rendered with VTK (installed with cadquery) off-screen: OpenGL with a depth buffer and FXAA, the
scene of :mod:`torus_cad.preview.vtk_scene` (the studio's too), from OpenCascade's tessellation of
the fused solid. Each face is
coloured by the part it came from, as the build reports it (``Propeller.face_parts``): the hub
grey, every blade its own colour. No window or display is needed: without an X display VTK
draws through EGL (Mesa's software rasteriser on a machine without a GPU)::

    from torus_cad.propeller import build_propeller
    from torus_cad.preview.picture import write_preview
    write_preview(build_propeller(), "propeller.png", size=(1200, 600))

VTK is imported only when a picture is made.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import cadquery as cq
import numpy as np
from numpy.typing import NDArray

from torus_cad.build_stages import Stage
from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.errors import TorusCadError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.mass_properties import mass_properties
from torus_cad.parameters import PropellerParameters
from torus_cad.preview.size import checked_size
from torus_cad.runtime.files import atomic_path

if TYPE_CHECKING:  # pragma: no cover
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

#: Default picture size in pixels (width, height): two square views side by side.
DEFAULT_SIZE: tuple[int, int] = (1200, 600)

#: The classic isometric elevation (the (1, 1, 1) direction), degrees.
ISOMETRIC_ELEVATION_DEG = math.degrees(math.atan(1.0 / math.sqrt(2.0)))

#: Elevations (degrees) the oblique view may take: the isometric one up to 55°.
VIEW_ELEVATIONS_DEG = (ISOMETRIC_ELEVATION_DEG, 40.0, 45.0, 50.0, 55.0)

BACKGROUND_RGB = (1.0, 1.0, 1.0)
_TEXT_RGB = (0.2, 0.2, 0.2)


class _HasParts(Protocol):
    parameters: PropellerParameters
    face_parts: tuple[int, ...]

    @property
    def solid(self) -> cq.Solid: ...

    @property
    def blades(self) -> list[cq.Solid]: ...


@dataclass(frozen=True)
class SceneMesh:
    """A triangle mesh with one colour per triangle.

    Attributes:
        vertices: ``(k, 3)`` points, mm.
        triangles: ``(m, 3)`` vertex indices, counter-clockwise seen from outside.
        colors: ``(m, 3)`` RGB in 0..1.
        parts: ``(m,)`` part of each triangle (HUB_PART or a blade index; any int for other scenes).
    """

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    colors: NDArray[np.float64]
    parts: NDArray[np.int64]


@dataclass(frozen=True)
class View:
    """An orthographic view: ``toward_camera`` unit vector from the scene to the camera, ``up``
    the screen's up direction (any vector not along it), ``label`` text under the view."""

    toward_camera: tuple[float, float, float]
    up: tuple[float, float, float]
    label: str = ""


#: Looking down the spin axis from +z: x to the right, y up.
AXIAL_VIEW = View((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), "along the spin axis (+z toward you)")


# -- the scene ------------------------------------------------------------------------------------


def propeller_mesh(
    solid: cq.Shape,
    face_parts: Sequence[int],
    blades: int,
    tolerance: float,
    angular_tolerance: float = 0.3,
) -> SceneMesh:
    """OpenCascade's tessellation of ``solid`` (of a copy: the caller's triangulation is left
    alone), each face coloured by its part: ``face_parts[k]`` for ``solid.Faces()[k]``.

    ``tolerance`` is the chordal deviation in mm, ``angular_tolerance`` in radians.
    """
    from torus_cad.kernel.tessellation import tessellate_faces

    faces = solid.Faces()
    if len(face_parts) != len(faces):
        raise ValueError(
            f"face_parts has {len(face_parts)} entries for a solid of {len(faces)} faces"
        )
    palette = np.array([HUB_COLOR] + [blade_color(index, blades) for index in range(blades)])
    vertices, triangles, parts = [], [], []
    offset = 0
    for face in tessellate_faces(solid, tolerance, angular_tolerance):
        vertices.append(face.vertices)
        triangles.append(face.triangles + offset)
        parts.append(np.full(len(face.triangles), face_parts[face.face_index], dtype=np.int64))
        offset += len(face.vertices)
    if not triangles:
        raise ValueError("the solid has no triangulated faces to draw")
    all_parts = np.concatenate(parts)
    return SceneMesh(
        np.concatenate(vertices),
        np.concatenate(triangles),
        palette[np.where(all_parts == HUB_PART, 0, all_parts + 1)],
        all_parts,
    )


def blade_silhouettes(
    mesh: SceneMesh, directions: NDArray[np.float64], most_triangles: int = 3000
) -> NDArray[np.float64]:
    """``(blades, d)``: each blade's projected area (mm^2) seen along each of ``(d, 3)`` unit
    ``directions``, as half the sum of its triangles' |projected area| (exact for a convex body,
    close for a blade). At most ``most_triangles`` evenly picked triangles per blade are summed,
    scaled up to the blade's whole area."""
    corners = mesh.vertices[mesh.triangles]
    weighted_normals = 0.5 * np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    silhouettes = []
    for part in sorted(set(mesh.parts.tolist()) - {HUB_PART}):
        normals = weighted_normals[mesh.parts == part]
        picked = normals[
            np.linspace(0, len(normals) - 1, min(most_triangles, len(normals))).astype(int)
        ]
        scale = np.linalg.norm(normals, axis=1).sum() / np.linalg.norm(picked, axis=1).sum()
        silhouettes.append(0.5 * scale * np.abs(picked @ directions.T).sum(axis=0))
    return np.array(silhouettes).reshape(-1, len(directions))


def oblique_view(mesh: SceneMesh) -> View:
    """A view from above that shows every blade: none edge-on.

    A blade of a toroidal propeller is a loop, nearly flat; seen along its plane it collapses
    into a thin sliver that reads as a broken fragment (the fixed isometric corner did that to
    one blade of the default). Each blade's visible size from a direction d is its silhouette
    area (:func:`blade_silhouettes`); the view takes the d, over azimuths in 2° steps and the
    elevations VIEW_ELEVATIONS_DEG (isometric 35.26° up to 55°), that maximises the smallest
    blade's silhouette as a fraction of the largest silhouette any blade shows from any of
    these directions. The blades are copies of one another, so this is the direction where the
    worst-placed blade looks most like itself. Ties go to the lower elevation. The azimuths span
    one blade pitch (360°/n) only: a view one pitch further shows the same picture with the blades
    relabelled, and choosing among those copies by rounding noise gave different cameras for one
    design (``build --preview`` and ``preview``).
    """
    blades = max(1, len(set(mesh.parts.tolist()) - {HUB_PART}))
    azimuths = np.radians(np.arange(0.0, 360.0 / blades - 1e-9, 2.0))
    elevations = np.radians(np.array(VIEW_ELEVATIONS_DEG))
    e, a = np.meshgrid(elevations, azimuths, indexing="ij")
    directions = np.column_stack(
        [(np.cos(e) * np.cos(a)).ravel(), (np.cos(e) * np.sin(a)).ravel(), np.sin(e).ravel()]
    )
    silhouettes = blade_silhouettes(mesh, directions)
    if silhouettes.size:
        worst = (silhouettes / silhouettes.max()).min(axis=0)
        # first within 0.1 % of the best: lowest elevation
        best = int(np.argmax(worst > worst.max() - 1e-3))
    else:
        best = int(np.argmin(np.abs(e.ravel() - math.radians(ISOMETRIC_ELEVATION_DEG))))
    elevation, azimuth = math.degrees(e.ravel()[best]), math.degrees(a.ravel()[best])
    x, y, z = (float(value) for value in directions[best])
    return View(
        (x, y, z),
        (0.0, 0.0, 1.0),
        f"from above: elevation {elevation:.0f}°, azimuth {azimuth:.0f}°",
    )


# -- rendering
# ---------------------------------------------------------------------------------------


def render_views(
    mesh: SceneMesh,
    views: Sequence[View],
    size: Sequence[int],
    title: str = "",
    smooth: bool = True,
) -> NDArray[np.uint8]:
    """``mesh`` seen in each of ``views``, side by side, under ``title``: an ``(height, width, 3)``
    RGB uint8 array of exactly ``size`` = (width, height) pixels."""
    from vtkmodules.vtkRenderingCore import vtkRenderer

    from torus_cad.preview.vtk_scene import add_lights, surface_actor, triangle_polydata

    width, height = checked_size(size)
    window = _offscreen_window(width, height)
    title_px = _title_height_px(height) if title else 0
    view_top = 1.0 - title_px / height
    actor = surface_actor(triangle_polydata(mesh.vertices, mesh.triangles, mesh.colors, smooth))
    for column, view in enumerate(views):
        renderer = vtkRenderer()
        renderer.SetViewport(column / len(views), 0.0, (column + 1) / len(views), view_top)
        renderer.SetBackground(*BACKGROUND_RGB)
        renderer.AddActor(actor)
        renderer.UseFXAAOn()
        add_lights(renderer)
        _place_camera(renderer, mesh.vertices, view, (width / len(views)) / (height * view_top))
        if view.label:
            label_px = _fitting_font_px(view.label, _label_size_px(height), width / len(views))
            renderer.AddViewProp(_text(view.label, label_px, (0.5, 0.015), vertical="bottom"))
        window.AddRenderer(renderer)
    if title:
        overlay = vtkRenderer()
        overlay.SetViewport(0.0, view_top, 1.0, 1.0)
        overlay.SetBackground(*BACKGROUND_RGB)
        overlay.AddViewProp(
            _text(
                title,
                _fitting_font_px(title, round(title_px * 0.5), width),
                (0.5, 0.45),
                vertical="center",
            )
        )
        window.AddRenderer(overlay)
    window.Render()
    image = _pixels(window, width, height)
    window.Finalize()
    return image


def render_preview(
    propeller: _HasParts,
    size: Sequence[int] = DEFAULT_SIZE,
    title: str | None = None,
    progress: Callable[[Stage], None] | None = None,
) -> NDArray[np.uint8]:
    """The preview picture as an ``(height, width, 3)`` RGB uint8 array of exactly ``size`` pixels.

    Args:
        propeller: a built :class:`torus_cad.propeller.Propeller`: its ``solid``, ``face_parts``
            (each face's colour) and ``blades``.
        size: (width, height) in pixels, each 64..8000.
        title: text above the views (default: the name, blade count and volume in mm^3).
        progress: optional callback, called with ``Stage.PREVIEW_TESSELLATE`` and
            ``Stage.PREVIEW_RENDER``.
    """
    width, height = checked_size(size)
    if progress:
        progress(Stage.PREVIEW_TESSELLATE)
    blades = len(propeller.blades)
    # About as fine as the picture can show: the chordal deviation is ~1/3 px of a view (the
    # smooth normals hide the facets; only the outline shows them).
    diagonal = propeller.solid.BoundingBox().DiagonalLength
    view_px = min(width / 2.0, height)
    mesh = propeller_mesh(
        propeller.solid, propeller.face_parts, blades, max(diagonal / (3.0 * view_px), 1e-3)
    )
    if title is None:
        volume = mass_properties(propeller.solid, 1.0).volume_mm3
        title = (
            f"{propeller.parameters.name}: {blades} blade{'s' if blades != 1 else ''}, "
            f"volume {volume:,.0f} mm³"
        )
    if progress:
        progress(Stage.PREVIEW_RENDER)
    return render_views(mesh, (oblique_view(mesh), AXIAL_VIEW), (width, height), title)


def write_preview(
    propeller: _HasParts,
    path: str | Path,
    size: Sequence[int] = DEFAULT_SIZE,
    title: str | None = None,
    progress: Callable[[Stage], None] | None = None,
) -> Path:
    """Render the preview (see :func:`render_preview`) and write it as a PNG, atomically; return the
    path."""
    return write_png(render_preview(propeller, size, title, progress), path)


def write_png(image: NDArray[np.uint8], path: str | Path) -> Path:
    """Write an ``(height, width, 3 or 4)`` uint8 picture as a PNG (VTK's writer), atomically;
    return the path."""
    from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkIOImage import vtkPNGWriter

    height, width, channels = image.shape
    data = vtkImageData()
    data.SetDimensions(width, height, 1)
    scalars = numpy_to_vtk(np.ascontiguousarray(image[::-1]).reshape(-1, channels), deep=True)  # type: ignore[no-untyped-call]
    data.GetPointData().SetScalars(scalars)
    path = Path(path)
    writer = vtkPNGWriter()
    # encoded here, written by Python: a full disk is an OSError naming the file
    writer.SetWriteToMemory(True)
    writer.SetInputData(data)
    writer.Write()
    if writer.GetErrorCode():
        raise TorusCadError(f"could not encode the picture {path}")
    encoded = vtk_to_numpy(writer.GetResult()).tobytes()  # type: ignore[no-untyped-call]
    with atomic_path(path) as temp:
        try:
            temp.write_bytes(encoded)
        except OSError as error:
            raise OSError(error.errno, error.strerror or str(error), str(path)) from None
    return path


def _offscreen_window(width: int, height: int) -> vtkRenderWindow:
    """An off-screen render window: EGL when there is no X display (no window system needed),
    else VTK's default for this platform."""
    import vtkmodules.vtkRenderingFreeType
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 - the OpenGL implementations
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

    window: vtkRenderWindow
    if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
        from vtkmodules.vtkRenderingOpenGL2 import vtkEGLRenderWindow

        window = vtkEGLRenderWindow()
    else:
        window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(width, height)
    window.SetMultiSamples(0)  # FXAA instead: multisampled off-screen buffers are not everywhere
    return window


def _pixels(window: vtkRenderWindow, width: int, height: int) -> NDArray[np.uint8]:
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    output = grab.GetOutput()
    got_width, got_height, _ = output.GetDimensions()
    scalars = vtk_to_numpy(output.GetPointData().GetScalars())  # type: ignore[no-untyped-call]
    pixels = scalars.reshape(got_height, got_width, -1)[::-1]
    corner = pixels[0, 0, :3].astype(float) / 255.0
    if (got_width, got_height) != (width, height) or np.abs(corner - BACKGROUND_RGB).max() > 0.02:
        raise TorusCadError(
            "off-screen OpenGL did not render the preview (no EGL or OSMesa? on Debian: "
            "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri)"
        )
    return np.ascontiguousarray(pixels[..., :3], dtype=np.uint8)


def _place_camera(renderer: Any, vertices: NDArray[np.float64], view: View, aspect: float) -> None:
    """Orthographic camera along ``view``, framing the projected ``vertices`` with a margin."""
    toward = np.asarray(view.toward_camera, dtype=float)
    toward /= np.linalg.norm(toward)
    up = np.asarray(view.up, dtype=float)
    up = up - (up @ toward) * toward
    up /= np.linalg.norm(up)
    right = np.cross(up, toward)
    across, along = vertices @ right, vertices @ up
    centre_screen = np.array(
        [(across.min() + across.max()) / 2.0, (along.min() + along.max()) / 2.0]
    )
    half = max((across.max() - across.min()) / 2.0 / aspect, (along.max() - along.min()) / 2.0)
    depth = vertices @ toward
    focal = (
        centre_screen[0] * right
        + centre_screen[1] * up
        + ((depth.min() + depth.max()) / 2.0) * toward
    )
    distance = float(depth.max() - depth.min()) + 10.0 * half + 1.0
    camera = renderer.GetActiveCamera()
    camera.ParallelProjectionOn()
    camera.SetFocalPoint(*focal)
    camera.SetPosition(*(focal + distance * toward))
    camera.SetViewUp(*up)
    camera.SetParallelScale(half * 1.1 + 1e-9)  # 10 % margin; room for the label below
    renderer.ResetCameraClippingRange()


def _text(text: str, size_px: int, position: tuple[float, float], vertical: str) -> Any:
    from vtkmodules.vtkRenderingCore import vtkTextActor

    actor = vtkTextActor()
    actor.SetInput(text)
    style = actor.GetTextProperty()
    style.SetFontSize(max(size_px, 8))
    style.SetColor(*_TEXT_RGB)
    style.SetFontFamilyToArial()
    style.SetJustificationToCentered()
    {
        "bottom": style.SetVerticalJustificationToBottom,
        "center": style.SetVerticalJustificationToCentered,
    }[vertical]()
    actor.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    actor.SetPosition(*position)
    return actor


#: Width of an average character of the text font, in font sizes (Arial: about 0.55).
_CHARACTER_WIDTH = 0.55


def _fitting_font_px(text: str, size_px: int, width_px: float) -> int:
    """``size_px``, or smaller so that ``text`` fits in 95 % of ``width_px``."""
    return max(min(size_px, int(0.95 * width_px / (_CHARACTER_WIDTH * max(len(text), 1)))), 6)


def _title_height_px(height: int) -> int:
    return round(min(0.12 * height, 60.0))


def _label_size_px(height: int) -> int:
    return round(min(max(0.028 * height, 9.0), 30.0))
