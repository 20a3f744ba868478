"""Robustness: random in-range designs, refusals before the kernel, and interrupted exports.

Kept fast: low resolution, few hypothesis examples, no deadline. The same sampler and the same
batch runner drive ``scripts/fuzz.py`` (N = 1000 there).
"""

from __future__ import annotations

import copy
import dataclasses
import faulthandler
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from batch_jobs import FAULT_KEY, PID_FILE_KEY, faulty
from conftest import HOOKED_TRAILING_EDGE_DESIGN
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import torus_cad
from studies import fuzz as fuzz_module
from studies.fuzz import (
    UNIT_DIMENSION,
    design_from_unit,
    fuzz_range,
    fuzz_tasks,
    random_design_dict,
)
from torus_cad.batch import DesignResult, DesignTask, LocalPool, Outcome, run_design, run_tasks
from torus_cad.cli import main
from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.errors import GeometryError, ParameterError
from torus_cad.geometry.analysis import feasibility
from torus_cad.geometry.blade.frames import Frames
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.schema import Bounds

LOW = {"sections": (24, 32), "points": (24, 32)}  # low points; sections near the default
unit_vectors = st.lists(st.floats(0.0, 1.0), min_size=UNIT_DIMENSION, max_size=UNIT_DIMENSION)


class _Watchdog:
    """Kill the test process (with a traceback dump) if one design hangs: a hang must fail, not
    stall CI."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds

    def __enter__(self) -> None:
        faulthandler.dump_traceback_later(self.seconds, exit=True)

    def __exit__(self, *exc) -> None:
        faulthandler.cancel_dump_traceback_later()


# -- properties over random designs ------------------------------------------------------------


@settings(
    max_examples=10, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(unit_vectors)
def test_every_design_is_a_valid_solid_or_a_clear_refusal(u):
    try:
        params = design_from_unit(u, **LOW)
    except ParameterError as error:  # a rule tying fields together refused it: also a clear refusal
        assert "\n" not in str(error)
        return
    with _Watchdog(120):
        result = run_design(DesignTask(params.name, params.to_dict(), write=False))
    assert result.outcome.acceptable, f"{result.outcome}: {result.reason}\n{result.detail}"
    if result.outcome is Outcome.REFUSED:
        assert result.reason and "\n" not in result.reason


@settings(
    max_examples=3,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(unit_vectors)
def test_cli_gives_files_or_exit_2_never_a_traceback(tmp_path_factory, u):
    folder = tmp_path_factory.mktemp("cli")
    try:
        params = design_from_unit(u, **LOW)
    except ParameterError:
        return
    config = folder / "design.toml"
    config.write_text(params.to_toml())
    out_dir = folder / "out"
    import contextlib
    import io

    err = io.StringIO()
    with _Watchdog(120), contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(["build", str(config), "--out", str(out_dir), "--no-stl"])
    assert code in (0, 2), err.getvalue()
    if code == 2:
        assert len(err.getvalue().strip().splitlines()) == 1
        assert not out_dir.exists() or not any(out_dir.iterdir())
    else:
        from torus_cad.kernel.checks import is_valid_closed_solid
        from torus_cad.kernel.step_readback import read_step

        assert is_valid_closed_solid(read_step(out_dir / f"{params.name}.step"))


def test_sampler_stays_in_range_and_is_reproducible():
    for seed in range(200):
        design = random_design_dict(seed)
        assert design == random_design_dict(seed)
        try:
            PropellerParameters.from_dict(design)
        except ParameterError as error:  # only rules that tie fields together may refuse
            assert "is out of range" not in str(error) and "must be" not in str(error), str(error)


def test_workshop_draws_add_only_workshop_features_and_stay_in_range():
    """``fuzz.py --workshop``: the same design as without, plus in-range workshop features."""
    workshop_keys = {
        "handedness",
        "hub.bore_diameter",
        "hub.bore_flat_depth",
        "hub.set_screw_diameter",
        "hub.chamfer",
        "airfoil.trailing_edge_thickness",
    }
    drawn = set()
    for seed in range(100):
        plain, design = (
            _flat(random_design_dict(seed)),
            _flat(random_design_dict(seed, workshop=True)),
        )
        changed = {key for key in design if design[key] != plain.get(key)}
        assert changed <= workshop_keys, changed
        drawn |= changed
        try:
            PropellerParameters.from_dict(random_design_dict(seed, workshop=True))
        except ParameterError as error:  # only rules that tie fields together may refuse
            assert "is out of range" not in str(error) and "must be" not in str(error), str(error)
    assert drawn == workshop_keys  # 100 seeds switch every feature on at least once


#: The fields the sampler draws directly, each within the schema's fuzz range.
FUZZED = (
    "blades",
    "phase_deg",
    "hub.radius",
    "hub.length",
    "airfoil.max_camber",
    "airfoil.camber_position",
    "airfoil.thickness",
    "airfoil.pivot",
    "resolution.sections",
    "resolution.points",
    "export.stl_linear_deflection",
    "export.stl_angular_deflection",
)


def _flat(design: dict, prefix: str = "") -> dict:
    flat = {}
    for key, value in design.items():
        flat.update(
            _flat(value, f"{prefix}{key}.") if isinstance(value, dict) else {prefix + key: value}
        )
    return flat


def test_sampler_ranges_come_from_the_schema(monkeypatch):
    draws = [_flat(random_design_dict(seed)) for seed in range(300)]
    for key in FUZZED:
        low, high = fuzz_range(key)
        values = [draw[key] for draw in draws]
        assert low <= min(values) and max(values) <= high, key
        assert max(values) - min(values) > 0.5 * (high - low), key  # the sampler covers the range
    # narrowing a field's fuzz range in its declaration narrows what the sampler draws
    spec = fuzz_module._SPECS["hub.radius"]
    monkeypatch.setitem(
        fuzz_module._SPECS, "hub.radius", dataclasses.replace(spec, fuzz=Bounds(11.0, 12.0))
    )
    assert {
        11.0 <= _flat(random_design_dict(seed))["hub.radius"] <= 12.0 for seed in range(50)
    } == {True}


def _process_gone(pid: int) -> bool:
    """No such process, or only its zombie (killed, not yet reaped)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    return state in ("Z", "X")


