"""The torus-cad command: files written, exit codes, one-line errors, nothing left behind on bad
input."""

import json
import subprocess
import sys

import pytest

from torus_cad.cli import main
from torus_cad.parameters import PropellerParameters


def test_build_writes_step_stl_and_report(tmp_path, capsys):
    assert (
        main(
            [
                "build",
                "--set",
                "resolution.sections=16",
                "--set",
                "resolution.points=48",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    names = sorted(path.name for path in tmp_path.iterdir())
    assert names == [
        "torus_propeller.json",
        "torus_propeller.step",
        "torus_propeller.stl",
        "torus_propeller_sections.csv",
        "torus_propeller_sections.png",
    ]
    report = json.loads((tmp_path / "torus_propeller.json").read_text())
    assert report["valid"] is True and report["solids"] == 1
    assert report["volume_mm3"] > 0 and report["surface_area_mm2"] > 0
    assert len(report["bounding_box_mm"]) == 2
    assert {"section_math", "wires", "loft", "fuse", "check", "step_write", "stl_write"} <= set(
        report["stage_seconds"]
    )
    assert PropellerParameters.from_dict(report["parameters"]).resolution.sections == 16
    assert "wrote" in capsys.readouterr().out


def test_defaults_prints_a_config_that_reads_back_as_the_defaults(tmp_path, capsys):
    assert main(["defaults"]) == 0
    path = tmp_path / "defaults.toml"
    path.write_text(capsys.readouterr().out)
    assert PropellerParameters.from_toml(path) == PropellerParameters()


@pytest.mark.parametrize(
    "config, fragment",
    [
        ("[hub]\nradius = -5.0\n", "hub.radius = -5 is out of range"),
        ("blades = 0\n", "blades = 0 is out of range"),
        ('blades = "three"\n', "blades must be a whole number"),
        ("[hub]\nradius = nan\n", "hub.radius = nan must be a finite number"),
        ("[hub]\nradius = inf\n", "hub.radius = inf must be a finite number"),
        ("[airfoil]\nthicknes = 0.2\n", "did you mean 'airfoil.thickness'"),
        ("", "is empty"),
        (
            "[transforms]\nscale_x = [0.0, 0.0, 40.0, -40.0, 9.9]\n",
            "transforms.scale_x must stay positive",
        ),
        ("[centerline]\np2 = [25.0, 3.0]\n", "centerline.p2 must be a list of 3 numbers"),
    ],
)
def test_bad_configuration_exits_2_with_one_line_and_writes_nothing(
    tmp_path, capsys, config, fragment
):
    path = tmp_path / "design.toml"
    path.write_text(config)
    out = tmp_path / "out"
    assert main(["build", str(path), "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert fragment in error
    assert error.count("\n") == 1 and "Traceback" not in error
    assert not out.exists()


def test_binary_file_and_missing_file_exit_2(tmp_path, capsys):
    binary = tmp_path / "design.toml"
    binary.write_bytes(bytes(range(256)))
    assert main(["build", str(binary), "--out", str(tmp_path / "out")]) == 2
    assert main(["build", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()
    assert "cannot read configuration" in capsys.readouterr().err


def test_refused_design_exits_2_before_the_kernel(tmp_path, capsys):
    # A root section far larger than the hub cannot be hidden by the fuse.
    assert (
        main(
            [
                "build",
                "--set",
                "transforms.scale_x=[0, 0, 0, 0, 40.0]",
                "--out",
                str(tmp_path / "out"),
            ]
        )
        == 2
    )
    assert "leaves the hub's inset" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_usage_errors_exit_2_and_help_exits_0():
    for argv in (["build", "--bogus"], ["nonsense"], ["build", "--density", "-1"]):
        with pytest.raises(SystemExit) as raised:
            main(argv)
        assert raised.value.code == 2
    with pytest.raises(SystemExit) as raised:
        main(["build", "--help"])
    assert raised.value.code == 0


def test_console_script_prints_no_traceback_on_bad_input(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "torus_cad",
            "build",
            "--set",
            "hub.length=-3",
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert "hub.length" in result.stderr and "Traceback" not in result.stderr


# -- issue 17: exit codes and one-line messages for failures --------------------------------------


def _memory_after_imports_kb(env: dict[str, str]) -> int:
    """Address space of a torus-cad process once everything is imported (VmPeak, kB)."""
    code = (
        "import torus_cad.propeller, torus_cad.outputs.output_set, torus_cad.cli, "
        "torus_cad.design.stl_budget\n"
        "print([l for l in open('/proc/self/status') if l.startswith('VmPeak')][0].split()[1])"
    )
    return int(
        subprocess.run(
            [sys.executable, "-c", code], env=env, check=True, capture_output=True, text=True
        ).stdout
    )


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc and sets RLIMIT_AS")
def test_out_of_memory_is_one_line_and_exit_1(tmp_path):
    """Case 6: a MemoryError printed a 46-line traceback with install paths. Here the process gets
    a little more address space than its imports take and builds the finest allowed blade: the
    geometry's arrays do not fit. (With ~200 MB more, the allocation that fails is OpenCascade's,
    which crashes the process: no Python code runs then.)"""
    import os
    import resource

    # BLAS thread buffers would fail first, outside Python
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    baseline_kb = _memory_after_imports_kb(env)
    outcomes = []
    for margin_mb in (50, 100):
        limit = (baseline_kb + margin_mb * 1000) * 1024

        def limit_memory(limit: int = limit) -> None:
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

        result = subprocess.run(
            [
                sys.executable,
                "-m",
                "torus_cad",
                "build",
                "--out",
                str(tmp_path / "out"),
                "-q",
                "--no-stl",
                "--set",
                "resolution.sections=400",
                "--set",
                "resolution.points=2000",
            ],
            env=env,
            preexec_fn=limit_memory,
            check=False,
            capture_output=True,
            text=True,
            timeout=900,
        )
        assert "Traceback" not in result.stderr and result.returncode in (0, 1), result.stderr
        if result.returncode == 1:
            assert result.stderr.strip() == (
                "torus-cad: out of memory; lower resolution.sections / "
                "resolution.points or raise the STL deflections"
            )
        outcomes.append(result.returncode)
    assert 1 in outcomes, f"no limit ran out of memory ({outcomes}): the test proved nothing"


def test_verify_exit_codes(tmp_path):
    """0 for a complete set, 1 naming the file for an incomplete one, 2 for a folder that is not
    one."""
    out = tmp_path / "out"
    assert (
        main(
            [
                "build",
                "--set",
                "resolution.sections=16",
                "--set",
                "resolution.points=48",
                "--no-stl",
                "-q",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert main(["verify", str(out), "-q"]) == 0
    (out / "torus_propeller.step").write_text("ISO-10303-21; truncated")
    assert main(["verify", str(out)]) == 1
    assert main(["verify", str(tmp_path / "missing")]) == 2


def test_a_sweep_file_given_to_build_points_to_the_sweep_command(tmp_path, capsys):
    assert main(["build", "examples/sweep_example.toml", "--out", str(tmp_path / "out")]) == 2
    assert "torus-cad sweep" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_numeric_naca_designation_on_the_command_line_is_the_designation(tmp_path):
    from torus_cad.cli.design_input import load_parameters

    assert load_parameters(None, ["airfoil.naca=4415"]).airfoil.naca == "4415"


def test_build_format_writes_a_3mf_that_trimesh_reads(tmp_path, capsys):
    trimesh = pytest.importorskip("trimesh")
    assert (
        main(
            [
                "build",
                "--format",
                "step,3mf",
                "--set",
                "resolution.sections=16",
                "--set",
                "resolution.points=48",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    assert {path.suffix for path in tmp_path.iterdir()} == {
        ".step",
        ".3mf",
        ".json",
        ".csv",
        ".png",
    }
    mesh = trimesh.load(tmp_path / "torus_propeller.3mf", force="mesh")
    assert mesh.is_watertight and mesh.volume > 0
    assert main(["build", "--format", "stp", "--out", str(tmp_path / "bad")]) == 2
    assert "export.formats" in capsys.readouterr().err


def test_build_says_on_the_terminal_when_the_part_is_not_printable(tmp_path, capsys):
    assert (
        main(
            [
                "build",
                "--set",
                "resolution.sections=16",
                "--set",
                "resolution.points=48",
                "--no-stl",
                "--out",
                str(tmp_path),
            ]
        )
        == 0
    )
    # a warning goes to stderr, beside the errors; stdout has the results
    written = capsys.readouterr()
    assert (
        "warning: not printable: the trailing edge" in written.err and "warning" not in written.out
    )


def test_each_subcommand_is_its_own_module_loaded_only_when_it_runs():
    """Parsing loads no command's module; running ``defaults`` loads its module and no other
    command's."""
    import argparse
    import importlib.util

    from torus_cad.cli import build_parser
    from torus_cad.cli.commands import COMMANDS

    choices = next(
        action.choices
        for action in build_parser()._actions
        if isinstance(action, argparse._SubParsersAction)
    )
    assert sorted(choices) == sorted(COMMANDS)
    for name in COMMANDS:
        assert importlib.util.find_spec(f"torus_cad.cli.commands.{name}") is not None, name
    probe = (
        "import sys\n"
        "from torus_cad.cli import build_parser, main\n"
        "build_parser().parse_args(['build'])\n"
        "before = sorted(m for m in sys.modules if m.startswith('torus_cad.cli.commands.'))\n"
        "main(['defaults'])\n"
        "after = sorted(m for m in sys.modules if m.startswith('torus_cad.cli.commands.'))\n"
        "print(before, after, 'cadquery' in sys.modules, file=sys.stderr)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert done.stderr.strip() == "[] ['torus_cad.cli.commands.defaults'] False"
