"""The geometry layer imports no CAD kernel: it must run with numpy / scipy / geomdl only."""

import ast
import subprocess
import sys
from pathlib import Path

import torus_cad.geometry

GEOMETRY_DIR = Path(torus_cad.geometry.__file__).parent
KERNEL_PACKAGES = {"OCP", "cadquery", "OCC", "build123d"}


def test_geometry_sources_import_no_kernel():
    offenders = []
    for source in GEOMETRY_DIR.glob("*.py"):
        for node in ast.walk(ast.parse(source.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            offenders += [f"{source.name}: {name}" for name in names if name.split(".")[0] in KERNEL_PACKAGES]
    assert offenders == []


def test_importing_geometry_loads_no_kernel_module():
    modules = [f"torus_cad.geometry.{path.stem}" for path in GEOMETRY_DIR.glob("*.py") if path.stem != "__init__"]
    code = ("import sys\n" + "".join(f"import {name}\n" for name in modules)
            + "loaded = sorted(m for m in sys.modules if m.split('.')[0] in {'OCP', 'cadquery'})\n"
            + "print(','.join(loaded))\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == ""
