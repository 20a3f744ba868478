"""Design sweeps (torus_cad.batch): the sweep file, design ids, the local pool and Dask, resuming,
failures, budgets, exit codes and signals."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from batch_jobs import crash_on_four_or_six_blades
from cli_exit import exit_code
from hypothesis import given, settings
from hypothesis import strategies as st

from torus_cad.batch import (
    BatchError,
    DesignTask,
    LocalPool,
    Outcome,
    design_id,
    generate_designs,
    load_sweep,
    parse_sweep,
    run_design,
    run_sweep,
    run_tasks,
)
from torus_cad.batch.job import FAILURE_FILE, REFUSAL_FILE
from torus_cad.batch.table import DESIGNS_DIR
from torus_cad.cli import main
from torus_cad.errors import KernelError, ParameterError

LIGHT = {"resolution": {"sections": 16, "points": 32}}

# 6 designs that all build at the light resolution, 2 blade counts x 3 cambers.
SMALL_SWEEP = """
[base.resolution]
sections = 16
points = 32

[sweep]
mode = "grid"
stl = false

[vary]
blades = {start = 2, stop = 3, step = 1}
"airfoil.max_camber" = [0.0, 0.02, 0.04]
"""


def write(path: Path, text: str) -> Path:
    path.write_text(textwrap.dedent(text))
    return path


def read_table(path: Path, drop_times: bool = True) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    if drop_times:  # wall times differ from run to run
        rows = [
            {key: value for key, value in row.items() if not key.startswith("time_")}
            for row in rows
        ]
    return rows


# -- the sweep file ------------------------------------------------------------------------------


def test_grid_lists_and_inclusive_ranges():
    spec = parse_sweep(
        {
            "base": LIGHT,
            "vary": {"blades": {"start": 2, "stop": 4, "step": 1}, "hub.radius": [9, 10.5]},
        }
    )
    designs = generate_designs(spec)
    assert [tuple(d.varied.values()) for d in designs] == [
        (2, 9.0),
        (2, 10.5),
        (3, 9.0),
        (3, 10.5),
        (4, 9.0),
        (4, 10.5),
    ]
    assert all(
        isinstance(d.varied["blades"], int) and isinstance(d.varied["hub.radius"], float)
        for d in designs
    )
    assert designs[3].parameters["blades"] == 3 and designs[3].parameters["hub"]["radius"] == 10.5
    assert designs[0].parameters["resolution"] == {"sections": 16, "points": 32}
    assert all(d.parameters["name"] == d.design_id for d in designs)
    float_range = parse_sweep(
        {"vary": {"airfoil.max_camber": {"start": 0.0, "stop": 0.03, "step": 0.01}}}
    )
    assert float_range.axes[0].values == (0.0, 0.01, 0.02, 0.03)
    linspace = parse_sweep({"vary": {"hub.length": {"start": 20, "stop": 30, "num": 3}}})
    assert linspace.axes[0].values == (20.0, 25.0, 30.0)


def test_vector_elements_whole_vectors_and_nested_keys():
    spec = parse_sweep(
        {
            "vary": {
                "centerline.p2[2]": [20.0, 24],
                "centerline": {"p3": [[70, 15, 22], [80, 15, 22]]},
            }
        }
    )
    designs = generate_designs(spec)
    assert len(designs) == 4
    assert designs[0].parameters["centerline"]["p2"] == [25.0, 3.0, 20.0]
    assert designs[3].parameters["centerline"]["p2"] == [25.0, 3.0, 24.0]
    assert designs[3].parameters["centerline"]["p3"] == [80.0, 15.0, 22.0]


@pytest.mark.parametrize("mode", ["random", "latin_hypercube"])
def test_sampling_is_seeded_within_bounds_and_keeps_ints(mode):
    data = {
        "sweep": {"mode": mode, "samples": 20, "seed": 7},
        "vary": {
            "hub.radius": {"low": 8, "high": 12},
            "blades": {"low": 2, "high": 4},
            "centerline.frame": ["frenet", "rotation_minimizing"],
        },
    }
    designs = generate_designs(parse_sweep(data))
    again = generate_designs(parse_sweep(data))
    other_seed = generate_designs(parse_sweep({**data, "sweep": {**data["sweep"], "seed": 8}}))
    assert [d.design_id for d in designs] == [d.design_id for d in again]
    assert [d.design_id for d in designs] != [d.design_id for d in other_seed]
    radii = [d.varied["hub.radius"] for d in designs]
    assert all(isinstance(r, float) and 8.0 <= r < 12.0 for r in radii)
    assert {d.varied["blades"] for d in designs} == {2, 3, 4}
    assert all(isinstance(d.varied["blades"], int) for d in designs)
    assert {d.varied["centerline.frame"] for d in designs} == {"frenet", "rotation_minimizing"}
    if mode == "latin_hypercube":  # one sample in each of the 20 equal strata of the radius
        assert sorted(int((r - 8.0) / 4.0 * 20) for r in radii) == list(range(20))


@settings(max_examples=40, deadline=None)
@given(
    low=st.floats(0.6, 50.0),
    width=st.floats(0.01, 50.0),
    int_low=st.integers(4, 10),
    int_width=st.integers(0, 5),
    seed=st.integers(0, 2**32),
    mode=st.sampled_from(["random", "latin_hypercube"]),
)
def test_samples_stay_within_their_bounds(low, width, int_low, int_width, seed, mode):
    spec = parse_sweep(
        {
            "sweep": {"mode": mode, "samples": 7, "seed": seed},
            "vary": {
                "hub.radius": {"low": low, "high": low + width},
                "resolution.sections": {"low": int_low, "high": int_low + int_width + 1},
            },
        }
    )
    for design in generate_designs(spec):
        assert low <= design.varied["hub.radius"] < low + width
        sections = design.varied["resolution.sections"]
        assert isinstance(sections, int) and int_low <= sections <= int_low + int_width + 1


def test_design_id_is_a_stable_hash_of_the_parameters_without_the_name():
    params = {"blades": 3, "hub": {"radius": 10.0, "length": 20.0}, "name": "a"}
    same = {"hub": {"length": 20.0, "radius": 10.0}, "name": "b", "blades": 3}
    assert design_id(params) == design_id(same)
    assert len(design_id(params)) == 12 and int(design_id(params), 16) >= 0
    assert design_id({**params, "blades": 4}) != design_id(params)
    first = generate_designs(parse_sweep({"vary": {"blades": [2, 3]}}))
    second = generate_designs(parse_sweep({"base": {"name": "other"}, "vary": {"blades": [3, 2]}}))
    assert {d.design_id for d in first} == {d.design_id for d in second}


def test_duplicate_designs_are_merged():
    designs = generate_designs(parse_sweep({"vary": {"blades": [3, 3, 2]}}))
    assert [d.varied["blades"] for d in designs] == [3, 2]
    assert [d.index for d in designs] == [0, 1]


def test_base_config_is_relative_to_the_sweep_file_and_inline_values_override_it(tmp_path):
    (tmp_path / "configs").mkdir()
    write(tmp_path / "configs" / "prop.toml", "blades = 4\n[hub]\nradius = 12.0\n")
    sweep = write(
        tmp_path / "s.toml",
        """
        [base]
        config = "configs/prop.toml"
        [base.hub]
        length = 24.0
        [vary]
        "airfoil.thickness" = [0.4, 0.5]
        """,
    )
    spec = load_sweep(sweep)
    assert (spec.base.blades, spec.base.hub.radius, spec.base.hub.length) == (4, 12.0, 24.0)
    assert spec.name == "s" and len(generate_designs(spec)) == 2


EXAMPLE_AIRFOILS = Path(__file__).resolve().parent.parent / "examples" / "airfoils"

# A sweep naming .dat airfoils: inline in its base design and as a varied value.
AIRFOIL_SWEEP = """
[base.airfoil]
file = "airfoils/clarky.dat"
[base.resolution]
sections = 16
points = 32
[sweep]
stl = false
[vary]
"airfoil.file" = ["airfoils/clarky.dat", "airfoils/naca2412.dat"]
"""


@pytest.fixture
def airfoil_project(tmp_path, monkeypatch) -> Path:
    """A project folder with airfoils/*.dat, a design file and sweep files; the working directory
    elsewhere."""
    project = tmp_path / "project"
    shutil.copytree(EXAMPLE_AIRFOILS, project / "airfoils")
    write(project / "prop.toml", '[airfoil]\nfile = "airfoils/naca2412.dat"\n')
    write(project / "via_config.toml", '[base]\nconfig = "prop.toml"\n[vary]\nblades = [2, 3]\n')
    write(project / "airfoils.toml", AIRFOIL_SWEEP)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    return project


def test_airfoil_files_in_a_sweep_are_relative_to_the_file_naming_them(airfoil_project):
    """As ``torus-cad build CONFIG`` reads a config's airfoil.file, whatever the working
    directory."""
    clarky, naca2412 = (
        str(airfoil_project / "airfoils" / name) for name in ("clarky.dat", "naca2412.dat")
    )
    # in the base design file
    assert load_sweep(Path("../project/via_config.toml")).base.airfoil.file == naca2412
    spec = load_sweep(Path("../project/airfoils.toml"))
    assert spec.base.airfoil.file == clarky  # inline in the sweep file
    assert [design.parameters["airfoil"]["file"] for design in generate_designs(spec)] == [
        clarky,
        naca2412,
    ]


def test_a_sweep_run_from_another_folder_builds_each_design_from_its_airfoil_file(
    airfoil_project, capsys
):
    assert (
        main(["sweep", "../project/airfoils.toml", "--workers", "1", "--out", "out", "--quiet"])
        == 0
    ), capsys.readouterr()
    table = read_table(Path("out") / "results.csv")
    assert [row["status"] for row in table] == ["valid", "valid"]
    reports = [
        json.loads((Path("out") / DESIGNS_DIR / row["id"] / f"{row['id']}.json").read_text())
        for row in table
    ]
    assert [report["parameters"]["airfoil"]["file"] for report in reports] == [
        str(airfoil_project / "airfoils" / name) for name in ("clarky.dat", "naca2412.dat")
    ]
    # each design was built from its own file
    assert reports[0]["volume_mm3"] != reports[1]["volume_mm3"]


@pytest.mark.parametrize(
    "data, message",
    [
        ({"vary": {"hub.radiu": [1.0]}}, "'hub.radiu'; did you mean 'hub.radius'"),
        ({"vary": {"blade": [2]}}, "did you mean 'blades'"),
        ({"vary": {"hub.radius": {"low": 8.0, "high": 12.0}}}, "need sweep.mode = 'random'"),
        ({"sweep": {"mode": "sobol"}}, "sweep.mode = 'sobol' is not allowed"),
        (
            {"sweep": {"mode": "random"}, "vary": {"blades": [2]}},
            "sweep.samples must be a whole number",
        ),
        ({"sweep": {"samples": 3}}, "sweep.samples applies to mode"),
        ({"sweep": {"sed": 3}}, "did you mean 'sweep.seed'"),
        ({"varry": {}}, "unknown table [varry]"),
        ({"vary": {"blades": [2.5]}}, "'blades' item 0 must be a whole number"),
        ({"vary": {"hub.radius": ["big"]}}, "'hub.radius' item 0 must be a finite number"),
        (
            {
                "vary": {"blades": {"low": 2.0, "high": 4.0}},
                "sweep": {"mode": "random", "samples": 2},
            },
            "'blades' low must be a whole number",
        ),
        ({"vary": {"centerline.p2[3]": [1.0]}}, "index 3 is out of range"),
        ({"vary": {"hub.radius[0]": [1.0]}}, "not a vector"),
        ({"vary": {"centerline.p2": [1.0]}}, "must be a list of 3 finite numbers"),
        (
            {"vary": {"centerline.p2": [[1, 2, 3]], "centerline.p2[1]": [1.0]}},
            "set the same parameter",
        ),
        (
            {"vary": {"hub.radius": {"start": 9.0, "stop": 8.0, "step": 1.0}}},
            "must not be below start",
        ),
        ({"vary": {"hub.radius": {"start": 9.0, "step": 1.0}}}, "use {start, stop, step}"),
        (
            {
                "vary": {"hub.radius": {"low": 9.0, "high": 9.0}},
                "sweep": {"mode": "random", "samples": 2},
            },
            "must be below high",
        ),
        ({"vary": {"name": ["a", "b"]}}, "the name cannot be varied"),
        ({"vary": {"hub": [1.0]}}, "is a table"),
        ({"vary": {"blades": []}}, "empty list"),
        # the schema's ranges and choices, checked before any design is made
        (
            {"vary": {"hub.radius": [10.0, 0.1]}},
            "vary.'hub.radius' item 1: hub.radius = 0.1 is out of range; allowed [0.5, 1000] mm",
        ),
        (
            {"vary": {"blades": {"start": 0, "stop": 3, "step": 1}}},
            "blades = 0 is out of range; allowed [1, 12]",
        ),
        (
            {"vary": {"transforms.scale_x[4]": [6.0, 2e4]}},
            "transforms.scale_x[4] = 20000 is out of range",
        ),
        (
            {"vary": {"centerline.frame": ["frenet", "spiral"]}},
            "'spiral' is not allowed; choose one of frenet, rotation_minimizing",
        ),
        (
            {
                "vary": {"airfoil.thickness": {"low": 0.0, "high": 0.5}},
                "sweep": {"mode": "random", "samples": 2},
            },
            "airfoil.thickness = 0 is out of range; allowed (0, 1]",
        ),
        ({"base": {"hub": {"radius": -1.0}}}, "[base] hub.radius = -1 is out of range"),
        ({"base": {"config": "missing.toml"}}, "base.config: cannot read configuration"),
    ],
)
def test_bad_sweep_files_raise_one_line_parameter_errors_naming_the_key(data, message):
    with pytest.raises(ParameterError) as caught:
        parse_sweep(data, source="sweep file 'x.toml'")
    text = str(caught.value)
    assert message in text and "\n" not in text and text.startswith("sweep file 'x.toml': ")


def test_cli_refuses_a_bad_sweep_file_with_exit_2(tmp_path, capsys):
    sweep = write(tmp_path / "bad.toml", '[vary]\n"hub.radiu" = [9.0]\n')
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "did you mean 'hub.radius'" in err and "\n" not in err
    assert not (tmp_path / "out").exists()
    assert main(["sweep", str(tmp_path / "missing.toml")]) == 2
    write(tmp_path / "ok.toml", "[vary]\nblades = [2]\n")
    assert (
        exit_code(
            ["sweep", str(tmp_path / "ok.toml"), "--workers", "0", "--out", str(tmp_path / "o")]
        )
        == 2
    )


# -- one design, in this process
# ---------------------------------------------------------------------


def _task(tmp_path: Path, **changes) -> DesignTask:
    design = generate_designs(
        parse_sweep({"base": LIGHT, "vary": {key: [value] for key, value in changes.items()}})
    )[0]
    return DesignTask(
        design.design_id, design.parameters, str(tmp_path / design.design_id), stl=False
    )


def test_run_design_records_a_refusal_and_never_raises(tmp_path):
    # the blade's root sticks out of the hub: GeometryError
    task = _task(tmp_path, **{"hub.radius": 3.0})
    result = run_design(task)
    assert result.outcome is Outcome.REFUSED and "hub" in result.reason
    record = json.loads((Path(task.folder) / REFUSAL_FILE).read_text())
    assert (
        record["status"] == "refused"
        and record["error"] == "GeometryError"
        and record["reason"] == result.reason
    )
    parameters = json.loads(json.dumps(task.parameters))
    parameters["airfoil"]["thickness"] = 1.5  # a sweep file refuses it; a task may still carry it
    out_of_range = DesignTask("out_of_range", parameters, str(tmp_path / "out_of_range"), stl=False)
    assert run_design(out_of_range).outcome is Outcome.REFUSED
    assert "airfoil.thickness = 1.5 is out of range" in run_design(out_of_range).reason


@pytest.mark.parametrize(
    "error, status",
    [
        (KernelError("the loft failed"), "failed"),
        (MemoryError("no memory"), "error"),
        (RuntimeError("boom"), "error"),
    ],
)
def test_run_design_records_kernel_failures_and_unexpected_errors(
    tmp_path, monkeypatch, error, status
):
    import torus_cad.propeller

    def broken(params):
        raise error

    monkeypatch.setattr(torus_cad.propeller, "build_propeller", broken)
    task = _task(tmp_path, blades=3)
    result = run_design(task)
    assert result.outcome == status and str(error) in result.reason
    assert json.loads((Path(task.folder) / FAILURE_FILE).read_text())["status"] == status


# -- whole sweeps: local pool, Dask, resume
# ------------------------------------------------------------


@pytest.fixture(scope="module")
def small_sweep(tmp_path_factory) -> Path:
    return write(tmp_path_factory.mktemp("sweep_file") / "small.toml", SMALL_SWEEP)


@pytest.fixture(scope="module")
def local_run(small_sweep, tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    return run_sweep(load_sweep(small_sweep), out, workers=2, progress=False)


def test_local_sweep_builds_every_design_into_its_folder(local_run):
    assert [row["status"] for row in local_run.rows] == ["valid"] * 6 and local_run.built == 6
    for design, row in zip(local_run.designs, local_run.rows):
        folder = local_run.out_dir / DESIGNS_DIR / design.design_id
        assert sorted(path.name for path in folder.iterdir()) == [
            f"{design.design_id}.json",
            f"{design.design_id}.step",
        ]
        report = json.loads((folder / f"{design.design_id}.json").read_text())
        assert report["parameters"] == design.parameters
        assert row["volume_mm3"] == report["volume_mm3"] > 0 and row["valid"] is True
        assert row["time_fuse_s"] > 0 and row["time_stl_write_s"] is None
    table = read_table(local_run.out_dir / "results.csv", drop_times=False)
    assert [row["id"] for row in table] == [d.design_id for d in local_run.designs]
    assert {
        "blades",
        "airfoil.max_camber",
        "volume_mm3",
        "surface_area_mm2",
        "spin_axis_inertia_g_mm2",
        "time_fuse_s",
        "time_total_s",
        "reason",
        "valid",
    } <= set(table[0])
    assert [(row["blades"], row["airfoil.max_camber"]) for row in table][:2] == [
        ("2", "0.0"),
        ("2", "0.02"),
    ]
    manifest = json.loads((local_run.out_dir / "sweep.json").read_text())
    assert [d["id"] for d in manifest["designs"]] == [d.design_id for d in local_run.designs]


def test_the_table_is_also_written_as_parquet_when_pyarrow_is_installed(local_run):
    from pyarrow import parquet

    table = parquet.read_table(local_run.tables["parquet"]).to_pylist()
    assert [row["id"] for row in table] == [d.design_id for d in local_run.designs]
    assert [row["volume_mm3"] for row in table] == [row["volume_mm3"] for row in local_run.rows]
    assert all(isinstance(row["blades"], int) and row["valid"] is True for row in table)


def test_dask_local_cluster_gives_the_same_table_as_the_local_pool(
    local_run, small_sweep, tmp_path
):
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        result = run_sweep(
            load_sweep(small_sweep), tmp_path / "dask", client=client, progress=False
        )
    assert result.backend.startswith("dask") and result.built == 6
    assert read_table(tmp_path / "dask" / "results.csv") == read_table(
        local_run.out_dir / "results.csv"
    )


def test_resuming_rebuilds_only_the_designs_whose_files_are_gone(local_run, small_sweep, tmp_path):
    out = tmp_path / "resume"
    shutil.copytree(local_run.out_dir, out)
    designs = local_run.designs
    shutil.rmtree(out / DESIGNS_DIR / designs[4].design_id)  # one design's folder gone
    # another's STEP
    (out / DESIGNS_DIR / designs[1].design_id / f"{designs[1].design_id}.step").unlink()
    kept = out / DESIGNS_DIR / designs[0].design_id / f"{designs[0].design_id}.json"
    before = kept.stat().st_mtime_ns
    result = run_sweep(load_sweep(small_sweep), out, workers=2, progress=False)
    assert (result.skipped, result.built) == (4, 2)
    assert kept.stat().st_mtime_ns == before
    assert read_table(out / "results.csv") == read_table(local_run.out_dir / "results.csv")
    again = run_sweep(load_sweep(small_sweep), out, workers=2, progress=False)  # nothing left to do
    assert (again.skipped, again.built, again.backend) == (6, 0, "nothing to run")


def test_cli_sweep_with_an_impossible_design_records_the_refusal_and_finishes_the_others(
    tmp_path, capsys
):
    sweep = write(
        tmp_path / "mixed.toml",
        """
        [base.resolution]
        sections = 16
        points = 32
        [vary]
        "hub.radius" = [10.0, 3.0]   # the blade's root does not fit in a 3 mm hub
        """,
    )
    out = tmp_path / "out"
    # refusals alone: 0
    assert main(["sweep", str(sweep), "--out", str(out), "--workers", "2", "--no-stl"]) == 0
    summary = capsys.readouterr().out
    assert "1 valid, 1 refused, 0 failed" in summary and "refused" in summary.splitlines()[-1]
    table = read_table(out / "results.csv")
    assert [(row["hub.radius"], row["status"], row["valid"]) for row in table] == [
        ("10.0", "valid", "True"),
        ("3.0", "refused", "False"),
    ]
    assert "hub" in table[1]["reason"] and table[1]["volume_mm3"] == ""
    refused = out / DESIGNS_DIR / table[1]["id"]
    assert [path.name for path in refused.iterdir()] == [REFUSAL_FILE]
    # a rerun retries nothing: the refusal is recorded, the other design is done
    assert main(["sweep", str(sweep), "--out", str(out), "--no-stl", "-q"]) == 0
    assert capsys.readouterr().out == ""


# -- a worker process that dies --------------------------------------------------------------------


def test_a_worker_crash_is_recorded_for_its_design_and_the_others_go_on(tmp_path):
    designs = generate_designs(parse_sweep({"vary": {"blades": [2, 3, 4, 5, 6, 7, 8]}}))
    tasks = [
        DesignTask(d.design_id, d.parameters, str(tmp_path / d.design_id), stl=False)
        for d in designs
    ]
    results = {}
    run_tasks(
        tasks,
        lambda task, result: results.__setitem__(task.parameters["blades"], result),
        lambda: LocalPool(2),
        window=4,
        job=crash_on_four_or_six_blades,
    )
    assert {blades: result.outcome.value for blades, result in results.items()} == {
        2: "valid",
        3: "valid",
        4: "crash",
        5: "valid",
        6: "crash",
        7: "valid",
        8: "valid",
    }
    assert "worker process died" in results[4].reason
    assert (
        json.loads((tmp_path / tasks[2].design_id / FAILURE_FILE).read_text())["status"] == "crash"
    )


def test_an_unreachable_scheduler_is_a_batch_error(tmp_path, small_sweep, monkeypatch):
    pytest.importorskip("dask.distributed")
    monkeypatch.setattr("torus_cad.batch.cluster.CONNECT_TIMEOUT_S", 1.0)
    with pytest.raises(BatchError, match="cannot connect to the Dask scheduler"):
        run_sweep(
            load_sweep(small_sweep), tmp_path / "out", scheduler="tcp://127.0.0.1:1", progress=False
        )


# -- budgets and numbers that are not numbers (issue 17)
# ------------------------------------------------


def _sweep_cli(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "torus_cad", "sweep", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


@pytest.mark.parametrize(
    "vary, mode, expected",
    [
        ('"hub.radius" = {start = 9.0, stop = 12.0, num = 100000000}', "", "100,000,000 designs"),
        (
            '"hub.radius" = {low = 9.0, high = 12.0}',
            'mode = "random"\nsamples = 3000000',
            "3,000,000 designs",
        ),
        (
            '"hub.radius" = {start = 5.0, stop = 15.0, step = '
            '0.002}\n"hub.length" = {start = 10.0, stop = 30.0, step = 0.004}',
            "",
            "25,010,001 designs = 5,001 (hub.radius) x 5,001 (hub.length)",
        ),
        ('"hub.radius" = {start = 9.0, stop = 10.0, step = 5e-324}', "", "more than 1e308 designs"),
    ],
)
def test_a_sweep_over_the_budget_is_refused_before_any_design_is_made(
    tmp_path, vary, mode, expected
):
    sweep = write(tmp_path / "huge.toml", f"[sweep]\n{mode}\n[vary]\n{vary}\n")
    done = _sweep_cli(str(sweep), "--out", str(tmp_path / "out"), timeout=60)
    assert done.returncode == 2, done.stderr
    message = done.stderr.strip()
    assert (
        "\n" not in message and expected in message and "the limit is 1,000,000 designs" in message
    )
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "vary, mode, expected",
    [
        (
            '"hub.radius" = {start = 9.0, stop = nan, step = 0.5}',
            "",
            "'hub.radius' stop must be a finite number in [0.5, 1000] mm, got nan",
        ),
        (
            '"hub.radius" = {start = 9.0, stop = inf, step = 0.5}',
            "",
            "'hub.radius' stop must be a finite number in [0.5, 1000] mm, got inf",
        ),
        (
            "blades = {start = 2, stop = nan, step = 1}",
            "",
            "'blades' stop must be a whole number in [1, 12], got nan",
        ),
        (
            '"hub.radius" = [9.0, nan]',
            "",
            "'hub.radius' item 1 must be a finite number in [0.5, 1000] mm, got nan",
        ),
        (
            '"hub.radius" = {low = -inf, high = inf}',
            'mode = "random"\nsamples = 4',
            "'hub.radius' low must be a finite number in [0.5, 1000] mm, got -inf",
        ),
        ('"centerline.p2" = [[25.0, 3.0, inf]]', "", "must be a list of 3 finite numbers"),
    ],
)
def test_not_a_number_in_a_sweep_is_bad_input(tmp_path, vary, mode, expected):
    sweep = write(tmp_path / "nan.toml", f"[sweep]\n{mode}\n[vary]\n{vary}\n")
    done = _sweep_cli(str(sweep), "--out", str(tmp_path / "out"), timeout=60)
    assert done.returncode == 2, done.stderr
    assert "\n" not in done.stderr.strip() and expected in done.stderr
    assert not (tmp_path / "out").exists()


def _no_nan(constant: str) -> float:
    raise AssertionError(f"{constant} in a JSON file")


def test_sweep_json_is_strict_json(local_run):
    manifest = json.loads((local_run.out_dir / "sweep.json").read_text(), parse_constant=_no_nan)
    assert manifest["vary"]["blades"] == [2, 3] and len(manifest["designs"]) == 6


# -- exit codes ------------------------------------------------------------------------------------


def test_a_sweep_whose_designs_error_exits_1(tmp_path):
    sweep = write(
        tmp_path / "s.toml",
        "[base.resolution]\nsections = 16\npoints = 32\n[sweep]\nstl = false\n"
        "[vary]\nblades = [2, 3]\n",
    )
    out = tmp_path / "out"
    out.mkdir()
    # every design errors
    (out / DESIGNS_DIR).write_text("a file where the designs' folders should go\n")
    done = _sweep_cli(str(sweep), "--out", str(out), "--workers", "1")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "0 valid, 0 refused, 0 failed, 2 errors" in done.stdout
    assert [row["status"] for row in read_table(out / "results.csv")] == ["error", "error"]


# -- signals ---------------------------------------------------------------------------------------


def _state(pid: int) -> str:
    """The process's state letter from /proc ('' when it is gone; 'Z' for a zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return ""


def _children(pid: int) -> list[int]:
    kids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == pid:
                kids.append(int(stat.parent.name))
        except (OSError, IndexError, ValueError):
            continue
    return kids


def _descendants(pid: int) -> list[int]:
    found, todo = [], [pid]
    while todo:
        for child in _children(todo.pop()):
            found.append(child)
            todo.append(child)
    return found


def _wait_for(condition, seconds: float, what: str) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


_DRIVER = """
import sys
sys.path.insert(0, {tests!r})
from batch_jobs import announce_and_sleep
from torus_cad.batch import load_sweep, run_sweep

if __name__ == "__main__":
    run_sweep(load_sweep(sys.argv[1]), sys.argv[2], workers=2, job=announce_and_sleep, progress=False)
"""  # noqa: E501 (code or text written out verbatim)


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_sweep_workers_die_with_the_sweep_when_it_is_killed(tmp_path):
    """SIGKILL to the sweep's process: its fork server and workers (each in a ten-minute design) go
    too."""
    driver = write(tmp_path / "driver.py", _DRIVER.format(tests=str(Path(__file__).parent)))
    sweep = write(tmp_path / "s.toml", "[vary]\nblades = [2, 3, 4, 5]\n")
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, str(driver), str(sweep), str(out)])
    try:
        _wait_for(
            lambda: len(list((out / DESIGNS_DIR).glob("*.started"))) == 2,
            180,
            "two designs to start",
        )
        workers = [int(path.read_text()) for path in (out / DESIGNS_DIR).glob("*.started")]
        helpers = _descendants(process.pid)
        assert set(workers) <= set(helpers)
        process.kill()  # and not reaped yet: the workers must not wait for its pid to disappear
        _wait_for(
            lambda: all(_state(pid) in ("", "Z") for pid in helpers), 10, "the workers to die"
        )
        process.wait(30)
    finally:
        if process.poll() is None:
            process.kill()
        for pid in _descendants(process.pid):
            os.kill(pid, signal.SIGKILL)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_the_sweep_with_one_line_its_exit_code_and_the_table(tmp_path, signum):
    sweep = write(
        tmp_path / "s.toml",
        "[base.resolution]\nsections = 16\npoints = 32\n[sweep]\nstl = false\n"
        '[vary]\nblades = [2, 3, 4, 5, 6]\n"airfoil.max_camber" = [0.0, 0.02]\n',
    )
    out = tmp_path / "out"
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "torus_cad",
            "sweep",
            str(sweep),
            "--out",
            str(out),
            "--workers",
            "1",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        _wait_for(lambda: any((out / DESIGNS_DIR).glob("*/*.json")), 180, "a first design")
        helpers = _descendants(process.pid)
        process.send_signal(signum)
        stdout, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 128 + signum, stderr
    name = signal.Signals(signum).name
    assert (
        stdout == ""
        and len(stderr.strip().splitlines()) == 1
        and f"interrupted by {name}" in stderr
    )
    statuses = [row["status"] for row in read_table(out / "results.csv")]
    assert len(statuses) == 10 and "valid" in statuses and "pending" in statuses
    _wait_for(lambda: all(_state(pid) in ("", "Z") for pid in helpers), 10, "the workers to stop")


def test_workers_are_capped_at_the_available_cores_with_one_line(monkeypatch):
    import os

    from torus_cad.batch.runner import available_cores, capped_workers

    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1})  # a process allowed on 2 cores
    assert available_cores() == 2
    lines: list[str] = []
    assert capped_workers(100_000, 9, warn=lines.append) == 2
    assert lines == [
        "--workers 100000 capped at the 2 cores available (--oversubscribe to start 9)"
    ]
    assert (
        capped_workers(100_000, 9, oversubscribe=True, warn=lines.append) == 9 and len(lines) == 1
    )
    assert capped_workers(None, 9) == 2 and capped_workers(8, 1) == 1 and capped_workers(2, 5) == 2
    assert len(lines) == 1
