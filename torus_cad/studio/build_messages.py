"""The messages between the studio and its build processes (torus_cad.studio.worker starts them,
torus_cad.studio.exact runs in them): kernel-free, so that the server side imports no kernel."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from torus_cad.studio.scene import PartMesh


@dataclass(frozen=True)
class BuildRequest:
    """One exact build: the design (``PropellerParameters.to_dict()``) and where its files go."""

    build_id: int
    design: dict[str, Any]
    out_dir: Path


@dataclass(frozen=True)
class SolidResult:
    """What the view and the readouts need from an exact build.

    Attributes:
        parts: one mesh per part (the hub first, then blade 0, 1, ...).
        stage_seconds: seconds per pipeline stage, plus ``display_mesh`` (the tessellation above).
        fuse_route: how the blades were joined, in words (torus_cad.kernel.fuse.FuseRoute.description).

    The solid is valid: a build that is not one valid, closed solid fails instead.
    """

    parts: list[PartMesh]
    stage_seconds: dict[str, float]
    fuse_route: str
