"""The full boolean-argument analysis (FreeCAD's check with BOP) of the solid and of its STEP file read back."""

from __future__ import annotations

from pathlib import Path

import cadquery as cq
import pytest
from conftest import EXAMPLES_DIR, SHIPPED_DESIGNS

from torus_cad.errors import KernelError
from torus_cad.kernel.step_readback import argument_faults, check_step_readback, step_readback_faults
from torus_cad.kernel.writers.step import write_step

#: Open (issue 33 item 2): a root fillet's faces meet the blade and hub only within up to 2.5e-5 mm (OpenCascade
#: approximates the fillet surface), which its edges' tolerances cover in memory but a STEP file cannot
#: carry per edge (its reader samples each edge's deviation at 23 points and falls short of the largest).
FILLET_OPEN = "a root fillet's file reads back with InvalidCurveOnSurface faults (issue 33)"


def _c0_face() -> cq.Face:
    """A face on a degree-1 B-spline surface with an interior knot: only C0 there (a GeomAbs_C0 fault)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.GeomAbs import GeomAbs_C0
    from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface
    from OCP.gp import gp_Pnt
    from OCP.TColgp import TColgp_Array2OfPnt

    points = TColgp_Array2OfPnt(1, 3, 1, 3)
    for i in range(1, 4):
        for j in range(1, 4):
            points.SetValue(i, j, gp_Pnt(10.0 * i, 10.0 * j, 5.0 if (i, j) == (2, 2) else 0.0))
    surface = GeomAPI_PointsToBSplineSurface(points, 1, 1, GeomAbs_C0, 1e-6).Surface()
    return cq.Face(BRepBuilderAPI_MakeFace(surface, 1e-6).Face())


def test_a_step_file_that_reads_back_faulty_is_not_written(tmp_path: Path) -> None:
    with pytest.raises(KernelError, match=r"c0\.step: the STEP file read back fails .*GeomAbs_C0"):
        write_step(_c0_face(), tmp_path / "c0.step", "c0", check_readback=True)
    assert list(tmp_path.iterdir()) == []


def test_the_read_back_check_names_a_c0_surface_in_the_file(tmp_path: Path) -> None:
    path = write_step(_c0_face(), tmp_path / "c0.step", "c0")
    assert step_readback_faults(path).counts == {"GeomAbs_C0": 5}  # the face and its four edges
    with pytest.raises(KernelError, match=r"the C0 face: the STEP file read back fails .*: 5 GeomAbs_C0; first: GeomAbs_C0"):
        check_step_readback(path, "the C0 face")


@pytest.mark.long
def test_the_default_solid_passes_every_analyzer_test_in_memory(default_propeller) -> None:
    faults = argument_faults(default_propeller.solid.wrapped)
    assert faults.counts == {}, faults.first


def test_the_default_step_file_read_back_passes_every_analyzer_test(default_files) -> None:
    # every test, self-interference included (the build leaves that one to its strict check of the solid)
    faults = step_readback_faults(default_files["step"])
    assert faults.counts == {}, faults.first


def _shipped(design: Path) -> object:
    if "fillet" in design.stem:
        return pytest.param(design, marks=pytest.mark.xfail(strict=True, reason=FILLET_OPEN))
    return design


@pytest.mark.long
@pytest.mark.parametrize("design", [_shipped(design) for design in SHIPPED_DESIGNS], ids=lambda d: d.stem)
def test_every_shipped_design_reads_back_from_step_valid(design: Path, tmp_path: Path) -> None:
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(design)
    path = write_step(propeller.solid, tmp_path / "design.step", propeller.parameters.name)
    check_step_readback(path, design.stem)


def test_a_root_fillet_has_no_c0_face_or_edge_and_passes_the_analyzer_in_memory(tmp_path: Path) -> None:
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(EXAMPLES_DIR / "workshop_fillet.toml")
    # every test but self-interference, which the build's strict check runs on the solid
    faults = argument_faults(propeller.solid.wrapped, self_interference=False)
    assert faults.counts == {}, faults.first  # were 18 GeomAbs_C0 (6 faces, 12 edges) and 3 InvalidCurveOnSurface
    path = write_step(propeller.solid, tmp_path / "design.step", propeller.parameters.name)
    assert "GeomAbs_C0" not in step_readback_faults(path, self_interference=False).counts
