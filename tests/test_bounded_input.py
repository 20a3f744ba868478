"""Bounded input (issue 34): every file a person hands the program goes through the design file's
shape limits, every numeric option has a range (in its --help, checked as it is parsed), and error
messages cut long values short.

Each refusal is exit 2, one line on stderr naming the key or option, and no output folder.
"""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest
from cli_exit import exit_code

from torus_cad.cli import main
from torus_cad.cli.parser import build_parser
from torus_cad.errors import ParameterError, bounded_message, cut, shown
from torus_cad.tolerances import (
    MESSAGE_MAX_CHARS,
    MESSAGE_VALUE_MAX_CHARS,
    MESSAGE_WORD_MAX_CHARS,
    TOML_NESTING_LIMIT,
)

DEEP = "[" * 500 + "1" + "]" * 500
DEEP_TABLE = "{a = " * 500 + "1" + "}" * 500
HUGE = "9" * 5001
DOTTED = ".".join(["a"] * 3000)

STUDY_HEAD = '[study]\nname = "s"\ntrials = 3\n'
VARY = '[vary]\n"airfoil.thickness" = [0.2, 0.6]\n'
OBJECTIVE = '[[objective]]\nmetric = "mass_g"\ndirection = "minimize"\n'
SWEEP_VARY = "[vary]\nblades = [2, 3]\n"

#: (file kind, attack, file text, words of the one line)
FILE_ATTACKS = [
    (
        "study",
        "digits",
        '[study]\nname = "s"\ntrials = ' + HUGE + "\n" + VARY + OBJECTIVE,
        ["line 3: study.trials holds a number of 5001 digits"],
    ),
    (
        "study",
        "nesting in [vary]",
        STUDY_HEAD + '[vary]\n"airfoil.thickness" = ' + DEEP + "\n" + OBJECTIVE,
        ['line 5: vary."airfoil.thickness" is nested more than'],
    ),
    (
        "study",
        "nesting in [constraints]",
        STUDY_HEAD + VARY + OBJECTIVE + "[constraints]\n"
        '"printability.thinnest_wall_mm" = ' + DEEP_TABLE + "\n",
        ['constraints."printability.thinnest_wall_mm" is nested'],
    ),
    (
        "study",
        "nesting in trials",
        '[study]\nname = "s"\ntrials = ' + DEEP + "\n" + VARY + OBJECTIVE,
        ["line 3: study.trials is nested more than"],
    ),
    (
        "study",
        "dotted key",
        STUDY_HEAD + "[vary]\n" + DOTTED + " = [1, 2]\n" + OBJECTIVE,
        ["vary.a.a.a", "is nested"],
    ),
    (
        "study",
        "table header",
        STUDY_HEAD + VARY + OBJECTIVE + "[constraints." + DOTTED + "]\nmin = 1\n",
        ["constraints.a.a.a", "is nested"],
    ),
    (
        "study",
        "size",
        STUDY_HEAD + VARY + OBJECTIVE + "# " + "x" * (2 << 20) + "\n",
        ["over the limit of 1,048,576 bytes"],
    ),
    (
        "sweep",
        "digits",
        "[sweep]\nseed = " + HUGE + "\n" + SWEEP_VARY,
        ["line 2: sweep.seed holds a number of 5001"],
    ),
    (
        "sweep",
        "nesting in [vary]",
        "[vary]\nblades = " + DEEP + "\n",
        ["line 2: vary.blades is nested more than"],
    ),
    (
        "sweep",
        "nesting in [base]",
        "[base]\nname = " + DEEP_TABLE + "\n" + SWEEP_VARY,
        ["base.name is nested"],
    ),
    ("sweep", "dotted key", "[vary]\n" + DOTTED + " = [1, 2]\n", ["vary.a.a.a", "is nested"]),
    ("sweep", "table header", "[vary." + DOTTED + "]\nb = [1, 2]\n", ["vary.a.a.a", "is nested"]),
    (
        "sweep",
        "size",
        SWEEP_VARY + "# " + "x" * (2 << 20) + "\n",
        ["over the limit of 1,048,576 bytes"],
    ),
    ("design", "dotted key", DOTTED + " = 1\n", ["a.a.a", "is nested"]),
    ("design", "table header", "[" + DOTTED + "]\nb = 1\n", ["a.a.a", "is nested"]),
]
COMMANDS = {"study": "optimize", "sweep": "sweep", "design": "build"}


def _one_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err[:2000]
    return lines[0]


@pytest.mark.parametrize(
    ("kind", "attack", "text", "words"),
    FILE_ATTACKS,
    ids=[f"{kind}-{attack}" for kind, attack, _, _ in FILE_ATTACKS],
)
def test_a_study_sweep_or_design_file_out_of_shape_exits_2_naming_the_key(
    tmp_path, capsys, kind, attack, text, words
):
    """Today a study's 5001-digit trials was "internal error (ValueError)", its 500-deep nesting and
    the dotted keys and headers of both were "internal error (RecursionError)"."""
    path = tmp_path / f"{kind}.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main([COMMANDS[kind], str(path), "--out", str(out)]) == 2
    line = _one_line(capsys)
    assert line.startswith("torus-cad: error: ") and f"{kind}.toml" in line, line
    for word in words:
        assert word in line, line
    assert len(line) < 400
    assert not out.exists()


