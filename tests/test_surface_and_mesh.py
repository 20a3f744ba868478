"""Blade surface (spec §2.3, §4.2, §6.1) and its structured mesh (spec §7.1-7.2)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rotations import rotation_about_z

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.geometry.blade.blade_surface import surface_points
from torus_cad.geometry.blade.triangle_mesh import blade_mesh
from torus_cad.parameters import PropellerParameters


@pytest.mark.parametrize("blades", [2, 3, 5])
def test_blade_i_is_blade_0_rotated(blades):
    params = PropellerParameters().with_values({"blades": blades, "phase_deg": 17.0})
    first = sampled_blade_surface(params, 0).points
    for index in range(1, blades):
        rotated = first @ rotation_about_z(360.0 * index / blades).T
        np.testing.assert_allclose(sampled_blade_surface(params, index).points, rotated, atol=1e-9)


def test_leading_edge_sits_on_the_centerline(default_params):
    surface = sampled_blade_surface(default_params)
    np.testing.assert_allclose(
        surface.points[:, 0],
        propeller_geometry(default_params).centerline().points(surface.s),
        atol=1e-12,
    )


def test_pivot_puts_that_chord_point_on_the_centerline():
    params = PropellerParameters().with_values({"airfoil.max_camber": 0.0, "airfoil.pivot": 0.5})
    s = np.linspace(0, 1, 7)
    upper, lower = (
        surface_points(
            propeller_geometry(params).blade, propeller_geometry(params).centerline(), s, [0.5, 1.5]
        )[:, 0],
        surface_points(
            propeller_geometry(params).blade, propeller_geometry(params).centerline(), s, [0.5, 1.5]
        )[:, 1],
    )
    np.testing.assert_allclose(
        0.5 * (upper + lower), propeller_geometry(params).centerline().points(s), atol=1e-12
    )


def test_section_is_transformed_then_placed_on_n_and_b():
    params = PropellerParameters().with_values(
        {
            "airfoil.max_camber": 0.0,
            "transforms.angle_of_attack": [0, 0, 0, 0, 0.0],
            "transforms.scale_x": [0, 0, 0, 0, 5.0],
            "transforms.scale_y": [0, 0, 0, 0, 2.0],
        }
    )
    surface = sampled_blade_surface(params, sections=5, points=40)
    trailing_edge = surface.points[:, surface.trailing_edge_index]
    expected = surface.frames.origin + 5.0 * surface.frames.normal  # chord 1 along N, scaled by Sx
    np.testing.assert_allclose(trailing_edge, expected, atol=1e-12)


def test_mesh_is_closed_and_outward(default_params):
    mesh = blade_mesh(sampled_blade_surface(default_params))
    assert mesh.is_watertight()
    assert np.all(mesh.edge_use_counts() == 2)
    assert mesh.volume > 0


def test_mesh_volume_converges_with_resolution(default_params):
    volumes = [
        blade_mesh(sampled_blade_surface(default_params, sections=k, points=4 * k)).volume
        for k in (20, 40, 80)
    ]
    assert volumes[0] < volumes[1] < volumes[2]  # inscribed polyhedra grow toward the surface
    assert (volumes[2] - volumes[1]) < 0.3 * (volumes[1] - volumes[0])  # second-order convergence


@settings(max_examples=15, deadline=None)
@given(
    sections=st.integers(4, 30),
    points=st.integers(16, 120),
    camber=st.floats(0.0, 0.05),
    thickness=st.floats(0.05, 0.5),
    camber_normal=st.booleans(),
)
def test_mesh_is_closed_for_any_sampling(sections, points, camber, thickness, camber_normal):
    params = PropellerParameters().with_values(
        {
            "airfoil.max_camber": camber,
            "airfoil.thickness": thickness,
            "airfoil.camber_normal": camber_normal,
        }
    )
    mesh = blade_mesh(sampled_blade_surface(params, sections=sections, points=points))
    assert mesh.is_watertight() and mesh.volume > 0
    assert mesh.faces.shape[0] == 2 * (sections - 1) * points + 2 * (points - 2)
