"""`torus-cad mesh`: a closed 2-manifold at any resolution, converging to the B-rep, parts named in
every file as other readers see them, bad resolutions refused with the minimum that works."""

from __future__ import annotations

import importlib
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from torus_cad.cli import main
from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.mesh.cleanup import collapse_junction_needles
from torus_cad.mesh.grids import (
    blade_grid,
    blade_meshes,
    cell_size,
    hub_layout,
    hub_mesh,
    section_parameters,
)
from torus_cad.mesh.mesh_formats import MeshFormat
from torus_cad.mesh.pipeline import build_surface_mesh
from torus_cad.mesh.quality import aspect_ratios, edge_topology
from torus_cad.mesh.resolution import check_resolution
from torus_cad.mesh.union import MeshBooleanError, unite
from torus_cad.mesh.writers import write_mesh_files
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.design import SectionSpacing

trimesh = pytest.importorskip("trimesh")

PARTS = ["hub", "blade_0", "blade_1", "blade_2"]


def _params(sections: int, points: int, spacing: str = "arc_length") -> PropellerParameters:
    return PropellerParameters().with_values(
        {"mesh.sections": sections, "mesh.points": points, "mesh.spacing": spacing}
    )


@pytest.fixture(scope="module")
def coarse_mesh():
    return build_surface_mesh(_params(24, 48)).mesh


@pytest.mark.parametrize(
    "sections, points, spacing",
    [(24, 48, "arc_length"), (48, 120, "parameter"), (96, 240, "arc_length")],
)
def test_mesh_is_one_closed_two_manifold_with_every_part(sections, points, spacing):
    mesh = build_surface_mesh(_params(sections, points, spacing)).mesh
    assert edge_topology(mesh.faces).closed
    # An independent check: trimesh's own watertightness, winding and connectivity.
    other = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    assert other.is_watertight and other.is_winding_consistent and other.volume > 0
    assert other.body_count == 1
    assert sorted(set(mesh.part.tolist())) == [0, 1, 2, 3] and list(mesh.part_names) == PARTS
    # the blades are rotated copies; only their junctions with the hub's grid differ
    counts = np.bincount(mesh.part)[1:]
    assert counts.max() - counts.min() < 0.01 * counts.min()


def test_volume_converges_to_the_brep_at_second_order(default_propeller):
    from torus_cad.kernel.mass_properties import precise_volume

    brep = precise_volume(default_propeller.solid)
    errors = [
        abs(build_surface_mesh(_params(24 * k, 48 * k)).mesh.triangle_mesh.volume / brep - 1.0)
        for k in (1, 2, 4)
    ]
    assert errors[0] > errors[1] > errors[2]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # measured 2.05, 2.01: flat faces, error ~ h^2
    assert np.all((orders > 1.8) & (orders < 2.3)), orders
    assert errors[-1] < 3e-4


def test_groups_survive_obj_and_ascii_stl_through_trimesh(coarse_mesh, tmp_path):
    paths = write_mesh_files(
        coarse_mesh, tmp_path, "prop", (MeshFormat.OBJ, MeshFormat.STL_ASCII, MeshFormat.STL)
    )
    expected = dict(zip(PARTS, np.bincount(coarse_mesh.part).tolist()))
    groups = trimesh.load(
        paths[MeshFormat.OBJ], group_material=False, split_groups=True, process=False, force="scene"
    )
    assert {name: len(part.faces) for name, part in groups.geometry.items()} == expected
    solids = trimesh.load(paths[MeshFormat.STL_ASCII], force="scene")
    assert {name: len(part.faces) for name, part in solids.geometry.items()} == expected
    whole = trimesh.load(paths[MeshFormat.STL])  # binary STL: vertices merged by trimesh
    assert whole.is_watertight and len(whole.faces) == len(coarse_mesh.faces)
    # float32 coordinates
    assert whole.volume == pytest.approx(coarse_mesh.triangle_mesh.volume, rel=1e-5)