def test_tables_nested_up_to_the_limit_are_read():
    """The depth walk counts tables and lists; a file right at the limit is a valid TOML table."""
    from torus_cad.parameters.config_file import parse_config_text

    at_limit = ".".join(["a"] * TOML_NESTING_LIMIT) + " = [1]\n"  # 15 tables and a list: 16 levels
    assert parse_config_text(at_limit, "x") is not None
    with pytest.raises(ParameterError, match="is nested more than"):
        parse_config_text(".".join(["a"] * (TOML_NESTING_LIMIT + 1)) + " = [1]\n", "x")


# -- numeric options ------------------------------------------------------------------------------


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def _help_of(name: str, sub: argparse.ArgumentParser, capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit):
        sub.parse_args(["--help"])  # also adds the options the subcommand takes from the schema
    return " ".join(capsys.readouterr().out.split())


def _bounded_options(
    capsys: pytest.CaptureFixture[str],
) -> list[tuple[str, str, argparse.Action, str]]:
    """(command, option, action, its --help text) of every numeric option of every command."""
    options = []
    for name, sub in _subparsers().items():
        text = _help_of(name, sub, capsys)
        for action in sub._actions:
            if (
                action.option_strings
                and action.type is not None
                and not hasattr(action.type, "ranges")
            ):
                options.append((name, action.option_strings[-1], action, text))
    return options


def _compound_options(
    capsys: pytest.CaptureFixture[str],
) -> list[tuple[str, str, argparse.Action, str]]:
    """(command, option, action, its --help text) of every option whose value holds several numbers
    (``--observer DIST_M:ANGLE_DEG``): its type carries its ranges as text and values outside
    them."""
    options = []
    for name, sub in _subparsers().items():
        text = _help_of(name, sub, capsys)
        options += [
            (name, action.option_strings[-1], action, text)
            for action in sub._actions
            if action.option_strings and hasattr(action.type, "ranges")
        ]
    return options


def test_every_option_of_several_numbers_shows_its_ranges_and_refuses_values_outside_them(capsys):
    parser = build_parser()
    options = _compound_options(capsys)
    assert {option for _, option, _, _ in options} >= {"--observer"}
    for command, option, action, text in options:
        assert " ".join(action.type.ranges.split()) in text, (
            f"{command} {option}: its ranges not in its --help"
        )
        for value in action.type.outside:
            with pytest.raises(SystemExit) as stopped:
                parser.parse_args(_arguments(command, option, value))
            line = _one_line(capsys)
            assert stopped.value.code == 2 and option in line and "allowed" in line, line
            assert len(line) < 300, line


def test_every_numeric_option_has_a_range_shown_in_its_help(capsys):
    options = _bounded_options(capsys)
    assert {option for _, option, _, _ in options} >= {
        "--threads",
        "--workers",
        "--processes",
        "--iterations",
        "--trials",
        "--sections",
        "--points",
        "--density",
        "--time-limit",
        "--rpm",
        "--thrust",
        "--airspeed",
        "--thrust-runs",
        "--thrust-tolerance",
        "--port",
        "--far-size",
        "--growth-rate",
    }
    for command, option, action, text in options:
        assert action.type not in (int, float), (
            f"{command} {option} takes any {action.type.__name__}"
        )
        bounds = getattr(action.type, "bounds", None)
        assert bounds is not None and bounds.low is not None and bounds.high is not None, (
            f"{command} {option}"
        )
        assert str(bounds) in text, f"{command} {option}: {bounds} not in its --help"


def _arguments(command: str, option: str, value: str) -> list[str]:
    positional = {"sweep": ["s.toml"], "optimize": ["s.toml"], "verify": ["folder"]}.get(
        command, []
    )
    speed = ["--rpm", "1"] if command == "simulate" and option not in ("--rpm", "--thrust") else []
    return [command, *positional, *speed, option, value]


def _outside(bounds) -> list[str]:
    high = int(bounds.high) + 1 if float(bounds.high).is_integer() else bounds.high * 1.5
    return [str(high), str(bounds.low - 1), "1e999", "nan", HUGE, "x" * 100_000]


def test_every_numeric_option_refuses_values_outside_its_range_with_one_line(capsys):
    """Out of range, not finite, 5001 digits or 100,000 characters: exit 2 while parsing, one short
    line."""
    parser = build_parser()
    for command, option, action, _ in _bounded_options(capsys):
        for value in _outside(action.type.bounds):
            if action.type.__name__ == "whole number" and value in ("1e999", "nan"):
                value = "1.5"
            with pytest.raises(SystemExit) as stopped:
                parser.parse_args(_arguments(command, option, value))
            line = _one_line(capsys)
            assert stopped.value.code == 2, (command, option, value[:20])
            assert option in line and ("out of range" in line or "must be" in line), line
            assert len(line) < 300, line


