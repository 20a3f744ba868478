"""Every example in README.md and the documentation (docs/) runs: ```python blocks as they are, and
every ``torus-cad`` line of the ```sh / ```bash blocks, in a scratch folder with the repository's
examples/ and scripts/.

A block preceded by a ``<!-- not-run: reason -->`` line is skipped (an example that needs a cluster,
say); the README says so next to it. ``pip install``, ``pytest`` and ``bash .ci/run`` (the README's
test command) are not run here: CI runs them itself.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = ROOT / "docs"
#: The pages whose examples run: the README, then the documentation site's pages (the spec is
#: quoted, not run).
PAGES = [README] + sorted(
    path for path in DOCS.rglob("*.md") if "spec" not in path.relative_to(DOCS).parts
)
PARAMETERS_PAGE = DOCS / "reference" / "parameters.md"
FENCE = re.compile(r"^```(\w*)\s*$")
NOT_RUN = "<!-- not-run:"


@dataclass(frozen=True)
class Block:
    language: str
    code: str
    line: int
    skipped: bool
    page: str = "README.md"
    number: int = 1

    @property
    def where(self) -> str:
        """The page and the line the block starts on (for messages)."""
        return f"{self.page}:{self.line}"

    @property
    def key(self) -> str:
        """The page and the block's place among the page's blocks: the test id, which an edit above
        the block on its page does not change (tests/tiers.json names tests by it)."""
        return f"{self.page}#{self.number}"


def page_blocks(page: Path) -> list[Block]:
    """The fenced code blocks of one page, with the line each starts on."""
    blocks, lines, name = [], page.read_text().splitlines(), str(page.relative_to(ROOT))
    index = 0
    while index < len(lines):
        match = FENCE.match(lines[index])
        if match and match.group(1):
            end = next(j for j in range(index + 1, len(lines)) if lines[j].startswith("```"))
            skipped = index > 0 and lines[index - 1].strip().startswith(NOT_RUN)
            blocks.append(
                Block(
                    match.group(1),
                    "\n".join(lines[index + 1 : end]),
                    index + 1,
                    skipped,
                    name,
                    len(blocks) + 1,
                )
            )
            index = end
        index += 1
    return blocks


def readme_blocks() -> list[Block]:
    """The fenced code blocks of the README and the documentation pages, page by page."""
    return [block for page in PAGES for block in page_blocks(page)]


def shell_commands(block: Block) -> list[str]:
    """The torus-cad commands of a shell block (comments dropped; pip and pytest steps left to
    CI)."""
    commands = []
    for raw in block.code.splitlines():
        line = raw.split(" #")[0].strip()
        for part in (piece.strip() for piece in line.split("&&")):
            if (
                part.startswith("torus-cad ")
                or part.startswith("python3 -m torus_cad")
                or part.startswith("python scripts/")
            ):
                commands.append(part)
    return commands


@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    """A scratch folder laid out like the repository for the examples."""
    folder = tmp_path_factory.mktemp("readme")
    # validation/: the APC example's station table
    for name in ("examples", "scripts", "validation"):
        shutil.copytree(ROOT / name, folder / name)
    return folder


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


def _run_shell(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    python = sys.executable
    command = re.sub(r"^torus-cad ", f"{python} -m torus_cad ", command)
    command = re.sub(r"^python3? ", f"{python} ", command)
    return subprocess.run(
        command,
        shell=True,
        cwd=cwd,
        env=_environment(),
        capture_output=True,
        text=True,
        timeout=600,
    )


BLOCKS = readme_blocks()
SHELL = [block for block in BLOCKS if block.language in ("sh", "bash") and shell_commands(block)]
PYTHON = [block for block in BLOCKS if block.language == "python"]


def test_readme_has_examples():
    assert len(SHELL) >= 3 and len(PYTHON) >= 3


@pytest.mark.parametrize("block", SHELL, ids=[block.key for block in SHELL])
def test_shell_example_runs(block: Block, workdir: Path):
    if block.skipped:
        pytest.skip("marked not-run in the README")
    for command in shell_commands(block):
        result = _run_shell(command, workdir)
        assert result.returncode == 0, (
            f"{block.where}: {command!r} exited {result.returncode}: {result.stderr[-2000:]}"
        )


def test_python_examples_run_in_order(workdir: Path, monkeypatch):
    """The Python blocks, page by page in order, in one namespace (later ones use earlier names)."""
    if not (workdir / "my_prop.toml").exists():
        _run_shell("torus-cad defaults > my_prop.toml", workdir)
    monkeypatch.chdir(workdir)
    monkeypatch.syspath_prepend(str(ROOT))
    namespace: dict[str, object] = {"__name__": "__main__"}
    for block in PYTHON:
        if block.skipped:
            continue
        try:
            exec(compile(block.code, block.where, "exec"), namespace)
        except Exception as error:
            pytest.fail(f"python block at {block.where} raised {type(error).__name__}: {error}")


def test_parameter_table_is_current():
    from torus_cad.parameters.parameter_reference import replace_table

    text = PARAMETERS_PAGE.read_text()
    assert replace_table(text) == text, (
        "docs/reference/parameters.md is stale: run python scripts/reference_pages.py"
    )


def test_readme_links_stay_inside_the_repository():
    for target in re.findall(r"\]\(([^)]+)\)", README.read_text()):
        if not target.startswith(("http://", "https://", "#")):
            assert not target.startswith(".."), target
            assert (ROOT / target.split("#")[0]).exists(), (
                f"README links to a missing file: {target}"
            )