def test_part_index_survives_ply_and_vtk(coarse_mesh, tmp_path):
    meshio = pytest.importorskip("meshio")
    paths = write_mesh_files(coarse_mesh, tmp_path, "prop", (MeshFormat.PLY, MeshFormat.VTK))
    vtk = meshio.read(paths[MeshFormat.VTK])
    assert np.array_equal(vtk.cell_data["part"][0], coarse_mesh.part)
    assert np.allclose(vtk.points, coarse_mesh.vertices)
    ply = trimesh.load(paths[MeshFormat.PLY], process=False)
    assert np.array_equal(
        ply.metadata["_ply_raw"]["face"]["data"]["part"].ravel(), coarse_mesh.part
    )
    assert np.array_equal(ply.faces, coarse_mesh.faces)


def test_sections_spacing_in_arc_length_or_in_s():
    geometry = propeller_geometry(PropellerParameters())
    centerline = geometry.centerline(0)
    in_s = section_parameters(centerline, 30, SectionSpacing.PARAMETER)
    assert np.allclose(np.diff(in_s), 1.0 / 29)
    in_length = section_parameters(centerline, 30, SectionSpacing.ARC_LENGTH)
    steps = np.linalg.norm(np.diff(centerline.points(in_length), axis=0), axis=1)
    assert steps.max() / steps.min() < 1.01
    grid = blade_grid(geometry, 30, 64, SectionSpacing.ARC_LENGTH)
    assert grid.points.shape == (30, 64, 3) and np.allclose(grid.s, in_length)


@settings(max_examples=15, deadline=None)
@given(radius=st.floats(0.5, 50.0), length=st.floats(2.5, 80.0), cells=st.floats(3.0, 30.0))
def test_hub_grid_is_closed_and_even(radius, length, cells):
    cell = max(radius, length) / cells
    hub = hub_mesh(radius, length, cell)
    assert hub.is_watertight() and len(hub.faces) == hub_layout(radius, length, cell).triangles
    assert 0.9 * np.pi * radius**2 * length < hub.volume <= np.pi * radius**2 * length
    # no slivers, not even at the caps' centres
    assert aspect_ratios(hub.vertices, hub.faces).max() < 6.0


def test_resolution_too_coarse_names_the_minimum_that_works():
    geometry = propeller_geometry(PropellerParameters())
    with pytest.raises(ParameterError, match=r"mesh.sections >= (\d+)") as refused:
        check_resolution(geometry, 6, 64, SectionSpacing.ARC_LENGTH)
    minimum = int(refused.value.args[0].split("mesh.sections >= ")[1].split()[0])
    check_resolution(geometry, minimum, 64, SectionSpacing.ARC_LENGTH)  # the suggestion is accepted
    with pytest.raises(ParameterError):
        check_resolution(geometry, minimum - 2, 64, SectionSpacing.ARC_LENGTH)


def test_thin_sections_need_more_points():
    # equal arc-length points (spec §5) are sparse at a thin section's small leading-edge radius
    check_resolution(propeller_geometry(PropellerParameters()), 400, 16, SectionSpacing.ARC_LENGTH)
    thin = propeller_geometry(PropellerParameters().with_values({"airfoil.thickness": 0.06}))
    with pytest.raises(ParameterError, match=r"mesh.points >= \d+") as refused:
        check_resolution(thin, 400, 16, SectionSpacing.ARC_LENGTH)
    minimum = int(refused.value.args[0].split("mesh.points >= ")[1].split()[0])
    assert minimum > 16
    check_resolution(thin, 400, minimum, SectionSpacing.ARC_LENGTH)


def test_cleanup_collapses_the_junction_needles_and_keeps_the_surface_closed():
    geometry = propeller_geometry(PropellerParameters())
    grid = blade_grid(geometry, 48, 120, SectionSpacing.ARC_LENGTH)
    parts = [hub_mesh(10.0, 20.0, cell_size(grid).matched), *blade_meshes(geometry, grid)]
    united, _ = unite(parts, PARTS)
    cleaned, cleanup = collapse_junction_needles(united)
    before = aspect_ratios(united.vertices, united.faces)
    after = aspect_ratios(cleaned.vertices, cleaned.faces)
    assert cleanup.collapsed > 0 and np.sum(after > 100) <= np.sum(before > 100) // 10
    assert (
        cleanup.over_100_before == np.sum(before > 100)
        and cleanup.aspect_ratio_max_before == before.max()
    )
    assert after.max() < before.max() / 10
    assert edge_topology(cleaned.faces).closed
    assert cleaned.triangle_mesh.volume == pytest.approx(united.triangle_mesh.volume, rel=1e-5)
    assert np.array_equal(np.unique(cleaned.part), np.unique(united.part))


