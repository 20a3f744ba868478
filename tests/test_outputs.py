"""Output sets: a build's files appear together or not at all, and ``torus-cad verify`` tells a
complete set.

Issue 17, cases 1, 2 and 6: same-name builds clobbered each other's temp files and published
the STEP of one design with the JSON of another; a full disk or a kill between the renames left a
new STEP beside an old STL and JSON; a full disk was reported as an OpenCascade failure.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from torus_cad.errors import IncompleteOutputError, OutputError
from torus_cad.outputs.output_set import (
    FILES_KEY,
    OutputSet,
    check_writable_folder,
    set_names,
    verify_set,
)
from torus_cad.runtime.files import owner_tag

#: Low resolution and a coarse STL keep each build short; the transaction does not depend on them.
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


def cli(*args: str, timeout: float = 600, **kwargs) -> subprocess.CompletedProcess:
    """Run ``python -m torus_cad ARGS`` in a new process."""
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
        **kwargs,
    )


def start_cli(*args: str, **kwargs) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "torus_cad", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def hidden_entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def step_blade_count(path: Path) -> int:
    """Blades in a STEP file read back by OpenCascade: two B-spline side faces (lower and upper
    surface, a sharp trailing edge) per blade."""
    from torus_cad.kernel.step_readback import read_step

    side_faces = sum(face.geomType() == "BSPLINE" for face in read_step(path).Faces())
    assert side_faces % 2 == 0
    return side_faces // 2


def assert_consistent_set(folder: Path, name: str = "torus_propeller") -> int:
    """The set verifies and its STEP (read back) has the blades its report says; return that
    count."""
    verified = verify_set(folder, name)
    report = json.loads(verified.report.read_text())
    assert step_blade_count(folder / f"{name}.step") == report["parameters"]["blades"]
    return report["parameters"]["blades"]


def _text_writer(text: str):
    return lambda path: Path(path).write_text(text)


# -- the transaction, without a kernel -------------------------------------------------------------


def test_published_set_lists_every_file_with_its_hash(tmp_path):
    with OutputSet(tmp_path, "part") as output:
        output.write("step", _text_writer("solid"))
        output.write("stl", _text_writer("mesh"))
        paths = output.publish({"name": "part"})
    assert list(paths) == ["step", "stl", "json"]
    report = json.loads(paths["json"].read_text())
    assert set(report[FILES_KEY]) == {"step", "stl"}
    assert report[FILES_KEY]["stl"]["bytes"] == 4 and len(report[FILES_KEY]["stl"]["sha256"]) == 64
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.json", "part.step", "part.stl"]
    assert verify_set(tmp_path, "part").files == (
        tmp_path / "part.step",
        tmp_path / "part.stl",
        tmp_path / "part.json",
    )


def test_verify_names_a_file_of_another_build(tmp_path):
    for text in ("first", "second"):
        with OutputSet(tmp_path / text, "part") as output:
            output.write("step", _text_writer(f"{text} solid"))
            output.write("stl", _text_writer(f"{text} mesh"))
            output.publish({})
    shutil.copy(tmp_path / "second" / "part.stl", tmp_path / "first" / "part.stl")  # a mixed set
    with pytest.raises(IncompleteOutputError, match=r"mixed set: part\.stl"):
        verify_set(tmp_path / "first", "part")
    result = cli("verify", str(tmp_path / "first"))
    assert result.returncode == 1
    assert (
        result.stderr.strip().splitlines() == [result.stderr.strip()]
        and "part.stl" in result.stderr
    )
    assert cli("verify", str(tmp_path / "second"), "part").returncode == 0


def test_verify_reports_a_missing_report_or_file(tmp_path):
    (tmp_path / "part.step").write_text("orphan")
    with pytest.raises(IncompleteOutputError, match=r"part\.json is missing beside part\.step"):
        verify_set(tmp_path, "part")
    assert set_names(tmp_path) == ["part"]
    with OutputSet(tmp_path, "part") as output:
        output.write("step", _text_writer("solid"))
        output.write("stl", _text_writer("mesh"))
        output.publish({})
    (tmp_path / "part.stl").unlink()
    with pytest.raises(IncompleteOutputError, match=r"part\.stl is missing"):
        verify_set(tmp_path, "part")
    assert cli("verify", str(tmp_path / "nowhere")).returncode == 2


def test_a_new_set_removes_the_old_sets_files_it_does_not_have(tmp_path):
    with OutputSet(tmp_path, "part") as output:
        output.write("step", _text_writer("old solid"))
        output.write("stl", _text_writer("old mesh"))
        output.publish({})
    with OutputSet(tmp_path, "part") as output:  # like --no-stl
        output.write("step", _text_writer("new solid"))
        output.publish({})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["part.json", "part.step"]
    verify_set(tmp_path, "part")


def test_a_failed_write_keeps_the_previous_set_and_leaves_nothing_staged(tmp_path):
    with OutputSet(tmp_path, "part") as output:
        output.write("step", _text_writer("old solid"))
        output.publish({"version": 1})

    def fails(path: Path) -> None:
        path.write_text("half")
        raise OSError(28, "No space left on device")

    with (
        pytest.raises(OutputError, match=r"no space left on device writing .*part\.step'"),
        OutputSet(tmp_path, "part") as output,
    ):
        output.write("step", fails)
    assert (tmp_path / "part.step").read_text() == "old solid"
    verify_set(tmp_path, "part")
    assert hidden_entries(tmp_path) == []


def test_stale_staging_of_a_dead_process_is_removed_and_a_live_ones_kept(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    dead_tag = owner_tag().replace(f"-{os.getpid()}-", f"-{dead.pid}-")
    (tmp_path / f".part.staging-{dead_tag}0badc0de").mkdir()
    (tmp_path / f".part.step.tmp-{dead_tag}x1y2").write_text("half a file")
    (tmp_path / f".part.staging-{owner_tag()}0000beef").mkdir()  # this process: alive
    (tmp_path / ".part.staging-otherhost-1-0000cafe").mkdir()  # another host sharing the folder
    with OutputSet(tmp_path, "part") as output:
        from torus_cad.runtime.files import atomic_path

        with atomic_path(output.stage("step")) as temp:
            temp.write_text("solid")
        # atomic_path cleans its own folder
        assert (tmp_path / f".part.step.tmp-{dead_tag}x1y2").exists()
        with atomic_path(tmp_path / "part.step") as temp:
            temp.write_text("solid")
        output.publish({})
    assert hidden_entries(tmp_path) == sorted(
        [f".part.staging-{owner_tag()}0000beef", ".part.staging-otherhost-1-0000cafe"]
    )


def test_an_unwritable_output_folder_is_refused_before_building(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    with pytest.raises(OutputError, match="is not a folder"):
        check_writable_folder(blocker / "out")
    check_writable_folder(tmp_path / "new" / "deeper")  # made when the set is published
    assert not (tmp_path / "new").exists()


# -- real builds
# --------------------------------------------------------------------------------------


def test_same_name_builds_in_one_folder_all_succeed_and_publish_whole_sets(tmp_path):
    """Case 1: ``for b in 2 3 4 5; do torus-cad build --out D --set blades=$b & done``."""
    processes = [
        start_cli("build", "--out", str(tmp_path), "-q", "--set", f"blades={b}", *FAST)
        for b in (2, 3, 4, 5)
    ]
    results = [(process.wait(600), process.stderr.read()) for process in processes]
    assert [code for code, _ in results] == [0, 0, 0, 0], results
    assert assert_consistent_set(tmp_path) in (2, 3, 4, 5)
    assert hidden_entries(tmp_path) == []


_KILL_DURING_PUBLISH = textwrap.dedent("""
    import os, signal, sys
    from torus_cad.cli import main
    renames = []
    real_replace = os.replace
    def replace(source, target):
        real_replace(source, target)
        renames.append(target)
        if str(target).endswith(".step") and ".staging-" not in str(target):  # the first rename of the publish
            os.kill(os.getpid(), getattr(signal, sys.argv[1]))
    os.replace = replace
    sys.exit(main(sys.argv[2:]))
