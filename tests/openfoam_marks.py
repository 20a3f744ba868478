"""The one skip mark of the tests that run OpenFOAM's programs (Debian's openfoam package; .ci/run
installs it)."""

from __future__ import annotations

import shutil

import pytest

#: simpleFoam and snappyHexMesh on PATH: the solver and the layered mesher.
HAS_OPENFOAM = all(shutil.which(program) is not None for program in ("simpleFoam", "snappyHexMesh"))
needs_openfoam = pytest.mark.skipif(
    not HAS_OPENFOAM, reason="OpenFOAM (simpleFoam, snappyHexMesh) is not installed"
)
