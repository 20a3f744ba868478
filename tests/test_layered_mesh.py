"""The boundary-layer mesh route of `torus-cad simulate` (torus_cad.simulate.snappy): the first
layer's height from the y+ target, the levels' sizes, checkMesh's and snappyHexMesh's reports read
back, a failed checkMesh is one named line with exit 1, and any closed surface (not only a toroidal
design) meshes with prism layers."""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from cli_exit import exit_code
from openfoam_marks import needs_openfoam

foamlib = pytest.importorskip("foamlib")

from torus_cad.errors import ParameterError  # noqa: E402
from torus_cad.simulate.pipeline import MESH_REPORT, MeshCheckError, _checked_mesh  # noqa: E402
from torus_cad.simulate.run import openfoam_environment  # noqa: E402
from torus_cad.simulate.settings import (  # noqa: E402
    AIR_15C,
    LAST_LAYER_MIN_FRACTION,
    LAYER_EXPANSION_RATIO,
    LAYER_STACK_MAX_SURFACE_CELLS,
    LAYERS,
    REFINEMENT_RATIO,
    SURFACE_LEVEL,
    Y_PLUS_REFERENCE_RADIUS,
    Level,
)
from torus_cad.simulate.snappy import (  # noqa: E402
    MESH_COMMANDS,
    first_cell_height_m,
    layer_count,
    layer_coverage,
    layer_stack_m,
    parse_check_mesh,
    read_stl_points_mm,
    skin_friction,
    write_layered_mesh,
)
from torus_cad.tolerances import SIMULATE_MAX_SURFACE_REFINEMENT  # noqa: E402

CHECK_MESH_OK = """
Mesh stats
    points:           58301
    cells:            51845
Overall number of cells of each type:
    hexahedra:     36536
    prisms:        1033
    wedges:        0
    pyramids:      0
    tet wedges:    146
    tetrahedra:    4
    polyhedra:     14126
    Mesh non-orthogonality Max: 65.058827 average: 9.2
    Max skewness = 3.4 OK.

Mesh OK.
"""

CHECK_MESH_FAILED = CHECK_MESH_OK.replace(
    "    Max skewness = 3.4 OK.\n\nMesh OK.",
    (
        " ***Max skewness = 4.44769, 2 highly skew faces "
        "detected which may impair the quality of the results\n\n"
        "Failed 1 mesh checks."
    ),
)

LAYER_TABLES = """
patch     faces    layers   overall thickness
                            [m]       [%]
-----     -----    ------   ---       ---
propeller 5948     8      1.34e-05  0.000313

patch     faces    layers   overall thickness
                            [m]       [%]
-----     -----    ------   ---       ---
propeller 6032     2.66     0.000202  66.9
"""


def test_the_first_layer_is_the_flat_plate_estimate_at_three_quarter_radius():
    diameter, rpm = 0.0451, 10000.0
    speed = rpm * 2 * math.pi / 60 * Y_PLUS_REFERENCE_RADIUS * diameter / 2
    reynolds = speed * 0.1 * diameter / AIR_15C.viscosity_m2_s
    u_tau = speed * math.sqrt(0.026 * reynolds ** (-1 / 7) / 2)
    assert first_cell_height_m(diameter, rpm, 0.0) == pytest.approx(AIR_15C.viscosity_m2_s / u_tau)
    assert first_cell_height_m(diameter, rpm, 0.0, y_plus=30.0) == pytest.approx(
        30 * first_cell_height_m(diameter, rpm, 0.0)
    )
    # faster: thinner
    assert first_cell_height_m(diameter, 2 * rpm, 0.0) < first_cell_height_m(diameter, rpm, 0.0)
    assert first_cell_height_m(diameter, rpm, 20.0) < first_cell_height_m(diameter, rpm, 0.0)
    # a still propeller still gets a layer
    assert math.isfinite(first_cell_height_m(diameter, 0.0, 0.0))
    assert skin_friction(1e6) == pytest.approx(0.026 / 1e6 ** (1 / 7))


def test_check_mesh_output_gives_the_verdict_the_cell_types_and_the_failed_checks():
    check = parse_check_mesh(CHECK_MESH_OK)
    assert check.ok and check.cells == 51845 and check.failures == []
    assert check.cell_types["prisms"] == 1033 and check.cell_types["polyhedra"] == 14126
    assert check.cell_types["tet wedges"] == 146 and check.max_non_orthogonality == pytest.approx(
        65.058827
    )
    failed = parse_check_mesh(CHECK_MESH_FAILED)
    assert not failed.ok and failed.failures == [
        "***Max skewness = 4.44769, 2 highly skew faces "
        "detected which may impair the quality of the results"
    ]