""")  # noqa: E501 (code or text written out verbatim)


@pytest.mark.parametrize("signal_name", ["SIGKILL", "SIGTERM", "SIGINT"])
def test_a_signal_between_the_renames_never_leaves_a_silent_mix(tmp_path, signal_name):
    """Case 2: a kill between the renames over an older 4-blade build."""
    out = tmp_path / "out"
    assert cli("build", "--out", str(out), "-q", "--set", "blades=4", *FAST).returncode == 0
    script = tmp_path / "killer.py"
    script.write_text(_KILL_DURING_PUBLISH)
    result = subprocess.run(
        [
            sys.executable,
            str(script),
            signal_name,
            "build",
            "--out",
            str(out),
            "-q",
            "--set",
            "blades=3",
            *FAST,
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=600,
    )
    if signal_name == "SIGKILL":  # nothing can wait for SIGKILL: the set is visibly incomplete
        assert result.returncode == -signal.SIGKILL
        verified = cli("verify", str(out))
        assert verified.returncode == 1 and "torus_propeller.json is missing" in verified.stderr
        # repaired
        assert cli("build", "--out", str(out), "-q", "--set", "blades=3", *FAST).returncode == 0
    else:  # the signal waits until the new set is complete
        assert result.returncode == {"SIGTERM": 143, "SIGINT": 130}[signal_name], result.stderr
        assert result.stderr.strip().splitlines() == [result.stderr.strip()]
        assert f"interrupted by {signal_name}" in result.stderr
    assert assert_consistent_set(out) == 3
    assert hidden_entries(out) == []


@pytest.mark.parametrize("delay_s", [0.5, 2.0, 4.0, 6.0])
@pytest.mark.parametrize("signal_name", ["SIGKILL", "SIGTERM", "SIGINT"])
def test_a_signal_at_any_moment_leaves_the_old_set_the_new_set_or_a_reported_incomplete_one(
    tmp_path, signal_name, delay_s
):
    """Case 2: SIGKILL, SIGTERM or SIGINT at some moment of a build over an older 4-blade build."""
    import time

    assert cli("build", "--out", str(tmp_path), "-q", "--set", "blades=4", *FAST).returncode == 0
    process = start_cli("build", "--out", str(tmp_path), "-q", "--set", "blades=3", *FAST)
    time.sleep(delay_s)
    process.send_signal(getattr(signal, signal_name))
    code = process.wait(600)
    assert code in (0, -signal.SIGKILL, 130, 143), process.stderr.read()
    verified = cli("verify", str(tmp_path))
    if verified.returncode == 0:
        assert assert_consistent_set(tmp_path) in (3, 4)
    # only SIGKILL can leave this: inside the publishing renames an incomplete set, anywhere its
    # staging
    else:
        # folder (no process left to remove it; the next build there does): verify says which
        assert signal_name == "SIGKILL"
        assert "incomplete set" in verified.stderr or "left by a stopped process" in verified.stderr
    if code != -signal.SIGKILL:
        assert hidden_entries(tmp_path) == []


DESIGNS = [
    ["--set", "blades=2"],
    ["--set", "blades=3", "--set", "hub.radius=11"],
    ["--set", "blades=4", "--set", "phase_deg=10"],
    ["--set", "blades=5", "--set", "hub.length=24"],
]


def test_stress_eight_same_name_builds_of_four_designs_twice(tmp_path):
    """8 concurrent builds of one name (4 designs, twice each) into one folder, 2 rounds: every
    build succeeds, a reader verifying the folder all along never sees an incomplete or mixed set,
    and each round's set has the STEP its report describes."""
    import threading

    assert cli("build", "--out", str(tmp_path), "-q", *FAST).returncode == 0
    failures: list[str] = []
    verified = 0
    done = threading.Event()

    def reader() -> None:
        nonlocal verified
        while not done.is_set():
            try:
                verify_set(tmp_path, "torus_propeller")
                verified += 1
            except IncompleteOutputError as error:
                failures.append(str(error))
            done.wait(0.02)

    thread = threading.Thread(target=reader)
    thread.start()
    try:
        for round_index in range(2):
            processes = [
                start_cli("build", "--out", str(tmp_path), "-q", *FAST, *DESIGNS[i % 4])
                for i in range(8)
            ]
            results = [(process.wait(900), process.stderr.read()) for process in processes]
            assert [code for code, _ in results] == [0] * 8, (round_index, results)
            assert assert_consistent_set(tmp_path) in (2, 3, 4, 5)
            assert hidden_entries(tmp_path) == []
    finally:
        done.set()
        thread.join()
    assert failures == [] and verified > 0


