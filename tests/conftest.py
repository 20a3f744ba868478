"""Shared fixtures: the default design, a light design for fast kernel tests, and built
propellers."""

from __future__ import annotations

import json
import signal
import subprocess
import tomllib
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from torus_cad.parameters import PropellerParameters

EXAMPLES_DIR = Path(__file__).resolve().parent.parent / "examples"


def _is_design(path: Path) -> bool:
    """A design file, not a sweep or an optimisation study (those live in examples/ too)."""
    document = tomllib.loads(path.read_text(encoding="utf-8"))
    return not ({"sweep", "study"} & document.keys())


#: Every design file shipped in examples/ (sweeps and studies left out), sorted.
SHIPPED_DESIGNS = sorted(path for path in EXAMPLES_DIR.glob("*.toml") if _is_design(path))

#: Camber far aft on a thin, flattened section: with 25 points its curve crosses itself at the
#: trailing edge (scripts/fuzz.py design fuzz_334); the section fit refuses it before the kernel.
HOOKED_TRAILING_EDGE_DESIGN: dict = {
    "name": "hooked",
    "blades": 4,
    "phase_deg": -66.88,
    "hub": {"radius": 6.9435, "length": 17.2294},
    "airfoil": {
        "max_camber": 0.0553,
        "camber_position": 0.8961,
        "thickness": 0.2224,
        "camber_normal": False,
        "pivot": 0.2828,
    },
    "centerline": {
        "p2": [6.6187, 6.5621, 11.7937],
        "p3": [60.9186, 17.2106, 13.0448],
        "p4": [70.0547, 11.1791],
        "frame": "rotation_minimizing",
    },
    "transforms": {
        "angle_of_attack": [-13.8302, 16.3106, 20.0189, 0.0671, 47.4585],
        "scale_x": [6.2055, -12.411, -0.8573, 6.5329, 1.9422],
        "scale_y": [-2.5747, 5.1495, -6.3959, 4.1085, 0.3264],
    },
    "resolution": {"sections": 40, "points": 25},
}

#: The shared-intersection fuse and one general fuse integrate the same surfaces; their volumes,
#: each integrated to VOLUME_PRECISION, agree far below this (measured ~1e-9).
ROUTE_VOLUME_TOLERANCE = 1e-7
VOLUME_PRECISION = 1e-8


def assert_same_volume_as_general_fuse(propeller) -> None:
    """The propeller's solid has the volume of one general fuse of its hub and blades; same faces
    too."""
    from torus_cad.kernel.checks import single_valid_solid
    from torus_cad.kernel.fuse import fuse_all
    from torus_cad.kernel.mass_properties import precise_volume

    general = single_valid_solid(
        fuse_all(propeller.hub, propeller.blades).shape, "the general fuse"
    )
    assert precise_volume(propeller.solid, VOLUME_PRECISION) == pytest.approx(
        precise_volume(general, VOLUME_PRECISION), rel=ROUTE_VOLUME_TOLERANCE
    )
    assert len(propeller.solid.Faces()) == len(general.Faces())


def read_binary_stl(path: Path) -> np.ndarray:
    """Triangles of a binary STL file: ``(f, 3, 3)`` float32, mm."""
    data = path.read_bytes()
    count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
    assert len(data) == 84 + 50 * count, "binary STL length does not match its triangle count"
    records = np.frombuffer(
        data,
        dtype=np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")]),
        count=count,
        offset=84,
    )
    return records["vertices"].copy()


@pytest.fixture
def tmpfs(tmp_path) -> Iterator[Callable[[int], Path]]:
    """``tmpfs(size_kb)``: a small tmpfs mounted in ``tmp_path`` (needs root; the test is skipped
    where it cannot be mounted), unmounted afterwards: a disk that fills up."""
    mounted: list[Path] = []

    def mount(size_kb: int) -> Path:
        mount_point = tmp_path / f"disk{len(mounted)}"
        mount_point.mkdir()
        result = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(mount_point)],
            check=False,
            capture_output=True,
            text=True,
        )
        if result.returncode != 0:
            pytest.skip(f"cannot mount a small tmpfs: {result.stderr.strip()}")
        mounted.append(mount_point)
        return mount_point

    yield mount
    for mount_point in mounted:
        subprocess.run(["umount", "-l", str(mount_point)], check=False)


@pytest.fixture(scope="session")
def default_params() -> PropellerParameters:
    return PropellerParameters()


@pytest.fixture(scope="session")
def light_params() -> PropellerParameters:
    """A coarser default, for kernel tests that need a real solid but not the full resolution."""
    return PropellerParameters().with_values(
        {"resolution.sections": 16, "resolution.points": 48, "name": "light"}
    )


@pytest.fixture(scope="session")
def default_propeller(default_params):
    from torus_cad.propeller import build_propeller

    return build_propeller(default_params)


@pytest.fixture(scope="session")
def default_files(default_propeller, tmp_path_factory) -> dict[str, Path]:
    return default_propeller.write(tmp_path_factory.mktemp("default_build"))


#: The test tiers, chosen by measured duration (scripts/test_tiers.py writes the file): ``pytest -m
#: fast`` is the quick tier that touches every module, ``pytest -m long`` the multi-minute tests CI
#: leaves out.
TIERS = json.loads((Path(__file__).resolve().parent / "tiers.json").read_text(encoding="utf-8"))


def pytest_configure(config):
    """pytest-xdist's workers start with SIGINT ignored, and an ignored signal stays ignored in
    every program they start; the signal tests need what a shell gives a command: SIGINT's
    default."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def stale_tier_ids(
    tier_ids: set[str], collected: set[str], whole_files: set[str], root: Path
) -> list[str]:
    """The ids of ``tier_ids`` that name no test: their file is gone, or it was collected whole
    (listed in ``whole_files``) and holds no test ``collected`` under that id (a test renamed,
    removed or re-parametrised)."""
    return sorted(
        nodeid
        for nodeid in tier_ids
        if not (root / nodeid.split("::")[0]).is_file()
        or (nodeid.split("::")[0] in whole_files and nodeid not in collected)
    )


# before -k, -m and --deselect leave tests out: every test of a file is here
@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    fast, long = set(TIERS["fast"]), set(TIERS["long"])
    for item in items:
        if item.nodeid in fast:
            item.add_marker(pytest.mark.fast)
        if item.nodeid in long:
            item.add_marker(pytest.mark.long)
    root = Path(str(config.rootpath))
    named = {str((Path.cwd() / arg.split("::")[0]).resolve()) for arg in config.args if "::" in arg}
    whole = {
        item.nodeid.split("::")[0]
        for item in items  # files of which every test was collected
        if str((root / item.nodeid.split("::")[0]).resolve()) not in named
    }
    config.stale_tier_ids = stale_tier_ids(
        fast | long, {item.nodeid for item in items}, whole, root
    )


def pytest_runtest_setup(item):
    """Every test fails while tests/tiers.json names a test that does not exist (under pytest-xdist
    a collection error would not name the ids)."""
    stale = getattr(item.config, "stale_tier_ids", [])
    if stale:
        pytest.fail(
            f"tests/tiers.json names {len(stale)} test(s) that do not exist: {', '.join(stale[:5])}"
            f"{' ...' if len(stale) > 5 else ''} (scripts/test_tiers.py writes the file again)",
            pytrace=False,
        )
