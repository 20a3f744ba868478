"""Measures of a B-rep face that tests share (imported by test modules as ``face_measures``)."""

from __future__ import annotations

import cadquery as cq
import numpy as np
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools

from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.checks import distances_to_shape

#: A face's tessellation vertices lie on its own part to this (mm); at least half of them are
#: farther than ON_OTHER_PART_MM from every other part (the rest may lie on a shared edge).
ON_PART_MM, OFF_OTHER_PART_MM = 1e-4, 1e-2


def principal_curvatures(face: cq.Face) -> list[float]:
    """|k_min|, |k_max| (1/mm, ascending) at the middle of ``face``'s parameter box: a fillet face
    of radius r has 1/r as the larger one."""
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face.wrapped)
    properties = BRepLProp_SLProps(
        BRepAdaptor_Surface(face.wrapped), (u_min + u_max) / 2, (v_min + v_max) / 2, 2, 1e-9
    )
    return sorted((abs(properties.MinCurvature()), abs(properties.MaxCurvature())))


def assert_faces_come_from_their_parts(
    solid, face_parts, propeller, fillet_radius_mm: float = 0.0
) -> None:
    """Every face of ``solid`` lies on the part ``face_parts`` names (``propeller.hub`` or
    ``propeller.blades[i]``, as built before the fuse) and off every other; every part shows. With
    a root fillet, a face lies within two radii of its part and nearer it than any other blade."""
    faces = solid.Faces()
    blades = len(propeller.blades)
    assert len(face_parts) == len(faces)
    assert set(face_parts) == {HUB_PART, *range(blades)}  # every part shows
    parts = {HUB_PART: propeller.hub, **dict(enumerate(propeller.blades))}
    for face, part in zip(faces, face_parts, strict=True):
        vertices, _ = face.tessellate(0.2, 0.5)
        points = np.array([vertex.toTuple() for vertex in vertices]).reshape(-1, 3)
        if not len(points):  # a face too small to tessellate: the middle of its parameter box
            points = np.array([face.positionAt(0.5, 0.5).toTuple()])
        points = points[np.linspace(0, len(points) - 1, min(8, len(points))).astype(int)]
        distance = {
            other: float(np.median(distances_to_shape(shape, points)))
            for other, shape in parts.items()
        }
        if fillet_radius_mm == 0.0:
            assert distance[part] < ON_PART_MM, (part, distance)
            assert all(distance[other] > OFF_OTHER_PART_MM for other in parts if other != part), (
                part,
                distance,
            )
        # a hub end face cut back through the fillet's run-out reaches into the fillet's section too
        else:
            rivals = (
                range(blades)
                if part == HUB_PART
                else [other for other in range(blades) if other != part]
            )
            assert distance[part] < 2.0 * fillet_radius_mm + ON_PART_MM, (part, distance)
            assert all(distance[part] < distance[other] for other in rivals), (part, distance)
