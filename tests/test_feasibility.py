"""Feasibility before the kernel (issue 33): ``torus-cad check`` answers with the build's own
refusal or one line, without OpenCascade; the build refuses nothing geometric that ``check`` passed;
sweeps and studies refuse such designs in their own process and count them apart."""

from __future__ import annotations

import copy
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import HOOKED_TRAILING_EDGE_DESIGN, SHIPPED_DESIGNS

from torus_cad.batch import (
    DesignResult,
    DesignTask,
    Outcome,
    generate_designs,
    parse_sweep,
    run_sweep,
)
from torus_cad.batch.job import REFUSAL_FILE
from torus_cad.batch.table import DESIGNS_DIR
from torus_cad.cli import main
from torus_cad.design.design_checks import check_design
from torus_cad.errors import GeometryError, ParameterError
from torus_cad.parameters import PropellerParameters

ROOT = Path(__file__).resolve().parent.parent

#: Designs the checks refuse: the overrides that make each, and words of the build's refusal.
INFEASIBLE = {
    "fold": (["transforms.scale_x=[0,0,-32,32,6]"], "the blade folds over itself near s = "),
    "root_leaves_the_inset": (
        ["transforms.scale_x=[0,0,-16,16,20]"],
        "root (s = 0) section leaves the hub's inset",
    ),
    "end_face": (["centerline.p2=[25,-15,2]"], "leaves the hub through an end face"),
    "sparse_sections": (["resolution.sections=4"], "resolution.sections = 4 is too few"),
    "bore_into_the_blades": (
        ["hub.bore_diameter=14"],
        "hub.bore_diameter = 14 mm cuts the blade roots",
    ),
}


