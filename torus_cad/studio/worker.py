"""The studio's exact builds, each in its own process, so the page never waits on OpenCascade.

A build runs :func:`torus_cad.propeller.build_propeller` in a process forked from a
forkserver that has already imported cadquery (a new build starts in ~10 ms, not the ~3 s
of a fresh interpreter). A newer change kills the older build's process: a superseded build
never finishes, a slow one never queues the next, and an OpenCascade crash takes down only
that process. Results come back over a pipe as messages, in this order::

    ("solid", build_id, SolidResult)        the fused solid's tessellation, per part
    ("properties", build_id, dict)          MassProperties.to_dict() at 1 g/cm^3
    ("files", build_id, {"step": Path, "stl": Path})
    ("refused", build_id, "one-line reason")    ParameterError / GeometryError
    ("failed", build_id, "one-line reason")     KernelError or anything unexpected

Only the parent side (:class:`BuildRunner`) runs in the server process; it imports no kernel.
"""

from __future__ import annotations

import asyncio
import multiprocessing
import multiprocessing.connection
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.studio.scene import HUB_PART, PartMesh

#: Chordal deviation of the exact solid's display mesh, as a fraction of its bounding-box diagonal.
DISPLAY_RELATIVE_DEFLECTION = 1.0 / 1000.0

#: Angular deviation of the display mesh, radians.
DISPLAY_ANGULAR_DEFLECTION = 0.3

Message = tuple[str, int, Any]


@dataclass(frozen=True)
class BuildRequest:
    """One exact build: the design (``PropellerParameters.to_dict()``) and where its files go."""

    build_id: int
    design: dict[str, Any]
    out_dir: Path


@dataclass(frozen=True)
class SolidResult:
    """What the view and the readouts need from an exact build.

    Attributes:
        parts: one mesh per part (the hub first, then blade 0, 1, ...).
        stage_seconds: seconds per pipeline stage, plus ``tessellate``.
        fuse_route: how the blades were joined (torus_cad.propeller.FUSE_ROUTES).
        tip_diameter_mm: twice the largest distance of the solid from the spin axis, mm.
        solids: number of solids in the result (1: the build checks it).
    """

    parts: list[PartMesh]
    stage_seconds: dict[str, float]
    fuse_route: str
    tip_diameter_mm: float
    solids: int = 1
    valid: bool = True
    extra: dict[str, Any] = field(default_factory=dict)


# -- child side ------------------------------------------------------------------------------------

def preload() -> None:
    """Import the kernel and the pipeline (run once in the forkserver, before any build is forked)."""
    import torus_cad.kernel.export  # noqa: F401
    import torus_cad.propeller  # noqa: F401


def _face_parts(propeller: Any, faces: list[Any], face_vertices: list[NDArray[np.float64]]) -> list[int]:
    """Hub (-1) or blade i for each face: the hub's faces are its cylinder and end planes; a blade
    face belongs to the blade whose sampled surface passes nearest its vertices."""
    from scipy.spatial import cKDTree

    from torus_cad.geometry.centerline import blade_angle_deg

    blade_points = propeller.surface.points.reshape(-1, 3)
    clouds, labels = [], []
    for index in range(propeller.parameters.blades):
        turn = np.radians(blade_angle_deg(propeller.parameters, index) - blade_angle_deg(propeller.parameters, 0))
        rotation = np.array([[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0, 0, 1.0]])
        clouds.append(blade_points @ rotation.T)
        labels.append(np.full(len(blade_points), index))
    tree, label = cKDTree(np.concatenate(clouds)), np.concatenate(labels)
    parts = []
    for face, vertices in zip(faces, face_vertices):
        if face.geomType() in ("CYLINDER", "PLANE"):
            parts.append(HUB_PART)
            continue
        samples = vertices[np.linspace(0, len(vertices) - 1, min(25, len(vertices))).astype(int)]
        nearest = label[tree.query(samples)[1]]
        parts.append(int(np.bincount(nearest).argmax()))
    return parts


def _face_triangulation(face: Any) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The vertices ``(k, 3)`` and outward triangles ``(m, 3)`` of a meshed face (empty if unmeshed)."""
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_REVERSED
    from OCP.TopLoc import TopLoc_Location

    location = TopLoc_Location()
    triangulation = BRep_Tool.Triangulation_s(face, location)
    if triangulation is None:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    transform = location.Transformation()
    vertices = np.array([triangulation.Node(i).Transformed(transform).Coord()
                         for i in range(1, triangulation.NbNodes() + 1)], dtype=float)
    triangles = np.array([triangulation.Triangle(i).Get() for i in range(1, triangulation.NbTriangles() + 1)],
                         dtype=np.int64).reshape(-1, 3) - 1
    if face.Orientation() == TopAbs_REVERSED:
        triangles = triangles[:, ::-1]
    return vertices, triangles


def tessellate_parts(propeller: Any) -> list[PartMesh]:
    """The fused solid's triangles, grouped by part (hub, blade 0, 1, ...), for display."""
    import cadquery as cq
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    shape = propeller.solid.copy().wrapped  # leave the solid's own triangulation (used by the STL) alone
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    tolerance = max(np.sqrt(box.SquareExtent()) * DISPLAY_RELATIVE_DEFLECTION, 1e-3)
    BRepMesh_IncrementalMesh(shape, tolerance, False, DISPLAY_ANGULAR_DEFLECTION, False)
    faces, face_vertices, face_triangles = [], [], []
    for face in cq.Shape.cast(shape).Faces():
        vertices, triangles = _face_triangulation(face.wrapped)
        if len(triangles):
            faces.append(face)
            face_vertices.append(vertices)
            face_triangles.append(triangles)
    parts = _face_parts(propeller, faces, face_vertices)
    meshes = []
    for part in [HUB_PART, *range(propeller.parameters.blades)]:
        chosen = [index for index, owner in enumerate(parts) if owner == part]
        offsets = np.cumsum([0] + [len(face_vertices[index]) for index in chosen])
        vertices = np.concatenate([face_vertices[index] for index in chosen]) if chosen else np.zeros((0, 3))
        triangles = (np.concatenate([face_triangles[index] + offset for index, offset in zip(chosen, offsets)])
                     if chosen else np.zeros((0, 3), dtype=np.int64))
        meshes.append(PartMesh(part, vertices, triangles))
    return meshes


