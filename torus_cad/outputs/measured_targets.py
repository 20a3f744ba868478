"""The designer's targets checked on what was built: where blade 0 passes a radius, and the
geometric pitch of the built solid's section there, measured on the B-rep (tests and
``scripts/measure_targets.py`` compare it with the pitch asked for)."""

from __future__ import annotations

from typing import Any

import numpy as np

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.geometry.analysis.blade_elements import blade_angles
from torus_cad.geometry.blade.blade_surface import blade_frames
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.transforms import evaluate_quartic
from torus_cad.outputs.sections_table import elements_of


def radius_crossings(
    params: Any, radius_mm: float, sections: int = 801
) -> list[tuple[float, float]]:
    """``(s, geometric pitch mm)`` where blade 0 passes ``radius_mm`` (analytic, ``sections``
    samples)."""
    fine = elements_of(sampled_blade_surface(params, sections=sections, points=48))
    found = []
    for i in np.flatnonzero(np.diff(np.sign(fine.radius_mm - radius_mm))):
        w = (radius_mm - fine.radius_mm[i]) / (fine.radius_mm[i + 1] - fine.radius_mm[i])
        found.append(
            (
                float(fine.s[i] + w * (fine.s[i + 1] - fine.s[i])),
                float(fine.pitch_mm[i] + w * (fine.pitch_mm[i + 1] - fine.pitch_mm[i])),
            )
        )
    return found


def pitch_on_solid(propeller: Any, s: float, spin: Handedness = Handedness.CW) -> float:
    """Geometric pitch (mm) of the built solid's section in the plane of section ``s``.

    Measured on the B-rep: the plane cuts the solid and the contour through the centerline's
    point is sampled. The leading edge is the contour's point on the centerline (the spec's
    pivot 0 puts it there); the trailing edge is the middle of the contour's straight edge
    (a flat blunt base) if it has one, the middle of the chord of a round cap's cut (its ends are
    the surfaces' ends, as the design's trailing edge is their middle), else the contour's point
    farthest from the leading edge.
    """
    from torus_cad.kernel.measure import (
        contour_through,
        edge_points,
        farthest_middle_edge,
        plane_section_edges,
        straight_edges,
    )

    geometry = propeller_geometry(propeller.parameters)
    frames = blade_frames(geometry.blade, geometry.centerline(0), [s])
    # A ccw solid is the spec's blade mirrored (y -> -y, kernel/mirror.py): cut it in the mirrored
    # plane, and mirror what is measured back, so the pitch is the spec blade's, as designed.
    # here: the schema resolves design targets itself
    from torus_cad.parameters.design import Handedness

    flip = np.array([1.0, -1.0 if propeller.parameters.handedness == Handedness.CCW else 1.0, 1.0])
    origin = frames.origin[0] * flip
    reach = 2.0 * float(np.max(evaluate_quartic(geometry.blade.laws.scale_x_mm, [s])))
    edges = contour_through(
        plane_section_edges(propeller.solid, origin, frames.tangent[0] * flip, reach), origin
    )
    points = edge_points(edges, 1000)
    leading = points[int(np.argmin(np.linalg.norm(points - origin, axis=1)))]
    bases = straight_edges(edges)
    if bases:
        trailing = np.asarray(bases[0].positionAt(0.5).toTuple(), dtype=float)
    elif propeller.surface.round_trailing_edge:
        cap = farthest_middle_edge(edges, leading)
        trailing = 0.5 * np.add(cap.startPoint().toTuple(), cap.endPoint().toTuple())
    else:
        trailing = points[int(np.argmax(np.linalg.norm(points - leading, axis=1)))]
    leading, trailing = leading * flip, trailing * flip
    middle = 0.5 * (leading + trailing)
    beta, _ = blade_angles(middle[None], (trailing - leading)[None], spin)
    return float(2.0 * np.pi * np.hypot(middle[0], middle[1]) * np.tan(np.radians(beta[0])))