def test_a_part_that_is_not_closed_fails_naming_the_step():
    hub = hub_mesh(10.0, 20.0, 2.0)
    open_hub = TriangleMesh(hub.vertices, hub.faces[1:])
    with pytest.raises(MeshBooleanError, match="step 'load hub'"):
        unite([open_hub], ["hub"])


def test_cli_writes_files_report_and_one_line(tmp_path, capsys):
    assert (
        main(
            [
                "mesh",
                "--sections",
                "24",
                "--points",
                "48",
                "--format",
                "stl,obj",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert out.count("\n") == 4 and "closed 2-manifold (0 open, 0 non-manifold edges)" in out
    assert sorted(path.name for path in tmp_path.iterdir()) == [
        "torus_propeller_mesh.json",
        "torus_propeller_mesh.obj",
        "torus_propeller_mesh.stl",
    ]
    report = json.loads((tmp_path / "torus_propeller_mesh.json").read_text())
    assert report["topology"]["open_edges"] == 0 and report["topology"]["non_manifold_edges"] == 0
    assert abs(report["volume_relative_difference"]) < 0.01
    assert (
        report["blades_away_from_junctions"]["edge_ratio"]
        < report["opencascade_stl"]["blades_away_from_junctions"]["edge_ratio"]
    )
    assert report["settings"] == {
        "sections": 24,
        "points": 48,
        "spacing": "arc_length",
        "formats": ["stl", "obj"],
    }


def test_mesh_stages_are_announced_in_order_and_timed_by_the_build_stage_timer(tmp_path):
    """One StageTimer (torus_cad.runtime.stage_timer) for the build, mesh and CFD pipelines: the
    mesh's own copy is gone."""
    from torus_cad.mesh.pipeline import MeshStage, write_surface_mesh

    seen: list[str] = []
    report, _ = write_surface_mesh(_params(24, 48), tmp_path, compare=False, progress=seen.append)
    assert seen == [stage.value for stage in MeshStage]
    assert list(report["stage_seconds"]) == seen and all(
        seconds >= 0.0 for seconds in report["stage_seconds"].values()
    )
    assert (
        json.loads((tmp_path / "torus_propeller_mesh.json").read_text())["stage_seconds"]
        == report["stage_seconds"]
    )
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("torus_cad.mesh.timing")


def test_mesh_table_in_a_design_file_sets_the_resolution(tmp_path):
    design = tmp_path / "design.toml"
    design.write_text(
        '[mesh]\nsections = 26\npoints = 44\nspacing = "parameter"\nobj = false\nvtk = true\n'
    )
    assert main(["mesh", str(design), "--out", str(tmp_path / "out"), "--no-compare", "-q"]) == 0
    report = json.loads((tmp_path / "out" / "torus_propeller_mesh.json").read_text())
    assert report["settings"] == {
        "sections": 26,
        "points": 44,
        "spacing": "parameter",
        "formats": ["stl", "vtk"],
    }
    assert "brep_volume_mm3" not in report


@pytest.mark.parametrize(
    "arguments, fragment",
    [
        (["--sections", "5", "--points", "64"], "use mesh.sections >= "),
        (["--sections", "3"], "mesh.sections = 3 is out of range"),
        (["--points", "8"], "mesh.points = 8 is out of range"),
        (["--sections", "20000", "--points", "50000"], "GB of memory, over the limit of 4.0 GB"),
        (["--format", "step"], "--format 'step' is not a mesh format"),
        (["--spacing", "random"], "invalid choice"),
        (["--set", "centerline.p4=[100,25]"], "centerline.p4[1]"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, arguments, fragment):
    out = tmp_path / "out"
    assert _exit_code(["mesh", *arguments, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


def _exit_code(argv: list[str]) -> int:
    """``main``'s exit code, also when argparse exits (bad choices)."""
    try:
        return main(argv)
    except SystemExit as stop:
        return int(stop.code or 0)
