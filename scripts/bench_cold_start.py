#!/usr/bin/env python3
"""Benchmark the cold start of ``torus-cad build`` (the default design, a new process each run) against
a plain OCP script that makes a comparable part and writes STEP + STL, in the same run::

    python scripts/bench_cold_start.py --runs 5

The reference script (:data:`REFERENCE_SCRIPT`) imports only the OCP modules it uses, lofts three
NACA 0012 blades through five sections each, fuses them with a cylindrical hub and writes STEP and
STL: the least any tool pays for an OpenCascade part. Runs alternate (build, script, build, ...)
so that a change of the machine's speed touches both; the medians and their ratio are printed,
then the floor: the reference script's own imports alone (:data:`REFERENCE_IMPORTS`), which any
program that makes this part through OCP pays, as a share of the whole script; and the heaviest
imports of ``torus-cad build`` (``python -X importtime``).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REFERENCE_SCRIPT = r'''
import math, sys
from OCP.BRep import BRep_Builder
from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeWire, BRepBuilderAPI_Transform
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
from OCP.GeomAPI import GeomAPI_PointsToBSpline
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.StlAPI import StlAPI_Writer
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf

def naca0012(x):
    return 0.6 * (0.2969 * math.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)

def section_wire(radius, chord, twist_deg):
    xs = [0.5 * (1 - math.cos(math.pi * i / 40)) for i in range(41)]
    ring = [(x, naca0012(x)) for x in reversed(xs)] + [(x, -naca0012(x)) for x in xs[1:]]
    points = TColgp_Array1OfPnt(1, len(ring))
    c, s = math.cos(math.radians(twist_deg)), math.sin(math.radians(twist_deg))
    for index, (x, y) in enumerate(ring, start=1):
        u, v = (x - 0.25) * chord, y * chord
        points.SetValue(index, gp_Pnt(u * c - v * s, radius, u * s + v * c))
    curve = GeomAPI_PointsToBSpline(points).Curve()
    return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(curve).Edge()).Wire()

def blade():
    loft = BRepOffsetAPI_ThruSections(True, False)
    for radius, chord, twist in ((8, 12, 30), (15, 14, 25), (22, 13, 20), (29, 10, 15), (35, 6, 10)):
        loft.AddWire(section_wire(radius, chord, twist))
    loft.Build()
    return loft.Shape()

one = blade()
shape = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -5), gp_Dir(0, 0, 1)), 10.0, 10.0).Shape()
for index in range(3):
    turn = gp_Trsf()
    turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2 * math.pi * index / 3)
    shape = BRepAlgoAPI_Fuse(shape, BRepBuilderAPI_Transform(one, turn, True).Shape()).Shape()
writer = STEPControl_Writer()
writer.Transfer(shape, STEPControl_AsIs)
writer.Write(sys.argv[1] + "/reference.step")
BRepMesh_IncrementalMesh(shape, 0.05, False, 0.3, True)
StlAPI_Writer().Write(shape, sys.argv[1] + "/reference.stl")
'''


#: The reference script's import lines alone: the floor of any OCP program that makes the part.
REFERENCE_IMPORTS = "\n".join(line for line in REFERENCE_SCRIPT.splitlines() if line.startswith(("import", "from")))


def _timed(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def _heaviest_imports(count: int, folder: Path) -> list[tuple[float, str]]:
    """The ``count`` top-level imports of ``torus-cad build`` with the largest cumulative time (s)."""
    done = subprocess.run([sys.executable, "-X", "importtime", "-m", "torus_cad", "build", "--out", str(folder), "-q"],
                          capture_output=True, text=True, check=True)
    rows = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = line.split("|")
        if cumulative.strip().isdigit() and not name.startswith("   "):  # top level: one leading space
            rows.append((int(cumulative) / 1e6, name.strip()))
    return sorted(rows, reverse=True)[:count]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    build_s, reference_s, floor_s = [], [], []
    with tempfile.TemporaryDirectory(prefix="bench_cold_start_") as scratch:
        folder = Path(scratch)
        for _ in range(args.runs):
            build_s.append(_timed([sys.executable, "-m", "torus_cad", "build", "--out", str(folder / "build"), "-q"]))
            reference_s.append(_timed([sys.executable, "-c", REFERENCE_SCRIPT, scratch]))
            floor_s.append(_timed([sys.executable, "-c", REFERENCE_IMPORTS]))
        imports = _heaviest_imports(8, folder / "imports")
    build, reference, floor = statistics.median(build_s), statistics.median(reference_s), statistics.median(floor_s)
    print(f"torus-cad build (default, STEP + STL + sections table + JSON), median of {args.runs}: {build:.2f} s "
          f"(runs {', '.join(f'{value:.2f}' for value in build_s)})")
    print(f"reference OCP script (STEP + STL), median of {args.runs}: {reference:.2f} s "
          f"(runs {', '.join(f'{value:.2f}' for value in reference_s)})")
    print(f"ratio build / reference: {build / reference:.2f} (target <= 0.65; and <= 2.0 s)")
    print(f"floor: the reference script's imports alone, median of {args.runs}: {floor:.2f} s = "
          f"{floor / reference:.2f} x the reference (runs {', '.join(f'{value:.2f}' for value in floor_s)})")
    print("heaviest top-level imports of torus-cad build (cumulative s):")
    for seconds, name in imports:
        print(f"  {seconds:6.2f}  {name}")


if __name__ == "__main__":
    main()