def test_the_layer_report_is_snappys_last_table():
    coverage = layer_coverage(LAYER_TABLES)
    assert coverage is not None
    assert coverage["mean_layers"] == 2.66 and coverage["thickness_fraction"] == pytest.approx(
        0.669
    )
    assert coverage["coverage"] == pytest.approx(2.66 / LAYERS)
    assert layer_coverage("no layers here") is None


def test_a_mesh_checkmesh_refuses_is_a_named_error_and_the_report_is_kept(tmp_path):
    (tmp_path / "log.checkMesh").write_text(CHECK_MESH_FAILED)
    with pytest.raises(
        MeshCheckError,
        match=r"checkMesh did not report 'Mesh OK' on the coarse level \(snappy "
        r"mesher\): \*\*\*Max skewness = 4.44769",
    ):
        _checked_mesh(tmp_path, {"mesher": "snappy", "level": "coarse", "cells": None})
    assert (tmp_path / MESH_REPORT).is_file()
    (tmp_path / "log.checkMesh").write_text(CHECK_MESH_OK)
    assert (
        _checked_mesh(tmp_path, {"mesher": "snappy", "level": "coarse", "cells": None})[
            "cell_types"
        ]["prisms"]
        == 1033
    )


def _box_stl(path: Path, half: tuple[float, float, float]) -> Path:
    """A closed box (mm) centred on the origin: two 'blades' across the axis, as an ASCII STL."""
    corners = np.array(
        [
            [sx * half[0], sy * half[1], sz * half[2]]
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    lines = ["solid box"]
    for a, b, c, d in quads:
        for tri in ((a, b, c), (a, c, d)):
            p = corners[list(tri)]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            lines += [
                f"facet normal {' '.join(map(str, normal / np.linalg.norm(normal)))}",
                "outer loop",
                *(f"vertex {x} {y} {z}" for x, y, z in p),
                "endloop",
                "endfacet",
            ]
    path.write_text("\n".join([*lines, "endsolid box"]) + "\n")
    return path


def test_levels_scale_every_length_by_the_refinement_ratio(tmp_path):
    stl = _box_stl(tmp_path / "box.stl", (20.0, 3.0, 1.0))
    assert read_stl_points_mm(stl)[:, 0].max() == pytest.approx(20.0)
    meshes = {
        level: write_layered_mesh(stl, 40.0, level, tmp_path / level.value, 2e-5) for level in Level
    }
    cells = [meshes[level].background_cell_m for level in Level]
    firsts = [meshes[level].first_layer_m for level in Level]
    assert cells[0] / cells[1] == pytest.approx(REFINEMENT_RATIO) and cells[1] / cells[
        2
    ] == pytest.approx(REFINEMENT_RATIO)
    assert firsts[0] == pytest.approx(2e-5) and firsts[0] / firsts[2] == pytest.approx(
        REFINEMENT_RATIO**2
    )
    # a first layer too thin for the surface cell is raised until the last layer is a set share of
    # that cell
    raised = write_layered_mesh(stl, 40.0, Level.COARSE, tmp_path / "raised", 1e-6)
    surface_cell = raised.background_cell_m / 2**SURFACE_LEVEL
    assert raised.first_layer_m * LAYER_EXPANSION_RATIO ** (LAYERS - 1) == pytest.approx(
        LAST_LAYER_MIN_FRACTION * surface_cell
    )
    snappy = foamlib.FoamFile(tmp_path / "fine" / "system" / "snappyHexMeshDict")
    layers = snappy["addLayersControls"]
    assert (
        layers["firstLayerThickness"] == pytest.approx(firsts[2])
        and layers["expansionRatio"] == LAYER_EXPANSION_RATIO
    )
    assert layers["layers"]["propeller"]["nSurfaceLayers"] == LAYERS
    zone = snappy["castellatedMeshControls"]["refinementSurfaces"]["rotating_zone"]
    assert zone["cellZone"] == "rotating_zone" and zone["faceZone"] == "rotating_zone"
    for level in Level:  # whole cubes of the level's edge, the box at least the domain asked for
        block = foamlib.FoamFile(tmp_path / level.value / "system" / "blockMeshDict")
        assert [name for name, _ in block["boundary"]] == ["inlet", "outlet", "farfield"]
        vertices, counts = np.array(block["vertices"]), block["blocks"][2]
        size = vertices.max(axis=0) - vertices.min(axis=0)
        assert size / np.array(counts) == pytest.approx(np.full(3, meshes[level].background_cell_m))
        assert size[0] >= 2 * 3 * 0.04 and vertices[:, 2].max() == pytest.approx(2 * 0.04)
        assert vertices[:, 2].min() <= -4 * 0.04
    domain = meshes[Level.COARSE].domain
    assert domain.inlet_z_m == pytest.approx(2 * 0.04) and domain.outlet_z_m == pytest.approx(
        -4 * 0.04
    )
    assert domain.zone_z_m == pytest.approx((-0.001 - 0.004, 0.001 + 0.004))


def test_a_surface_that_does_not_fit_its_diameter_is_refused_naming_it(tmp_path):
    stl = _box_stl(tmp_path / "box.stl", (20.0, 3.0, 1.0))
    with pytest.raises(
        ParameterError,
        match=r"surface 'box.stl' reaches 20.22 mm from the axis, outside the rotating "
        r"zone's radius 18.00 mm \(0.6 D\)",
    ):
        write_layered_mesh(stl, 30.0, Level.COARSE, tmp_path / "case", 1e-5)
    with pytest.raises(ParameterError, match=r"diameter = 0 mm is out of range"):
        write_layered_mesh(stl, 0.0, Level.COARSE, tmp_path / "case", 1e-5)
    assert not (tmp_path / "case").exists()


@needs_openfoam
def test_any_closed_surface_meshes_with_prism_layers_and_checkmesh_says_ok(tmp_path):
    """Not a toroidal design: a box surface and its diameter go through the same route."""
    stl = _box_stl(tmp_path / "box.stl", (20.0, 3.0, 1.0))
    case = tmp_path / "case"
    mesh = write_layered_mesh(
        stl, 40.0, Level.COARSE, case, first_cell_height_m(0.04, 10000.0, 0.0)
    )
    assert mesh.commands == [list(command) for command in MESH_COMMANDS]
    environment = {**os.environ, **openfoam_environment()}
    logs = {}
    for command in mesh.commands:
        done = subprocess.run(
            command, cwd=case, env=environment, capture_output=True, text=True, timeout=300
        )
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
        logs[command[0]] = done.stdout
    check = parse_check_mesh(logs["checkMesh"])
    assert check.ok, check.failures
    assert check.cell_types["hexahedra"] > 0 and sum(check.cell_types.values()) == check.cells
    coverage = layer_coverage(logs["snappyHexMesh"])
    assert coverage is not None and coverage["mean_layers"] > 1.0, coverage
    boundary = (case / "constant" / "polyMesh" / "boundary").read_text()
    for patch in ("propeller", "inlet", "outlet", "farfield"):
        assert patch in boundary
    assert "rotating_zone" in (case / "constant" / "polyMesh" / "cellZones").read_text()


@needs_openfoam
def test_mesh_from_a_case_of_another_level_or_mesher_exits_2_naming_both(tmp_path, capsys):
    from torus_cad.cli import main

    source = tmp_path / "torus_propeller_case"
    (source / "constant" / "polyMesh").mkdir(parents=True)
    (source / "constant" / "polyMesh" / "boundary").write_text("")
    (source / MESH_REPORT).write_text(
        json.dumps({"name": "torus_propeller", "mesher": "snappy", "level": "fine"})
    )
    out = tmp_path / "out"
    assert main(["simulate", "--rpm", "1000", "--mesh-from", str(source), "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert (
        error.count("\n") == 1
        and "was meshed for design 'torus_propeller', mesher 'snappy', level 'fine', "
        "surface refinement 0, not 'torus_propeller', 'snappy', 'coarse', 0"
        in error
    )
    assert (
        main(
            [
                "simulate",
                "--rpm",
                "1000",
                "--mesher",
                "tet",
                "--level",
                "fine",
                "--mesh-from",
                str(source),
                "--out",
                str(out),
            ]
        )
        == 2
    )
    assert (
        "mesher 'snappy', level 'fine', surface refinement "
        "0, not 'torus_propeller', 'tet', 'fine', 0" in capsys.readouterr().err
    )
    assert (
        main(
            [
                "simulate",
                "--rpm",
                "1000",
                "--level",
                "fine",
                "--surface-refinement",
                "1",
                "--mesh-from",
                str(source),
                "--out",
                str(out),
            ]
        )
        == 2
    )
    assert (
        "level 'fine', surface refinement 0, not 'torus_propeller', 'snappy', 'fine', 1"
        in capsys.readouterr().err
    )
    assert not out.exists() or not list(out.iterdir())


def test_surface_refinement_halves_the_propellers_cells_and_keeps_the_levels_layers(tmp_path):
    stl = _box_stl(tmp_path / "box.stl", (20.0, 3.0, 1.0))
    plain = write_layered_mesh(stl, 40.0, Level.MEDIUM, tmp_path / "plain", 1e-6)
    refined = write_layered_mesh(
        stl, 40.0, Level.MEDIUM, tmp_path / "refined", 1e-6, surface_refinement=2
    )
    assert (
        refined.first_layer_m == plain.first_layer_m
        and refined.background_cell_m == plain.background_cell_m
    )
    levels = {}
    for name in ("plain", "refined"):
        snappy = foamlib.FoamFile(tmp_path / name / "system" / "snappyHexMeshDict")
        controls = snappy["castellatedMeshControls"]
        levels[name] = (
            list(controls["refinementSurfaces"]["propeller"]["level"]),
            controls["features"][0]["level"],
            list(controls["refinementSurfaces"]["rotating_zone"]["level"]),
        )
        assert snappy["addLayersControls"]["firstLayerThickness"] == pytest.approx(
            plain.first_layer_m
        )
    assert levels["plain"] == ([SURFACE_LEVEL] * 2, SURFACE_LEVEL + 1, [2, 2])
    assert levels["refined"] == ([SURFACE_LEVEL + 2] * 2, SURFACE_LEVEL + 3, [2, 2])


def test_the_layers_fit_the_refined_surface_with_the_first_layer_kept(tmp_path):
    """Each surface refinement halves the surface cell; from the step where the level's eight layers
    would stand taller than LAYER_STACK_MAX_SURFACE_CELLS cells, fewer are asked for, the first
    layer unchanged."""
    stl = _box_stl(tmp_path / "box.stl", (20.0, 3.0, 1.0))
    asked, first = [], set()
    for refinement in range(SIMULATE_MAX_SURFACE_REFINEMENT + 1):
        mesh = write_layered_mesh(
            stl, 40.0, Level.COARSE, tmp_path / str(refinement), 1e-6, surface_refinement=refinement
        )
        layers = foamlib.FoamFile(tmp_path / str(refinement) / "system" / "snappyHexMeshDict")[
            "addLayersControls"
        ]
        asked.append(layers["layers"]["propeller"]["nSurfaceLayers"])
        first.add(layers["firstLayerThickness"])
        surface_cell = mesh.background_cell_m / 2.0 ** (SURFACE_LEVEL + refinement)
        assert (
            layer_stack_m(mesh.first_layer_m, asked[-1])
            <= LAYER_STACK_MAX_SURFACE_CELLS * surface_cell
        )
    assert (
        len(first) == 1
        and asked[0] == LAYERS
        and asked == sorted(asked, reverse=True)
        and asked[-1] < LAYERS
    )
    assert layer_count(1e-3, 1e-6) == 1  # never none


def test_the_layer_coverage_is_over_the_layers_asked_for():
    coverage = layer_coverage(LAYER_TABLES.replace("     8      1.34e-05", "     5      1.34e-05"))
    assert (
        coverage is not None
        and coverage["wanted_layers"] == 5
        and coverage["coverage"] == pytest.approx(2.66 / 5)
    )


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--surface-refinement", "5"], "--surface-refinement = 5 is out of range; allowed [0, 4]"),
        (
            ["--surface-refinement", "1", "--mesher", "tet"],
            "--surface-refinement = 1 refines snappyHexMesh's surface; "
            "allowed only with --mesher snappy",
        ),
    ],
)
def test_a_surface_refinement_out_of_range_or_without_snappy_exits_2_naming_it(
    tmp_path, capsys, arguments, message
):
    out = tmp_path / "out"
    assert (
        exit_code(["simulate", "--rpm", "1000", "--case-only", *arguments, "--out", str(out)]) == 2
    )
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and message in error
    assert not out.exists()


def test_the_tip_diameter_is_the_designs_as_built_with_its_diameter_target():
    from torus_cad.parameters import PropellerParameters
    from torus_cad.simulate.pipeline import Request, check_request
    from torus_cad.simulate.settings import OperatingPoint

    targeted = PropellerParameters().with_values({"diameter": 100.0})
    assert check_request(Request(targeted, OperatingPoint(1000.0))) == pytest.approx(0.1, rel=1e-3)
    assert check_request(Request(PropellerParameters(), OperatingPoint(1000.0))) == pytest.approx(
        0.0451, rel=1e-3
    )