def _tip_diameter(parts: list[PartMesh]) -> float:
    radii = [np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1]).max() for mesh in parts if len(mesh.vertices)]
    return 2.0 * float(max(radii))


def run_build(request: BuildRequest, connection: multiprocessing.connection.Connection) -> None:
    """Build, tessellate, measure and export ``request``, sending each result as soon as it exists."""
    import time

    from torus_cad import PropellerParameters
    from torus_cad.errors import GeometryError, ParameterError, TorusCadError
    from torus_cad.kernel.checks import mass_properties
    from torus_cad.kernel.export import write_step, write_stl
    from torus_cad.propeller import build_propeller

    build_id = request.build_id
    try:
        params = PropellerParameters.from_dict(request.design)
        propeller = build_propeller(params)
        start = time.perf_counter()
        parts = tessellate_parts(propeller)
        stages = {**propeller.stage_seconds, "tessellate": time.perf_counter() - start}
        connection.send(("solid", build_id, SolidResult(parts, stages, propeller.fuse_route, _tip_diameter(parts))))
        start = time.perf_counter()
        properties = mass_properties(propeller.solid, 1.0).to_dict()
        properties["seconds"] = time.perf_counter() - start
        connection.send(("properties", build_id, properties))
        start = time.perf_counter()
        export = params.export
        paths = {"step": write_step(propeller.solid, request.out_dir / f"{params.name}.step", params.name,
                                    str(export.step_schema)),
                 "stl": write_stl(propeller.solid, request.out_dir / f"{params.name}.stl",
                                  export.stl_linear_deflection, export.stl_angular_deflection)}
        connection.send(("files", build_id, {"paths": paths, "seconds": time.perf_counter() - start}))
    except (ParameterError, GeometryError) as error:
        connection.send(("refused", build_id, str(error)))
    except TorusCadError as error:
        connection.send(("failed", build_id, f"OpenCascade failed: {error}"))
    except Exception as error:  # noqa: BLE001 - reported on the page, never a crashed server
        traceback.print_exc()
        connection.send(("failed", build_id, f"internal error ({type(error).__name__}): {error}"))
    finally:
        connection.close()


# -- parent side -----------------------------------------------------------------------------------

class BuildRunner:
    """Runs at most one build process at a time; a new request kills the one running.

    ``on_message(kind, build_id, payload)`` is called on the event loop for every message, and
    with ``("failed", build_id, reason)`` if the process dies without finishing.
    """

    def __init__(self, on_message: Callable[[str, int, Any], None]) -> None:
        self._on_message = on_message
        self._context = multiprocessing.get_context("forkserver")
        self._context.set_forkserver_preload([__name__])
        self._process: multiprocessing.process.BaseProcess | None = None
        self._connection: multiprocessing.connection.Connection | None = None
        self._build_id = -1
        self._finished = True

    @property
    def busy(self) -> bool:
        """Whether a build is running."""
        return self._process is not None and not self._finished

    def submit(self, request: BuildRequest) -> None:
        """Start ``request``, killing any build still running (it is superseded)."""
        self.cancel()
        request.out_dir.mkdir(parents=True, exist_ok=True)
        receiver, sender = self._context.Pipe(duplex=False)
        process = self._context.Process(target=_child_main, args=(request, sender), daemon=True,
                                        name=f"torus-cad-studio-build-{request.build_id}")
        process.start()
        sender.close()  # the child holds the only writer: its death ends our reads with EOF
        self._process, self._connection = process, receiver
        self._build_id, self._finished = request.build_id, False
        asyncio.get_running_loop().add_reader(receiver.fileno(), self._readable)

    def cancel(self) -> None:
        """Kill the running build, if any; its messages are dropped."""
        if self._connection is not None:
            asyncio.get_running_loop().remove_reader(self._connection.fileno())
            self._connection.close()
            self._connection = None
        if self._process is not None:
            if self._process.is_alive():
                self._process.kill()
            self._process.join(timeout=0)
            self._process = None
        self._finished = True

    def _readable(self) -> None:
        connection, build_id = self._connection, self._build_id
        if connection is None:
            return
        try:
            while connection.poll():
                kind, message_id, payload = connection.recv()
                self._on_message(kind, message_id, payload)
                if kind in ("files", "refused", "failed"):
                    self._finished = True
        except (EOFError, OSError):
            if not self._finished:
                code = self._process.exitcode if self._process is not None else None
                self._finished = True
                self._on_message("failed", build_id, f"the build process stopped unexpectedly (exit code {code})")
            if self._connection is connection:
                self.cancel()


def _child_main(request: BuildRequest, connection: multiprocessing.connection.Connection) -> None:
    run_build(request, connection)
