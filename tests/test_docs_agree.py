"""The documentation agrees with the program: the files a build writes, the command-line reference
(generated from the parser, current in the repository), the getting-started synopsis, and every
install line of an extra pinned by constraints.txt."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
GETTING_STARTED = ROOT / "docs" / "getting-started.md"
CLI_PAGE = ROOT / "docs" / "reference" / "cli.md"


def _help(*command: str) -> str:
    result = subprocess.run(
        [sys.executable, "-m", "torus_cad", *command, "--help"],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
        env={"PYTHONPATH": str(ROOT), "COLUMNS": "200", "PATH": "/usr/bin:/bin"},
    )
    return " ".join(result.stdout.split())


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    from torus_cad.cli import build_parser

    parser = build_parser()
    return next(
        action for action in parser._actions if isinstance(action, argparse._SubParsersAction)
    ).choices


def test_readme_and_build_help_name_every_file_a_build_writes(tmp_path):
    from torus_cad.cli import main

    out = tmp_path / "out"
    assert (
        main(
            [
                "build",
                "--set",
                "resolution.sections=16",
                "--set",
                "resolution.points=48",
                "--out",
                str(out),
                "-q",
            ]
        )
        == 0
    )
    written = sorted(path.name.removeprefix("torus_propeller") for path in out.iterdir())
    # what the docs below describe
    assert written == [".json", ".step", ".stl", "_sections.csv", "_sections.png"]
    help_text = _help("build")
    readme = " ".join(README.read_text().split())
    getting_started = " ".join(GETTING_STARTED.read_text().split())
    for suffix in written:
        assert f"<name>{suffix}" in help_text, suffix
        assert f"`{suffix}`" in readme or f"torus_propeller{suffix}" in readme, suffix
        assert f"`{suffix}`" in getting_started or f"torus_propeller{suffix}" in getting_started, (
            suffix
        )
    for text in (help_text, readme, getting_started):  # the files only some options write
        assert "3mf" in text.lower() and "--format" in text and "--preview" in text


def test_the_two_commands_read_the_same_in_the_readme_and_getting_started_and_say_what_ci_runs():
    def block(path: Path) -> str:
        text = path.read_text()
        start = text.index("# 1. install")
        return text[start : text.index("```", start)]

    assert block(README) == block(GETTING_STARTED)
    ci = (ROOT / ".ci" / "run").read_text()
    assert '-m "not long"' in ci
    assert (
        "tests but the long tier" in block(README)
        and "whole test suite" not in GETTING_STARTED.read_text()
    )


def test_the_getting_started_synopsis_lists_every_command_and_every_build_option():
    text = GETTING_STARTED.read_text()
    synopsis = text[text.index("## Command line") :]
    synopsis = synopsis[: synopsis.index("```", synopsis.index("```text") + 7)]
    commands = _subcommands()
    for name in commands:
        assert f"torus-cad {name}" in synopsis, name
    for action in commands["build"]._actions:
        if action.option_strings and "--help" not in action.option_strings:
            assert any(option in synopsis for option in action.option_strings), (
                action.option_strings
            )


def test_the_cli_reference_page_is_current_and_not_a_placeholder():
    from torus_cad.cli.reference import replace_reference

    page = CLI_PAGE.read_text()
    assert replace_reference(page) == page, (
        "docs/reference/cli.md is stale: run python3 scripts/reference_pages.py"
    )
    for name in _subcommands():
        assert f"## `torus-cad {name}`" in page, name
    # schema options and build's alike
    assert "--cells-per-chord" in page and "--require-printable" in page


#: Where install lines are: the README, the documentation, and the program's own messages and help.
INSTALL_SOURCES = [
    README,
    *sorted((ROOT / "docs").rglob("*.md")),
    *sorted((ROOT / "torus_cad").rglob("*.py")),
    *sorted((ROOT / "scripts").rglob("*.py")),
    *sorted((ROOT / "tests").rglob("*.py")),
]
PIP_INSTALL = re.compile(r"pip3? install\b[^`\n]*")


def test_every_install_line_pins_versions_with_constraints_txt():
    found = []
    for path in INSTALL_SOURCES:
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for match in PIP_INSTALL.finditer(line):
                if "PIP_INSTALL" in line or "pip install``" in line:
                    # this test's own pattern; a docstring naming the command, not an install line
                    continue
                found.append(f"{path.relative_to(ROOT)}:{number}: {match.group(0)}")
    # a regex's too
    unpinned = [line for line in found if not re.search(r"-c constraints\\?\.txt", line)]
    assert len(found) > 10 and not unpinned, "\n".join(unpinned)


@pytest.mark.parametrize(
    "extra", ["mesh", "cfd", "simulate", "optimize", "sweep", "studio", "docs"]
)
def test_the_hint_of_every_extra_is_an_install_line_with_the_constraints(extra):
    from torus_cad.runtime.extras import install_line, missing_extra_message

    assert install_line(extra) == f"pip install -c constraints.txt -e '.[{extra}]'"
    assert install_line(extra) in missing_extra_message("torus-cad x", extra, "module")


#: A measured mesh size in the docs: "231,405 tetrahedra", "55,056 cells".
MESH_FIGURE = re.compile(r"\d{1,3}(?:,\d{3})+\**\s+(?:linear\s+)?(?:tetrahedra|cells)\b")
#: How a paragraph says where its figure comes from: the command or script that measures it, or that
#: it is an example of its time. Limits ("over 3,000,000 tetrahedra is refused") are not
#: measurements.
SOURCE = re.compile(
    r"torus-cad |scripts/|pytest|python3? |example of its time|limit|refused", re.IGNORECASE
)


def test_every_measured_mesh_size_in_the_docs_names_its_command_or_is_an_example_of_its_time():
    pages = [
        README,
        *sorted(path for path in (ROOT / "docs").rglob("*.md") if "spec" not in path.parts),
    ]
    unsourced = []
    for page in pages:
        if page == CLI_PAGE:
            continue
        for paragraph in re.split(r"\n\s*\n", page.read_text(encoding="utf-8")):
            if MESH_FIGURE.search(paragraph) and not SOURCE.search(paragraph):
                unsourced.append(
                    f"{page.relative_to(ROOT)}: {MESH_FIGURE.search(paragraph).group(0)}"
                )
    assert not unsourced, unsourced


ARCHITECTURE = ROOT / "docs" / "explanation" / "architecture.md"


def test_the_architecture_page_names_every_module_and_every_path_it_names_exists():
    page = ARCHITECTURE.read_text(encoding="utf-8")
    rows = {
        match[1]: match[0]
        for match in re.finditer(r"^\| `(torus_cad/[^`]*/)`.*$", page, re.MULTILINE)
    }
    unnamed = []
    for module in sorted((ROOT / "torus_cad").rglob("*.py")):
        relative = module.relative_to(ROOT).as_posix()
        if module.name == "__init__.py" and module.parent != ROOT / "torus_cad":
            continue  # a package: its row
        package = next(
            (
                folder
                for folder in sorted(rows, key=len, reverse=True)
                if relative.startswith(folder)
            ),
            None,
        )
        named = relative in page or (package is not None and f"`{module.stem}`" in rows[package])
        if not named and f"`{module.name}`" not in page and f"{module.name}`" not in page:
            unnamed.append(relative)
    assert not unnamed, unnamed
    named_paths = set(
        re.findall(r"`((?:torus_cad|scripts|tests|docs|studies|examples)/[^`\s<>]*)`", page)
    )
    missing = sorted(path for path in named_paths if not (ROOT / path.rstrip("/")).exists())
    assert not missing, missing