# -- the disk and the folder fail -----------------------------------------------------------------


@pytest.fixture
def small_disk(tmpfs):
    """A 3200 KB disk: room for an old set without STL (1.1 MB) and a new 4-blade STEP (1.4 MB; the
    blade-hub edges rebuilt from exact points, torus_cad.kernel.edge_curves), not for its 2.8 MB STL
    too."""
    return tmpfs(3200)


def test_a_full_disk_keeps_the_old_set_and_says_no_space_left(small_disk):
    """Cases 2 and 6: the disk fills up after the STEP; the old set stays, the message names the
    cause."""
    old = cli("build", "--out", str(small_disk), "-q", "--no-stl", *FAST)
    assert old.returncode == 0, old.stderr
    result = cli(
        "build",
        "--out",
        str(small_disk),
        "-q",
        "--set",
        "blades=4",
        "--set",
        "export.stl_linear_deflection=0.01",
        "--set",
        "export.stl_angular_deflection=0.2",
        "--set",
        "resolution.sections=16",
        "--set",
        "resolution.points=48",
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert (
        "no space left on device writing" in result.stderr
        and "torus_propeller.stl" in result.stderr
    )
    assert "OpenCascade" not in result.stderr and ".staging-" not in result.stderr
    assert assert_consistent_set(small_disk) == 3
    assert hidden_entries(small_disk) == []


def test_a_file_size_limit_is_named_and_keeps_the_old_set(tmp_path):
    """The same with RLIMIT_FSIZE (no root needed): the writer fails, the cause is named."""
    import resource

    assert cli("build", "--out", str(tmp_path), "-q", "--no-stl", *FAST).returncode == 0

    def limit_file_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))

    result = cli(
        "build",
        "--out",
        str(tmp_path),
        "-q",
        "--set",
        "blades=4",
        *FAST,
        preexec_fn=limit_file_size,
    )
    assert result.returncode == 1
    assert "file size limit" in result.stderr and "torus_propeller.st" in result.stderr
    assert assert_consistent_set(tmp_path) == 3
    assert hidden_entries(tmp_path) == []


