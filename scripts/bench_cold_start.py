"""Benchmark the cold start of ``torus-cad build`` (the default design, a new process each run)
against a bare OCP script that makes the same part and writes STEP + STL, in the same run::

    python scripts/bench_cold_start.py --runs 5
    python scripts/bench_cold_start.py --write-reference /tmp/reference
        # the script and its data alone

The reference script (:data:`REFERENCE_SCRIPT`) imports only the OCP modules it uses and lofts the
default design's own sections: the 25 section B-splines the build lofts (their poles and shared
knots, fitted by the geometry layer to the 25 x 80 points of ``resolution``, read from a JSON file
that this script writes before the runs, untimed) through BRepOffsetAPI_ThruSections, turns the
blade to the design's 3 angles, fuses them with the hub cylinder (radius and length of the design)
in one BRepAlgoAPI_Fuse, writes STEP (AP214) and a binary STL meshed at the design's deflections
(0.05 mm, 0.2 rad). It checks nothing: it is the least any program pays for this OpenCascade part.
Runs alternate (build, script, build, ...) so that a change of the machine's speed touches both; the
medians and their ratio are printed, wall and CPU (user + sys of the process and the children it
waited
for: on a shared machine the CPU ratio is the steadier one), then the floor: the reference script's
own imports alone (:data:`REFERENCE_IMPORTS`), as a share of the whole script; and the heaviest
imports of ``torus-cad build`` (``python -X importtime``, wall) and the CPU seconds of its import
groups
(:data:`IMPORT_GROUPS`).
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REFERENCE_SCRIPT = r"""
import json, math, sys
from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeWire, BRepBuilderAPI_Transform
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepOffsetAPI import BRepOffsetAPI_ThruSections
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
from OCP.Geom import Geom_BSplineCurve
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.StlAPI import StlAPI_Writer
from OCP.TColgp import TColgp_Array1OfPnt
from OCP.TColStd import TColStd_Array1OfInteger, TColStd_Array1OfReal
from OCP.TopTools import TopTools_ListOfShape
from OCP.gp import gp_Ax1, gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf

design = json.load(open(sys.argv[1]))
out = sys.argv[2]
distinct = sorted(set(design["knots"]))
knots, multiplicities = TColStd_Array1OfReal(1, len(distinct)), TColStd_Array1OfInteger(1, len(distinct))
for index, knot in enumerate(distinct, start=1):
    knots.SetValue(index, knot)
    multiplicities.SetValue(index, design["knots"].count(knot))

def section_wire(poles):
    pole_array = TColgp_Array1OfPnt(1, len(poles))
    for index, (x, y, z) in enumerate(poles, start=1):
        pole_array.SetValue(index, gp_Pnt(x, y, z))
    curve = Geom_BSplineCurve(pole_array, knots, multiplicities, design["degree"])
    return BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(curve).Edge()).Wire()

loft = BRepOffsetAPI_ThruSections(True, False)
loft.CheckCompatibility(False)
for poles in design["poles_mm"]:
    loft.AddWire(section_wire(poles))
loft.Build()
blade = loft.Shape()
length = design["hub_length_mm"]
hub = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -length / 2), gp_Dir(0, 0, 1)), design["hub_radius_mm"],
                               length).Shape()
hubs, blades = TopTools_ListOfShape(), TopTools_ListOfShape()
hubs.Append(hub)
for index in range(design["blades"]):
    turn = gp_Trsf()
    turn.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2 * math.pi * index / design["blades"])
    blades.Append(BRepBuilderAPI_Transform(blade, turn, True).Shape())
fuse = BRepAlgoAPI_Fuse()
fuse.SetArguments(hubs)
fuse.SetTools(blades)
fuse.Build()
shape = fuse.Shape()
writer = STEPControl_Writer()
writer.Transfer(shape, STEPControl_AsIs)
writer.Write(out + "/reference.step")
BRepMesh_IncrementalMesh(shape, design["stl_linear_deflection_mm"], False, design["stl_angular_deflection_rad"], True)
stl = StlAPI_Writer()
stl.ASCIIMode = False
stl.Write(shape, out + "/reference.stl")
"""  # noqa: E501 (code or text written out verbatim)


def reference_design() -> dict[str, Any]:
    """What the reference script builds, as JSON data: the default design's section B-splines (the
    fit the build lofts, from the geometry layer), its blade count, hub and STL deflections (mm,
    rad)."""
    from torus_cad.design.prepared_design import prepare_design
    from torus_cad.geometry.section.section_fit import DEGREE

    prepared = prepare_design()
    params, surface, fit = prepared.parameters, prepared.surface, prepared.fit
    return {
        "poles_mm": fit.poles.tolist(),
        "knots": fit.knots.tolist(),
        "degree": DEGREE,
        "sections": int(surface.points.shape[0]),
        "points": int(surface.points.shape[1]),
        "blades": params.blades,
        "hub_radius_mm": params.hub.radius,
        "hub_length_mm": params.hub.length,
        "stl_linear_deflection_mm": params.export.stl_linear_deflection,
        "stl_angular_deflection_rad": params.export.stl_angular_deflection,
    }


def write_reference(folder: Path) -> tuple[Path, Path]:
    """``folder/reference.py`` (:data:`REFERENCE_SCRIPT`) and ``folder/design.json``, its data; run
    it as ``python folder/reference.py folder/design.json OUT``."""
    folder.mkdir(parents=True, exist_ok=True)
    script, data = folder / "reference.py", folder / "design.json"
    script.write_text(REFERENCE_SCRIPT)
    data.write_text(json.dumps(reference_design()))
    return script, data


#: The reference script's import lines alone: the floor of any OCP program that makes the part.
REFERENCE_IMPORTS = "\n".join(
    line for line in REFERENCE_SCRIPT.splitlines() if line.startswith(("import", "from"))
)


def _timed(command: list[str], cpu: list[float] | None = None) -> float:
    """Wall seconds of ``command``; its CPU seconds (user + sys, with the children it waited for)
    appended to
    ``cpu``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if cpu is not None:
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return wall


