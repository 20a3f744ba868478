"""Round blunt trailing edge (issue 13 parts 3 and 5): a cap tangent to both surfaces, so the
section is one smooth closed curve, the trailing edge has the requested thickness, and the root
fillet rolls round it."""

from __future__ import annotations

import numpy as np
import pytest
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepLProp import BRepLProp_SLProps
from OCP.BRepTools import BRepTools
from scipy.interpolate import BSpline

from torus_cad.geometry.arc_length import ROUND_CAP_MINIMUM_POINTS, equal_arc_length_section
from torus_cad.geometry.printability import printability
from torus_cad.geometry.section import (
    RoundTrailingEdge,
    cap_points,
    closed_points,
    end_tangents,
    half_ends,
)
from torus_cad.geometry.surface import blade_frames, sections_along
from torus_cad.geometry.trailing_edge import (
    ROUND_CAP_HANDLE_FRACTION,
    blunt_sections,
    section_matrices,
    trailing_edge_thickness_mm,
)
from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.kernel.measure import contour_through, farthest_middle_edge, plane_section_edges, straight_edges
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import TrailingEdgeShape
from torus_cad.propeller import build_propeller

LIGHT = {"resolution.sections": 16, "resolution.points": 48}
ANGLE, SCALE_X, SCALE_Y = [20.0, 35.0], [12.0, 6.0], [4.0, 2.0]


def _round_sections(thickness_mm=0.4):
    airfoil = PropellerParameters().geometry().blade.airfoil
    return blunt_sections(airfoil, thickness_mm, ANGLE, SCALE_X, SCALE_Y, round_cap=True)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def test_round_cap_leaves_each_surface_along_its_tangent():
    for section in _round_sections():
        assert isinstance(section, RoundTrailingEdge)
        poles = section.cap_poles()
        tangents = end_tangents(section)
        leaving, arriving = poles[1] - poles[0], poles[3] - poles[2]
        # the cap starts in the upper surface's direction and arrives along the lower one's reversed
        assert abs(_cross(leaving / np.linalg.norm(leaving), tangents[0])) < 1e-12
        assert leaving @ tangents[0] > 0.0
        assert abs(_cross(arriving / np.linalg.norm(arriving), -tangents[1])) < 1e-12
        # closed_points runs through the cap between t = 1 and 2, from U to L
        np.testing.assert_allclose(closed_points(section, [1.0, 2.0]), half_ends(section), atol=1e-14)


def test_round_cap_keeps_the_thickness_and_is_a_near_half_circle_in_mm():
    sections = _round_sections(0.4)
    np.testing.assert_allclose(trailing_edge_thickness_mm(sections, ANGLE, SCALE_X, SCALE_Y), 0.4, rtol=1e-10)
    matrices = section_matrices(ANGLE, SCALE_X, SCALE_Y)
    for matrix, section in zip(matrices, sections):
        poles_mm = section.cap_poles() @ matrix.T
        handles_mm = np.linalg.norm(poles_mm[[1, 2]] - poles_mm[[0, 3]], axis=1)
        np.testing.assert_allclose(handles_mm, ROUND_CAP_HANDLE_FRACTION * 0.4, rtol=1e-9)
        cap_mm = cap_points(section, np.linspace(0.0, 1.0, 201)) @ matrix.T
        # it reaches aft of its ends by about a radius (a half circle: 0.2 mm; less where the surfaces converge)
        across = (poles_mm[0] - poles_mm[3]) / 0.4
        aft = np.array([across[1], -across[0]])
        reach = np.max(np.abs((cap_mm - 0.5 * (poles_mm[0] + poles_mm[3])) @ aft))
        assert 0.1 < reach < 0.25


def test_equal_arc_length_sampling_covers_the_cap():
    section = _round_sections()[0]
    sampling = equal_arc_length_section(section, 200)
    te, lower = sampling.trailing_edge_index, sampling.lower_corner_index
    assert lower - te >= ROUND_CAP_MINIMUM_POINTS
    cap = sampling.points[te:lower + 1]
    np.testing.assert_allclose(cap[[0, -1]], half_ends(section), atol=1e-14)
    # the points lie on the cap and are equally spaced in its arc length
    np.testing.assert_allclose(closed_points(section, sampling.t[te:lower + 1]), cap, atol=1e-14)
    cap_t = sampling.t[te:lower + 1] - 1.0
    arcs = [np.linalg.norm(np.diff(cap_points(section, np.linspace(a, b, 2001)), axis=0), axis=1).sum()
            for a, b in zip(cap_t[:-1], cap_t[1:])]
    assert max(arcs) / min(arcs) < 1.001


def test_sharp_default_is_the_same_whatever_the_shape():
    round_surface = PropellerParameters().blade_surface()
    flat_surface = PropellerParameters().with_values({"airfoil.trailing_edge_shape": "flat"}).blade_surface()
    assert np.array_equal(round_surface.points, flat_surface.points)
    assert round_surface.lower_corner_index is None and not round_surface.round_trailing_edge