@pytest.mark.parametrize(
    "arguments",
    [
        ["cfd", "--threads", "1000000000"],
        ["cfd", "--threads", "100000"],
        ["cfd", "--far-size", HUGE],
        ["mesh", "--sections", "1000000000"],
        ["simulate", "--rpm", "1000", "--processes", "100000"],
        ["simulate", "--rpm", "1000", "--iterations", "1000000000"],
        ["sweep", "s.toml", "--workers", "100000"],
        ["optimize", "s.toml", "--trials", "1000000000"],
        ["build", "--density", "nan"],
    ],
    ids=lambda arguments: " ".join(arguments)[:40],
)
def test_an_option_out_of_range_makes_no_output_folder(tmp_path, capsys, monkeypatch, arguments):
    monkeypatch.chdir(tmp_path)  # each command's default output folder would go here
    assert exit_code(arguments) == 2
    assert "out of range" in _one_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_cfd_with_100000_threads_exits_2_not_a_crash(tmp_path):
    """Today: libgomp 'Thread creation failed', SIGSEGV (exit 139 from a shell), a staging folder
    left."""
    result = subprocess.run(
        [sys.executable, "-m", "torus_cad", "cfd", "--threads", "100000"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    assert (
        result.stderr.count("\n") == 1
        and "--threads = 100000 is out of range; allowed [0, " in result.stderr
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("source", ["/etc", "/dev/zero"])
def test_simulate_mesh_from_a_wrong_case_makes_no_output_folder(tmp_path, capsys, source):
    out = tmp_path / "out"
    assert (
        main(["simulate", "--rpm", "3000", "--case-only", "--mesh-from", source, "--out", str(out)])
        == 2
    )
    assert f"--mesh-from {source!r} is not a meshed case" in _one_line(capsys)
    assert not out.exists()


# -- long values in messages
# ----------------------------------------------------------------------------

LONG_VALUES = [
    ("name", 'name = "{}"\n', "n"),
    ("airfoil.naca", '[airfoil]\nnaca = "{}"\n', "1"),
    ("handedness", 'handedness = "{}"\n', "c"),
    ("airfoil.file", '[airfoil]\nfile = "{}"\n', "f"),
    ("export.formats", '[export]\nformats = ["{}"]\n', "s"),
]


@pytest.mark.parametrize("length", [10_000, 900_000])
@pytest.mark.parametrize(
    ("key", "template", "letter"), LONG_VALUES, ids=[key for key, _, _ in LONG_VALUES]
)
def test_a_long_value_is_cut_in_the_message(tmp_path, capsys, key, template, letter, length):
    """Today the whole value was echoed: a 900 kB line."""
    design = tmp_path / "long.toml"
    design.write_text(template.format(letter * length))
    out = tmp_path / "out"
    assert main(["build", str(design), "--out", str(out)]) == 2
    line = _one_line(capsys)
    assert key in line and "..." in line and letter * MESSAGE_WORD_MAX_CHARS not in line, line[:300]
    assert len(line) < 500, len(line)
    assert not out.exists()


@pytest.mark.parametrize(
    "arguments",
    [
        ["build", "--set", "name=" + "x" * 100_000],
        ["build", "--format", "x" * 100_000],
        ["simulate", "--rpm", "1", "--level", "x" * 100_000],
        ["build", "x" * 100_000],
    ],
    ids=["--set", "--format", "--level choice", "config path"],
)
def test_a_long_command_line_value_is_cut_in_the_message(tmp_path, capsys, monkeypatch, arguments):
    monkeypatch.chdir(tmp_path)
    assert exit_code(arguments) == 2
    line = _one_line(capsys)
    assert "..." in line and len(line) < 600, line[:300]


@pytest.mark.parametrize(
    "text", ["", "short", "x" * 79, "x" * 80, "x" * 81, "é" * 1000, "x" * 900_000]
)
def test_cut_keeps_both_ends_within_the_limit(text):
    result = cut(text)
    assert len(result) <= MESSAGE_VALUE_MAX_CHARS
    if len(text) <= MESSAGE_VALUE_MAX_CHARS:
        assert result == text
    else:
        head, tail = result.split("...")
        assert text.startswith(head) and text.endswith(tail) and len(head) >= 30 and len(tail) >= 30
    assert cut(result) == result


def test_shown_and_bounded_message_bound_any_value():
    assert shown(10**5000) == "a huge number"
    assert shown("short") == "'short'"
    message = bounded_message("a = " + "x" * 900_000 + " is wrong\nsecond line " + "y " * 5000)
    assert "\n" not in message and len(message) <= MESSAGE_MAX_CHARS
    assert message.startswith("a = xxx") and message.endswith("y ")
    error = ParameterError("name = " + repr("n" * 900_000) + " must be short")
    assert len(str(error)) < 2 * MESSAGE_WORD_MAX_CHARS and str(error).endswith("must be short")