def _without_dac_override() -> list[str] | None:
    """A command prefix that runs a process without root's permission override, or None."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return None
    return [setpriv, "--inh-caps=-all", "--bounding-set=-dac_override,-dac_read_search", "--"]


def test_permission_denied_on_the_output_folder_is_found_before_building(tmp_path):
    """Case 6: the error names the folder (not a hidden temp file) and comes before the build: here
    the design would be refused by the geometry checks (exit 2) if it were built first."""
    prefix = _without_dac_override()
    if prefix is None:
        pytest.skip("running as root without setpriv: permissions are not enforced")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        result = subprocess.run(
            [
                *prefix,
                sys.executable,
                "-m",
                "torus_cad",
                "build",
                "--out",
                str(locked),
                "--set",
                "transforms.scale_x=[0, 0, 0, 0, 40.0]",
            ],
            check=False,
            capture_output=True,
            text=True,
            timeout=600,
        )
    finally:
        locked.chmod(0o755)
    assert result.returncode == 1, result.stderr
    assert (
        result.stderr.strip()
        == f"torus-cad: build failed: cannot write to output folder {str(locked)!r}: "
        f"permission denied"
    )
    assert list(locked.iterdir()) == []


def test_verify_walks_sub_folders_and_names_every_problem_of_a_tampered_copy(tmp_path):
    """A folder with sets in sub-folders (as the mesh how-to makes): verify checks them all, and on
    a tampered copy it reports each problem, one line each, not only the first."""
    for folder, name in (("top", "part"), ("top/ply", "part"), ("top/ply/deeper", "other")):
        with OutputSet(tmp_path / folder, name) as output:
            output.write("step", _text_writer(f"{folder} solid"))
            output.write("stl", _text_writer(f"{folder} mesh"))
            output.publish({})
    top = tmp_path / "top"
    result = cli("verify", str(top))
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 3 and "ply/deeper/other" in result.stdout
    (top / "part.stl").write_text("changed")
    (top / "ply" / "part.step").unlink()
    (top / "ply" / "part.stl").write_text("changed")
    (top / "ply" / "deeper" / "other.stl").unlink()
    result = cli("verify", str(top), "-q")
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 4, lines
    assert any("mixed set: part.stl" in line and "ply/" not in line for line in lines)
    assert any(
        line.startswith("torus-cad: verify: ply/part: incomplete set: part.step is missing")
        for line in lines
    )
    assert any(
        line.startswith("torus-cad: verify: ply/part: mixed set: part.stl") for line in lines
    )
    assert any(
        line.startswith("torus-cad: verify: ply/deeper/other: incomplete set: other.stl")
        for line in lines
    )
    with pytest.raises(IncompleteOutputError) as raised:
        verify_set(top / "ply", "part")
    assert len(raised.value.problems) == 2
