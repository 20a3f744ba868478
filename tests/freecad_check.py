"""FreeCAD's own verdict on STEP files: what a CAD user sees with "Check geometry" and its BOP
check.

Runs ``freecadcmd`` (Debian's FreeCAD) on a script that reads each file with FreeCAD's STEP import
(``Part.Shape.read``) and calls ``Shape.check(True)``, which raises with the list of faults that
BOPAlgo_ArgumentAnalyzer finds (curve on surface included). One process for all the files.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

FREECADCMD = shutil.which("freecadcmd")

#: The script freecadcmd runs: paths from a JSON file beside it, one JSON verdict per file to
#: another.
_SCRIPT = """
import json, Part
folder = "{folder}"
verdicts = {{}}
for path in json.load(open(folder + "/paths.json")):
    shape = Part.Shape()
    shape.read(path)
    try:
        shape.check(True)
        faults = ""
    except Exception as error:
        faults = str(error)
    verdicts[path] = {{"solids": len(shape.Solids), "valid": shape.isValid(), "faults": faults}}
json.dump(verdicts, open(folder + "/verdicts.json", "w"))
"""


def freecad_verdicts(paths: Sequence[Path], folder: Path) -> dict[str, dict[str, object]]:
    """By path: FreeCAD's solid count, ``isValid()`` and the text of ``check(True)``'s faults (""
    for none)."""
    assert FREECADCMD is not None, "freecadcmd is not installed (.ci/run installs Debian's freecad)"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "paths.json").write_text(json.dumps([str(path) for path in paths]))
    script = folder / "check.py"
    script.write_text(_SCRIPT.format(folder=folder))
    subprocess.run([FREECADCMD, str(script)], check=True, capture_output=True, timeout=300)
    return dict(json.loads((folder / "verdicts.json").read_text()))


#: The script that lists, for one file, the pairs of faces that meet tangentially along a shared
#: edge (normals within TANGENT_DEG there) and that FreeCAD's check with BOP finds interfering when
#: checked as a pair: the largest angle between their normals along their shared edges (deg), and
#: the pieces of their section that are not their shared edges (length, largest distance from those
#: edges; mm).
_TANGENT_PAIRS_SCRIPT = """
import itertools, json, math, Part
folder = "{folder}"
shape = Part.Shape()
shape.read(json.load(open(folder + "/path.json")))
faces = shape.Faces
by_edge = {{}}
for index, face in enumerate(faces):
    for edge in face.Edges:
        by_edge.setdefault(edge.hashCode(), set()).add(index)
pairs = sorted(
    {{pair for shared in by_edge.values() for pair in itertools.combinations(sorted(shared), 2)}}
)

def normal_angle(first, second, shared, fractions):
    angle = 0.0
    for edge in shared:
        for t in fractions:
            start, end = edge.FirstParameter, edge.LastParameter
            point = edge.valueAt(start + t * (end - start))
            pair = (faces[first], faces[second])
            normals = [f.normalAt(*f.Surface.parameter(point)) for f in pair]
            angle = max(angle, math.degrees(normals[0].getAngle(normals[1])))
    return angle

found = []
for first, second in pairs:
    shared = [e for e in faces[first].Edges if any(e.isSame(g) for g in faces[second].Edges)]
    if normal_angle(first, second, shared, (0.5,)) > {tangent_deg}:
        continue
    try:
        Part.makeCompound([faces[first], faces[second]]).check(True)
        continue
    except Exception as error:
        if "SelfIntersect" not in str(error):
            continue
    off = []
    for piece in faces[first].section(faces[second]).Edges:
        distance = max(
            min(e.distToShape(Part.Vertex(p))[0] for e in shared) for p in piece.discretize(10)
        )
        if distance > 1e-9:
            off.append({{"length_mm": piece.Length, "distance_mm": distance}})
    angle = normal_angle(first, second, shared, (0.1, 0.3, 0.5, 0.7, 0.9))
    found.append({{"faces": [first, second], "normal_angle_deg": angle, "off_edges": off}})
json.dump(found, open(folder + "/pairs.json", "w"))
"""

#: Two faces whose normals part by at most this along their shared edges meet tangentially (deg).
TANGENT_DEG = 1.0


def freecad_tangent_interferences(path: Path, folder: Path) -> list[dict[str, object]]:
    """The pairs of faces of ``path`` that meet tangentially along a shared edge and that FreeCAD's
    check with BOP finds interfering as a pair, each with its faces' indices, the largest angle
    between their normals along the shared edges (deg) and the pieces of their section off those
    edges (mm)."""
    assert FREECADCMD is not None, "freecadcmd is not installed (.ci/run installs Debian's freecad)"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "path.json").write_text(json.dumps(str(path)))
    script = folder / "pairs.py"
    script.write_text(_TANGENT_PAIRS_SCRIPT.format(folder=folder, tangent_deg=TANGENT_DEG))
    subprocess.run([FREECADCMD, str(script)], check=True, capture_output=True, timeout=600)
    return list(json.loads((folder / "pairs.json").read_text()))
