"""A command whose extra is not installed says so in one line (the extra, the install command with
the repository's constraints), exits 2 and writes nothing: the module is hidden from a real
``torus-cad`` process."""

from __future__ import annotations

import importlib.metadata
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

#: ``python -c`` body: hide the modules named in argv[1] (as an absent package looks:
#: ModuleNotFoundError from the import system), then run torus-cad with the rest of argv.
HIDING_RUNNER = """
import importlib.abc, sys
hidden = set(sys.argv[1].split(","))
class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in hidden:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, Hide())
from torus_cad.cli import main
sys.exit(main(sys.argv[2:]))
"""

#: (hidden modules, command line without --out, the extra the line must name)
CASES = [
    ("manifold3d", ["mesh"], "mesh"),
    ("meshio", ["mesh"], "mesh"),
    ("gmsh", ["cfd"], "cfd"),
    ("gmsh", ["simulate", "--rpm", "5000"], "simulate"),
    ("foamlib", ["simulate", "--rpm", "5000", "--case-only"], "simulate"),
    ("optuna", ["optimize", str(EXAMPLES / "optimize_light.toml")], "optimize"),
    (
        "dask,distributed",
        ["optimize", str(EXAMPLES / "optimize_light.toml"), "--scheduler", "local"],
        "optimize",
    ),
    (
        "dask,distributed",
        ["sweep", str(EXAMPLES / "sweep_example.toml"), "--scheduler", "local"],
        "sweep",
    ),
    ("trame", ["studio", "--port", "0"], "studio"),
    ("trame_vuetify", ["studio", "--port", "0"], "studio"),
]


@pytest.mark.parametrize("hidden, command, extra", CASES, ids=[f"{c[1][0]}-{c[0]}" for c in CASES])
def test_a_missing_extra_is_one_line_with_its_install_command_exit_2_and_nothing_written(
    tmp_path, hidden, command, extra
):
    out = tmp_path / "out"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    # studio writes nothing anyway
    out_option = [] if command[0] == "studio" else ["--out", str(out)]
    result = subprocess.run(
        [sys.executable, "-c", HIDING_RUNNER, hidden, *command, *out_option],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    assert f"needs the {extra} extra" in result.stderr
    assert f"pip install -c constraints.txt -e '.[{extra}]'" in result.stderr
    assert "internal error" not in result.stderr and result.stdout == ""
    assert list(tmp_path.iterdir()) == []  # no OUT, no OUT/trials/, no database


def test_every_module_named_for_an_extra_is_installed_by_that_extra_in_pyproject():
    """The table the messages come from agrees with pyproject.toml's extras (read by tomllib; which
    distribution provides a module, by importlib.metadata)."""
    from torus_cad.runtime.extras import EXTRA_MODULES, OPTIONAL_MODULES, extra_of_module

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"
    ]
    providers = importlib.metadata.packages_distributions()

    def names(extra: str) -> set[str]:
        """The distributions an extra installs, with those of its requirements' own extras
        (dask[distributed])."""
        found = set()
        for requirement in extras[extra]:
            found.update(re.findall(r"[A-Za-z0-9_.-]+", re.split(r"[<>=!~ ]", requirement)[0]))
        return {name.lower().replace("_", "-") for name in found}

    modules = [(extra, module) for extra, listed in EXTRA_MODULES.items() for module in listed]
    modules += [(extra, module) for module, extra in OPTIONAL_MODULES.items()]
    for extra, module in modules:
        distributions = {
            name.lower().replace("_", "-") for name in providers.get(module.split(".")[0], [])
        }
        if not distributions:
            continue  # not installed here (e.g. the docs extra): nothing to compare
        assert distributions & names(extra), (extra, module, distributions)
        assert extra_of_module(module) is not None
