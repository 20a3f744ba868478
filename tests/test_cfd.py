"""`torus-cad cfd`: the .msh files read back (in gmsh and in meshio) with every physical group, and the
meshed fluid fills the domain minus the propeller; bad input and a missing gmsh are one clear line."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from torus_cad.cfd.domain import SURFACE_GROUPS, VOLUME_GROUPS, tetrahedra_volume
from torus_cad.cli import main

gmsh = pytest.importorskip("gmsh")

#: Coarse sizes, so the test meshes in seconds (the default sizes are measured by scripts/bench_mesh.py).
COARSE = ["--cells-per-chord", "4", "--curvature-cells", "0", "--growth-rate", "1.6", "--far-size", "0.3",
          "--domain-radius", "2", "--upstream", "1.5", "--downstream", "2"]


@pytest.fixture(scope="module")
def cfd_out(tmp_path_factory):
    out = tmp_path_factory.mktemp("cfd")
    assert main(["cfd", *COARSE, "--out", str(out), "-q"]) == 0
    return out


def _read_back(path) -> tuple[dict[str, int], dict[str, float]]:
    """Physical groups (name -> dim) and meshed volume per physical volume, as gmsh reads the file."""
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        groups = {gmsh.model.getPhysicalName(dim, tag): dim for dim, tag in gmsh.model.getPhysicalGroups()}
        node_tags, coordinates, _ = gmsh.model.mesh.getNodes()
        nodes = np.zeros((int(node_tags.max()) + 1, 3))
        nodes[node_tags.astype(np.int64)] = coordinates.reshape(-1, 3)
        volumes = {}
        for dim, tag in gmsh.model.getPhysicalGroups(3):
            tets = [gmsh.model.mesh.getElementsByType(4, entity)[1] for entity in
                    gmsh.model.getEntitiesForPhysicalGroup(dim, tag)]
            volumes[gmsh.model.getPhysicalName(dim, tag)] = tetrahedra_volume(
                nodes, np.concatenate(tets).astype(np.int64).reshape(-1, 4))
        return groups, volumes
    finally:
        gmsh.finalize()


@pytest.mark.slow
@pytest.mark.parametrize("file_name", ["torus_propeller_cfd.msh", "torus_propeller_cfd_v2.msh"])
def test_msh_reads_back_with_every_group_and_the_fluid_volume(cfd_out, file_name):
    report = json.loads((cfd_out / "torus_propeller_cfd.json").read_text())
    groups, volumes = _read_back(cfd_out / file_name)
    assert groups == {**{name: 2 for name in SURFACE_GROUPS}, **{name: 3 for name in VOLUME_GROUPS}}
    domain = report["domain_mm"]
    outer = np.pi * domain["outer_radius"] ** 2 * (domain["outer_z"][1] - domain["outer_z"][0])
    zone = np.pi * domain["zone_radius"] ** 2 * (domain["zone_z"][1] - domain["zone_z"][0])
    propeller = report["propeller_volume_mm3"]
    assert sum(volumes.values()) == pytest.approx(outer - propeller, rel=0.01)
    # the rotating zone alone: the propeller (~10 % of it here) is cut out, not meshed over
    assert volumes["rotating_zone"] == pytest.approx(zone - propeller, rel=0.01)
    assert volumes["fluid"] == pytest.approx(outer - zone, rel=0.01)


@pytest.mark.slow
def test_meshio_reads_the_gmshtofoam_file_and_the_report_and_readme_agree(cfd_out):
    meshio = pytest.importorskip("meshio")
    mesh = meshio.read(cfd_out / "torus_propeller_cfd_v2.msh")
    assert set(SURFACE_GROUPS) | set(VOLUME_GROUPS) <= set(mesh.field_data)
    report = json.loads((cfd_out / "torus_propeller_cfd.json").read_text())
    assert sum(len(block.data) for block in mesh.cells if block.type == "tetra") == report["tetrahedra_total"]
    assert report["sicn_min"] > 0.0  # no inverted element
    assert all(count > 0 for count in report["triangles"].values())
    readme = (cfd_out / "README.txt").read_text()
    assert "gmshToFoam torus_propeller_cfd_v2.msh" in readme and "rotating_interface" in readme
    assert sorted(path.name for path in cfd_out.iterdir()) == [
        "README.txt", "torus_propeller.step", "torus_propeller_cfd.json", "torus_propeller_cfd.msh",
        "torus_propeller_cfd_v2.msh"]


@pytest.mark.parametrize("arguments, fragment", [
    (["--zone-radius", "0.4"], "cfd.zone_radius = 0.4 is out of range"),
    (["--growth-rate", "1"], "cfd.growth_rate = 1 is out of range"),
    (["--domain-radius", "1", "--zone-radius", "0.9"], "must be at least 1.5 x cfd.zone_radius"),
    (["--upstream", "0.5", "--zone-clearance", "1"], "put an end of the domain inside the rotating zone"),
    (["--threads", "-1"], "--threads = -1 is out of range"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, arguments, fragment):
    out = tmp_path / "out"
    assert main(["cfd", *arguments, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


def test_without_gmsh_one_line_names_the_extra(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "gmsh", None)  # what Python does when the package is absent: ImportError
    assert main(["cfd", "--out", str(tmp_path / "out")]) == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "pip install 'torus_cad[cfd]'" in error
    assert not (tmp_path / "out").exists()
