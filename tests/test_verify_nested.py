"""``torus-cad verify`` on nested folders: an OpenFOAM case is a set of its own (its surface STL no
incomplete set), and a staging folder left by a stopped process is found at any depth."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from torus_cad.cli import main
from torus_cad.runtime.files import host_tag


def _case(folder: Path) -> Path:
    """A case folder as ``simulate --case-only`` writes it, with the surface STL in
    constant/triSurface."""
    for entry in (
        "system/controlDict",
        "system/fvSchemes",
        "system/fvSolution",
        "Allrun",
        "constant/triSurface/propeller_mm.stl",
        "0/U",
    ):
        (folder / entry).parent.mkdir(parents=True, exist_ok=True)
        (folder / entry).write_text("x\n")
    return folder


def test_a_case_folder_verifies_as_an_openfoam_case(tmp_path: Path, capsys) -> None:
    _case(tmp_path / "prop_case")
    assert main(["verify", str(tmp_path)]) == 0
    assert "OpenFOAM case" in capsys.readouterr().out


def test_an_incomplete_case_folder_is_named(tmp_path: Path, capsys) -> None:
    (_case(tmp_path / "prop_case") / "system" / "fvSolution").unlink()
    assert main(["verify", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert (
        "prop_case: incomplete OpenFOAM case: system/fvSolution missing" in err
        and err.count("\n") == 1
    )


def test_staging_debris_is_found_at_any_depth(tmp_path: Path, default_files, capsys) -> None:
    for path in default_files.values():
        shutil.copy(path, tmp_path / path.name)
    assert main(["verify", str(tmp_path)]) == 0
    dead_pid = 2**22 + 12345  # above any pid this machine hands out
    assert not os.path.exists(f"/proc/{dead_pid}")
    debris = (
        tmp_path
        / "trials"
        / "0"
        / "simulate"
        / "coarse"
        / f".x.staging-{host_tag()}-{dead_pid}-abcd"
    )
    debris.mkdir(parents=True)
    capsys.readouterr()
    assert main(["verify", str(tmp_path)]) == 1
    assert "trials/0/simulate/coarse/.x.staging-" in capsys.readouterr().err
