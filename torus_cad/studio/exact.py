"""The exact solid for the studio, in the build process: build, tessellate by part, measure, export.

Runs in the worker process (torus_cad.studio.worker), never in the server: it imports the kernel.
"""

from __future__ import annotations

import multiprocessing.connection
import time

import numpy as np
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib

from torus_cad import PropellerParameters
from torus_cad.errors import GeometryError, ParameterError, TorusCadError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.mass_properties import mass_properties
from torus_cad.kernel.tessellation import tessellate_faces
from torus_cad.propeller import Propeller, build_propeller
from torus_cad.studio.messages import BuildRequest, SolidResult, failures_reported
from torus_cad.studio.scene import PartMesh, tip_diameter_mm

#: Chordal deviation of the exact solid's display mesh, as a fraction of its bounding-box diagonal.
DISPLAY_RELATIVE_DEFLECTION = 1.0 / 1000.0

#: Angular deviation of the display mesh, radians. It sets the cost: 0.3 meshes the default
#: 4-blade propeller in twice the time of 0.5 (13k against 5k triangles); the view smooths normals.
DISPLAY_ANGULAR_DEFLECTION = 0.5


def tessellate_parts(propeller: Propeller) -> list[PartMesh]:
    """The fused solid's triangles, grouped by part (hub, blade 0, 1, ...), for display."""
    box = Bnd_Box()
    BRepBndLib.Add_s(propeller.solid.wrapped, box)
    tolerance = max(np.sqrt(box.SquareExtent()) * DISPLAY_RELATIVE_DEFLECTION, 1e-3)
    # Not in parallel: on a busy 2-core machine the mesher's threads only contend with the server.
    tessellated = tessellate_faces(
        propeller.solid, tolerance, DISPLAY_ANGULAR_DEFLECTION, parallel=False
    )
    face_vertices = [face.vertices for face in tessellated]
    face_triangles = [face.triangles for face in tessellated]
    # from the build's history
    parts = [propeller.face_parts[face.face_index] for face in tessellated]
    meshes = []
    for part in [HUB_PART, *range(propeller.parameters.blades)]:
        chosen = [index for index, owner in enumerate(parts) if owner == part]
        offsets = np.cumsum([0] + [len(face_vertices[index]) for index in chosen])
        vertices = (
            np.concatenate([face_vertices[index] for index in chosen])
            if chosen
            else np.zeros((0, 3))
        )
        triangles = (
            np.concatenate(
                [face_triangles[index] + offset for index, offset in zip(chosen, offsets)]
            )
            if chosen
            else np.zeros((0, 3), dtype=np.int64)
        )
        meshes.append(PartMesh(part, vertices, triangles))
    return meshes


def run_build(
    request: BuildRequest,
    connection: multiprocessing.connection.Connection,
    memory_limit_bytes: int | None = None,
) -> None:
    """Build, tessellate, measure and export ``request``, sending each result as soon as it exists.

    ``memory_limit_bytes``: the process's memory limit, named when an allocation fails.
    """
    build_id = request.build_id
    with failures_reported(
        connection,
        build_id,
        "the exact build",
        memory_limit_bytes,
        "; lower resolution.sections / resolution.points",
    ):
        try:
            _build_and_send(request, connection)
        except (ParameterError, GeometryError) as error:
            connection.send(("refused", build_id, str(error)))
        except TorusCadError as error:
            connection.send(("failed", build_id, f"OpenCascade failed: {error}"))


def _build_and_send(
    request: BuildRequest, connection: multiprocessing.connection.Connection
) -> None:
    """The solid, its mass properties and its files, each sent as soon as it exists."""
    build_id = request.build_id
    propeller = build_propeller(PropellerParameters.from_dict(request.design))
    params = propeller.parameters  # with the design targets (diameter, pitch, naca) applied
    start = time.perf_counter()
    parts = tessellate_parts(propeller)
    stages = {**propeller.stage_seconds, "display_mesh": time.perf_counter() - start}
    connection.send(
        ("solid", build_id, SolidResult(parts, stages, propeller.fuse_route.description))
    )
    start = time.perf_counter()
    properties = mass_properties(propeller.solid, 1.0).to_dict()
    properties["seconds"] = time.perf_counter() - start
    properties["tip_diameter_mm"] = tip_diameter_mm(params)
    connection.send(("properties", build_id, properties))
    start = time.perf_counter()
    # The files `torus-cad build` writes: export.formats (STEP, STL, 3MF), the blade-element table,
    # the report.
    paths = propeller.write(request.out_dir, stl=True, sections_table=True)
    connection.send(("files", build_id, {"paths": paths, "seconds": time.perf_counter() - start}))
