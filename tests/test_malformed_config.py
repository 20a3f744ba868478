"""Malformed configuration files: each is refused with exit 2, one line naming the problem, no file
written.

Every key of a design file is optional (a missing key takes its default, as ``torus-cad
defaults`` documents), so "missing" here means a key without a value, a list missing an
element, or a table header without its table's keys being valid.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from torus_cad.cli import main

# (case id, file content, words that must appear in the message)
TEXT_CASES = [
    ("blades_string", 'blades = "three"\n', ["blades"]),
    ("blades_float", "blades = 3.5\n", ["blades"]),
    ("radius_string", '[hub]\nradius = "ten"\n', ["hub.radius"]),
    ("radius_bool", "[hub]\nradius = true\n", ["hub.radius"]),
    ("hub_not_table", "hub = 10\n", ["hub"]),
    ("point_wrong_length", "[centerline]\np2 = [25.0, 3.0]\n", ["centerline.p2"]),
    ("point_not_list", "[centerline]\np3 = 75.0\n", ["centerline.p3"]),
    ("quartic_short", "[transforms]\nscale_x = [1.0, 2.0]\n", ["transforms.scale_x"]),
    ("point_string_item", '[centerline]\np2 = [25.0, "x", 22.0]\n', ["centerline.p2[1]"]),
    ("missing_value", "[hub]\nradius =\n", ["not valid TOML"]),
    ("unknown_top_key", "bladez = 3\n", ["bladez", "blades"]),
    ("unknown_nested_key", "[hub]\nradiuss = 3\n", ["hub.radiuss", "hub.radius"]),
    ("unknown_table", "[propeller]\nblades = 3\n", ["propeller"]),
    ("nan_radius", "[hub]\nradius = nan\n", ["hub.radius", "finite"]),
    ("inf_length", "[hub]\nlength = inf\n", ["hub.length", "finite"]),
    ("minus_inf_phase", "phase_deg = -inf\n", ["phase_deg", "finite"]),
    ("nan_in_list", "[centerline]\np2 = [25.0, nan, 22.0]\n", ["centerline.p2[1]", "finite"]),
    (
        "nan_quartic",
        "[transforms]\nangle_of_attack = [0.0, 0.0, 0.0, 0.0, nan]\n",
        ["angle_of_attack", "finite"],
    ),
    ("negative_radius", "[hub]\nradius = -5.0\n", ["hub.radius"]),
    ("negative_length", "[hub]\nlength = -20.0\n", ["hub.length"]),
    ("zero_radius", "[hub]\nradius = 0.0\n", ["hub.radius"]),
    ("negative_thickness", "[airfoil]\nthickness = -0.1\n", ["airfoil.thickness"]),
    ("negative_sections", "[resolution]\nsections = -3\n", ["resolution.sections"]),
    (
        "negative_scale",
        "[transforms]\nscale_x = [0.0, 0.0, 0.0, 0.0, -6.0]\n",
        ["transforms.scale_x", "positive"],
    ),
    (
        "scale_crossing_zero",
        "[transforms]\nscale_y = [0.0, 0.0, 0.0, -4.0, 2.0]\n",
        ["transforms.scale_y"],
    ),
    (
        "negative_deflection",
        "[export]\nstl_linear_deflection = -0.1\n",
        ["export.stl_linear_deflection"],
    ),
    ("zero_blades", "blades = 0\n", ["blades"]),
    ("negative_blades", "blades = -2\n", ["blades"]),
    ("too_many_blades", "blades = 1000\n", ["blades"]),
    ("bad_frame", '[centerline]\nframe = "bishop"\n', ["centerline.frame"]),
    ("bad_name", 'name = "../../etc/passwd"\n', ["name"]),
    ("empty_file", "", ["empty"]),
    ("whitespace_file", "  \n\n\t\n", ["empty"]),
    ("not_toml", "this is not a design file\n", ["not valid TOML"]),
    ("json_file", '{"blades": 3}\n', ["not valid TOML"]),
    ("duplicate_key", "blades = 3\nblades = 4\n", ["not valid TOML"]),
]

BINARY_CASES = [
    ("nul_bytes", b"\x00" * 64),
    ("png_header", b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256))),
    ("random_bytes", bytes((i * 197 + 13) % 256 for i in range(4096))),
    ("latin1_text", "blades = 3 # caf\xe9\n".encode("latin-1")),
]


def _run_cli(capsys, config: Path, out_dir: Path) -> tuple[int, str, str]:
    code = main(["build", str(config), "--out", str(out_dir)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _assert_refused(code: int, out: str, err: str, out_dir: Path, words: list[str]) -> None:
    assert code == 2, f"exit code {code}, stderr {err!r}"
    lines = err.strip().splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {err!r}"
    assert lines[0].startswith("torus-cad: error: ")
    assert "Traceback" not in err and "Traceback" not in out
    for word in words:
        assert word in lines[0], f"{word!r} not named in {lines[0]!r}"
    assert not out_dir.exists() or not any(out_dir.iterdir()), "a refused design wrote files"


@pytest.mark.parametrize("case, content, words", TEXT_CASES, ids=[case[0] for case in TEXT_CASES])
def test_malformed_text_config(tmp_path, capsys, case, content, words):
    config = tmp_path / f"{case}.toml"
    config.write_text(content)
    out_dir = tmp_path / "out"
    _assert_refused(*_run_cli(capsys, config, out_dir), out_dir, words)


@pytest.mark.parametrize("case, content", BINARY_CASES, ids=[case[0] for case in BINARY_CASES])
def test_binary_config(tmp_path, capsys, case, content):
    config = tmp_path / f"{case}.toml"
    config.write_bytes(content)
    out_dir = tmp_path / "out"
    code, out, err = _run_cli(capsys, config, out_dir)
    # NUL bytes decode as UTF-8 but are not TOML; the others are not UTF-8 at all.
    _assert_refused(code, out, err, out_dir, [str(config.name)])


def test_missing_file(tmp_path, capsys):
    out_dir = tmp_path / "out"
    _assert_refused(
        *_run_cli(capsys, tmp_path / "nowhere.toml", out_dir), out_dir, ["nowhere.toml"]
    )


def test_directory_as_config(tmp_path, capsys):
    folder = tmp_path / "a_folder.toml"
    folder.mkdir()
    out_dir = tmp_path / "out"
    _assert_refused(*_run_cli(capsys, folder, out_dir), out_dir, ["a_folder.toml"])


@pytest.mark.parametrize(
    "override, words",
    [
        ("hub.radius=nan", ["hub.radius"]),
        ("blades=0", ["blades"]),
        ("hub.radiuss=3", ["hub.radiuss"]),
        ("hub.radius", ["key=value"]),
        ("centerline.p2=[1,2]", ["centerline.p2"]),
    ],
    ids=["nan", "zero_blades", "unknown", "no_value", "short_list"],
)
def test_malformed_override(tmp_path, capsys, override, words):
    out_dir = tmp_path / "out"
    code = main(["build", "--set", override, "--out", str(out_dir)])
    captured = capsys.readouterr()
    _assert_refused(code, captured.out, captured.err, out_dir, words)


@pytest.mark.parametrize(
    "content",
    [b"\xff\xfe\x00garbage\x00", b"[hub]\nradius = nan\n", b"blades = 0\n"],
    ids=["binary", "nan", "zero_blades"],
)
def test_command_line_prints_no_traceback(tmp_path, content):
    """The real entry point, in a new process: exit 2, one line, no traceback, nothing written."""
    config = tmp_path / "design.toml"
    config.write_bytes(content)
    out_dir = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "torus_cad", "build", str(config), "--out", str(out_dir)],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr + result.stdout
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_subnormal_quartic_coefficient_is_not_a_traceback(tmp_path, capsys):
    out_dir = tmp_path / "out"
    code = main(
        [
            "build",
            "--set",
            "transforms.scale_x=[1e-310, 1.0, 0.0, 0.0, 5.0]",
            "--out",
            str(out_dir),
            "--no-stl",
        ]
    )
    assert code in (0, 2)


# -- issue 17: files that are not design files, sizes, encodings, numbers too big for anything
# ------


def _run_new_process(*args: str, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def _assert_one_line_refusal(
    result: subprocess.CompletedProcess, out_dir: Path, words: list[str]
) -> None:
    assert result.returncode == 2, result.stderr
    line = result.stderr.strip()
    assert (
        line.splitlines() == [line]
        and line.startswith("torus-cad: error: ")
        and "Traceback" not in line
    )
    for word in words:
        assert word in line, f"{word!r} not in {line!r}"
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_dev_zero_is_refused_at_once_without_reading_it(tmp_path):
    """Case 3: ``torus-cad build /dev/zero`` read 2.2 GB."""
    start = time.monotonic()
    result = _run_new_process("build", "/dev/zero", "--out", str(tmp_path / "out"))
    _assert_one_line_refusal(
        result, tmp_path / "out", ["/dev/zero", "character device", "not a regular file"]
    )
    assert time.monotonic() - start < 60


def test_a_named_pipe_is_refused_without_waiting_for_a_writer(tmp_path):
    """Case 3: a named pipe blocked forever."""
    pipe = tmp_path / "design.toml"
    os.mkfifo(pipe)
    result = _run_new_process("build", str(pipe), "--out", str(tmp_path / "out"), timeout=60)
    _assert_one_line_refusal(result, tmp_path / "out", ["design.toml", "named pipe"])


def test_a_config_over_the_size_limit_is_refused(tmp_path, capsys):
    from torus_cad.tolerances import CONFIG_FILE_MAX_BYTES

    big = tmp_path / "big.toml"
    big.write_text("blades = 3\n" + "# padding\n" * (CONFIG_FILE_MAX_BYTES // 10 + 1))
    out_dir = tmp_path / "out"
    _assert_refused(
        *_run_cli(capsys, big, out_dir),
        out_dir,
        ["big.toml", "over the limit", f"{CONFIG_FILE_MAX_BYTES:,}"],
    )


def test_a_utf8_bom_is_accepted(tmp_path, capsys):
    """Case 4: a file with a UTF-8 byte-order mark (Windows editors write one) was refused as
    invalid TOML."""
    from torus_cad.parameters import PropellerParameters

    config = tmp_path / "windows.toml"
    config.write_bytes("\ufeffblades = 4\n[resolution]\nsections = 16\npoints = 48\n".encode())
    assert PropellerParameters.from_toml(config).blades == 4
    out_dir = tmp_path / "out"
    assert main(["build", str(config), "--out", str(out_dir), "--no-stl", "-q"]) == 0, (
        capsys.readouterr().err
    )
    from torus_cad.outputs.output_set import verify_set

    assert [path.name for path in verify_set(out_dir, "torus_propeller").files][-2:] == [
        "torus_propeller_sections.png",
        "torus_propeller.json",
    ]
    assert (out_dir / "torus_propeller.step").is_file() and not (
        out_dir / "torus_propeller.stl"
    ).exists()


@pytest.mark.parametrize("digits", [401, 5001])
def test_huge_integers_are_bad_input(tmp_path, digits):
    """Case 4: a 401-digit integer gave "internal error (OverflowError)", a 5001-digit one a
    ValueError."""
    number = "1" + "0" * (digits - 1)
    config = tmp_path / "huge.toml"
    config.write_text(f"blades = {number}\n")
    for result in (
        _run_new_process("build", str(config), "--out", str(tmp_path / "out")),
        _run_new_process("build", "--set", f"blades={number}", "--out", str(tmp_path / "out")),
    ):
        _assert_one_line_refusal(result, tmp_path / "out", [])
        # the field where the schema sees the number; the file or --set where the TOML reader cannot
        # read it
        assert "blades" in result.stderr or "huge.toml" in result.stderr, result.stderr


def test_a_name_with_a_newline_is_refused(tmp_path, capsys):
    """Case 4: ``name = "abc\\n"`` passed the name check and wrote ``abc⏎.step``."""
    config = tmp_path / "newline.toml"
    config.write_text('name = "abc\\n"\n')
    out_dir = tmp_path / "out"
    _assert_refused(*_run_cli(capsys, config, out_dir), out_dir, ["name"])