#: The build's import groups in the order the build loads them, each timed in CPU seconds after the
#: ones before.
IMPORT_GROUPS = (
    "torus_cad.cli.design_input",
    "torus_cad.propeller",
    "torus_cad.outputs.output_set",
    "meshlib.mrmeshpy",
    "matplotlib.figure",
)

_IMPORT_CPU = """
import importlib, json, resource, sys
def cpu():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime
seconds = {}
for name in sys.argv[1:]:
    before = cpu()
    importlib.import_module(name)
    seconds[name] = cpu() - before
print(json.dumps({"seconds": seconds, "cadquery": "cadquery" in sys.modules}))
"""


def import_cpu_seconds() -> tuple[dict[str, float], bool]:
    """CPU seconds (user + sys) of importing each of :data:`IMPORT_GROUPS` in a new process, each
    after the ones before it (what it adds), and whether cadquery got loaded."""
    done = subprocess.run(
        [sys.executable, "-c", _IMPORT_CPU, *IMPORT_GROUPS],
        capture_output=True,
        text=True,
        check=True,
    )
    outcome = json.loads(done.stdout)
    return outcome["seconds"], outcome["cadquery"]


def _heaviest_imports(count: int, folder: Path) -> list[tuple[float, str]]:
    """The ``count`` top-level imports of ``torus-cad build`` with the largest cumulative time
    (s)."""
    done = subprocess.run(
        [
            sys.executable,
            "-X",
            "importtime",
            "-m",
            "torus_cad",
            "build",
            "--out",
            str(folder),
            "-q",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    rows = []
    for line in done.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cumulative, name = line.split("|")
        # top level: one leading space
        if cumulative.strip().isdigit() and not name.startswith("   "):
            rows.append((int(cumulative) / 1e6, name.strip()))
    return sorted(rows, reverse=True)[:count]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument(
        "--write-reference",
        metavar="FOLDER",
        type=Path,
        help=(
            "only write the reference script and its data into FOLDER (to time it with other tools)"
        ),
    )
    args = parser.parse_args()
    if args.write_reference:
        script, data = write_reference(args.write_reference)
        print(f"{sys.executable} {script} {data} OUT_FOLDER")
        return
    build_s, reference_s, floor_s = [], [], []
    build_cpu, reference_cpu = [], []
    with tempfile.TemporaryDirectory(prefix="bench_cold_start_") as scratch:
        folder = Path(scratch)
        script, data = write_reference(folder / "reference")
        for _ in range(args.runs):
            build_s.append(
                _timed(
                    [
                        sys.executable,
                        "-m",
                        "torus_cad",
                        "build",
                        "--out",
                        str(folder / "build"),
                        "-q",
                    ],
                    build_cpu,
                )
            )
            reference_s.append(
                _timed([sys.executable, str(script), str(data), scratch], reference_cpu)
            )
            floor_s.append(_timed([sys.executable, "-c", REFERENCE_IMPORTS]))
        imports = _heaviest_imports(8, folder / "imports")
    build, reference, floor = (
        statistics.median(build_s),
        statistics.median(reference_s),
        statistics.median(floor_s),
    )
    pairs = statistics.median(b / r for b, r in zip(build_s, reference_s))
    print(
        "torus-cad build (default, STEP + STL + sections "
        f"table + JSON), median of {args.runs}: {build:.2f} s "
        f"(runs {', '.join(f'{value:.2f}' for value in build_s)})"
    )
    print(
        "reference OCP script (the default's sections "
        f"lofted, fused, STEP + STL), median of {args.runs}: "
        f"{reference:.2f} s (runs {', '.join(f'{value:.2f}' for value in reference_s)})"
    )
    print(
        f"ratio build / reference: {build / reference:.2f} of "
        f"the medians, {pairs:.2f} the median of the pairs "
        "(target <= 1.0)"
    )
    print(
        "CPU (user + sys, children included), median of "
        f"{args.runs}: build {statistics.median(build_cpu):.2f} s "
        f"(runs {', '.join(f'{value:.2f}' for value in build_cpu)}), "
        f"reference {statistics.median(reference_cpu):.2f} s "
        f"(runs {', '.join(f'{value:.2f}' for value in reference_cpu)}); ratio "
        f"{statistics.median(build_cpu) / statistics.median(reference_cpu):.2f} of the medians, "
        f"{statistics.median(b / r for b, r in zip(build_cpu, reference_cpu)):.2f}"
        " the median of the pairs"
    )
    print(
        f"floor: the reference script's imports alone, median of {args.runs}: {floor:.2f} s = "
        f"{floor / reference:.2f} x the reference (runs "
        f"{', '.join(f'{value:.2f}' for value in floor_s)})"
    )
    print("heaviest top-level imports of torus-cad build (cumulative s):")
    for seconds, name in imports:
        print(f"  {seconds:6.2f}  {name}")
    runs = [import_cpu_seconds() for _ in range(args.runs)]
    print(
        "CPU of the build's imports, each group after the "
        f"ones before (median of {args.runs}; cadquery loaded: "
        f"{runs[0][1]}):"
    )
    for name in IMPORT_GROUPS:
        print(f"  {statistics.median(seconds[name] for seconds, _ in runs):6.2f}  {name}")


if __name__ == "__main__":
    main()
