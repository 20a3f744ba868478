"""`torus-cad cfd`: the .msh files read back (in gmsh and in meshio) with every physical group, and
the meshed fluid fills the domain minus the propeller; coarse sizes and a blunt trailing edge mesh
(no crossing triangles, by meshlib); README.txt's OpenFOAM steps give "Mesh OK" and no empty patch;
a mesh over the budget is refused before any work; the files are one output set (verify, signals,
a file size limit); bad input and a missing gmsh are one clear line."""

from __future__ import annotations

import contextlib
import io
import json
import random
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from cli_exit import exit_code

from torus_cad.cfd_domain.domain import SURFACE_GROUPS, VOLUME_GROUPS, tetrahedra_volume
from torus_cad.cfd_domain.readme import openfoam_block
from torus_cad.cli import main
from torus_cad.outputs.output_set import verify_set
from torus_cad.tolerances import CFD_TETRAHEDRA_LIMIT

gmsh = pytest.importorskip("gmsh")

#: Coarse sizes, so the test meshes in seconds (the default sizes are measured by
#: scripts/bench_mesh.py).
COARSE = [
    "--cells-per-chord",
    "4",
    "--curvature-cells",
    "0",
    "--growth-rate",
    "1.6",
    "--far-size",
    "0.3",
    "--domain-radius",
    "2",
    "--upstream",
    "1.5",
    "--downstream",
    "2",
]


@pytest.fixture(scope="module")
def cfd_run(tmp_path_factory):
    """The coarse mesh's folder and what the command printed on stderr (not a terminal: no stage
    lines)."""
    out = tmp_path_factory.mktemp("cfd")
    stderr = io.StringIO()
    with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
        assert main(["cfd", *COARSE, "--out", str(out)]) == 0
    return out, stderr.getvalue()


@pytest.fixture(scope="module")
def cfd_out(cfd_run):
    return cfd_run[0]


def cli(*args: str, **kwargs) -> subprocess.CompletedProcess:
    """``python -m torus_cad ARGS`` in a new process."""
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=1200,
        **kwargs,
    )


def _read_back(path) -> tuple[dict[str, int], dict[str, float]]:
    """Physical groups (name -> dim) and meshed volume per physical volume, as gmsh reads the
    file."""
    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        groups = {
            gmsh.model.getPhysicalName(dim, tag): dim for dim, tag in gmsh.model.getPhysicalGroups()
        }
        node_tags, coordinates, _ = gmsh.model.mesh.getNodes()
        nodes = np.zeros((int(node_tags.max()) + 1, 3))
        nodes[node_tags.astype(np.int64)] = coordinates.reshape(-1, 3)
        volumes = {}
        for dim, tag in gmsh.model.getPhysicalGroups(3):
            tets = [
                gmsh.model.mesh.getElementsByType(4, entity)[1]
                for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
            ]
            volumes[gmsh.model.getPhysicalName(dim, tag)] = tetrahedra_volume(
                nodes, np.concatenate(tets).astype(np.int64).reshape(-1, 4)
            )
        return groups, volumes
    finally:
        gmsh.finalize()


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


def test_meshio_reads_the_gmshtofoam_file_and_the_report_and_readme_agree(cfd_out):
    meshio = pytest.importorskip("meshio")
    mesh = meshio.read(cfd_out / "torus_propeller_cfd_v2.msh")
    assert set(SURFACE_GROUPS) | set(VOLUME_GROUPS) <= set(mesh.field_data)
    report = json.loads((cfd_out / "torus_propeller_cfd.json").read_text())
    assert (
        sum(len(block.data) for block in mesh.cells if block.type == "tetra")
        == report["tetrahedra_total"]
    )
    assert report["sicn_min"] > 0.0  # no inverted element
    assert all(count > 0 for count in report["triangles"].values())
    readme = (cfd_out / "README.txt").read_text()
    assert (
        'gmshToFoam "$MESH/torus_propeller_cfd_v2.msh"' in readme and "rotating_interface" in readme
    )
    assert sorted(path.name for path in cfd_out.iterdir()) == [
        "README.txt",
        "torus_propeller_cfd.json",
        "torus_propeller_cfd.msh",
        "torus_propeller_cfd.step",
        "torus_propeller_cfd_v2.msh",
    ]


