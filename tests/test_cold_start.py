"""``torus-cad build`` loads only what it uses: not cadquery (and with it VTK, ezdxf, casadi), whose
import costs over a second of a cold start (docs: measurements, cold start)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

#: Modules the default build must not load in its own process.
NOT_LOADED = ("cadquery", "vtkmodules", "vtk", "ezdxf", "casadi")

_BUILD = """
import json, sys
from torus_cad.cli import main
code = main(["build", "--out", sys.argv[1], "-q", "--set", "resolution.sections=12", "--set", "resolution.points=40"])
print(json.dumps({"code": code, "loaded": sorted({name.split(".")[0] for name in sys.modules})}))
"""  # noqa: E501 (code or text written out verbatim)


def test_the_build_loads_no_cadquery_and_writes_its_files(tmp_path):
    """A coarse default (12 sections of 40 points: the same path, a quarter of the work)."""
    done = subprocess.run(
        [sys.executable, "-c", _BUILD, str(tmp_path)],
        capture_output=True,
        text=True,
        check=True,
        cwd=Path(__file__).resolve().parent.parent,
    )
    outcome = json.loads(done.stdout.strip().splitlines()[-1])
    assert outcome["code"] == 0
    assert [name for name in NOT_LOADED if name in outcome["loaded"]] == []
    assert "OCP" in outcome["loaded"]  # the kernel did run
    report = json.loads((tmp_path / "torus_propeller.json").read_text())
    assert set(report["files"]) == {"step", "stl", "sections_csv", "sections_png"}
    assert (
        report["checks"]["boolean_check_self_intersection"]
        and report["checks"]["stl_self_intersections"]
    )
    # OpenCascade quiet
    assert done.stderr.count("Statistics on Transfer") == 0 and "Statistics" not in done.stdout
