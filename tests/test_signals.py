"""SIGINT and SIGTERM at any moment of ``torus-cad build``: one line, exit 130 / 143, nothing staged
left.

Issue 17, case 5: Ctrl-C in the first ~1.3 s (while CadQuery is imported) printed "internal error
(ImportError) ... please report" or segfaulted, and SIGTERM printed nothing.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from torus_cad.outputs.output_set import verify_set

FAST = [
    "--set",
    "resolution.sections=16",
    "--set",
    "resolution.points=48",
    "--set",
    "export.stl_linear_deflection=0.2",
    "--set",
    "export.stl_angular_deflection=0.5",
]
EXIT_CODES = {signal.SIGINT: 130, signal.SIGTERM: 143}


def _startup_seconds() -> float:
    """How long this machine takes to start Python up to torus_cad's handlers (measured, worst of
    3).

    Before that, no program can handle a signal: Python itself is still starting.
    """
    times = []
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import torus_cad.runtime.interrupts"], check=True)
        times.append(time.perf_counter() - start)
    return max(times)


@pytest.fixture(scope="module")
def startup_s() -> float:
    return _startup_seconds()


def _block_ending_signals() -> None:
    """In the child before exec: the documented way to start a command that must end cleanly at
    every
    moment (torus_cad.runtime.interrupts): a signal during Python's own start waits for the
    handlers."""
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM, signal.SIGHUP})


def _interrupt_build(out: Path, signum: int, delay_s: float) -> subprocess.CompletedProcess:
    process = subprocess.Popen(
        [sys.executable, "-m", "torus_cad", "build", "--out", str(out), "-q", *FAST],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_block_ending_signals,
    )
    time.sleep(delay_s)
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=600)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def _assert_clean_end(result: subprocess.CompletedProcess, signum: int, out: Path) -> None:
    name = signal.Signals(signum).name
    assert result.returncode != -signal.SIGSEGV, "segfault"
    assert "internal error" not in result.stderr and "Traceback" not in result.stderr, result.stderr
    if result.returncode == 0:  # the build finished before the signal
        verify_set(out, "torus_propeller")
    else:
        assert result.returncode == EXIT_CODES[signum], result.stderr
        expected = (
            f"torus-cad: interrupted by {name}; staged files "
            "removed, published output sets are complete"
        )
        assert result.stderr.strip().splitlines() == [expected]
    staged = [p.name for p in out.iterdir() if p.name.startswith(".")] if out.exists() else []
    assert staged == [], f"staged files left behind: {staged}"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
@pytest.mark.parametrize(
    "after_startup_s", [0.0, 0.03, 0.1, 0.2, 0.35, 0.5, 0.7, 1.0, 1.3, 1.7, 2.5, 4.0]
)
def test_a_signal_at_any_moment_ends_the_build_with_one_line(
    tmp_path, startup_s, signum, after_startup_s
):
    out = tmp_path / "out"
    result = _interrupt_build(out, signum, startup_s + after_startup_s)
    _assert_clean_end(result, signum, out)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_while_cadquery_loads_ends_with_one_line(tmp_path, startup_s, signum):
    """The moment of the issue's "internal error (ImportError)": imports under way (before the
    build)."""
    out = tmp_path / "out"
    result = _interrupt_build(out, signum, startup_s + 0.2)
    _assert_clean_end(result, signum, out)
    assert result.returncode == EXIT_CODES[signum]
    assert not out.exists()


def test_an_ignored_sigint_stays_ignored(tmp_path):
    """``torus-cad build &`` in a script ignores SIGINT (the shell sets SIG_IGN); so does the
    build."""

    def ignore_sigint() -> None:
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    process = subprocess.Popen(
        [sys.executable, "-m", "torus_cad", "build", "--out", str(tmp_path), "-q", *FAST],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=ignore_sigint,
    )
    time.sleep(_startup_seconds() + 0.5)
    process.send_signal(signal.SIGINT)
    assert process.wait(600) == 0, process.stderr.read()
    verify_set(tmp_path, "torus_propeller")
