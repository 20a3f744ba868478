"""The install is the same everywhere: every dependency of every extra is pinned in constraints.txt,
and README command 1 and .ci/run install through it."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parent.parent


def _normalised(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "constraints.txt").read_text().splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, _, version = line.partition("==")
            assert version, f"constraints.txt: {line!r} is not pinned with =="
            pins[_normalised(name)] = version
    return pins


def _requirements() -> list[Requirement]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    names = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        names += extra
    return [Requirement(text) for text in names]


def test_every_dependency_is_pinned_within_its_range():
    pins = _pins()
    for requirement in _requirements():
        name = _normalised(requirement.name)
        assert name in pins, f"{requirement.name} (pyproject.toml) is not pinned in constraints.txt"
        assert requirement.specifier.contains(pins[name]), (
            f"constraints.txt pins {requirement.name}=={pins[name]}"
            f" outside pyproject's {requirement.specifier}"
        )


def test_readme_command_and_ci_install_through_the_constraints():
    assert "pip install -c constraints.txt -e ." in (ROOT / "README.md").read_text()
    assert re.search(
        r"pip install .*-c constraints\.txt -e \"\.\[test,docs\]\"",
        (ROOT / ".ci" / "run").read_text(),
    )
