"""The B-rep propeller and its files: what a CAD user relies on (issue: loft, pattern, fuse, STEP +
STL)."""

import re

import numpy as np
import pytest
from conftest import assert_same_volume_as_general_fuse, read_binary_stl

from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.geometry.blade.blade_surface import surface_points
from torus_cad.kernel.checks import distances_to_shape, is_valid_closed_solid
from torus_cad.kernel.fuse import FuseRoute
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.kernel.step_readback import read_step
from torus_cad.propeller import build_propeller
from torus_cad.tolerances import READ_BACK_RELATIVE_TOLERANCE

#: Analytic surface points must lie on the B-rep within this fraction of the local chord.
SURFACE_ACCURACY_RELATIVE = 1e-3


def test_result_is_one_valid_closed_solid(default_propeller):
    assert is_valid_closed_solid(default_propeller.solid)
    assert len(default_propeller.blades) == 3


def test_volume_lies_between_hub_and_hub_plus_blades(default_propeller):
    volume = precise_volume(default_propeller.solid)
    hub = precise_volume(default_propeller.hub)
    blade = precise_volume(default_propeller.blades[0])
    assert hub == pytest.approx(np.pi * 10.0**2 * 20.0, rel=1e-9)
    assert hub < volume < hub + 3 * blade
    # The blade ends are inside the hub, so the fused volume is strictly below the plain sum.
    assert volume < hub + 3 * blade - 1.0


def test_step_reads_back_as_the_same_solid(default_propeller, default_files):
    shape = read_step(default_files["step"])
    assert is_valid_closed_solid(shape)
    assert precise_volume(shape) == pytest.approx(
        precise_volume(default_propeller.solid), rel=READ_BACK_RELATIVE_TOLERANCE
    )


def test_step_names_the_product_and_uses_millimetres(default_files):
    text = default_files["step"].read_text(errors="replace")
    assert re.search(r"PRODUCT\('torus_propeller'", text)
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    assert "AUTOMOTIVE_DESIGN" in text  # AP214


def test_stl_is_watertight_and_keeps_the_volume(default_propeller, default_files):
    triangles = read_binary_stl(default_files["stl"]).astype(np.float64)
    vertices, index = np.unique(triangles.reshape(-1, 3), axis=0, return_inverse=True)
    faces = index.reshape(-1, 3)
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert np.all(uses == 2), "every STL edge must be shared by exactly two triangles"
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    stl_volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    assert stl_volume == pytest.approx(precise_volume(default_propeller.solid), rel=0.01)


def test_analytic_surface_lies_on_the_brep(default_propeller, default_params):
    # Between the sections (s at mid-intervals) and away from the hub (middle of the blade).
    sections = default_params.resolution.sections
    s = (np.arange(4, sections - 5) + 0.5) / (sections - 1)
    t = np.linspace(0.03, 1.97, 9)
    points = surface_points(
        propeller_geometry(default_params).blade,
        propeller_geometry(default_params).centerline(),
        s,
        t,
    )
    chord = np.linalg.norm(
        surface_points(
            propeller_geometry(default_params).blade,
            propeller_geometry(default_params).centerline(),
            s,
            [1.0],
        )[:, 0]
        - surface_points(
            propeller_geometry(default_params).blade,
            propeller_geometry(default_params).centerline(),
            s,
            [0.0],
        )[:, 0],
        axis=-1,
    )
    distances = distances_to_shape(default_propeller.blades[0], points.reshape(-1, 3)).reshape(
        points.shape[:2]
    )
    assert np.all(distances <= SURFACE_ACCURACY_RELATIVE * chord[:, None])


def test_stl_deflection_is_user_settable(light_params, tmp_path):
    coarse = light_params.with_values(
        {"export.stl_linear_deflection": 0.5, "export.stl_angular_deflection": 0.8}
    )
    fine = light_params.with_values({"export.stl_linear_deflection": 0.02})
    sizes = [
        build_propeller(p).write(tmp_path / p.name / str(i))["stl"].stat().st_size
        for i, p in enumerate((coarse, fine))
    ]
    assert sizes[0] < sizes[1]


def test_ap242_is_available(light_params, tmp_path):
    params = light_params.with_values({"export.step_schema": "AP242"})
    path = build_propeller(params).write(tmp_path, stl=False)["step"]
    assert "AP242" in path.read_text(errors="replace")[:2000]
    assert is_valid_closed_solid(read_step(path))


@pytest.mark.parametrize("blades", [1, 2, 4])
def test_any_blade_count_fuses_into_one_solid(light_params, blades):
    # Narrow the angular sweep so that neighbours stay clear, and the chord so that the tighter
    # loop does not fold over (both are refused before the kernel otherwise).
    sweep = min(1.0, 3.0 / blades)
    propeller = build_propeller(
        light_params.with_values(
            {
                "blades": blades,
                "centerline.p2": [25 * sweep, 3.0, 22.0],
                "centerline.p3": [75 * sweep, 15.0, 22.0],
                "centerline.p4": [100 * sweep, 18.0],
                "transforms.scale_x": [0.0, 0.0, -8.0, 8.0, 5.0],
            }
        )
    )
    assert is_valid_closed_solid(propeller.solid)
    assert len(propeller.blades) == blades
    assert precise_volume(propeller.solid) > precise_volume(propeller.hub)
    # One blade-hub intersection serves every blade, and gives what one general fuse gives.
    assert propeller.fuse_route != FuseRoute.GENERAL
    assert_same_volume_as_general_fuse(propeller)
