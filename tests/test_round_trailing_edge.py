"""Round blunt trailing edge: a cap tangent to both surfaces, so the
section is one smooth closed curve, the trailing edge has the requested thickness, and the root
fillet rolls round it, on the solid (the geometry: tests/test_trailing_edge.py)."""

from __future__ import annotations

import numpy as np
import pytest
from face_measures import principal_curvatures
from scipy.interpolate import BSpline

from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.geometry.blade.blade_surface import blade_frames
from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.kernel.measure import (
    contour_through,
    farthest_middle_edge,
    plane_section_edges,
    straight_edges,
)
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

LIGHT = {"resolution.sections": 16, "resolution.points": 48}


def _section_curve_tangents(curves, section, parameter):
    """Unit tangents just before and just after ``parameter`` on one section's kernel curve."""
    curve = BSpline(curves.knots, curves.poles[section], 3)
    derivative = curve.derivative()
    before, after = derivative(parameter - 1e-12), derivative(parameter + 1e-12)
    return before / np.linalg.norm(before), after / np.linalg.norm(after)


def test_section_curves_are_g1_at_the_round_cap():
    propeller = build_propeller(None, {"airfoil.trailing_edge_thickness": 0.4, **LIGHT})
    curves = propeller.section_curves
    assert curves.round_trailing_edge
    distinct, multiplicities = np.unique(curves.knots, return_counts=True)
    # the cap ends at L, a knot of multiplicity 3
    lower_joint = distinct[1:-1][multiplicities[1:-1] == 3][0]
    for section in range(curves.poles.shape[0]):
        before, after = _section_curve_tangents(curves, section, lower_joint)
        assert np.linalg.norm(np.cross(before, after)) < 1e-9 and before @ after > 0.0
        # at U the curve closes: its end tangent continues into its start tangent
        start, _ = _section_curve_tangents(curves, section, 1e-11)
        end, _ = _section_curve_tangents(curves, section, 1.0 - 1e-11)
        assert np.linalg.norm(np.cross(start, end)) < 1e-9 and start @ end > 0.0


def _cap_chords_mm(propeller, s_values):
    """Distance between the ends of the round cap's cut in the section planes at ``s_values``."""
    geometry = propeller_geometry(propeller.parameters)
    frames = blade_frames(geometry.blade, geometry.centerline(0), s_values)
    chords = []
    for origin, tangent in zip(frames.origin, frames.tangent):
        edges = contour_through(plane_section_edges(propeller.solid, origin, tangent, 15.0), origin)
        assert not straight_edges(edges)  # no flat base
        cap = farthest_middle_edge(edges, origin)
        chords.append((cap.endPoint() - cap.startPoint()).Length)
    return chords


def test_round_edge_measured_on_the_solid():
    """The chord of the cap's cut in a section plane (the cap's ends, where it meets the surfaces)
    is the requested thickness, on a section and half-way between two."""
    params = PropellerParameters().with_values({"airfoil.trailing_edge_thickness": 0.4, **LIGHT})
    propeller = build_propeller(params)
    assert is_valid_closed_solid(propeller.solid)
    for chord in _cap_chords_mm(propeller, [0.5, 0.5 + 0.5 / 15.0]):
        assert chord == pytest.approx(0.4, rel=0.01)


@pytest.mark.parametrize("thickness_mm, radius_mm", [(0.3, 0.5), (0.8, 1.0)])
def test_root_fillet_rolls_round_the_round_edge(thickness_mm, radius_mm):
    """The default with a round blunt edge and a root fillet: one valid solid, a fillet face of the
    requested radius, and the edge still the requested thickness."""
    propeller = build_propeller(
        None, {"airfoil.trailing_edge_thickness": thickness_mm, "hub.root_fillet_radius": radius_mm}
    )
    assert is_valid_closed_solid(propeller.solid)
    fillet_faces = [
        face
        for face in propeller.solid.Faces()
        if principal_curvatures(face)[1] == pytest.approx(1 / radius_mm, rel=1e-3)
    ]
    assert len(fillet_faces) >= 3  # at least one per blade
    assert _cap_chords_mm(propeller, [0.5])[0] == pytest.approx(thickness_mm, rel=0.01)


def test_flat_edge_fillet_failure_names_the_round_edge(tmp_path, capsys):
    """A flat base's corners stop the fillet: exit 1, nothing written, and the message says which
    shape takes it."""
    from torus_cad.cli import main

    assert (
        main(
            [
                "build",
                "--set",
                "airfoil.trailing_edge_thickness=0.3",
                "--set",
                "airfoil.trailing_edge_shape=flat",
                "--set",
                "hub.root_fillet_radius=0.5",
                "--out",
                str(tmp_path / "out"),
            ]
        )
        == 1
    )
    error = capsys.readouterr().err
    assert "root fillet failed" in error and "airfoil.trailing_edge_shape = 'round'" in error
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())