@pytest.mark.parametrize(
    "arguments, fragment",
    [
        (["--zone-radius", "0.4"], "cfd.zone_radius = 0.4 is out of range"),
        (["--growth-rate", "1"], "cfd.growth_rate = 1 is out of range"),
        (
            ["--domain-radius", "1", "--zone-radius", "0.9"],
            "must be at least 1.5 x cfd.zone_radius",
        ),
        (
            ["--upstream", "0.5", "--zone-clearance", "1"],
            "put an end of the domain inside the rotating zone",
        ),
        (["--threads", "-1"], "--threads = -1 is out of range"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, arguments, fragment):
    out = tmp_path / "out"
    assert exit_code(["cfd", *arguments, "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error and error.count("\n") == 1
    assert not out.exists()


def test_without_gmsh_one_line_names_the_extra(tmp_path, capsys, monkeypatch):
    # what Python does when the package is absent: ImportError
    monkeypatch.setitem(sys.modules, "gmsh", None)
    assert main(["cfd", "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and "the cfd extra" in error
        and "pip install -c constraints.txt -e '.[cfd]'" in error
    )
    assert not (tmp_path / "out").exists()


def _crossing_pairs(msh_path, group: str) -> int:
    """Intersecting triangle pairs of one physical surface group of a .msh file (meshio reads it,
    meshlib checks)."""
    meshio = pytest.importorskip("meshio")
    mr = pytest.importorskip("meshlib.mrmeshpy")
    from meshlib import mrmeshnumpy

    mesh = meshio.read(msh_path)
    tag = mesh.field_data[group][0]
    triangles = np.concatenate(
        [
            block.data[tags == tag]
            for block, tags in zip(mesh.cells, mesh.cell_data["gmsh:physical"])
            if block.type == "triangle"
        ]
    )
    used, inverse = np.unique(triangles, return_inverse=True)
    surface = mrmeshnumpy.meshFromFacesVerts(
        np.ascontiguousarray(inverse.reshape(-1, 3), dtype=np.int32),
        np.ascontiguousarray(mesh.points[used], dtype=np.float64),
    )
    return len(mr.findSelfCollidingTriangles(surface))


def test_the_coarse_propeller_wall_has_no_crossing_triangles_and_the_estimate_is_near(cfd_out):
    assert _crossing_pairs(cfd_out / "torus_propeller_cfd.msh", "propeller") == 0
    report = json.loads((cfd_out / "torus_propeller_cfd.json").read_text())
    assert report["surface_refinement"]["crossing_triangles"][-1] == 0
    assert 0.5 < report["estimate"]["tetrahedra"] / report["tetrahedra_total"] < 2.0


def test_the_estimate_is_printed_with_its_factor_and_time_and_the_mesh_falls_within_it(cfd_run):
    from torus_cad.cfd_domain.estimate import REAL_OVER_ESTIMATE, TETS_PER_SECOND

    out, stderr = cfd_run
    report = json.loads((out / "torus_propeller_cfd.json").read_text())
    (line,) = [text for text in stderr.splitlines() if text.startswith("torus-cad cfd: estimate")]
    estimate = report["estimate"]["tetrahedra"]
    assert (
        line.startswith(f"torus-cad cfd: estimate: about {estimate:,} tetrahedra")
        and "tetrahedra/s" in line
    )
    low, high = (
        int(text.replace(",", "")) for text in re.search(r": ([\d,]+) to ([\d,]+)\)", line).groups()
    )
    assert low <= report["tetrahedra_total"] <= high  # the stated range holds on this mesh
    assert low == pytest.approx(REAL_OVER_ESTIMATE[0] * estimate, abs=500)
    assert report["estimate"]["wall_seconds"] == pytest.approx(estimate / TETS_PER_SECOND)


def test_a_long_stage_prints_a_heartbeat_with_its_time():
    from torus_cad.cfd_domain.interruptible import run_in_worker
    from torus_cad.runtime.progress import StageProgress

    stream = io.StringIO()
    progress = StageProgress(enabled=True, stream=stream)
    progress("volume_mesh")
    assert (
        run_in_worker(lambda: time.sleep(1.2) or 7, on_wait=lambda: progress.heartbeat(every_s=0.4))
        == 7
    )
    lines = stream.getvalue().splitlines()
    assert lines[0].endswith("] volume mesh") and len(lines) >= 2
    assert all(
        re.search(r"volume mesh: still running, \d+ s in this stage$", line) for line in lines[1:]
    )
    progress.heartbeat(every_s=3600.0)  # no line unless the last one is that old
    assert stream.getvalue().splitlines() == lines


def test_the_same_design_gives_the_same_mesh_on_every_run(cfd_out, tmp_path):
    # A CFD engineer compares designs, not mesh noise: gmsh on one thread repeats itself byte for
    # byte.
    assert main(["cfd", *COARSE, "--out", str(tmp_path), "-q"]) == 0
    for name in ("torus_propeller_cfd.msh", "torus_propeller_cfd_v2.msh"):
        assert (tmp_path / name).read_bytes() == (cfd_out / name).read_bytes(), name


def test_a_blunt_trailing_edge_meshes_at_coarse_sizes(tmp_path):
    """A 0.1 mm edge (thinner than the coarse triangles) meshes; its wall has no crossing
    triangles."""
    out = tmp_path / "out"
    result = cli(
        "cfd", *COARSE, "--set", "airfoil.trailing_edge_thickness=0.1", "--out", str(out), "-q"
    )
    assert result.returncode == 0, result.stderr
    assert _crossing_pairs(out / "torus_propeller_cfd_v2.msh", "propeller") == 0


@pytest.mark.skipif(shutil.which("gmshToFoam") is None, reason="OpenFOAM is not installed")
def test_readme_txt_openfoam_steps_give_mesh_ok_and_no_empty_patch(cfd_out, tmp_path):
    """README.txt's OpenFOAM lines, as written, in a fresh case folder inside the output folder
    after the folder was moved: checkMesh says "Mesh OK", every patch has faces, the propeller is a
    wall, the zones are there."""
    moved = tmp_path / "moved"
    shutil.copytree(cfd_out, moved)
    case = moved / "case"
    case.mkdir()
    script = openfoam_block((moved / "README.txt").read_text())
    result = subprocess.run(
        ["sh", "-e", "-c", script],
        cwd=case,
        check=False,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Mesh OK" in (case / "log.checkMesh").read_text()
    boundary = (case / "constant" / "polyMesh" / "boundary").read_text()
    patches = dict(re.findall(r"\n\s*(\w+)\s*\{[^}]*?nFaces\s+(\d+);", boundary))
    assert set(patches) == {"propeller", "inlet", "outlet", "farfield"}, boundary
    assert all(int(count) > 0 for count in patches.values()), patches
    assert re.search(r"propeller\s*\{\s*type\s+wall;", boundary)
    assert "rotating_interface" in (case / "constant" / "polyMesh" / "faceZones").read_text()
    cell_zones = (case / "constant" / "polyMesh" / "cellZones").read_text()
    assert "rotating_zone" in cell_zones and "fluid" in cell_zones


def test_a_mesh_over_the_budget_is_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["cfd", "--cells-per-chord", "200", "--far-size", "0.01", "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and "tetrahedra" in error
        and f"limit of {CFD_TETRAHEDRA_LIMIT:,}" in error
    )
    assert "cfd.cells_per_chord = 200" in error and "cfd.far_size = 0.01" in error
    assert not out.exists()


def test_the_estimate_grows_with_finer_sizes():
    from torus_cad.cfd_domain.estimate import estimate_cfd_mesh
    from torus_cad.parameters import PropellerParameters

    base = PropellerParameters()
    counts = [
        estimate_cfd_mesh(base.with_values({"cfd.cells_per_chord": cells})).tetrahedra
        for cells in (4, 10, 20)
    ]
    assert counts == sorted(counts) and counts[2] > 3 * counts[0]
    coarser = estimate_cfd_mesh(base.with_values({"cfd.growth_rate": 1.6})).tetrahedra
    assert coarser < counts[1]


def test_verify_accepts_the_cfd_set_and_names_a_changed_file(cfd_out, tmp_path):
    folder = tmp_path / "copy"
    shutil.copytree(cfd_out, folder)
    assert cli("verify", str(folder)).returncode == 0
    with open(folder / "torus_propeller_cfd_v2.msh", "a") as handle:
        handle.write("\n")
    result = cli("verify", str(folder))
    assert result.returncode == 1 and "torus_propeller_cfd_v2.msh" in result.stderr


def _blades(folder) -> int:
    verify_set(folder, "torus_propeller_cfd")
    return json.loads((folder / "torus_propeller_cfd.json").read_text())["blades"]


def test_sigterm_at_a_random_moment_leaves_the_old_set_or_the_new_one(tmp_path):
    """Over a 4-blade set, a 3-blade run is stopped by SIGTERM at random moments: one line, exit 143
    (or 0 if it had finished), nothing staged left, and verify passes on the set that is there."""
    start = time.perf_counter()
    assert cli("cfd", *COARSE, "--set", "blades=4", "--out", str(tmp_path), "-q").returncode == 0
    duration = time.perf_counter() - start
    moments = random.Random(7).sample(range(1, 100), 3)
    for percent in moments:
        process = subprocess.Popen(
            [sys.executable, "-m", "torus_cad", "cfd", *COARSE, "--out", str(tmp_path), "-q"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(duration * percent / 100.0)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=600)
        assert process.returncode in (0, 143), (percent, stderr)
        if process.returncode == 143:
            assert stderr.strip().splitlines() == [
                "torus-cad: interrupted by SIGTERM; staged files "
                "removed, published output sets are complete"
            ]
        assert cli("verify", str(tmp_path)).returncode == 0
        blades = _blades(tmp_path)
        assert blades == 3 if process.returncode == 0 else blades in (3, 4)
        assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_a_file_size_limit_names_the_file_and_keeps_the_old_set(cfd_out, tmp_path):
    """The .msh (1.8 MB) cannot be written under a 1.2 MB file size limit; the STEP (0.8 MB) can."""
    import resource

    folder = tmp_path / "out"
    shutil.copytree(cfd_out, folder)

    def limit_file_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1_200_000, 1_200_000))

    result = cli(
        "cfd", *COARSE, "--set", "blades=4", "--out", str(folder), "-q", preexec_fn=limit_file_size
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert (
        "file size limit exceeded writing" in result.stderr
        and "torus_propeller_cfd.msh" in result.stderr
    )
    assert _blades(folder) == 3
    assert sorted(p.name for p in folder.iterdir() if p.name.startswith(".")) == []
