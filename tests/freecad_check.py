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