def _outcomes(designs: list[dict], pool: Callable[[], LocalPool]) -> dict[str, DesignResult]:
    results: dict[str, DesignResult] = {}
    run_tasks(
        fuzz_tasks(designs, write=True, stl=True),
        lambda task, result: results.__setitem__(task.design_id, result),
        pool,
        window=2,
        job=faulty,
    )
    return results


def test_the_runner_counts_a_hang_and_a_crash_and_goes_on(tmp_path):
    """The fuzz runner survives a design that never finishes and a worker that dies; files are read
    back.

    The time limit is a wide multiple of what the good design takes here and now (its wall time in a
    worker of a pool without a limit), with a floor: the good design runs in a worker that replaced
    the crashed one while the other test worker may be running OpenFOAM on both cores, and a limit
    of four times an idle baseline (6 s floor) once timed it out in CI. Whatever the limit, the hang
    must end as a timeout with its worker killed.
    """
    good = PropellerParameters().with_values({"resolution.points": 24, "name": "good"}).to_dict()
    # also starts the fork server (imports the kernel)
    baseline = _outcomes([good], lambda: LocalPool(1))["good"]
    assert baseline.outcome is Outcome.VALID
    limit_s = max(20.0, 10.0 * baseline.seconds)
    pid_file = tmp_path / "hang.pid"
    designs = [
        {"name": "hang", FAULT_KEY: "hang", PID_FILE_KEY: str(pid_file)},
        {"name": "crash", FAULT_KEY: "crash"},
        {"name": "bad", "blades": "x"},
        good,
    ]
    # a hang the pool does not stop fails the run instead of stalling it
    with _Watchdog(limit_s + 600.0):
        results = _outcomes(designs, lambda: LocalPool(1, time_limit_s=limit_s))
    assert {name: result.outcome for name, result in results.items()} == {
        "hang": Outcome.TIMEOUT,
        "crash": Outcome.CRASH,
        "bad": Outcome.REFUSED,
        "good": Outcome.VALID,
    }
    assert f"({limit_s} s)" in results["hang"].reason
    hung_pid = int(pid_file.read_text())
    deadline = time.monotonic() + 60.0
    # killed; reaping may lag a little
    while not _process_gone(hung_pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _process_gone(hung_pid), f"the hung worker {hung_pid} is still running"


# -- refusals before the kernel, each with its reason -------------------------------------------

REFUSALS = {
    "fold": ({"transforms.scale_x": [0.0, 0.0, -32.0, 32.0, 6.0]}, "folds over itself"),
    "root_outside_inset": (
        {"transforms.scale_x": [0.0, 0.0, -16.0, 16.0, 20.0]},
        "root (s = 0) section leaves",
    ),
    "end_face": ({"centerline.p2": [25.0, -15.0, 2.0]}, "leaves the hub through an end face"),
    "sparse_sections": ({"resolution.sections": 4}, "resolution.sections = 4 is too few"),
    # alpha = 20 + 1600 s^2 (1 - s)^2 degrees: 100 degrees of twist at mid-span, ends unchanged
    "twist_between_sections": (
        {
            "resolution.sections": 8,
            "transforms.angle_of_attack": [1600.0, -3200.0, 1600.0, 0.0, 20.0],
        },
        "too few",
    ),
}


@pytest.mark.parametrize("name", list(REFUSALS))
def test_unsound_design_is_refused_before_the_kernel(name):
    changes, reason = REFUSALS[name]
    params = PropellerParameters().with_values(changes)
    stages: list[str] = []
    from torus_cad.propeller import build_propeller

    with pytest.raises(GeometryError) as caught:
        build_propeller(params, progress=stages.append)
    message = str(caught.value)
    assert reason in message
    assert "\n" not in message
    assert "wires" not in stages and "loft" not in stages and "fuse" not in stages


def test_refused_design_exits_2_with_one_line_and_no_files(tmp_path, capsys):
    out_dir = tmp_path / "out"
    code = main(["build", "--set", "transforms.scale_x=[0,0,-32,32,6]", "--out", str(out_dir)])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "folds over itself" in err
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_default_design_passes_every_check_with_margin():
    params = PropellerParameters()
    surface = sampled_blade_surface(params)
    feasibility.check_feasible(propeller_geometry(params), surface)
    grid, step = feasibility.tube_grid(len(surface.s))
    fine = feasibility.sample_tube(
        propeller_geometry(params), propeller_geometry(params).centerline(), grid, surface.t
    )
    assert feasibility.fold_ratio(fine)[0] < 0.95
    assert (
        feasibility.resolution_deviation(surface, fine, step)[0]
        < feasibility.RESOLUTION_DEVIATION_LIMIT / 3
    )


def test_interleaved_blades_are_not_refused():
    """Toroidal blades nest: six default blades clear each other although each spans 100 > 60
    degrees."""
    params = PropellerParameters().with_values({"blades": 6})
    feasibility.check_feasible(propeller_geometry(params), sampled_blade_surface(params))


def _circle_tube(centers: np.ndarray, radius: float, points: int = 24) -> feasibility.Tube:
    """A tube of circular sections around a polyline (frames by finite differences)."""
    tangent = np.gradient(centers, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    helper = np.where(np.abs(tangent[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    normal = np.cross(helper, tangent)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    binormal = np.cross(tangent, normal)
    angle = np.linspace(0.0, 2 * np.pi, points, endpoint=False)
    planar = np.broadcast_to(
        np.stack([radius * np.cos(angle), radius * np.sin(angle)], -1), (len(centers), points, 2)
    ).copy()
    surface = (
        centers[:, None] + planar[..., :1] * normal[:, None] + planar[..., 1:] * binormal[:, None]
    )
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(centers, axis=0), axis=1))])
    frames = Frames(np.linspace(0, 1, len(centers)), centers, tangent, normal, binormal)
    return feasibility.Tube(frames, planar, surface, np.zeros_like(centers), arc)


def test_self_intersection_is_found():
    # a helix that climbs less than its tube's width per turn
    turns = np.linspace(0.0, 2.5 * np.pi, 160)
    helix = np.stack([30 * np.cos(turns), 30 * np.sin(turns), 0.5 * turns], -1)
    with pytest.raises(GeometryError, match="intersects itself"):
        feasibility.check_no_self_intersection(
            propeller_geometry(PropellerParameters()).hub, _circle_tube(helix, 3.0)
        )
    # well apart per turn
    apart = np.stack([30 * np.cos(turns), 30 * np.sin(turns), 8.0 * turns], -1)
    feasibility.check_no_self_intersection(
        propeller_geometry(PropellerParameters()).hub, _circle_tube(apart, 3.0)
    )


def test_blades_running_into_each_other_are_found():
    # radial rods, 8 mm thick
    rod = np.stack([np.linspace(12.0, 30.0, 40), np.zeros(40), np.zeros(40)], -1)
    # 30 degrees apart: axes 6.2 mm apart at r = 12
    crowded = PropellerParameters().with_values({"blades": 12})
    with pytest.raises(GeometryError, match="intersect each other"):
        feasibility.check_blades_clear(propeller_geometry(crowded), _circle_tube(rod, 4.0))
    feasibility.check_blades_clear(
        propeller_geometry(PropellerParameters().with_values({"blades": 3})), _circle_tube(rod, 4.0)
    )


def test_hooked_trailing_edge_with_too_few_points_is_refused():
    """Camber far aft on a thin, flattened section: 25 points leave its curve crossing itself at the
    trailing edge (scripts/fuzz.py design fuzz_334, which failed in the fuse); 48 points build."""
    design = copy.deepcopy(HOOKED_TRAILING_EDGE_DESIGN)
    from torus_cad.propeller import build_propeller

    with pytest.raises(GeometryError, match=r"resolution\.points = 25 is too few"):
        build_propeller(PropellerParameters.from_dict(design))


# -- an interrupted export leaves no partial file -------------------------------------------------

_WRITER = textwrap.dedent("""
    import sys
    from pathlib import Path
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.kernel.writers.stl import write_stl
    kind, out = sys.argv[1], Path(sys.argv[2])
    params = PropellerParameters().with_values({"resolution.points": 40})
    solid = build_propeller(params).solid
    print("built", flush=True)
    for _ in range(1000):  # write again and again until killed
        if kind == "stl":
            write_stl(solid, out, 0.005, 0.1)  # ~50 000 triangles: 2.6 MB per write
        else:
            write_step(solid, out, "killed", check_readback=False)
""")


@pytest.mark.parametrize("kind", ["stl", "step"])
def test_killed_mid_write_leaves_no_partial_file(tmp_path, kind):
    target = tmp_path / f"propeller.{kind}"
    script = tmp_path / "writer.py"
    script.write_text(_WRITER)
    process = subprocess.Popen(
        [sys.executable, str(script), kind, str(target)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert process.stdout.readline().strip() == "built"
        deadline = time.monotonic() + 120
        caught_mid_write = False
        while time.monotonic() < deadline:
            temps = list(tmp_path.glob(f".{target.name}.tmp-*"))
            if (
                temps
                and not target.exists()
                and any(t.exists() and t.stat().st_size > 0 for t in temps)
            ):
                caught_mid_write = True
                break
            if target.exists():  # a write finished: remove it and catch the next one in flight
                target.unlink()
            time.sleep(0.0005)
        os.kill(process.pid, signal.SIGKILL)
        process.wait(30)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(30)
    assert process.returncode == -signal.SIGKILL
    assert caught_mid_write, "never saw a write in flight"
    # Between our check and the kill a write may have completed and renamed; such a file is whole.
    if target.exists():
        if kind == "stl":
            data = target.read_bytes()
            assert len(data) == 84 + 50 * int.from_bytes(data[80:84], "little")
        else:
            assert target.read_text(errors="replace").rstrip().endswith("END-ISO-10303-21;")
    # The next export removes the stale temp file and leaves exactly the final file.
    from torus_cad.runtime.files import atomic_path

    with atomic_path(target) as temp:
        temp.write_text("ok")
    assert target.read_text() == "ok"
    assert not list(tmp_path.glob(f".{target.name}.tmp-*"))


def test_the_product_never_imports_the_studies():
    """The fuzz sampler and the function-space study live in studies/, outside the installed
    package."""
    code = (
        "import sys, torus_cad.cli, torus_cad.batch, "
        "torus_cad.propeller, torus_cad.preview.picture; "
        "print(sorted(name for name in sys.modules if name.startswith('studies')))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True
    )
    assert done.stdout.strip() == "[]"
    assert not (Path(torus_cad.__file__).parent / "studies").exists()
