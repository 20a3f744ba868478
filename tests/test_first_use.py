"""What a new user trips over first (issue 35, item 7): the case's Allrun as root, the cfd README's
steps that survive moving the folder, the default output folders ignored by git, an empty --out
removed after Ctrl-C, the first line of ``cfd``, TOML arrays called arrays, the sections picture's
beta panel."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from terminal import terminal_text_until

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.skipif(
    shutil.which("mpiexec") is None or os.geteuid() != 0, reason="needs OpenMPI's mpiexec, as root"
)
def test_allrun_starts_mpiexec_as_root(tmp_path):
    """OpenMPI refuses root unless two variables are set: the Allrun sets them itself (the lines
    before its first OpenFOAM command, then mpiexec, run as the script runs)."""
    pytest.importorskip("foamlib")
    from torus_cad.parameters.design import Handedness
    from torus_cad.simulate.case import CaseSpec, allrun_text
    from torus_cad.simulate.settings import OperatingPoint

    spec = CaseSpec(
        OperatingPoint(5000.0),
        Handedness.CW,
        0.05,
        -1.0,
        iterations=10,
        processes=2,
        msh_file="x.msh",
    )
    lines = allrun_text(spec).splitlines()
    prelude = lines[: next(index for index, line in enumerate(lines) if "> log." in line)]
    script = tmp_path / "Allrun_prelude"
    script.write_text("\n".join([*prelude, "mpiexec -n 1 true"]) + "\n")
    environment = {key: value for key, value in os.environ.items() if not key.startswith("OMPI_")}
    result = subprocess.run(
        ["sh", str(script)],
        env=environment,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-500:]


def _cfd_readme() -> str:
    from torus_cad.cfd_domain.readme import openfoam_block, readme_text

    report = {
        "gmsh_version": "4.13.1",
        "tetrahedra_total": 3,
        "tetrahedra": {"rotating_zone": 1, "fluid": 2},
        "sicn_min": 0.2,
        "triangles": {"rotating_interface": 4},
        "domain_mm": {
            "inlet_z": 90.0,
            "outlet_z": -180.0,
            "tip_diameter": 45.0,
            "outer_radius": 135.0,
            "zone_radius": 30.0,
            "zone_z": (-20.0, 20.0),
        },
    }
    text = readme_text("torus_propeller", report)
    return text + "\n" + openfoam_block(text)


def test_the_cfd_readme_points_to_a_runnable_case_and_names_no_absolute_path():
    text = _cfd_readme()
    assert "torus-cad simulate" in text and "--case-only" in text and "--mesher tet" in text
    block = text.split("\n\n")[-1]
    # the folder of README.txt, from a case folder made inside it
    assert 'MESH="${MESH:-..}"' in block
    assert str(Path.cwd()) not in text and "MESH='/" not in text


def _default_out_folders() -> set[str]:
    """The first path part of every subcommand's default --out (from the parser itself), with the
    folders sweep and optimize default to (sweep_out/<file>, optimize_out/<file>) and preview
    (step_out/<name>.png)."""
    import argparse

    from torus_cad.cli import build_parser

    parser = build_parser()
    commands = next(
        action for action in parser._actions if isinstance(action, argparse._SubParsersAction)
    )
    folders = {"sweep_out", "optimize_out", "step_out"}
    for subparser in commands.choices.values():
        for action in subparser._actions:
            if action.dest == "out" and isinstance(action.default, str):
                folders.add(Path(action.default).parts[0])
    return folders


@pytest.mark.skipif(
    shutil.which("git") is None or not (ROOT / ".git").exists(), reason="not a git checkout"
)
def test_every_default_output_folder_is_ignored_by_git():
    folders = _default_out_folders()
    assert {"mesh_out", "cfd_out", "simulate_out"} <= folders
    for folder in sorted(folders):
        result = subprocess.run(
            ["git", "check-ignore", "-q", f"{folder}/some_file.stl"], cwd=ROOT, check=False
        )
        assert result.returncode == 0, f"{folder}/ is not in .gitignore"


def test_an_output_folder_made_for_a_set_that_is_never_published_is_removed(tmp_path):
    from torus_cad.outputs.output_set import OutputSet

    (tmp_path / "kept").mkdir()
    with (
        pytest.raises(RuntimeError),
        OutputSet(tmp_path / "kept" / "new" / "deeper", "part") as output,
    ):
        output.write("step", lambda path: path.write_text("solid") and path)
        raise RuntimeError("the build failed")
    assert [path.name for path in tmp_path.iterdir()] == ["kept"] and not any(
        (tmp_path / "kept").iterdir()
    )


#: A process that installs the command line's signal handlers, enters an output set in a new folder
#: (as build, mesh and cfd do) and waits there for the signal.
WAITING_IN_A_SET = """
import sys, time
from torus_cad.runtime.interrupts import exit_on_signals
exit_on_signals()
from torus_cad.outputs.output_set import OutputSet
with OutputSet(sys.argv[1], "part") as output:
    output.write("step", lambda path: path.write_text("half a solid") and path)
    print("ready", flush=True)
    time.sleep(60)
