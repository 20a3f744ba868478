"""`torus-cad mesh` carries every feature of the design and never crosses itself: read back by
trimesh and meshlib."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from torus_cad.cli import main
from torus_cad.design.described_geometry import propeller_geometry

trimesh = pytest.importorskip("trimesh")
mr = pytest.importorskip("meshlib.mrmeshpy")

WORKSHOP = Path(__file__).resolve().parent.parent / "examples" / "workshop_motor_mount.toml"


def _crossing_pairs(path: Path) -> int:
    """Intersecting triangle pairs of a mesh file, as meshlib reads and checks it."""
    return len(mr.findSelfCollidingTriangles(mr.loadMesh(str(path))))


def _mesh(tmp_path: Path, *arguments: str) -> tuple[dict, Path]:
    out = tmp_path / "out"
    assert main(["mesh", *arguments, "--format", "stl", "--out", str(out), "-q"]) == 0
    (report,) = out.glob("*_mesh.json")
    return json.loads(report.read_text()), next(out.glob("*_mesh.stl"))


@pytest.fixture(scope="module")
def workshop_mesh(tmp_path_factory):
    # the example's hub on the knife-edged blade this test was measured on: with the example's 0.8
    # mm round trailing edge (issue 35) the mesh's zero-area triangles where the set-screw hole is
    # tangent to the D-flat (mesh.md) share positions that trimesh's vertex merge joins into edges
    # of 4 and 6 triangles
    return _mesh(
        tmp_path_factory.mktemp("workshop"),
        str(WORKSHOP),
        "--sections",
        "48",
        "--points",
        "160",
        "--set",
        "airfoil.trailing_edge_thickness=0",
    )


def test_the_hub_features_are_in_the_mesh_with_the_breps_volume(workshop_mesh):
    report, stl = workshop_mesh
    mesh = trimesh.load(stl)  # vertices merged by trimesh
    assert mesh.is_watertight and mesh.is_winding_consistent
    # the B-rep (OpenCascade, with the same bore, flat, set screw and chamfers) within 0.2 %
    assert mesh.volume == pytest.approx(report["brep_volume_mm3"], rel=2e-3)
    features = report["hub_features"]
    bore_radius = features["bore_diameter_mm"] / 2.0
    flat = bore_radius - features["bore_flat_depth_mm"]
    angle = math.radians(features["set_screw_angle_deg"])
    x, y, z = mesh.vertices.T.astype(float)
    r = np.hypot(x, y)
    tolerance = 1e-4  # float32 coordinates of the STL
    # nothing inside the bore (the flat is its nearest wall)
    assert r.min() > flat - tolerance
    on_bore = np.abs(r - bore_radius) < tolerance
    # the bore's wall, end to end (L = 20 mm)
    assert on_bore.sum() > 100 and np.ptp(z[on_bore]) > 19.9
    toward = x * math.cos(angle) + y * math.sin(angle)
    # the D-flat, facing the screw
    assert np.sum((np.abs(toward - flat) < tolerance) & (r < bore_radius)) > 10
    across = -x * math.sin(angle) + y * math.cos(angle)
    on_screw = (
        np.abs(np.hypot(across, z) - features["set_screw_diameter_mm"] / 2.0) < tolerance
    ) & (toward > 0)
    # the set-screw hole, from the bore out
    assert np.ptp(toward[on_screw]) > 10.0 - bore_radius - 0.5
    ends = np.abs(np.abs(z) - 10.0) < tolerance
    assert r[ends].max() < 10.0 - features["chamfer_mm"] + tolerance  # chamfered end edges
    assert _crossing_pairs(stl) == 0 and report["self_intersections"] == 0


def test_without_the_features_the_volume_is_the_plain_hubs(workshop_mesh, tmp_path):
    """The features' volume is really gone: the plain design's mesh is larger by what they
    remove."""
    from torus_cad.geometry.hub.mounting import HubMounting

    report, _ = workshop_mesh
    plain, _ = _mesh(tmp_path, "--sections", "48", "--points", "160", "--no-compare")
    features = report["hub_features"]
    removed = HubMounting(
        features["bore_diameter_mm"], features["bore_flat_depth_mm"], 0.0, features["chamfer_mm"]
    ).removed_volume_mm3(10.0, 20.0)
    # about, wall 2 to 2.5 mm
    screw = math.pi * (features["set_screw_diameter_mm"] / 2.0) ** 2 * (10.0 - 2.0)
    assert plain["volume_mm3"] - report["volume_mm3"] == pytest.approx(removed + screw, rel=0.05)


@pytest.mark.parametrize(
    "arguments",
    [
        # crossed at 66 pairs with one diagonal direction everywhere
        ["--sections", "20", "--points", "64"],
        ["--set", "airfoil.thickness=0.06", "--sections", "48", "--points", "160"],
        [
            "--set",
            "airfoil.trailing_edge_thickness=0.3",
            "--set",
            "airfoil.trailing_edge_shape=flat",
            "--sections",
            "48",
            "--points",
            "160",
        ],
        ["--set", "airfoil.trailing_edge_thickness=0.3", "--sections", "48", "--points", "160"],
        ["--set", "blades=5", "--set", "handedness=ccw", "--sections", "40", "--points", "120"],
    ],
)
def test_no_intersecting_triangles(tmp_path, arguments):
    report, stl = _mesh(tmp_path, *arguments, "--no-compare")
    assert _crossing_pairs(stl) == 0
    assert (
        report["self_intersections"] == 0
        and report["self_intersection_check"]["scope"] == "whole mesh"
    )
    assert trimesh.load(stl).is_watertight


def test_no_intersecting_triangles_at_the_default_resolution(tmp_path):
    report, stl = _mesh(tmp_path, "--no-compare")
    assert report["settings"]["sections"] == 100 and report["settings"]["points"] == 400
    assert _crossing_pairs(stl) == 0 and report["self_intersections"] == 0


def test_blunt_trailing_edges_are_meshed_with_the_breps_volume(tmp_path):
    for shape in ("flat", "round"):
        report, stl = _mesh(
            tmp_path / shape,
            "--set",
            "airfoil.trailing_edge_thickness=0.4",
            "--set",
            f"airfoil.trailing_edge_shape={shape}",
            "--sections",
            "48",
            "--points",
            "160",
        )
        assert report["hub_features"]["trailing_edge_shape"] == shape
        assert trimesh.load(stl).volume == pytest.approx(report["brep_volume_mm3"], rel=2e-3)


def test_a_coarse_resolution_whose_blade_crosses_itself_is_refused_naming_one_that_works(
    capsys, tmp_path
):
    """A 60 mm propeller (diameter target) at 30 x 80: its blade's mesh crosses itself; the
    resolution the refusal names is meshed without intersecting triangles (meshlib reading the
    STL)."""
    design = ["--set", "diameter=60"]
    assert (
        main(
            [
                "mesh",
                *design,
                "--sections",
                "30",
                "--points",
                "80",
                "--out",
                str(tmp_path / "refused"),
            ]
        )
        == 2
    )
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "crosses itself at" in error and "triangle pairs" in error
    sections, points = (word for word in error.split("use --sections ")[1].split()[:3:2])
    assert not (tmp_path / "refused").exists()
    report, stl = _mesh(
        tmp_path, *design, "--sections", sections, "--points", points, "--no-compare"
    )
    assert _crossing_pairs(stl) == 0 and report["self_intersections"] == 0


def test_a_resolution_whose_blade_crosses_itself_is_refused_naming_one_that_does_not(
    monkeypatch, capsys, tmp_path
):
    """With one diagonal direction everywhere (the layout before the mirrored diagonals) the blade's
    mesh at 20 x 64 crosses itself at its trailing edge; the refusal names a finer resolution that
    meshlib passes."""
    import torus_cad.mesh.grids as grids
    from torus_cad.mesh.crossings import crossing_pairs
    from torus_cad.parameters import PropellerParameters
    from torus_cad.parameters.design import SectionSpacing

    monkeypatch.setattr(
        grids, "split_along_a_d", lambda surface: np.ones(surface.points.shape[1], dtype=bool)
    )
    assert main(["mesh", "--sections", "20", "--points", "64", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "crosses itself at" in error and "triangle pairs" in error
    sections, points = (int(word) for word in error.split("use --sections ")[1].split()[:3:2])
    geometry = propeller_geometry(PropellerParameters())
    blade = grids.mirrored_diagonal_mesh(
        grids.blade_grid(geometry, sections, points, SectionSpacing.ARC_LENGTH)
    )
    assert crossing_pairs(blade.vertices, blade.faces) == 0 and (sections, points) != (20, 64)
    assert not (tmp_path / "out").exists()


def test_the_root_fillet_is_refused_with_one_line(tmp_path, capsys):
    assert (
        main(["mesh", "--set", "hub.root_fillet_radius=0.5", "--out", str(tmp_path / "out")]) == 2
    )
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and "hub.root_fillet_radius = 0.5 mm" in error
        and "cannot mesh" in error
    )
    assert not (tmp_path / "out").exists()
