"""Off-screen preview picture of a propeller: an isometric view and a view along the spin axis.

Rendered with matplotlib's Agg backend (no window, no display, no OpenGL) from OpenCascade's
tessellation of the fused solid. Each face of the fused solid is coloured by the part it came
from (the hub grey, every blade its own colour) and shaded by its facet normals; back faces are
culled per view and the rest painted far to near::

    from torus_cad.propeller import build_propeller
    from torus_cad.preview import write_preview
    write_preview(build_propeller(), "propeller.png", size=(1200, 600))

matplotlib is imported only when a picture is made.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from numpy.typing import NDArray

import cadquery as cq

from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.kernel.checks import distances_to_shape, precise_volume
from torus_cad.kernel.export import atomic_path

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

#: Default picture size in pixels (width, height): two square views side by side.
DEFAULT_SIZE: tuple[int, int] = (1200, 600)

#: Smallest and largest accepted picture edge, pixels.
MIN_EDGE, MAX_EDGE = 64, 8000

#: Isometric view: elevation and azimuth of the camera, degrees (the classic (1, 1, 1) direction).
ISOMETRIC_VIEW: tuple[float, float] = (35.264, 45.0)

#: Along the spin axis: looking down the z axis from +z, x to the right, y up.
AXIAL_VIEW: tuple[float, float] = (90.0, -90.0)

_BACKGROUND = "white"
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

    def normals(self) -> NDArray[np.float64]:
        """Unit outward normal of each triangle, ``(m, 3)``."""
        corners = self.vertices[self.triangles]
        normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        length = np.linalg.norm(normal, axis=1, keepdims=True)
        return normal / np.where(length > 0.0, length, 1.0)

    def vertex_normals(self) -> NDArray[np.float64]:
        """Unit normal at each vertex, ``(k, 3)``: the area-weighted mean of its triangles' normals.

        Vertices are not shared between B-rep faces, so sharp edges (the hub's rims) stay sharp.
        """
        corners = self.vertices[self.triangles]
        weighted = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])  # 2 x area x normal
        sums = np.zeros_like(self.vertices)
        for corner in range(3):
            np.add.at(sums, self.triangles[:, corner], weighted)
        length = np.linalg.norm(sums, axis=1, keepdims=True)
        return sums / np.where(length > 0.0, length, 1.0)


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


def preview_mesh(solid: cq.Shape, hub: cq.Shape, blades: Sequence[cq.Shape],
                 tolerance: float | None = None, angular_tolerance: float = 0.2,
                 max_edge: float | None = None) -> PreviewMesh:
    """Tessellate ``solid`` (a copy: the caller's triangulation is left alone) and tag each face
    with the part (hub or blade i) it lies on, measured by OpenCascade's point-to-face distance.

    ``tolerance`` is the chordal deviation in mm (default: 1/3000 of the bounding-box diagonal).
    Triangles are split until no edge is longer than ``max_edge`` mm (default: 1/50 of the
    diagonal): a painter's algorithm sorts small triangles far better than the hub's long strips.
    """
    shape = solid.copy()
    diagonal = shape.BoundingBox().DiagonalLength
    if tolerance is None:
        tolerance = max(diagonal / 3000.0, 1e-3)
    if max_edge is None:
        max_edge = diagonal / 50.0
    parts: list[cq.Shape] = [hub, *blades]
    all_vertices: list[NDArray[np.float64]] = []
    all_triangles: list[NDArray[np.int64]] = []
    all_parts: list[NDArray[np.int64]] = []
    offset = 0
    shape.mesh(tolerance, angular_tolerance)
    boxes = [_box(part) for part in parts]
    for face in shape.Faces():
        points, triangles = face.tessellate(tolerance, angular_tolerance)  # reuses the solid's mesh
        if not triangles:
            continue
        vertices = np.array([point.toTuple() for point in points], dtype=float)
        indices = np.asarray(triangles, dtype=np.int64)
        part = _face_part(vertices, indices, parts, boxes, 10.0 * tolerance)
        vertices, indices = split_long_edges(vertices, indices, max_edge)
        all_vertices.append(vertices)
        all_triangles.append(indices + offset)
        all_parts.append(np.full(len(indices), part, dtype=np.int64))
        offset += len(vertices)
    if not all_triangles:
        raise ValueError("the solid has no triangulated faces to draw")
    return PreviewMesh(np.concatenate(all_vertices), np.concatenate(all_triangles), np.concatenate(all_parts))


def split_long_edges(vertices: NDArray[np.float64], triangles: NDArray[np.int64],
                     max_edge: float) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Halve every triangle's longest edge until none is longer than ``max_edge``.

    Orientation is kept, and an edge split from either side (in any pass) gets one shared midpoint.
    """
    if max_edge <= 0.0:
        raise ValueError(f"max_edge must be positive, got {max_edge}")
    vertices, triangles = np.asarray(vertices, dtype=float), np.asarray(triangles, dtype=np.int64)
    midpoint_of: dict[tuple[int, int], int] = {}  # edge (low, high) -> index of its midpoint
    new_points: list[NDArray[np.float64]] = []
    while len(triangles):
        corners = vertices[triangles]
        lengths = np.linalg.norm(corners - np.roll(corners, -1, axis=1), axis=2)  # edges 01, 12, 20
        longest = lengths.argmax(axis=1)
        split = lengths[np.arange(len(triangles)), longest] > max_edge
        if not split.any():
            break
        chosen, which = triangles[split], longest[split]
        rows = np.arange(len(chosen))
        a, b, c = chosen[rows, which], chosen[rows, (which + 1) % 3], chosen[rows, (which + 2) % 3]
        middle = np.empty(len(chosen), dtype=np.int64)
        new_points.clear()
        for row, edge in enumerate(zip(np.minimum(a, b).tolist(), np.maximum(a, b).tolist())):
            index = midpoint_of.get(edge)
            if index is None:
                index = midpoint_of[edge] = len(vertices) + len(new_points)
                new_points.append((vertices[edge[0]] + vertices[edge[1]]) / 2.0)
            middle[row] = index
        if new_points:
            vertices = np.concatenate([vertices, np.array(new_points)])
        triangles = np.concatenate([triangles[~split], np.column_stack([a, middle, c]),
                                    np.column_stack([middle, b, c])])
    return vertices, triangles


def _face_part(vertices: NDArray[np.float64], triangles: NDArray[np.int64], parts: Sequence[cq.Shape],
               boxes: Sequence[tuple[NDArray[np.float64], NDArray[np.float64]]], slack: float) -> int:
    """-1 for the hub, i for blade i: the part whose boundary passes nearest a few of the face's facets.

    Parts whose bounding box (grown by ``slack`` mm) does not hold the samples are ruled out first;
    OpenCascade measures distances only when more than one part is left.
    """
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


def _view_vectors(elevation: float, azimuth: float) -> tuple[NDArray[np.float64], ...]:
    """Unit vectors toward the camera, to the screen's right and up, for matplotlib's view angles."""
    elev, azim = np.radians(elevation), np.radians(azimuth)
    eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
    right = np.array([-np.sin(azim), np.cos(azim), 0.0])
    up = np.cross(eye, right)
    return eye, right, up


def _shaded_colors(mesh: PreviewMesh, vertex_normals: NDArray[np.float64], keep: NDArray[np.bool_],
                   eye: NDArray[np.float64], right: NDArray[np.float64], up: NDArray[np.float64],
                   blades: int) -> NDArray[np.float64]:
    """RGBA per kept triangle: ambient + Lambert + a little Blinn-Phong (a key light above-left of
    the camera, a weak fill from the right), evaluated at the smooth vertex normals and averaged
    over each triangle's corners, so that the facets do not show."""
    light = eye + 0.55 * up - 0.35 * right
    light /= np.linalg.norm(light)
    fill = eye - 0.3 * up + 0.5 * right
    fill /= np.linalg.norm(fill)
    halfway = (light + eye) / np.linalg.norm(light + eye)
    n = vertex_normals[mesh.triangles[keep]]  # (m, 3 corners, 3)
    diffuse = np.clip(n @ light, 0.0, 1.0).mean(axis=1)
    fill_diffuse = np.clip(n @ fill, 0.0, 1.0).mean(axis=1)
    specular = (np.clip(n @ halfway, 0.0, 1.0) ** 40).mean(axis=1)
    palette = np.array([HUB_COLOR] + [blade_color(i, blades) for i in range(blades)])
    base = palette[mesh.parts[keep] + 1]
    intensity = (0.28 + 0.62 * diffuse + 0.18 * fill_diffuse)[:, None]
    rgb = np.clip(base * intensity + 0.35 * specular[:, None], 0.0, 1.0)
    return np.column_stack([rgb, np.ones(len(rgb))])


def _draw_view(figure: Figure, rect: Sequence[float], mesh: PreviewMesh, normals: NDArray[np.float64],
               vertex_normals: NDArray[np.float64], view: tuple[float, float], label: str, blades: int) -> None:
    """One orthographic view in ``rect`` (figure fractions): cull back faces, paint far to near."""
    from matplotlib.collections import PolyCollection

    eye, right, up = _view_vectors(*view)
    keep = normals @ eye > -1e-9  # back faces of a closed solid are hidden: cull them
    colors = _shaded_colors(mesh, vertex_normals, keep, eye, right, up, blades)
    screen = np.column_stack([mesh.vertices @ right, mesh.vertices @ up])  # orthographic projection, mm
    triangles = mesh.triangles[keep]
    order = np.argsort((mesh.vertices @ eye)[triangles].mean(axis=1), kind="stable")  # far first
    axes: Any = figure.add_axes(rect)
    # Edges stroked in the face colour, ~0.8 px wide, hide the antialiasing seams between facets.
    axes.add_collection(PolyCollection(screen[triangles[order]], facecolors=colors[order],
                                       edgecolors=colors[order], linewidths=0.8 * 72.0 / figure.dpi,
                                       antialiaseds=True))
    # Limits with the axes' own width : height ratio, so one mm is as long across as up.
    low, high = screen.min(axis=0), screen.max(axis=0)
    margin = 0.06 * float((high - low).max())
    low, high = low - margin, high + margin
    low[1] -= margin  # a little more room below, for the label
    box_ratio = rect[2] * figure.bbox.width / (rect[3] * figure.bbox.height)
    span_x, span_y = high - low
    span_x, span_y = max(span_x, span_y * box_ratio), max(span_y, span_x / box_ratio)
    centre = (low + high) / 2.0
    axes.set_xlim(centre[0] - span_x / 2.0, centre[0] + span_x / 2.0)
    axes.set_ylim(centre[1] - span_y / 2.0, centre[1] + span_y / 2.0)
    axes.set_axis_off()
    axes.text(0.5, 0.01, label, transform=axes.transAxes, ha="center", va="bottom", fontsize=10, color="0.35")


def render_preview(propeller: _HasParts, size: Sequence[int] = DEFAULT_SIZE, title: str | None = None,
                   progress: Callable[[str], None] | None = None) -> NDArray[np.uint8]:
    """The preview picture as an ``(height, width, 4)`` RGBA uint8 array of exactly ``size`` pixels.

    Args:
        propeller: a built propeller (``torus_cad.propeller.Propeller`` or
            ``torus_cad.propeller.Propeller``): its ``solid``, ``hub`` and ``blades``.
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
                        tolerance=max(diagonal / (2.5 * min(width / 2.0, height) * 2.0), 1e-3))
    normals, vertex_normals = mesh.normals(), mesh.vertex_normals()
    if title is None:
        volume = precise_volume(propeller.solid, 1e-5)  # shown to 4-5 digits: a coarser integral will do
        title = (f"{propeller.parameters.name}: {blades} blade{'s' if blades != 1 else ''}, "
                 f"volume {volume:,.0f} mm³")
    if progress:
        progress("render")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    dpi = max(height / 6.0, 20.0)  # text scales with the picture; 600 px high -> 100 dpi
    # A hair over the exact size so that Agg's int() truncation cannot lose a pixel.
    figure = Figure(figsize=((width + 1e-3) / dpi, (height + 1e-3) / dpi), dpi=dpi, facecolor=_BACKGROUND)
    canvas = FigureCanvasAgg(figure)
    top = 1.0 - min(0.12, 40.0 / dpi / (height / dpi))  # room for the title
    for column, (view, label) in enumerate(((ISOMETRIC_VIEW, "isometric"),
                                            (AXIAL_VIEW, "along the spin axis (+z toward you)"))):
        _draw_view(figure, (0.5 * column, 0.0, 0.5, top), mesh, normals, vertex_normals, view, label, blades)
    figure.suptitle(title, y=1.0 - 0.02, va="top", fontsize=13, color="0.15")
    canvas.draw()
    image = np.asarray(canvas.buffer_rgba())[:height, :width].copy()
    if image.shape[:2] != (height, width):  # pragma: no cover - Agg gave fewer pixels than asked
        padded = np.full((height, width, 4), 255, dtype=np.uint8)
        padded[: image.shape[0], : image.shape[1]] = image
        image = padded
    return image


def write_preview(propeller: _HasParts, path: str | Path, size: Sequence[int] = DEFAULT_SIZE,
                  title: str | None = None, progress: Callable[[str], None] | None = None) -> Path:
    """Render the preview (see :func:`render_preview`) and write it as a PNG, atomically; return the path."""
    from matplotlib.image import imsave

    image = render_preview(propeller, size, title, progress)
    path = Path(path)
    with atomic_path(path) as temp:
        imsave(temp, image, format="png")
    return path
