"""`torus-cad mesh` publishes one output set (torus_cad.outputs.output_set): whole or absent after
any signal, checked by `torus-cad verify`, which also catches tampering; write failures name the
file."""

from __future__ import annotations

import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

OLD = ["--sections", "24", "--points", "48", "--format", "stl,obj", "--no-compare"]
NEW = ["--sections", "40", "--points", "120", "--format", "stl,ply,stl_ascii", "--no-compare"]
SET = "torus_propeller_mesh"


def cli(*args: str, timeout: float = 600, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
        **kwargs,
    )


def members(folder: Path) -> set[str]:
    report = json.loads((folder / f"{SET}.json").read_text())
    return {entry["file"] for entry in report["files"].values()}


def test_verify_accepts_a_mesh_set_and_a_new_set_replaces_the_old_one_whole(tmp_path):
    assert cli("mesh", *OLD, "--out", str(tmp_path), "-q").returncode == 0
    verified = cli("verify", str(tmp_path))
    assert verified.returncode == 0, verified.stderr
    assert members(tmp_path) == {f"{SET}.stl", f"{SET}.obj"}
    assert cli("mesh", *NEW, "--out", str(tmp_path), "-q").returncode == 0
    assert cli("verify", str(tmp_path)).returncode == 0
    # the old OBJ is gone with the old set; the ASCII STL is a member, not a set of its own
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted(
        [f"{SET}.json", *members(tmp_path)]
    )
    assert members(tmp_path) == {f"{SET}.stl", f"{SET}.ply", f"{SET}_ascii.stl"}


@pytest.mark.parametrize("tamper", ["truncate", "flip", "remove"])
def test_verify_catches_a_tampered_mesh_set(tmp_path, tamper):
    assert cli("mesh", *OLD, "--out", str(tmp_path), "-q").returncode == 0
    obj = tmp_path / f"{SET}.obj"
    if tamper == "truncate":
        obj.write_bytes(obj.read_bytes()[:-100])
    elif tamper == "flip":
        data = bytearray(obj.read_bytes())
        data[len(data) // 2] ^= 0x01
        obj.write_bytes(bytes(data))
    else:
        obj.unlink()
    verified = cli("verify", str(tmp_path))
    assert verified.returncode == 1
    assert f"{SET}.obj" in verified.stderr and verified.stderr.count("\n") == 1
    assert ("missing" if tamper == "remove" else "size or SHA-256 differs") in verified.stderr


def _startup_s() -> float:
    start = time.perf_counter()
    assert cli("mesh", "--help").returncode == 0
    return time.perf_counter() - start


def test_sigterm_at_random_moments_leaves_the_old_set_or_the_new_one_whole(tmp_path):
    assert cli("mesh", *OLD, "--out", str(tmp_path), "-q").returncode == 0
    old = members(tmp_path)
    start = time.perf_counter()
    assert cli("mesh", *NEW, "--out", str(tmp_path / "timing"), "-q").returncode == 0
    whole_s = time.perf_counter() - start
    startup = _startup_s()
    chooser = random.Random(20261201)
    outcomes = []
    for delay in sorted(chooser.uniform(0.3 * startup, 1.1 * whole_s) for _ in range(6)):
        process = subprocess.Popen(
            [sys.executable, "-m", "torus_cad", "mesh", *NEW, "--out", str(tmp_path), "-q"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(delay)
        process.send_signal(signal.SIGTERM)
        code = process.wait(600)
        error = process.stderr.read()
        assert code in (0, 143), error
        if code == 143:
            assert error.strip().splitlines() == [
                "torus-cad: interrupted by SIGTERM; staged files removed, "
                "published output sets are complete"
            ]
        verified = cli("verify", str(tmp_path))
        assert verified.returncode == 0, (delay, verified.stderr)
        assert members(tmp_path) in (old, {f"{SET}.stl", f"{SET}.ply", f"{SET}_ascii.stl"})
        assert sorted(path.name for path in tmp_path.iterdir() if path.name != "timing") == sorted(
            [f"{SET}.json", *members(tmp_path)]
        )  # no staging folder, no stray file
        outcomes.append(code)
        # the new set is published: put the old one back for the next try
        if members(tmp_path) != old:
            assert cli("mesh", *OLD, "--out", str(tmp_path), "-q").returncode == 0
    assert 143 in outcomes


def test_a_file_size_limit_names_the_mesh_file_and_keeps_the_old_set(tmp_path):
    import resource

    assert cli("mesh", *OLD, "--out", str(tmp_path), "-q").returncode == 0
    old = members(tmp_path)

    def limit_file_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (400_000, 400_000))

    result = cli("mesh", *NEW, "--out", str(tmp_path), "-q", preexec_fn=limit_file_size)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert "file size limit exceeded writing" in result.stderr and f"{SET}." in result.stderr
    assert ".staging-" not in result.stderr
    assert cli("verify", str(tmp_path)).returncode == 0 and members(tmp_path) == old


@pytest.fixture
def small_disk(tmpfs):
    """A 1500 KB disk: room for the old set (about 700 KB), not for the new one."""
    return tmpfs(1500)


def test_a_full_disk_names_the_mesh_file_and_keeps_the_old_set(small_disk):
    assert cli("mesh", *OLD, "--out", str(small_disk), "-q").returncode == 0
    old = members(small_disk)
    result = cli("mesh", *NEW, "--out", str(small_disk), "-q")
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert (
        "no space left on device writing" in result.stderr
        and str(small_disk / SET) in result.stderr
    )
    assert "requested and" not in result.stderr and ".staging-" not in result.stderr
    assert cli("verify", str(small_disk)).returncode == 0 and members(small_disk) == old
    assert not [path for path in small_disk.iterdir() if path.name.startswith(".")]
