"""A signal in the first milliseconds of a command, while Python itself starts.

Before any of torus_cad's code runs, a SIGINT is the interpreter's (during its ``site`` import it
ends with "Fatal Python error" and exit 1). Started with the signals blocked (``env
--block-signal``), the command handles one that arrived at any moment of its start once its
handlers are in: one line and exit 130 / 143.
"""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import time

import pytest

EXPECTED = {signal.SIGINT: 130, signal.SIGTERM: 143}


@pytest.mark.skipif(shutil.which("env") is None, reason="needs coreutils env")
@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_a_signal_in_the_first_milliseconds_ends_with_one_line_when_started_blocked(signum):
    command = ["env", "--block-signal=INT,TERM,HUP", sys.executable, "-m", "torus_cad", "defaults"]
    handled = 0
    for attempt in range(24):
        process = subprocess.Popen(
            command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        time.sleep(0.0005 * attempt)  # 0 to 11.5 ms after the start
        process.send_signal(signum)
        _, stderr = process.communicate(timeout=120)
        assert "Fatal Python error" not in stderr and "Traceback" not in stderr, stderr
        # it arrived before env had blocked it: the default action, no message
        if process.returncode == -signum:
            continue
        assert process.returncode == EXPECTED[signum], stderr
        name = signal.Signals(signum).name
        assert stderr.strip().splitlines() == [
            f"torus-cad: interrupted by {name}; staged files removed, published "
            "output sets are complete"
        ]
        handled += 1
    assert handled >= 12  # most signals arrive after env blocked them
