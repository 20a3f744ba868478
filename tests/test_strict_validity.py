"""Truly valid: every published solid passes BRepCheck_Analyzer and BRepAlgoAPI_Check (small edges,
self-interference) on the whole solid, and its STL and 3MF have no intersecting triangle pairs,
by readers we did not write (meshlib; Debian's tetgen on an OFF file written by trimesh)."""

from __future__ import annotations

import json
import shutil
import subprocess
import zipfile
from pathlib import Path

import cadquery as cq
import numpy as np
import pytest
from conftest import SHIPPED_DESIGNS
from lxml import etree
from OCP.BRepAlgoAPI import BRepAlgoAPI_Check
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeWire
from OCP.BRepCheck import BRepCheck_Analyzer

from torus_cad.errors import KernelError
from torus_cad.kernel.fuse import fuse_pattern
from torus_cad.kernel.loft import loft_solid
from torus_cad.kernel.mesh_check import intersecting_pairs
from torus_cad.kernel.strict import CheckScope, strict_valid_solid
from torus_cad.kernel.wires import _bspline_curve, _edge
from torus_cad.propeller import build_propeller

EXAMPLES = SHIPPED_DESIGNS


def _assert_whole_solid_valid(solid: cq.Solid) -> None:
    assert BRepCheck_Analyzer(solid.wrapped).IsValid()
    check = BRepAlgoAPI_Check(solid.wrapped, True, True)
    faults = (
        [str(fault.GetCheckStatus()) for fault in check.Result()] if not check.IsValid() else []
    )
    assert check.IsValid(), faults


def _meshlib_pairs(path: Path) -> int:
    import meshlib.mrmeshpy as mr

    return len(mr.findSelfCollidingTriangles(mr.loadMesh(str(path))))


def _tetgen_finds_no_crossing(stl: Path, folder: Path) -> bool:
    import trimesh

    off = folder / "mesh.off"
    trimesh.load(stl).export(off)
    run = subprocess.run(
        ["tetgen", "-d", str(off)], capture_output=True, text=True, timeout=300, check=False
    )
    return "No faces are intersecting" in run.stdout


def _3mf_pairs(path: Path) -> int:
    with zipfile.ZipFile(path) as package:
        model = etree.fromstring(package.read("3D/3dmodel.model"))
    ns = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}
    vertices = np.array(
        [[float(v.get(axis)) for axis in "xyz"] for v in model.iterfind(".//m:vertex", ns)]
    )
    triangles = np.array(
        [
            [int(t.get(key)) for key in ("v1", "v2", "v3")]
            for t in model.iterfind(".//m:triangle", ns)
        ]
    )
    return intersecting_pairs(vertices, triangles)


def _assert_published_set_valid(propeller, folder: Path) -> dict:
    paths = propeller.write(folder)
    _assert_whole_solid_valid(propeller.solid)
    report = json.loads(paths["json"].read_text())
    assert report["checks"]["brepcheck"] and report["checks"]["boolean_check_self_intersection"]
    assert (
        report["checks"]["stl_self_intersections"]
        and report["stl_mesh"]["self_intersecting_pairs"] == 0
    )
    assert _meshlib_pairs(paths["stl"]) == 0
    if shutil.which("tetgen"):
        assert _tetgen_finds_no_crossing(paths["stl"], folder)
    if "3mf" in paths:
        assert _3mf_pairs(paths["3mf"]) == 0 and report["3mf_mesh"]["self_intersecting_pairs"] == 0
    return report


def test_the_default_is_strictly_valid_and_its_stl_intersection_free(default_propeller, tmp_path):
    report = _assert_published_set_valid(default_propeller, tmp_path)
    # the build's cheaper exact test was used
    assert report["checks"]["scope"] == CheckScope.PATTERN.value
    assert (
        report["stl_mesh"]["linear_deflection_mm"]
        <= default_propeller.parameters.export.stl_linear_deflection
    )


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda path: path.stem)
def test_every_shipped_example_is_strictly_valid(example, tmp_path):
    _assert_published_set_valid(build_propeller(example), tmp_path)


def test_a_sharp_edge_in_one_closed_face_is_refused_naming_the_check_and_the_blade(
    default_propeller,
):
    """The blade the build made before its sharp trailing edge became a true edge: the side as one
    face closed in u, its crease inside. BRepCheck accepts it; the strict check must not."""
    curves = default_propeller.section_curves
    wires = []
    for poles in curves.poles:
        builder = BRepBuilderAPI_MakeWire()
        builder.Add(_edge(_bspline_curve(poles, curves.knots)))
        wires.append(cq.Wire(builder.Wire()))
    blade = loft_solid(wires, default_propeller.surface.s)
    assert BRepCheck_Analyzer(blade.wrapped).IsValid()
    angles = [120.0 * index for index in range(3)]
    fused = fuse_pattern(default_propeller.hub, blade, angles).shape
    with pytest.raises(KernelError, match=r"BRepAlgoAPI_Check.*SelfIntersect.*blade \d"):
        strict_valid_solid(fused, "the propeller")


def test_the_default_blade_is_two_side_faces_meeting_at_the_trailing_edge(default_propeller):
    side = [face for face in default_propeller.blades[0].Faces() if face.geomType() == "BSPLINE"]
    assert len(side) == 2
    shared = {edge.hashCode() for edge in side[0].Edges()} & {
        edge.hashCode() for edge in side[1].Edges()
    }
    assert len(shared) == 2  # the trailing edge and the leading edge


def test_meshlib_sees_two_crossing_triangles_and_none_in_a_tetrahedron():
    crossing = np.array(
        [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0.5, 0.5, -1], [0.5, 0.5, 1], [1.5, 1.5, 0.2]], float
    )
    assert intersecting_pairs(crossing, np.array([[0, 1, 2], [3, 4, 5]])) == 1
    tetrahedron = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    assert (
        intersecting_pairs(tetrahedron, np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])) == 0
    )


def test_fuzz_designs_that_build_are_strictly_valid_with_intersection_free_stls():
    """>= 100 fuzz designs (workshop features included) at the default resolution, 2 worker
    processes."""
    from studies.strict_fuzz import fuzz_many

    outcomes = fuzz_many(range(100), workers=2)
    built = [outcome for outcome in outcomes if outcome.status == "built"]
    failed = [outcome for outcome in outcomes if outcome.status == "failed"]
    # a failure is the build refusing to publish, naming the check: never a crash or a silent flaw
    assert all(
        "BRepAlgoAPI_Check" in outcome.reason
        or "intersecting triangles" in outcome.reason
        or "OpenCascade" in outcome.reason
        for outcome in failed
    ), [(o.seed, o.reason) for o in failed]
    assert len(built) >= 30, [outcome.reason for outcome in outcomes if outcome.status != "built"][
        :5
    ]
    assert all(outcome.strict_valid for outcome in built), [
        outcome.seed for outcome in built if not outcome.strict_valid
    ]
    assert all(outcome.stl_pairs == 0 for outcome in built), [
        (o.seed, o.stl_pairs) for o in built if o.stl_pairs
    ]
