"""Every STEP file the project writes passes FreeCAD's "Check geometry" with BOP check, read back by
FreeCAD."""

from __future__ import annotations

from pathlib import Path

import pytest
from freecad_check import FREECADCMD, freecad_verdicts

pytestmark = pytest.mark.skipif(
    FREECADCMD is None, reason="needs freecadcmd (Debian's freecad; .ci/run installs it)"
)


def test_freecad_reads_the_default_step_file_as_one_solid_without_a_fault(
    default_files, tmp_path: Path
) -> None:
    verdict = freecad_verdicts([default_files["step"]], tmp_path)[str(default_files["step"])]
    assert verdict == {"solids": 1, "valid": True, "faults": ""}


def test_freecads_check_finds_a_curve_off_its_surface_that_the_build_would_refuse(
    tmp_path: Path,
) -> None:
    # the check can fail: an edge bumped between the STEP reader's samples
    # (tests/test_step_readback.py)
    from test_step_readback import _cylinder_with_a_bumped_edge

    from torus_cad.kernel.writers.step import write_step

    path = write_step(
        _cylinder_with_a_bumped_edge("out"),
        tmp_path / "bumped.step",
        "bumped",
        check_readback=False,
    )
    verdict = freecad_verdicts([path], tmp_path / "freecad")[str(path)]
    assert "BOPAlgo_InvalidCurveOnSurface" in str(verdict["faults"])
