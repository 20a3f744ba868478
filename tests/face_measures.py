"""Measures of a B-rep face that tests share (imported by test modules as ``face_measures``)."""

from __future__ import annotations

import cadquery as cq
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools


def principal_curvatures(face: cq.Face) -> list[float]:
    """|k_min|, |k_max| (1/mm, ascending) at the middle of ``face``'s parameter box: a fillet face
    of radius r has 1/r as the larger one."""
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face.wrapped)
    properties = BRepLProp_SLProps(BRepAdaptor_Surface(face.wrapped), (u_min + u_max) / 2, (v_min + v_max) / 2,
                                   2, 1e-9)
    return sorted((abs(properties.MinCurvature()), abs(properties.MaxCurvature())))
