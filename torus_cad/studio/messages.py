"""The messages between the studio and its child processes (torus_cad.studio.worker starts them;
torus_cad.studio.exact builds in them, torus_cad.studio.vortex_run solves in them), and how a child
reports its own failure: kernel-free, so that the server side imports no kernel."""

from __future__ import annotations

import multiprocessing.connection
import traceback
from collections.abc import Iterator
from contextlib import contextmanager
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
        fuse_route: how the blades were joined, in words
            (torus_cad.kernel.fuse.FuseRoute.description).

    The solid is valid: a build that is not one valid, closed solid fails instead.
    """

    parts: list[PartMesh]
    stage_seconds: dict[str, float]
    fuse_route: str


#: The report's keys the page shows or words.
REPORT_KEYS = ("thrust_n", "power_w", "figure_of_merit", "efficiency", "low_confidence_strips")


@dataclass(frozen=True)
class PerformanceRequest:
    """One operating point of one design: the design (``PropellerParameters.to_dict()``), rpm,
    airspeed m/s, and the folder the loading plot is drawn in."""

    request_id: int
    design: dict[str, Any]
    rpm: float
    airspeed_m_s: float
    out_dir: Path


@contextmanager
def failures_reported(
    connection: multiprocessing.connection.Connection,
    request_id: int,
    what: str,
    memory_limit_bytes: int | None,
    memory_advice: str = "",
) -> Iterator[None]:
    """Inside the block, an allocation that fails or an unexpected error is sent as ``("failed",
    request_id, reason)`` (the page shows it; the child never dies silently); ``connection`` is
    closed after it. ``what`` names the work ("the exact build"), ``memory_advice`` what to lower
    when memory runs out."""
    try:
        yield
    except MemoryError:
        limit = (
            f", the limit of {memory_limit_bytes / 2**30:g} GiB in the studio"
            if memory_limit_bytes
            else ""
        )
        connection.send(("failed", request_id, f"{what} ran out of memory{limit}{memory_advice}"))
    except Exception as error:  # reported on the page, never a crashed server
        traceback.print_exc()
        connection.send(("failed", request_id, f"internal error ({type(error).__name__}): {error}"))
    finally:
        connection.close()
