"""Every file a design names is untrusted input: ``airfoil.file`` is read like a configuration file.

Through the command line, each hostile kind of file named by ``airfoil.file`` is refused with exit
2 and one line naming the file, never its content: a device that reads forever, a named pipe with
no writer, a folder, a symlink to a private file, a file over the size limit, and a coordinate
file with more points than the checks may take. Sweeps store the refusal without the content.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from torus_cad.cli import main
from torus_cad.geometry.section.airfoil_file import read_airfoil_file, write_selig_file
from torus_cad.runtime.input_files import read_untrusted_bytes
from torus_cad.tolerances import AIRFOIL_FILE_MAX_BYTES, AIRFOIL_FILE_MAX_POINTS

AIRFOILS = Path(__file__).resolve().parent.parent / "examples" / "airfoils"

#: Lines of a private file the tests create; none may appear in any message, table or page.
SECRET_LINES = ("root:x:0:0:root:/root:/bin/bash", "alice:$6$SECRETHASHxyz:19000:0:99999:7:::")


def _private_file(folder: Path) -> Path:
    path = folder / "shadow"
    path.write_text("\n".join(SECRET_LINES) + "\n")
    return path


def _design(folder: Path, airfoil_file: str) -> Path:
    design = folder / "design.toml"
    design.write_text(
        f'[airfoil]\nfile = "{airfoil_file}"\n[resolution]\nsections = 16\npoints = 48\n'
    )
    return design


def _assert_refused(code: int, stderr: str, out: Path, words: list[str]) -> str:
    assert code == 2, stderr
    line = stderr.strip()
    assert line.splitlines() == [line] and line.startswith("torus-cad: error: airfoil.file: "), (
        stderr
    )
    assert "Traceback" not in line and "Warning" not in line
    for word in words:
        assert word in line, f"{word!r} not in {line!r}"
    for secret in SECRET_LINES:
        assert secret[-12:] not in line
    assert not out.exists() or not any(out.iterdir())
    return line


def _build(capsys: pytest.CaptureFixture[str], design: Path, out: Path) -> tuple[int, str]:
    code = main(["build", str(design), "--out", str(out), "-q"])
    return code, capsys.readouterr().err


def _build_in_new_process(design: Path, out: Path) -> tuple[int, str]:
    """In a process of its own with a timeout: a reader that blocks or reads forever fails the test,
    not the suite."""
    result = subprocess.run(
        [sys.executable, "-m", "torus_cad", "build", str(design), "--out", str(out), "-q"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    return result.returncode, result.stderr


def test_dev_zero_as_airfoil_file_is_refused_without_reading(tmp_path):
    _assert_refused(
        *_build_in_new_process(_design(tmp_path, "/dev/zero"), tmp_path / "out"),
        tmp_path / "out",
        ["/dev/zero", "not a regular file", "character device"],
    )


def test_a_named_pipe_as_airfoil_file_is_refused_without_waiting(tmp_path):
    os.mkfifo(tmp_path / "pipe.dat")
    _assert_refused(
        *_build_in_new_process(_design(tmp_path, "pipe.dat"), tmp_path / "out"),
        tmp_path / "out",
        ["pipe.dat", "named pipe"],
    )


def test_a_folder_as_airfoil_file_is_refused(tmp_path, capsys):
    (tmp_path / "folder.dat").mkdir()
    _assert_refused(
        *_build(capsys, _design(tmp_path, "folder.dat"), tmp_path / "out"),
        tmp_path / "out",
        ["folder.dat", "a folder"],
    )


@pytest.mark.parametrize("name", ["link.dat", "../private/shadow"])
def test_a_private_file_named_by_a_symlink_or_a_relative_path_is_never_quoted(
    tmp_path, capsys, name
):
    private = tmp_path / "private"
    private.mkdir()
    secret = _private_file(private)
    project = tmp_path / "project"
    project.mkdir()
    (project / "link.dat").symlink_to(secret)
    line = _assert_refused(
        *_build(capsys, _design(project, name), tmp_path / "out"),
        tmp_path / "out",
        [Path(name).name, "line 2", "expected two numbers"],
    )
    assert "/bin/bash" not in line and "SECRETHASH" not in line


def test_a_file_over_the_size_limit_is_refused(tmp_path, capsys):
    big = tmp_path / "big.dat"
    big.write_bytes(b"big foil\n" + b"0.5 0.0\n" * (AIRFOIL_FILE_MAX_BYTES // 8 + 1))
    _assert_refused(
        *_build(capsys, _design(tmp_path, "big.dat"), tmp_path / "out"),
        tmp_path / "out",
        ["big.dat", "over the limit", f"{AIRFOIL_FILE_MAX_BYTES:,}"],
    )


def test_a_file_that_grows_past_the_limit_while_read_is_cut_off(tmp_path, monkeypatch):
    """The read is capped: a size reported small (as /proc files report 0) does not let a long file
    through."""
    path = tmp_path / "grows.dat"
    path.write_bytes(b"x" * 4096)
    with pytest.raises(ValueError, match="over the limit of 1,000 bytes"):
        real_fstat = os.fstat

        def small_fstat(descriptor: int) -> os.stat_result:
            status = real_fstat(descriptor)
            return os.stat_result((status.st_mode, *tuple(status)[1:6], 10, *tuple(status)[7:]))

        monkeypatch.setattr(os, "fstat", small_fstat)
        read_untrusted_bytes(path, "airfoil file", 1000)


def test_a_huge_coordinate_file_under_the_size_limit_is_refused_by_the_point_budget(
    tmp_path, capsys
):
    """94,000 points (1.3 MB, under the size limit) took 8.5 minutes in an all-pairs crossing
    test."""
    u = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, 47_000)))
    loop = np.concatenate(
        [
            np.stack([u, 0.06 * np.sin(np.pi * u)], axis=1)[::-1],
            np.stack([u, -0.04 * np.sin(np.pi * u)], axis=1)[1:],
        ]
    )
    path = write_selig_file(tmp_path / "huge.dat", "huge", loop, digits=5)
    assert path.stat().st_size < AIRFOIL_FILE_MAX_BYTES
    line = _assert_refused(
        *_build(capsys, _design(tmp_path, "huge.dat"), tmp_path / "out"),
        tmp_path / "out",
        ["huge.dat", f"more than {AIRFOIL_FILE_MAX_POINTS:,} points", "limit"],
    )
    # the name line, then the points up to the limit
    assert f"line {AIRFOIL_FILE_MAX_POINTS + 2}:" in line


def test_a_dense_file_within_the_point_limit_is_read(tmp_path):
    """The crossing tests compare only nearby segments: a file at the point limit is read, and still
    checked."""
    u = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, AIRFOIL_FILE_MAX_POINTS // 2)))
    upper, lower = (
        np.stack([u, 0.06 * np.sin(np.pi * u)], axis=1),
        np.stack([u, -0.04 * np.sin(np.pi * u)], axis=1),
    )
    loop = np.concatenate([upper[::-1], lower[1:]])
    section = read_airfoil_file(write_selig_file(tmp_path / "dense.dat", "dense", loop, digits=12))
    assert len(section.loop) == len(loop) == AIRFOIL_FILE_MAX_POINTS - 1
    lower[len(u) // 2, 1] = 0.2  # one point of the lower surface pushed through the upper one
    with pytest.raises(ValueError, match="the surfaces cross"):
        read_airfoil_file(
            write_selig_file(
                tmp_path / "crossed.dat",
                "crossed",
                np.concatenate([upper[::-1], lower[1:]]),
                digits=12,
            )
        )


@pytest.mark.parametrize("value", ["1e308", "-1e300", "inf", "nan"])
def test_an_unusable_coordinate_names_the_line_without_numpy_warnings(tmp_path, capsys, value):
    text = (AIRFOILS / "naca2412.dat").read_text().splitlines()
    text[5] = f"{value} 0.01"
    (tmp_path / "bad.dat").write_text("\n".join(text) + "\n")
    line = _assert_refused(
        *_build(capsys, _design(tmp_path, "bad.dat"), tmp_path / "out"),
        tmp_path / "out",
        ["bad.dat", "line 6:"],
    )
    assert "finite" in line or "out of range" in line


def test_a_utf8_byte_order_mark_in_an_airfoil_file_is_accepted(tmp_path):
    plain = read_airfoil_file(AIRFOILS / "clarky.dat")
    (tmp_path / "bom.dat").write_bytes(b"\xef\xbb\xbf" + (AIRFOILS / "clarky.dat").read_bytes())
    assert np.array_equal(read_airfoil_file(tmp_path / "bom.dat").loop, plain.loop)


def test_a_sweep_stores_the_refusal_of_a_private_file_without_its_content(tmp_path, capsys):
    secret = _private_file(tmp_path)
    (tmp_path / "ok.dat").write_bytes((AIRFOILS / "clarky.dat").read_bytes())
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        "[base.resolution]\nsections = 16\npoints = "
        f'32\n[vary]\n"airfoil.file" = ["ok.dat", "{secret}"]\n'
    )
    out = tmp_path / "out"
    code = main(["sweep", str(sweep), "--out", str(out), "--workers", "1", "--no-stl", "-q"])
    captured = capsys.readouterr()
    assert code in (0, 2), captured.err
    stored = [
        path.read_bytes().decode("utf-8", "replace") for path in out.rglob("*") if path.is_file()
    ]
    texts = [captured.out, captured.err, *stored]
    assert not any(secret_line[-12:] in text for text in texts for secret_line in SECRET_LINES)
    assert "shadow" in " ".join(texts)  # the refusal names the file


# -- designs the TOML reader cannot take: named, exit 2
# ----------------------------------------------

DEEP = "[" * 500 + "]" * 500
HUGE = "9" * 5001


@pytest.mark.parametrize(
    ("text", "words"),
    [
        (f"[hub]\nradius = {DEEP}\n", ["line 2: hub.radius is nested more than", "levels deep"]),
        (
            "[centerline]\np2 = " + "{a = " * 500 + "1" + "}" * 500 + "\n",
            ["line 2: centerline.p2 is nested"],
        ),
        (f"blades = {HUGE}\n", ["line 1: blades holds a number of 5001 digits"]),
        (
            f'name = "x"\n[hub]\nlength = 20.0\nradius = {HUGE}.5\n',
            ["line 4: hub.radius holds a number of 5001 digits"],
        ),
        # strings skipped
        (
            f'name = "{HUGE}"\nblades = 3\n[hub]\nradius = {DEEP}\n',
            ["line 4: hub.radius is nested"],
        ),
    ],
)
def test_a_config_nested_too_deep_or_with_a_huge_number_names_the_key(
    tmp_path, capsys, text, words
):
    design = tmp_path / "deep.toml"
    design.write_text(text)
    code = main(["build", str(design), "--out", str(tmp_path / "out"), "-q"])
    line = capsys.readouterr().err.strip()
    assert code == 2 and line.splitlines() == [line] and "deep.toml" in line, line
    for word in words:
        assert word in line, line


@pytest.mark.parametrize(
    ("value", "words"),
    [
        (DEEP, ["--set: hub.radius is nested more than"]),
        (HUGE, ["--set: hub.radius holds a number of 5001 digits"]),
    ],
)
def test_a_set_value_nested_too_deep_or_huge_names_the_key(tmp_path, capsys, value, words):
    code = main(["build", "--set", f"hub.radius={value}", "--out", str(tmp_path / "out"), "-q"])
    line = capsys.readouterr().err.strip()
    assert code == 2 and line.splitlines() == [line], line
    for word in words:
        assert word in line, line


def test_verify_of_a_report_nested_too_deep_is_an_incomplete_set(tmp_path, capsys):
    (tmp_path / "part.step").write_text("x")
    (tmp_path / "part.json").write_text('{"files": ' + "[" * 100_000 + "]" * 100_000 + "}")
    assert main(["verify", str(tmp_path)]) == 1
    assert (
        capsys.readouterr().err.strip()
        == "torus-cad: verify: part: part.json is not a readable JSON report"
    )


def test_a_home_relative_airfoil_file_is_read_from_the_home_folder(tmp_path, monkeypatch):
    """``~/x.dat`` was kept unexpanded and then not found; it is the user's home, as in a shell."""
    from torus_cad.parameters import PropellerParameters

    home = tmp_path / "home"
    home.mkdir()
    (home / "clarky.dat").write_bytes((AIRFOILS / "clarky.dat").read_bytes())
    monkeypatch.setenv("HOME", str(home))
    params = PropellerParameters.from_toml(_design(tmp_path, "~/clarky.dat"))
    assert params.airfoil.file == str(home / "clarky.dat")
