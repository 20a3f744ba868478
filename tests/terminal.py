"""Run a torus-cad process on a pseudo-terminal and read what it shows (its stderr), for the
progress tests."""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: ANSI colour and cursor sequences, removed from what the terminal showed.
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


def terminal_text_until(arguments: list[str], marker: bytes, timeout_s: float = 120.0) -> str:
    """What ``python ARGUMENTS`` prints on a pseudo-terminal until ``marker`` appears (then it is
    killed), or until ``timeout_s``; without the ANSI sequences. A pseudo-terminal is the only way
    to see the progress lines, which are written only to a terminal."""
    controller, terminal = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, *arguments],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=terminal,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    os.close(terminal)
    shown = b""
    try:
        deadline = time.monotonic() + timeout_s
        while marker not in shown and time.monotonic() < deadline:
            if select.select([controller], [], [], 1.0)[0]:
                try:
                    shown += os.read(controller, 65536)
                except OSError:  # the child closed the terminal
                    break
    finally:
        process.kill()
        process.wait(30)
        os.close(controller)
    return ANSI.sub("", shown.decode(errors="replace"))
