"""Design sweeps: every design of a sweep file, built into its own folder and tabulated.

``OUT/designs/<id>/`` holds ``<id>.step``, ``<id>.stl`` and ``<id>.json`` of each design (or
its ``refusal.json`` / ``failure.json``); ``OUT/results.csv`` and ``OUT/results.parquet``
hold one row per design; ``OUT/sweep.json`` the sweep's settings and every design's id and
values. A design is *done* when its report (with its STEP file, and STL if asked for) or its
refusal exists: rerunning the sweep skips it, and every other design is tried again. The
table is rebuilt from those files at the end of every run, also after an interruption.

Before a worker is given a design, the sweep's own process runs the checks the build makes before
the kernel (:func:`torus_cad.batch.job.prescreen`, tens of ms): a design they refuse is recorded
at once, ``prescreened`` in its refusal and its row, and counted apart in the summary.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from torus_cad.batch import cluster
from torus_cad.batch.designs import Design, generate_designs
from torus_cad.batch.job import DesignTask, prescreen, read_design_status
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.batch.runner import (
    Interrupted,
    Job,
    LocalPool,
    capped_workers,
    default_workers,
    interrupts_raised,
    raise_if_interrupted,
    run_tasks,
)
from torus_cad.batch.sweep_file import SweepSpec
from torus_cad.batch.table import DESIGNS_DIR, collect_rows, table_columns, write_table
from torus_cad.errors import ParameterError
from torus_cad.outputs.output_set import remove_stale_staging
from torus_cad.runtime.progress import BatchProgress
from torus_cad.tolerances import DESIGN_TIME_LIMIT_MAX_S

__all__ = ["MANIFEST_FILE", "SweepInterrupted", "SweepResult", "run_pending", "run_sweep"]

MANIFEST_FILE = "sweep.json"

# named in the summary if any
_OTHER_OUTCOMES = (Outcome.BAD_FILE, Outcome.TIMEOUT, Outcome.CRASH, Outcome.PENDING)

#: Exit code of a sweep in which a design failed, errored, crashed or timed out (refusals alone: 0).
EXIT_DESIGNS_FAILED = 1


@dataclass
class SweepResult:
    """What a sweep run did.

    Attributes:
        spec: the sweep.
        out_dir: its output folder.
        designs: every design, in order.
        rows: the results table, one dict per design (see
            :func:`torus_cad.batch.table.collect_rows`).
        tables: the written table files by format (``csv``, and ``parquet`` when pyarrow is
            present).
        skipped: designs already done before this run.
        built: designs run in this run.
        seconds: wall time of this run, s.
        backend: ``"local pool, N workers"`` or ``"dask: ADDRESS, ..."``.
        interrupted_by: the signal's name (``"SIGINT"``, ``"SIGTERM"``) when the run was stopped,
            else ''.
    """

    spec: SweepSpec
    out_dir: Path
    designs: list[Design]
    rows: list[dict[str, Any]] = field(default_factory=list)
    tables: dict[str, Path] = field(default_factory=dict)
    skipped: int = 0
    built: int = 0
    seconds: float = 0.0
    backend: str = ""
    interrupted_by: str = ""

    def counts(self) -> dict[Outcome, int]:
        """Designs by outcome over the whole table, every outcome present."""
        counts = dict.fromkeys(Outcome, 0)
        for row in self.rows:
            counts[Outcome(row["status"])] += 1
        return counts

    @property
    def problems(self) -> int:
        """Designs that failed, errored, crashed, timed out or wrote a bad file."""
        return sum(count for outcome, count in self.counts().items() if outcome.problem)

    @property
    def exit_code(self) -> int:
        """0 when every design is valid or refused, :data:`EXIT_DESIGNS_FAILED` otherwise."""
        return EXIT_DESIGNS_FAILED if self.problems else 0

    def designs_per_minute(self) -> float:
        """Designs run in this run per minute of wall time."""
        return 60.0 * self.built / self.seconds if self.seconds > 0 else 0.0

    @property
    def prescreened(self) -> int:
        """Refused designs that the kernel-free checks refused before any worker built them."""
        return sum(1 for row in self.rows if row.get("prescreened"))

    def counts_text(self) -> str:
        """``"9 valid, 1 refused, 0 failed, 0 errors"``, any other outcome that occurred, and how
        many of the refused were pre-screened (``"; 1 refused before the kernel
        (pre-screened)"``)."""
        counts = self.counts()
        text = (
            f"{counts[Outcome.VALID]} valid, {counts[Outcome.REFUSED]}"
            f" refused, {counts[Outcome.FAILED]} failed, "
            f"{counts[Outcome.ERROR]} errors"
        )
        others = [
            f"{counts[outcome]} {outcome.value}" for outcome in _OTHER_OUTCOMES if counts[outcome]
        ]
        screened = (
            f"; {self.prescreened} refused before the kernel (pre-screened)"
            if self.prescreened
            else ""
        )
        return ", ".join([text, *others]) + screened

    def summary(self) -> str:
        """A few lines for the terminal: counts, rate, the table, the first problems."""
        lines = [
            f"sweep {self.spec.name!r}: {len(self.designs)} designs in {self.out_dir}"
            + (
                f" (INTERRUPTED by {self.interrupted_by}; rerun the same command to resume)"
                if self.interrupted_by
                else ""
            ),
            f"  {self.counts_text()}",
            (
                f"  {self.built} built in {_duration(self.seconds)}"
                f" ({self.designs_per_minute():.1f} designs/min, "
                f"{self.backend}); {self.skipped} already done"
            ),
        ]
        if self.tables:
            lines.append("  table: " + ", ".join(str(path) for path in self.tables.values()))
        problems = [
            row for row in self.rows if row["status"] not in (Outcome.VALID, Outcome.PENDING)
        ]
        for row in problems[:5]:
            lines.append(f"  {row['status']} {row['id']}: {row['reason']}")
        if len(problems) > 5:
            lines.append(f"  ... and {len(problems) - 5} more (see the table's reason column)")
        return "\n".join(lines)


class SweepInterrupted(Interrupted):
    """SIGINT or SIGTERM during :func:`run_sweep`; ``result`` is the partial run (its table is
    written)."""

    def __init__(self, signum: int, result: SweepResult) -> None:
        super().__init__(signum)
        self.result = result


def _duration(seconds: float) -> str:
    seconds = max(0, round(seconds))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return (
        f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s" if minutes else f"{secs}s"
    )


def run_sweep(
    spec: SweepSpec,
    out_dir: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    client: Any = None,
    stl: bool | None = None,
    density_g_cm3: float | None = None,
    time_limit_s: float | None = None,
    rebuild: bool = False,
    progress: bool | None = None,
    stream: TextIO | None = None,
    job: Job | None = None,
    oversubscribe: bool = False,
) -> SweepResult:
    """Run every design of ``spec`` that is not done yet and write the results table.

    Args:
        spec: the sweep (see :func:`torus_cad.batch.sweep_file.load_sweep`).
        out_dir: output folder; ``designs/<id>/`` per design, ``results.csv``, ``sweep.json``.
        workers: local processes (default: one per available core; more than the cores are capped at
            them, with one line on ``stream``, unless ``oversubscribe``); ignored with a scheduler
            or client.
        scheduler: a Dask scheduler address (``"tcp://host:8786"``), or ``"local"`` for a
            LocalCluster of ``workers`` single-threaded processes on this machine.
        client: an existing ``dask.distributed.Client`` to use instead of ``scheduler``.
        stl, density_g_cm3, time_limit_s: override the sweep file's ``stl``, ``density_g_cm3``
            (g/cm^3) and ``time_limit_s`` (s, per design, local pool only).
        rebuild: run every design again, even those already done.
        progress: draw the progress bar (default: when ``stream`` is a terminal).
        stream: where the progress bar goes (default: stderr).
        job: the function each worker runs per design (default: build and write it); for tests.

    A design never stops the sweep: its outcome is recorded in its folder and its row. On
    SIGINT or SIGTERM the workers are stopped, the table is written (unfinished designs as
    ``pending``) and :class:`SweepInterrupted` is raised. Raises BatchError when the Dask
    scheduler or the worker processes cannot be used.
    """
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ParameterError(f"--workers must be a whole number >= 1, got {workers!r}")
    if time_limit_s is not None and not 0.0 < time_limit_s <= DESIGN_TIME_LIMIT_MAX_S:
        raise ParameterError(
            f"--time-limit = {time_limit_s!r} is out of "
            f"range; allowed (0, {DESIGN_TIME_LIMIT_MAX_S:g}] s"
        )
    out_dir = Path(out_dir).resolve()
    stl = spec.stl if stl is None else stl
    density = spec.density_g_cm3 if density_g_cm3 is None else density_g_cm3
    result: SweepResult | None = None
    try:
        with interrupts_raised():
            designs, pending = _plan(spec, out_dir, stl, density, rebuild)
            raise_if_interrupted()  # before anything was built: no table to write
            if scheduler in (None, "local") and client is None and pending:
                workers = capped_workers(
                    workers,
                    len(pending),
                    oversubscribe,
                    lambda line: print(f"torus-cad: {line}", file=stream or sys.stderr),
                )
            result = run_pending(
                spec,
                out_dir,
                designs,
                pending,
                stl,
                workers=workers,
                scheduler=scheduler,
                client=client,
                time_limit_s=spec.time_limit_s if time_limit_s is None else time_limit_s,
                bar=BatchProgress(
                    len(designs), len(designs) - len(pending), enabled=progress, stream=stream
                ),
                job=job,
            )
    except SweepInterrupted:
        raise
    # before the first design, or while the table was written at the end
    except Interrupted as interrupt:
        partial = result if result is not None else SweepResult(spec, out_dir, [])
        partial.interrupted_by = interrupt.signal_name
        raise SweepInterrupted(interrupt.signum, partial) from None
    return result


def _plan(
    spec: SweepSpec, out_dir: Path, stl: bool, density: float | None, rebuild: bool
) -> tuple[list[Design], list[DesignTask]]:
    """Every design (listed in ``sweep.json``) and the tasks of those not done yet."""
    designs = generate_designs(spec)
    _write_manifest(spec, designs, out_dir, stl, density)
    pending = []
    for design in designs:
        raise_if_interrupted()  # a large sweep's designs take a while to look up
        if rebuild or not _is_done(out_dir, design, stl):
            pending.append(
                DesignTask(
                    design.design_id,
                    design.parameters,
                    str(out_dir / DESIGNS_DIR / design.design_id),
                    stl=stl,
                    density_g_cm3=density,
                )
            )
    return designs, pending


def run_pending(
    spec: SweepSpec,
    out_dir: Path,
    designs: list[Design],
    pending: list[DesignTask],
    stl: bool,
    *,
    workers: int | None,
    scheduler: str | None,
    client: Any,
    time_limit_s: float,
    bar: BatchProgress,
    job: Job | None,
) -> SweepResult:
    """Run ``pending`` (the designs not yet built) on the local pool or Dask and gather their
    results into the sweep's result; the table is written whatever happens
    (scripts/bench_optimize.py times this)."""
    result = SweepResult(spec, out_dir, designs, skipped=len(designs) - len(pending))
    results: dict[str, DesignResult] = {}

    def on_result(task: DesignTask, design_result: DesignResult) -> None:
        results[task.design_id] = design_result
        bar.update(design_result.outcome)
        if design_result.outcome is not Outcome.VALID and task.folder is not None:
            # of a worker stopped at its time limit, or killed
            remove_stale_staging(Path(task.folder))

    own_client = own_cluster = None
    start = time.perf_counter()
    tasks = _prescreened(pending, on_result)
    try:
        if not pending:
            result.backend = "nothing to run"
        elif client is not None or scheduler is not None:
            if client is None:
                own_client, own_cluster = cluster.connect(str(scheduler), workers)
                client = own_client
            executor = client.get_executor(pure=False)
            result.backend = f"dask: {cluster.client_label(client)}"
            run_tasks(tasks, on_result, lambda: executor, window=None, job=job, check_visible=True)
        else:
            count = max(1, min(workers or default_workers(), len(pending)))
            result.backend = f"local pool, {count} worker{'s' if count > 1 else ''}"
            run_tasks(
                tasks, on_result, lambda: LocalPool(count, time_limit_s), window=2 * count, job=job
            )
    except Interrupted as interrupt:
        result.interrupted_by = interrupt.signal_name
        # the pool is stopped: the staging folders its workers had open are debris now
        for task in pending:
            if (
                task.design_id not in results
                and task.folder is not None
                and os.path.isdir(task.folder)
            ):
                remove_stale_staging(Path(task.folder))
        raise SweepInterrupted(interrupt.signum, result) from None
    finally:
        bar.close()
        result.built = len(results)
        result.seconds = time.perf_counter() - start
        if own_client is not None:
            cluster.close_client(own_client, own_cluster)
        keys = [axis.key for axis in spec.axes]
        result.rows = collect_rows(designs, keys, out_dir, stl, results)
        result.tables = write_table(result.rows, out_dir, table_columns(keys))
    return result


def _prescreened(
    tasks: Iterable[DesignTask], on_result: Callable[[DesignTask, DesignResult], None]
) -> Iterator[DesignTask]:
    """The tasks that pass the kernel-free checks (:func:`torus_cad.batch.job.prescreen`), taken one
    at a time as workers free up; the others' refusals go to ``on_result`` at once, without a
    worker."""
    for task in tasks:
        refusal = prescreen(task)
        if refusal is None:
            yield task
        else:
            on_result(task, refusal)


def _is_done(out_dir: Path, design: Design, stl: bool) -> bool:
    status = read_design_status(
        out_dir / DESIGNS_DIR / design.design_id, design.design_id, design.parameters, stl
    )
    return status is not None and status[0].done


def _write_manifest(
    spec: SweepSpec,
    designs: Sequence[Design],
    out_dir: Path,
    stl: bool,
    density_g_cm3: float | None,
) -> None:
    """``sweep.json``: the sweep's settings and every design's id and varied values (strict JSON: no
    NaN)."""
    from torus_cad.runtime.files import atomic_path

    manifest = {
        "name": spec.name,
        "source": spec.source,
        "mode": spec.mode.value,
        "samples": spec.samples,
        "seed": spec.seed,
        "stl": stl,
        "density_g_cm3": density_g_cm3,
        "time_limit_s": spec.time_limit_s,
        "vary": {axis.key: axis.describe() for axis in spec.axes},
        "base": spec.base.to_dict(),
        "designs": [{"index": d.index, "id": d.design_id, "varied": d.varied} for d in designs],
    }
    with atomic_path(out_dir / MANIFEST_FILE) as temp:
        temp.write_text(json.dumps(manifest, indent=2, allow_nan=False) + "\n")
