"""Shared fixtures: the default design, a light design for fast kernel tests, and built propellers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from torus_cad.parameters import PropellerParameters

#: The shared-intersection fuse and one general fuse integrate the same surfaces; their volumes,
#: each integrated to VOLUME_PRECISION, agree far below this (measured ~1e-9).
ROUTE_VOLUME_TOLERANCE = 1e-7
VOLUME_PRECISION = 1e-8


def assert_same_volume_as_general_fuse(propeller) -> None:
    """The propeller's solid has the volume of one general fuse of its hub and blades; same faces too."""
    from torus_cad.kernel.checks import precise_volume, single_valid_solid
    from torus_cad.kernel.fuse import fuse_all

    general = single_valid_solid(fuse_all(propeller.hub, propeller.blades).shape, "the general fuse")
    assert precise_volume(propeller.solid, VOLUME_PRECISION) == pytest.approx(
        precise_volume(general, VOLUME_PRECISION), rel=ROUTE_VOLUME_TOLERANCE)
    assert len(propeller.solid.Faces()) == len(general.Faces())


def read_binary_stl(path: Path) -> np.ndarray:
    """Triangles of a binary STL file: ``(f, 3, 3)`` float32, mm."""
    data = path.read_bytes()
    count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
    assert len(data) == 84 + 50 * count, "binary STL length does not match its triangle count"
    records = np.frombuffer(data, dtype=np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)),
                                                  ("attribute", "<u2")]), count=count, offset=84)
    return records["vertices"].copy()


@pytest.fixture(scope="session")
def default_params() -> PropellerParameters:
    return PropellerParameters()


@pytest.fixture(scope="session")
def light_params() -> PropellerParameters:
    """A coarser default, for kernel tests that need a real solid but not the full resolution."""
    return PropellerParameters().with_values({"resolution.sections": 16, "resolution.points": 48,
                                              "name": "light"})


@pytest.fixture(scope="session")
def default_propeller(default_params):
    from torus_cad.propeller import build_propeller
    return build_propeller(default_params)


@pytest.fixture(scope="session")
def default_files(default_propeller, tmp_path_factory) -> dict[str, Path]:
    return default_propeller.write(tmp_path_factory.mktemp("default_build"))


#: Test modules that need no CAD kernel build, browser or worker pool: `pytest -m "not slow"`
#: runs these (under a minute on the 2-core machine); every other module is marked slow.
FAST_MODULES = {
    "test_airfoil", "test_airfoil_file", "test_arc_length", "test_centerline_and_frames", "test_layering",
    "test_parameters", "test_schema", "test_surface_and_mesh", "test_trailing_edge",
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.module.__name__.rpartition(".")[2] not in FAST_MODULES:
            item.add_marker(pytest.mark.slow)
