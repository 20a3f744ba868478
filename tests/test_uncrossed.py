"""The uncrossed tessellation: a strictly valid solid whose knife edges tessellate into crossing
triangles is written, STL and 3MF alike, as one closed mesh that no two triangles of cross, by
readers we did not write (meshlib reading the STL, Debian's tetgen, trimesh)."""

from __future__ import annotations

import shutil
import subprocess
import zipfile

import numpy as np
import pytest
import trimesh
from lxml import etree

from studies.fuzz import random_design
from torus_cad.kernel.uncrossed import uncrossed_mesh
from torus_cad.kernel.writers.stl import write_checked_stl
from torus_cad.kernel.writers.threemf import write_3mf
from torus_cad.propeller import build_propeller
from torus_cad.tolerances import MESH_REPAIR_MAX_DEVIATION_MM

#: A fuzz design (workshop features drawn) whose strictly valid solid the build refused for its STL
#: before: 133 crossing pairs even after 3 halvings of the deflection.
KNIFE_EDGE_SEED = 106


@pytest.fixture(scope="module")
def knife_edge():
    propeller = build_propeller(random_design(KNIFE_EDGE_SEED, workshop=True))
    export = propeller.parameters.export
    return propeller, uncrossed_mesh(
        propeller.solid, export.stl_linear_deflection, export.stl_angular_deflection
    )


def test_a_knife_edge_design_refused_before_writes_an_stl_no_reader_finds_crossing(
    knife_edge, tmp_path
):
    import meshlib.mrmeshpy as mr

    propeller, mesh = knife_edge
    # the tessellation itself crossed: the repair was needed
    assert mesh.repaired_pairs > 0 and mesh.repair
    assert mesh.repair_deviation_mm <= MESH_REPAIR_MAX_DEVIATION_MM
    export = propeller.parameters.export
    check = write_checked_stl(
        propeller.solid,
        tmp_path / "p.stl",
        export.stl_linear_deflection,
        export.stl_angular_deflection,
        mesh=mesh,
    )
    assert check.self_intersecting_pairs == 0 and check.repaired_pairs == mesh.repaired_pairs
    assert len(mr.findSelfCollidingTriangles(mr.loadMesh(str(tmp_path / "p.stl")))) == 0
    read = trimesh.load(tmp_path / "p.stl")
    assert read.is_watertight and read.is_winding_consistent
    assert read.volume == pytest.approx(propeller.solid.Volume(), rel=0.01)
    if shutil.which("tetgen"):
        read.export(tmp_path / "p.off")
        run = subprocess.run(
            ["tetgen", "-d", str(tmp_path / "p.off")],
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert "No faces are intersecting" in run.stdout, run.stdout[-500:]


def test_the_3mf_is_the_same_uncrossed_mesh(knife_edge, tmp_path):
    from torus_cad.kernel.mesh_check import intersecting_pairs

    propeller, mesh = knife_edge
    export = propeller.parameters.export
    write_3mf(
        propeller.solid,
        tmp_path / "p.3mf",
        "p",
        export.stl_linear_deflection,
        export.stl_angular_deflection,
        version="test",
        mesh=mesh,
    )
    with zipfile.ZipFile(tmp_path / "p.3mf") as package:
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
    assert len(triangles) == len(mesh.triangles)
    assert intersecting_pairs(vertices, triangles) == 0
    assert trimesh.Trimesh(vertices, triangles, process=False).is_watertight


#: A fuzz design whose tessellation BRepMesh left open at its deflection (each of its 7 blade
#: footprints on the hub is a crescent 0.03 mm wide: the chords of its two edges cross and the hub
#: face's triangles leave a gap), so the build refused its STL before.
OPEN_TESSELLATION_SEED = 55


# 30 s: the tessellation at half the deflection and meshlib's repair of its knife edges
@pytest.mark.long
def test_a_design_whose_tessellation_was_open_writes_a_watertight_uncrossed_stl(tmp_path):
    import meshlib.mrmeshpy as mr

    propeller = build_propeller(random_design(OPEN_TESSELLATION_SEED, workshop=True))
    export = propeller.parameters.export
    check = write_checked_stl(
        propeller.solid,
        tmp_path / "p.stl",
        export.stl_linear_deflection,
        export.stl_angular_deflection,
    )
    # made again finer: the design's was open
    assert check.linear_deflection_mm < export.stl_linear_deflection
    read = trimesh.load(tmp_path / "p.stl")
    assert read.is_watertight and read.is_winding_consistent
    assert read.volume == pytest.approx(propeller.solid.Volume(), rel=0.01)
    assert len(mr.findSelfCollidingTriangles(mr.loadMesh(str(tmp_path / "p.stl")))) == 0