"""


def test_sigint_while_a_set_is_written_removes_the_out_folder_the_command_made(tmp_path):
    import signal

    out = tmp_path / "out" / "deeper"
    process = subprocess.Popen(
        [sys.executable, "-c", WAITING_IN_A_SET, str(out)],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert process.stdout.readline() == "ready\n"
    assert out.is_dir()
    process.send_signal(signal.SIGINT)
    assert process.wait(60) == 130
    assert "interrupted by SIGINT" in process.stderr.read()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.long
def test_sigint_during_cfd_removes_the_out_folder_it_made(tmp_path):
    """Ctrl-C while cfd meshes (its output folder already made): exit 130 and no empty folder
    left."""
    pytest.importorskip("gmsh")
    import signal
    import time

    out = tmp_path / "out" / "cfd"
    process = subprocess.Popen(
        [sys.executable, "-m", "torus_cad", "cfd", "--out", str(out), "-q"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not out.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    assert out.exists(), "cfd never made its output folder"
    time.sleep(0.2)
    process.send_signal(signal.SIGINT)
    assert process.wait(60) == 130, process.stderr.read()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a pseudo-terminal")
def test_cfd_says_what_it_does_before_loading_anything_heavy(tmp_path):
    """The first progress line of cfd comes before the schema (pydantic), the CAD kernel and gmsh
    load: -X importtime reports each module on stderr as its import ends."""
    text = terminal_text_until(
        ["-X", "importtime", "-m", "torus_cad", "cfd", "--out", str(tmp_path / "out")],
        b"building the propeller",
    )
    assert "building the propeller" in text
    before = text[: text.index("building the propeller")]
    assert not any(
        module in before for module in ("pydantic", "cadquery", "OCP", "gmsh", "numpy")
    ), before[-500:]


@pytest.mark.parametrize(
    "toml, words",
    [
        (
            "[centerline]\np2 = [[25.0, 3.0, 1.0], [1.0, 2.0, 3.0]]\n",
            "got array of 3 items [25.0, 3.0, 1.0]",
        ),
        ("blades = 'four'\n", "got string 'four'"),
        ("hub = 3\n", "got integer 3"),
    ],
)
def test_a_wrong_value_is_described_in_toml_words_not_python_type_names(
    tmp_path, capsys, toml, words
):
    from torus_cad.cli import main

    design = tmp_path / "design.toml"
    design.write_text(toml)
    assert main(["defaults", "--resolved", str(design)]) == 2
    error = capsys.readouterr().err
    assert words in error, error
    assert not any(name in error for name in ("tuple", " str ", " int ", " list ", " dict "))


def test_the_sections_picture_plots_beta_without_the_jump_at_the_tip(default_params):
    """The default blade's beta jumps from about -5 to -172 degrees at the tip (the chord line turns
    back): the picture's curve continues instead, the same line's angle (mod 180), and spans tens of
    degrees."""
    from torus_cad.design.described_geometry import sampled_blade_surface
    from torus_cad.outputs.sections_table import elements_of, plotted_beta_deg

    elements = elements_of(sampled_blade_surface(default_params, points=400))
    raw, plotted = np.asarray(elements.beta_deg), plotted_beta_deg(elements)
    # the table's raw angle does jump (else this proves nothing)
    assert np.max(np.abs(np.diff(raw))) > 150.0
    assert np.max(np.abs(np.diff(plotted))) < 30.0
    assert np.ptp(plotted) < 60.0
    # the same chord line as the table's
    assert np.allclose(np.mod(plotted - raw + 90.0, 180.0), 90.0)


def test_a_refused_trial_appears_in_the_optimize_summary_and_the_history_picture():
    """The optimize example's refused trial (a design over a limit: no objective value) is named in
    the terminal summary and marked in the history picture, not silently missing."""
    optuna = pytest.importorskip("optuna")
    from optuna.distributions import FloatDistribution
    from optuna.trial import TrialState, create_trial

    from torus_cad.optimize.results import history_figure, trial_rows, unvalued_lines
    from torus_cad.optimize.storage import OUTCOME, REASON, RESULT
    from torus_cad.optimize.study_file import read_study_file

    spec = read_study_file(ROOT / "examples" / "optimize_light.toml")
    distributions = {"airfoil.thickness": FloatDistribution(0.2, 0.6)}
    reason = "airfoil.thickness: the blade is 10.1 % of the chord thick, over the limit of 10.0 %"
    trials = [
        create_trial(
            state=TrialState.COMPLETE,
            value=value,
            params={"airfoil.thickness": 0.3},
            distributions=distributions,
            user_attrs={RESULT: {OUTCOME: "valid"}},
        )
        for value in (5.0, 4.0)
    ]
    trials.insert(
        1,
        create_trial(
            state=TrialState.FAIL,
            params={"airfoil.thickness": 0.59},
            distributions=distributions,
            user_attrs={RESULT: {OUTCOME: "refused", REASON: reason}},
        ),
    )
    study = optuna.create_study()
    for trial in trials:
        study.add_trial(trial)
    trials = study.get_trials()
    rows, _ = trial_rows(spec, trials)
    assert unvalued_lines(rows) == [f"  trial 1 refused: {reason}"]
    figure = history_figure(spec, trials)
    marks = [line for line in figure.axes[0].get_lines() if "refused" in str(line.get_label())]
    assert len(marks) == 1 and list(marks[0].get_xdata()) == [1]
