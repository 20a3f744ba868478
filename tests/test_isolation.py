"""Kernel calls in a child process (torus_cad.runtime.isolation): a time limit, a crash, and no
child left behind."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import psutil
import pytest

from torus_cad.errors import KernelError
from torus_cad.runtime.isolation import IsolatedCall, IsolatedCrash, IsolatedTimeout, run_isolated


def _crash() -> None:
    os.kill(os.getpid(), signal.SIGSEGV)


def test_a_result_an_exception_a_hang_and_a_crash():
    assert run_isolated(sum, [1, 2, 3], timeout_s=30.0, what="a sum") == 6
    with pytest.raises(KernelError, match="boom"):
        run_isolated(
            lambda: (_ for _ in ()).throw(KernelError("boom")), timeout_s=30.0, what="a raise"
        )
    start = time.monotonic()
    with pytest.raises(IsolatedTimeout, match=r"a sleep did not finish within 0\.5 s"):
        run_isolated(time.sleep, 30.0, timeout_s=0.5, what="a sleep")
    assert time.monotonic() - start < 10.0
    with pytest.raises(IsolatedCrash, match="a segfault crashed"):
        run_isolated(_crash, timeout_s=30.0, what="a segfault")


def test_a_call_runs_beside_the_parent_and_is_killed_when_the_parent_gives_up():
    """The mesh route builds its B-rep comparison in a child while it makes the mesh."""
    start = time.monotonic()
    with IsolatedCall(time.sleep, 1.0, what="a sleep") as call:
        time.sleep(1.0)  # the parent's own work, at the same time
        assert call.result(timeout_s=30.0) is None
    assert time.monotonic() - start < 1.9
    with pytest.raises(RuntimeError, match="the parent failed"):
        with IsolatedCall(time.sleep, 120.0, what="a long sleep") as call:
            assert call.pid is not None
            child = psutil.Process(call.pid)
            raise RuntimeError("the parent failed")
    assert not child.is_running()


def _isolated_sum(values: list[int]) -> int:
    return run_isolated(sum, values, timeout_s=30.0, what="a sum")


def test_it_runs_in_a_pool_worker_which_is_a_daemonic_process():
    """The sweep's and the optimiser's designs are built in pebble's (daemonic) pool processes."""
    from pebble import ProcessPool

    with ProcessPool(max_workers=1) as pool:
        assert pool.schedule(_isolated_sum, ([4, 5],)).result(timeout=60) == 9


def test_a_killed_parent_leaves_no_child_running():
    script = (
        "import time; from torus_cad.runtime.isolation import run_isolated; "
        "print('started', flush=True); run_isolated(time.sleep, "
        "120.0, timeout_s=120.0, what='a sleep')"
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None and parent.stdout.readline().strip() == "started"
        deadline = time.monotonic() + 30.0
        children: list[psutil.Process] = []
        while not children and time.monotonic() < deadline:
            children = psutil.Process(parent.pid).children(recursive=True)
            time.sleep(0.1)
        assert children, "the call's child never started"
        parent.send_signal(signal.SIGKILL)
        parent.wait(timeout=30)
        _, alive = psutil.wait_procs(children, timeout=10.0)
        assert not alive, [process.pid for process in alive]
    finally:
        parent.kill()


def test_a_strict_check_over_its_time_limit_refuses_the_build(light_params, monkeypatch):
    import torus_cad.kernel.strict as strict
    from torus_cad.propeller import build_propeller

    monkeypatch.setattr(strict, "STRICT_CHECK_TIME_LIMIT_S", 0.01)
    with pytest.raises(
        KernelError, match=r"BRepAlgoAPI_Check .* did not finish within 0.01 s \(the limit\)"
    ):
        build_propeller(light_params)