def test_shape_choice_is_validated():
    params = PropellerParameters().with_values({"airfoil.trailing_edge_shape": "flat"})
    assert params.airfoil.trailing_edge_shape == TrailingEdgeShape.FLAT
    assert PropellerParameters().airfoil.trailing_edge_shape == TrailingEdgeShape.ROUND
    with pytest.raises(Exception, match="trailing_edge_shape"):
        PropellerParameters().with_values({"airfoil.trailing_edge_shape": "pointy"})


def test_coordinate_file_with_an_open_edge_gets_a_round_cap():
    params = PropellerParameters.from_toml("examples/prop_10x5_2blade.toml")
    blade = params.geometry().blade
    sections = sections_along(blade, [0.2, 0.5])
    assert all(isinstance(section, RoundTrailingEdge) for section in sections)
    # the cap closes the file's own gap: the surfaces are the file's
    np.testing.assert_allclose(half_ends(sections[0]), half_ends(blade.airfoil), atol=1e-12)
    assert params.blade_surface().round_trailing_edge


def test_printability_reports_the_round_edge_thickness():
    blade = PropellerParameters().with_values({"airfoil.trailing_edge_thickness": 0.9}).geometry().blade
    assert blade.round_trailing_edge
    result = printability(blade, 0.8)
    assert result.trailing_edge_thickness_mm == pytest.approx(0.9, rel=1e-6)


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
    lower_joint = distinct[1:-1][multiplicities[1:-1] == 3][0]  # the cap ends at L, a knot of multiplicity 3
    for section in range(curves.poles.shape[0]):
        before, after = _section_curve_tangents(curves, section, lower_joint)
        assert np.linalg.norm(np.cross(before, after)) < 1e-9 and before @ after > 0.0
        # at U the curve closes: its end tangent continues into its start tangent
        start, _ = _section_curve_tangents(curves, section, 1e-11)
        end, _ = _section_curve_tangents(curves, section, 1.0 - 1e-11)
        assert np.linalg.norm(np.cross(start, end)) < 1e-9 and start @ end > 0.0


def _cap_chords_mm(propeller, s_values):
    """Distance between the ends of the round cap's cut in the section planes at ``s_values``."""
    geometry = propeller.parameters.geometry()
    frames = blade_frames(geometry.blade, geometry.centerline(0), s_values)
    chords = []
    for origin, tangent in zip(frames.origin, frames.tangent):
        edges = contour_through(plane_section_edges(propeller.solid, origin, tangent, 15.0), origin)
        assert not straight_edges(edges)  # no flat base
        cap = farthest_middle_edge(edges, origin)
        chords.append((cap.endPoint() - cap.startPoint()).Length)
    return chords


@pytest.mark.slow
def test_round_edge_measured_on_the_solid():
    """The chord of the cap's cut in a section plane (the cap's ends, where it meets the surfaces)
    is the requested thickness, on a section and half-way between two."""
    params = PropellerParameters().with_values({"airfoil.trailing_edge_thickness": 0.4, **LIGHT})
    propeller = build_propeller(params)
    assert is_valid_closed_solid(propeller.solid)
    for chord in _cap_chords_mm(propeller, [0.5, 0.5 + 0.5 / 15.0]):
        assert chord == pytest.approx(0.4, rel=0.01)


def _principal_curvatures(face):
    u_min, u_max, v_min, v_max = BRepTools.UVBounds_s(face.wrapped)
    properties = BRepLProp_SLProps(BRepAdaptor_Surface(face.wrapped), (u_min + u_max) / 2, (v_min + v_max) / 2,
                                   2, 1e-9)
    return sorted((abs(properties.MinCurvature()), abs(properties.MaxCurvature())))


@pytest.mark.slow
@pytest.mark.parametrize("thickness_mm, radius_mm", [(0.3, 0.5), (0.8, 1.0)])
def test_root_fillet_rolls_round_the_round_edge(thickness_mm, radius_mm):
    """The default with a round blunt edge and a root fillet: one valid solid, a fillet face of the
    requested radius, and the edge still the requested thickness."""
    propeller = build_propeller(None, {"airfoil.trailing_edge_thickness": thickness_mm,
                                       "hub.root_fillet_radius": radius_mm})
    assert is_valid_closed_solid(propeller.solid)
    fillet_faces = [face for face in propeller.solid.Faces()
                    if _principal_curvatures(face)[1] == pytest.approx(1 / radius_mm, rel=1e-3)]
    assert len(fillet_faces) >= 3  # at least one per blade
    assert _cap_chords_mm(propeller, [0.5])[0] == pytest.approx(thickness_mm, rel=0.01)
