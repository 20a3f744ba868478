"""The report's ``set_screw_angle_deg`` is where the hole of the part as built points, for cw and
ccw parts.

The hole is found on the solid (its cylindrical faces of the set screw's radius, read back from
the STEP file the build wrote), not from the parameters.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.GeomAbs import GeomAbs_Cylinder

from torus_cad.cli import main
from torus_cad.kernel.step_readback import read_step

LIGHT = ["--set", "resolution.sections=16", "--set", "resolution.points=48"]
MOUNT = [
    "--set",
    "hub.bore_diameter=5.0",
    "--set",
    "hub.bore_flat_depth=0.5",
    "--set",
    "hub.set_screw_diameter=3.0",
]


def _hole_angle_deg(step_path) -> float:
    """The direction (deg about +z) of the mean of points spread over the solid's 1.5 mm-radius
    cylinder faces."""
    shape = read_step(step_path)
    points = []
    for face in shape.Faces():
        surface = BRepAdaptor_Surface(face.wrapped)
        if surface.GetType() == GeomAbs_Cylinder and surface.Cylinder().Radius() == pytest.approx(
            1.5, abs=1e-9
        ):
            for u in np.linspace(
                surface.FirstUParameter(), surface.LastUParameter(), 24, endpoint=False
            ):
                for v in np.linspace(surface.FirstVParameter(), surface.LastVParameter(), 5):
                    points.append(surface.Value(u, v).Coord())
    assert points, "no set-screw hole on the solid"
    x, y, _ = np.mean(points, axis=0)
    return math.degrees(math.atan2(y, x)) % 360.0


@pytest.mark.parametrize("handedness", ["cw", "ccw"])
def test_the_reported_set_screw_angle_is_where_the_hole_is(tmp_path, capsys, handedness):
    out = tmp_path / handedness
    assert (
        main(
            [
                "build",
                "--out",
                str(out),
                "--no-stl",
                "-q",
                "--set",
                f"handedness={handedness}",
                *LIGHT,
                *MOUNT,
            ]
        )
        == 0
    ), capsys.readouterr().err
    report = json.loads((out / "torus_propeller.json").read_text())
    measured = _hole_angle_deg(out / "torus_propeller.step")
    difference = (report["set_screw_angle_deg"] - measured + 180.0) % 360.0 - 180.0
    assert abs(difference) < 0.5, (report["set_screw_angle_deg"], measured)
