"""The progress display (torus_cad.runtime.progress): build stages and the batch bar, drawn only on
a terminal."""

from __future__ import annotations

import io
import re
import sys

import pytest
from terminal import ANSI as _ANSI
from terminal import terminal_text_until

from torus_cad.build_stages import Stage
from torus_cad.runtime.progress import BatchProgress, StageProgress


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _text(stream: io.StringIO) -> str:
    """What a terminal shows, without colour and cursor codes."""
    return _ANSI.sub("", stream.getvalue())


def test_stage_lines_with_elapsed_time_on_a_terminal():
    stream = _Terminal()
    progress = StageProgress.for_terminal(stream=stream)
    progress(Stage.KERNEL_IMPORT)
    progress(Stage.FUSE)
    progress("my_stage")
    progress.finish()
    lines = _text(stream).splitlines()
    assert len(lines) == 4
    assert (
        "CAD kernel" in lines[0]
        and "fusing" in lines[1]
        and "my stage" in lines[2]
        and "done" in lines[3]
    )
    assert all(re.match(r"torus-cad: \[ +\d+\.\d s\] ", line) for line in lines)


def test_stages_are_silent_when_quiet_or_not_a_terminal():
    terminal = _Terminal()
    progress = StageProgress.for_terminal(quiet=True, stream=terminal)
    progress("fuse")
    progress.finish()
    assert terminal.getvalue() == ""
    pipe = io.StringIO()  # isatty() is False: a pipe, a file, CI
    progress = StageProgress.for_terminal(stream=pipe)
    progress("fuse")
    progress.finish()
    assert pipe.getvalue() == ""
    assert progress.stages == ["fuse"]


def test_batch_bar_counts_outcomes_on_a_terminal_only():
    quiet, terminal = io.StringIO(), _Terminal()
    for stream in (quiet, terminal):
        with BatchProgress(4, already_done=1, stream=stream) as bar:
            for outcome in ("valid", "refused", "failed"):
                bar.update(outcome)
            bar.message("a line above the bar")
        assert bar.built == 3 and bar.rate_per_minute() > 0
    assert quiet.getvalue() == ""
    shown = _text(terminal)
    assert "a line above the bar" in shown
    last = shown.rstrip().splitlines()[-1]
    assert (
        "4/4" in last
        and "valid 1" in last
        and "refused 1" in last
        and "failed 1" in last
        and "/min" in last
    )


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")
def test_build_shows_a_line_before_the_kernel_is_imported(tmp_path):
    """On a terminal, `torus-cad build` says what it does before the seconds of importing the schema
    and cadquery.

    Python's -X importtime reports each module on stderr as its import ends; the first progress
    line must come before any line of cadquery, OCP, pydantic or scipy.
    """
    text = terminal_text_until(
        ["-X", "importtime", "-m", "torus_cad", "build", "--out", str(tmp_path), "--no-stl"],
        b"CAD kernel",
    )
    assert "CAD kernel" in text
    before = text[: text.index("CAD kernel")]
    assert not any(module in before for module in ("cadquery", "OCP", "pydantic", "scipy")), before[
        -500:
    ]