def _check(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["check", *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_check_passes_the_default_in_one_line(capsys):
    code, out, err = _check(capsys)
    assert (code, err) == (0, "")
    assert len(out.splitlines()) == 1 and out.startswith(
        "feasible: torus_propeller, 3 blades, tip diameter 45.1 mm"
    )
    assert (
        "fold ratio 0.91 (limit 1)" in out
        and "walls: thinnest 1.52 mm" in out
        and "without the kernel" in out
    )


@pytest.mark.parametrize("design", SHIPPED_DESIGNS, ids=lambda path: path.stem)
def test_check_passes_every_shipped_example(capsys, design):
    assert _check(capsys, str(design), "-q") == (0, "", "")


@pytest.mark.parametrize("name", list(INFEASIBLE))
def test_check_refuses_with_exit_2_and_the_build_s_own_line(capsys, tmp_path, name):
    overrides, words = INFEASIBLE[name]
    code, out, err = _check(
        capsys, *[item for pair in (("--set", o) for o in overrides) for item in pair]
    )
    assert code == 2 and out == "" and len(err.splitlines()) == 1 and words in err
    # the build refuses with exactly that line, writing nothing
    built = main(
        [
            "build",
            *[item for pair in (("--set", o) for o in overrides) for item in pair],
            "--out",
            str(tmp_path / "out"),
        ]
    )
    assert built == 2 and capsys.readouterr().err == err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_check_refuses_a_trailing_edge_the_section_fit_cannot_resolve_before_the_kernel(
    capsys, tmp_path
):
    """The hooked trailing edge of tests/test_robustness.py (25 points): refused by the section fit,
    which is kernel-free now, with the build's line."""
    design = copy.deepcopy(HOOKED_TRAILING_EDGE_DESIGN)
    path = tmp_path / "hooked.toml"
    path.write_text(PropellerParameters.from_dict(design).to_toml())
    code, _, err = _check(capsys, str(path))
    assert code == 2 and "resolution.points = 25 is too few for this airfoil's trailing edge" in err
    assert (
        main(["build", str(path), "--out", str(tmp_path / "out")]) == 2
        and capsys.readouterr().err == err
    )
    assert _check(capsys, str(path), "--set", "resolution.points=48", "-q")[0] == 0


def test_check_takes_a_design_file_with_set_overrides_and_require_printable(capsys, tmp_path):
    design = tmp_path / "wide.toml"
    design.write_text("blades = 2\n[hub]\nradius = 12.0\n")
    code, out, _ = _check(capsys, str(design), "--set", "blades=4")
    assert code == 0 and out.startswith("feasible: torus_propeller, 4 blades")
    # the default's sharp trailing edge
    code, _, err = _check(capsys, str(design), "--require-printable")
    assert code == 2 and err.startswith(
        "torus-cad: error: not printable (--require-printable): the trailing edge"
    )
    fine = (
        "--set",
        "export.stl_linear_deflection=0.001",
        "--set",
        "export.stl_angular_deflection=0.01",
    )
    code, _, err = _check(capsys, *fine)
    assert code == 2 and "the STL would have about" in err and "over the limit of 2,000,000" in err
    assert _check(capsys, *fine, "--no-stl", "-q") == (0, "", "")


def test_a_closed_elliptical_coordinate_file_passes(capsys, tmp_path):
    """80 points round a closed ellipse: refused by round-off as 'line 2: the surfaces cross' before
    issue 33."""
    angle = np.linspace(0.0, 2.0 * np.pi, 80)
    path = tmp_path / "ellipse.dat"
    path.write_text(
        "ellipse\n"
        + "\n".join(f"{0.5 + 0.5 * np.cos(a):.7f} {0.06 * np.sin(a):.7f}" for a in angle)
    )
    code, out, err = _check(capsys, "--set", f"airfoil.file={path}")
    assert (code, err) == (0, "") and out.startswith("feasible: ")


def test_check_never_loads_the_kernel_and_answers_in_under_a_second():
    code = (
        "import sys, time\n"
        "from torus_cad.cli import main\n"
        "start = time.perf_counter(); assert main(['check', '-q']) == 0\n"
        "from torus_cad.parameters import PropellerParameters\n"
        "from torus_cad.design.design_checks import check_design\n"
        "cpu = time.process_time(); check_design(PropellerParameters(), mesh=True)\n"
        "print(time.process_time() - cpu)\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in {'OCP', 'cadquery'}))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
    )
    seconds, loaded = done.stdout.splitlines()
    assert loaded == "[]"
    assert float(seconds) < 0.5  # CPU seconds of the checks on the default (measured ~0.1 s)


# -- agreement with the build
# -------------------------------------------------------------------------


def _fuzz_designs(seeds: range) -> list[dict]:
    sys.path.insert(0, str(ROOT))
    from studies.fuzz import random_design_dict

    return [random_design_dict(seed) for seed in seeds]


def _verdict(design: dict) -> str:
    try:
        check_design(PropellerParameters.from_dict(design), mesh=True)
    except (ParameterError, GeometryError) as error:
        return str(error)
    return ""


def test_what_check_refuses_the_build_refuses_with_the_same_line():
    """The fuzz sampler's designs 0-29: each one check refuses, build_propeller refuses with the
    same message before the kernel builds anything (cheap: no design here is built)."""
    from torus_cad.propeller import build_propeller

    refused = 0
    for design in _fuzz_designs(range(30)):
        verdict = _verdict(design)
        if not verdict:
            continue
        refused += 1
        stages: list[str] = []
        with pytest.raises((ParameterError, GeometryError)) as caught:
            build_propeller(PropellerParameters.from_dict(design), progress=stages.append)
        assert str(caught.value) == verdict and "loft" not in stages
    assert refused >= 8  # the sampler's wild designs (measured: 11 of 30)


@pytest.mark.long
def test_what_check_passes_the_build_and_its_files_refuse_nothing_geometric(tmp_path):
    """The fuzz sampler's designs 0-29, built and written as a sweep writes them (STEP and STL): no
    design check passed is refused by the build or the write (a kernel failure is not a refusal and
    is not judged here)."""
    from torus_cad.errors import KernelError
    from torus_cad.propeller import build_propeller

    passed = 0
    for index, design in enumerate(_fuzz_designs(range(30))):
        if _verdict(design):
            continue
        passed += 1
        try:
            build_propeller(PropellerParameters.from_dict(design)).write(tmp_path / str(index))
        except KernelError:
            continue
        finally:
            shutil.rmtree(tmp_path / str(index), ignore_errors=True)
    assert passed >= 10


# -- sweeps and studies
# ------------------------------------------------------------------------------


def valid_without_building(task: DesignTask) -> DesignResult:
    """A worker's job that builds nothing: every design that reaches a worker comes back valid."""
    return DesignResult(task.design_id, Outcome.VALID)


def test_a_sweep_refuses_infeasible_designs_before_any_worker_and_counts_them_apart(tmp_path):
    spec = parse_sweep(
        {
            "base": {"resolution": {"sections": 16, "points": 32}},
            "sweep": {"stl": False},
            "vary": {"transforms.scale_x[4]": [6.0, 20.0], "hub.radius": [10.0, 3.0]},
        }
    )
    result = run_sweep(
        spec, tmp_path / "out", workers=1, progress=False, job=valid_without_building
    )
    by_value = {(row["transforms.scale_x[4]"], row["hub.radius"]): row for row in result.rows}
    assert {key: (row["status"], row["prescreened"]) for key, row in by_value.items()} == {
        (6.0, 10.0): ("valid", False),
        (6.0, 3.0): ("refused", True),
        (20.0, 10.0): ("refused", True),
        (20.0, 3.0): ("refused", True),
    }
    assert "hub's inset" in by_value[(6.0, 3.0)]["reason"]
    assert (
        result.prescreened == 3
        and "1 valid, 3 refused, 0 failed, 0 errors; 3 refused before the kernel"
        in result.summary()
    )
    design = generate_designs(spec)[1]
    record = json.loads(
        (tmp_path / "out" / DESIGNS_DIR / design.design_id / REFUSAL_FILE).read_text()
    )
    assert record["prescreened"] is True and record["status"] == "refused"
    table = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert "prescreened" in table[0].split(",") and sum(",True," in line for line in table[1:]) == 3


def test_a_study_tells_prescreened_trials_at_once_and_counts_them(tmp_path):
    pytest.importorskip("optuna")
    from torus_cad.optimize import parse_study, run_study

    base = tmp_path / "base.toml"
    base.write_text('[resolution]\nsections = 16\npoints = 32\n[export]\nformats = ["step"]\n')
    spec = parse_study(
        {
            "study": {"name": "narrow_hub", "base": str(base), "trials": 3, "sampler": "random"},
            "vary": {"hub.radius": [2.5, 3.5]},
            "objective": [{"metric": "mass_g", "direction": "minimize"}],
        },
        tmp_path,
    )
    result = run_study(spec, tmp_path / "out", workers=1)
    assert result.ran == 3
    summary = json.loads((tmp_path / "out" / "narrow_hub_study.json").read_text())
    assert summary["prescreened"] == 3 and summary["outcomes"] == {"refused": 3}
    assert (
        "  trials: 0 valid, 3 refused (3 before the kernel, pre-screened), 0 failed"
        in result.summary()
    )
    header, *rows = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert header.startswith("number,state,outcome,feasible,reason,prescreened")
    assert all(",refused," in row and "hub's inset" in row for row in rows)


#: Seeds of the fuzz sampler's workshop designs (bores, D-flats, set screws, chamfers, blunt edges,
#: ccw; no root fillet) that check and the build both judge: the ones check passes are built.
AGREEMENT_SEEDS = range(100, 116)


def test_check_and_the_build_give_the_same_answer_on_random_workshop_designs():
    """Issue 47: check is "would it build?". On seeded random workshop designs, every design check
    refuses the build refuses with the same line before the kernel, and every design check passes
    builds (no kernel failure)."""
    sys.path.insert(0, str(ROOT))
    from studies.fuzz import random_design_dict
    from torus_cad.propeller import build_propeller

    answers = {"refused by both": 0, "built": 0}
    for seed in AGREEMENT_SEEDS:
        design = random_design_dict(seed, workshop=True)
        try:
            params = PropellerParameters.from_dict(design)
        except ParameterError:
            # the parameters themselves: check and build read them alike
            answers["refused by both"] += 1
            continue
        verdict = _verdict(design)
        try:
            build_propeller(params)
        except (ParameterError, GeometryError) as refusal:
            assert str(refusal) == verdict, seed
            answers["refused by both"] += 1
            continue
        assert verdict == "", (seed, verdict)  # check refused a design that builds
        answers["built"] += 1
    assert answers["built"] >= 4 and answers["refused by both"] >= 2, answers


def test_a_root_fillet_round_a_knife_edge_is_refused_by_check_as_by_the_build(tmp_path):
    """OpenCascade's fillet round a knife trailing edge leaves a self-crossing corner face (measured
    on every design tried): check and build refuse it before the kernel, exit 2, the same line,
    nothing written."""
    args = ["--set", "hub.root_fillet_radius=0.2"]
    check = subprocess.run(
        [sys.executable, "-m", "torus_cad", "check", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    build = subprocess.run(
        [sys.executable, "-m", "torus_cad", "build", *args, "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert check.returncode == build.returncode == 2 and check.stderr == build.stderr
    assert "hub.root_fillet_radius = 0.2 mm round a knife trailing edge" in check.stderr
    assert len(check.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("edge", "words"),
    [
        (
            {"airfoil.trailing_edge_thickness": 0.4, "airfoil.trailing_edge_shape": "flat"},
            "flat trailing edge",
        ),
        ({"airfoil.trailing_edge_thickness": 0.4}, "rolling ball fits"),
    ],
)
def test_check_says_the_root_fillet_is_the_kernels_to_decide(edge, words):
    """What check cannot know without the kernel it says on a note line (exit 0): a root fillet's
    outcome."""
    overrides = [
        f"--set={key}={value}" for key, value in {**edge, "hub.root_fillet_radius": 0.5}.items()
    ]
    done = subprocess.run(
        [sys.executable, "-m", "torus_cad", "check", *overrides],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    assert lines[0].startswith("feasible:") and lines[1].startswith("note: ") and words in lines[1]
    assert (
        "note"
        not in subprocess.run(
            [sys.executable, "-m", "torus_cad", "check"],
            capture_output=True,
            text=True,
            cwd=ROOT,
            check=True,
        ).stdout
    )
