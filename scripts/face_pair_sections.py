#!/usr/bin/env python3
"""Where a self-interference check waits: a STEP file's faces intersected pair by pair, timed.

A check with self-interference (FreeCAD's ``check(True)``, BOPAlgo_ArgumentAnalyzer) intersects
every pair of faces whose boxes overlap; one pair its OpenCascade cannot walk holds the whole check.
This intersects the pairs one at a time, in FreeCAD (``freecadcmd``: ``Part.Face.section``,
FreeCAD's own OpenCascade) or in this package's OpenCascade (``BRepAlgoAPI_Section``), and prints a
line as each pair starts and ends, so the pair a check stalls on is the last line without an end.

    python scripts/face_pair_sections.py FILE.step --freecad --limit 1800   # every pair, FreeCAD
    python scripts/face_pair_sections.py FILE.step --pairs 0,2 100,102       # these, OpenCascade

Faces are numbered as both list them (the order of TopExp's map of the faces, from 0). Each line:
``pair I J (AREA_I mm², AREA_J mm²): SECONDS s, EDGES edges``. Writes nothing but a scratch folder
for FreeCAD's script.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: The script freecadcmd runs (FreeCAD's Python): every pair whose boxes overlap, or the given ones,
#: one line each to a log beside it, flushed as it goes.
_FREECAD_SCRIPT = """
import time, Part
shape = Part.Shape()
shape.read({path!r})
faces = shape.Faces
pairs = {pairs!r} or [
    (i, j) for i in range(len(faces)) for j in range(i + 1, len(faces))
    if faces[i].BoundBox.intersect(faces[j].BoundBox)
]
with open({log!r}, "w") as log:
    for i, j in pairs:
        log.write("pair %d %d (%.2f mm², %.2f mm²): " % (i, j, faces[i].Area, faces[j].Area))
        log.flush()
        start = time.time()
        edges = len(faces[i].section(faces[j]).Edges)
        log.write("%.2f s, %d edges\\n" % (time.time() - start, edges))
        log.flush()
    log.write("done\\n")
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("step", type=Path)
    parser.add_argument("--freecad", action="store_true", help="in FreeCAD (freecadcmd)")
    parser.add_argument("--pairs", nargs="+", default=[], metavar="I,J", help="only these pairs")
    parser.add_argument("--limit", type=float, default=600.0, help="seconds in all (FreeCAD)")
    args = parser.parse_args(argv)
    pairs = [tuple(int(index) for index in text.split(",")) for text in args.pairs]
    if args.freecad:
        return _in_freecad(args.step.resolve(), pairs, args.limit)
    return _in_opencascade(args.step, pairs)


def _in_freecad(path: Path, pairs: list[tuple[int, ...]], limit_s: float) -> int:
    freecadcmd = shutil.which("freecadcmd")
    if freecadcmd is None:
        print("freecadcmd is not installed (Debian's freecad)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory() as scratch:
        log, script = Path(scratch) / "pairs.log", Path(scratch) / "pairs.py"
        script.write_text(_FREECAD_SCRIPT.format(path=str(path), pairs=pairs, log=str(log)))
        try:
            subprocess.run([freecadcmd, str(script)], capture_output=True, timeout=limit_s)
            stopped = ""
        except subprocess.TimeoutExpired:
            stopped = f"stopped at the limit, {limit_s:g} s"
        print(log.read_text() if log.exists() else "", end="")
        if stopped:
            print(f"\n{stopped}")
    return 0


def _in_opencascade(path: Path, pairs: list[tuple[int, ...]]) -> int:
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS
    from OCP.TopTools import TopTools_IndexedMapOfShape

    from torus_cad.kernel.step_readback import read_step_shape

    faces = TopTools_IndexedMapOfShape()
    TopExp.MapShapes_s(read_step_shape(path), TopAbs_FACE, faces)

    def area(index: int) -> float:
        properties = GProp_GProps()
        BRepGProp.SurfaceProperties_s(faces.FindKey(index + 1), properties)
        return float(properties.Mass())

    for i, j in pairs:
        print(f"pair {i} {j} ({area(i):.2f} mm², {area(j):.2f} mm²): ", end="", flush=True)
        start = time.perf_counter()
        section = BRepAlgoAPI_Section(
            TopoDS.Face_s(faces.FindKey(i + 1)), TopoDS.Face_s(faces.FindKey(j + 1))
        )
        edges = TopTools_IndexedMapOfShape()
        TopExp.MapShapes_s(section.Shape(), TopAbs_EDGE, edges)
        print(f"{time.perf_counter() - start:.2f} s, {edges.Extent()} edges")
    return 0


if __name__ == "__main__":
    sys.exit(main())
