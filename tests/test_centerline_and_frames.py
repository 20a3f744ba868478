"""Centerline in frame L (spec §3) and its moving frames (spec §4)."""

import numpy as np
import pytest

from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.errors import GeometryError
from torus_cad.geometry.blade.centerline import Centerline, local_to_cylindrical
from torus_cad.geometry.blade.frames import frenet_frames, rotation_minimizing_frames
from torus_cad.parameters import PropellerParameters

S = np.linspace(0.0, 1.0, 41)


def test_p1_sits_at_the_spec_position():
    params = PropellerParameters().with_values(
        {"hub.radius": 16.0, "hub.length": 30.0, "phase_deg": 30.0}
    )
    p1 = propeller_geometry(params).centerline().control_points[0]
    inset = 16.0 - 16.0 / 8.0
    np.testing.assert_allclose(
        p1, [inset * np.cos(np.radians(30)), inset * np.sin(np.radians(30)), 14.0]
    )


def test_frame_l_maps_like_the_change_of_basis_matrix():
    # x_L -> theta, y_L -> -z, z_L -> r (spec §3.3), offset by P1.
    cylindrical = local_to_cylindrical(
        [[10.0, 4.0, 2.0]], hub_radius=8.0, hub_length=20.0, blade_angle_deg=5.0
    )
    np.testing.assert_allclose(cylindrical, [[7.0 + 2.0, 15.0, 9.0 - 4.0]])


def test_curve_starts_at_p1_and_ends_at_p4(default_params):
    centerline = propeller_geometry(default_params).centerline()
    ends = centerline.points([0.0, 1.0])
    points = propeller_geometry(default_params).centerline().control_points
    np.testing.assert_allclose(ends, points[[0, 3]], atol=1e-12)
    # z_L = 0 for P4
    assert np.hypot(*ends[1, :2]) == pytest.approx(
        propeller_geometry(default_params).hub.inset_radius_mm
    )


def test_curve_is_the_cubic_bezier_of_its_control_points(default_params):
    points = propeller_geometry(default_params).centerline().control_points
    s = S[:, None]
    bezier = (
        (1 - s) ** 3 * points[0]
        + 3 * s * (1 - s) ** 2 * points[1]
        + 3 * s**2 * (1 - s) * points[2]
        + s**3 * points[3]
    )
    np.testing.assert_allclose(Centerline(points).points(S), bezier, atol=1e-12)


@pytest.mark.parametrize("frames_of", [frenet_frames, rotation_minimizing_frames])
def test_frames_are_orthonormal_and_right_handed(default_params, frames_of):
    frames = frames_of(propeller_geometry(default_params).centerline(), S)
    basis = np.stack([frames.tangent, frames.normal, frames.binormal], axis=1)
    np.testing.assert_allclose(
        basis @ basis.transpose(0, 2, 1), np.broadcast_to(np.eye(3), basis.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.cross(frames.tangent, frames.normal), frames.binormal, atol=1e-12)


def test_frenet_normal_points_along_the_turning_tangent(default_params):
    centerline = propeller_geometry(default_params).centerline()
    frames = frenet_frames(centerline, S)
    tangent = np.gradient(frames.tangent, S, axis=0)
    expected = tangent / np.linalg.norm(tangent, axis=1, keepdims=True)
    assert np.min(np.sum(expected[1:-1] * frames.normal[1:-1], axis=1)) > 0.999


def test_frenet_frame_on_a_straight_centerline_is_refused_with_the_place():
    straight = Centerline(np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]]))
    with pytest.raises(GeometryError, match=r"curvature vanishes near s = \d\.\d{3}"):
        frenet_frames(straight, S)


def test_frenet_frame_at_an_inflection_is_refused_with_the_place():
    s_curve = Centerline(np.array([[0.0, 0, 0], [1.0, 1.0, 0], [2.0, -1.0, 0], [3.0, 0, 0]]))
    with pytest.raises(GeometryError, match=r"s = 0\.5\d\d"):
        frenet_frames(s_curve, S)


def test_rotation_minimizing_frame_handles_straight_and_inflecting_curves():
    for points in (
        [[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0], [3.0, 0, 0]],
        [[0.0, 0, 0], [1.0, 1.0, 0], [2.0, -1.0, 0], [3.0, 0, 0]],
    ):
        frames = rotation_minimizing_frames(Centerline(np.array(points)), S)
        # A planar curve's rotation-minimising normal stays in (or normal to) its plane: no twist.
        assert np.allclose(np.abs(frames.binormal[:, 2]), np.abs(frames.binormal[0, 2]), atol=1e-9)


def test_rotation_minimizing_frame_starts_like_frenet(default_params):
    centerline = propeller_geometry(default_params).centerline()
    np.testing.assert_allclose(
        rotation_minimizing_frames(centerline, [0.0]).normal,
        frenet_frames(centerline, [0.0]).normal,
        atol=1e-12,
    )
