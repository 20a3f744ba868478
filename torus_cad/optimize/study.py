"""Running a study: optuna asks for designs, the batch runner builds them, their reports answer.

The loop is the batch runner's (:func:`torus_cad.batch.runner.run_tasks`) on the local pool or
a Dask cluster; its tasks come from a generator that asks optuna for the next trial only when a
worker is free (ask-and-tell), so the sampler always sees every finished trial. Each design is
first checked here without the kernel (:func:`torus_cad.batch.job.prescreen`): one the checks
refuse is told at once, ``prescreened`` in its record, and the generator asks for the next
without a worker. A design that
is refused or fails is a FAIL trial with its outcome and reason in the trial's user attrs; a
constraint goes to the sampler as a constraint (optuna's ``constraints_func``), never as a
penalty. ``--trials`` is the total over every run and every process sharing the study: a rerun
continues it, and trials of a killed run are asked again (:mod:`torus_cad.optimize.storage`).

A study of several mesh levels (``[simulate] levels``) runs each trial in stages: every trial is
built and simulated at the first (coarsest) level; its value there is reported to optuna
(``Trial.report`` at a step per level) and the pruner (``Trial.should_prune``: optuna's
MedianPruner or SuccessiveHalvingPruner for one objective; for several, where optuna's pruners do
not apply, :func:`dominated_at_level`) decides whether it climbs: a trial that climbs is queued
again, ahead of new trials, for the next level on the next free worker; one that does not is told
PRUNED, its values those of the level it reached. A trial that breaks a constraint at a screening
level stops there too. The trial's value is that of the finest level it reached.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import time
import warnings
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.batch import cluster
from torus_cad.batch.job import DesignTask, prescreen
from torus_cad.batch.outcome import DesignResult, Outcome
from torus_cad.batch.runner import (
    Interrupted,
    Job,
    LocalPool,
    interrupts_raised,
    raise_if_interrupted,
    run_tasks,
)
from torus_cad.errors import ParameterError
from torus_cad.optimize.metrics import metric_value
from torus_cad.optimize.results import write_results
from torus_cad.optimize.storage import (
    CONSTRAINT,
    FOLDER,
    HEARTBEAT_S,
    LEVEL,
    LEVEL_SECONDS,
    LEVELS,
    METRICS,
    OUTCOME,
    OWNER,
    PRESCREENED,
    PRUNED_AT,
    REASON,
    RESULT,
    SAME_AS,
    SECONDS,
    Heartbeat,
    claim_lock,
    count_trials,
    fail_and_retry,
    open_storage,
    owner_record,
    public_url,
    retry_stale_trials,
    storage_failures_named,
    storage_url,
    trial_result,
)
from torus_cad.optimize.study_file import Direction, Objective, PrunerKind, Sampler, StudySpec
from torus_cad.optimize.trial_job import (
    PERFORMANCE_DIR,
    TRIALS_DIR,
    TrialTask,
    performance_dir,
    run_trial,
    trial_name,
)
from torus_cad.runtime.progress import BatchProgress
from torus_cad.tolerances import MAX_STUDY_TRIALS

if TYPE_CHECKING:  # optuna is imported where it is used (the optimize extra)
    import optuna
    from optuna.distributions import BaseDistribution
    from optuna.pruners import BasePruner
    from optuna.samplers import BaseSampler
    from optuna.storages import RDBStorage
    from optuna.trial import FrozenTrial, Trial

__all__ = ["DEFINITION_ATTR", "StudyInterrupted", "StudyResult", "dominated_at_level", "run_study"]

# : study user attr: the digest of what must not change between runs
DEFINITION_ATTR = "torus_cad_definition"
#: Trials in flight per worker: one running and one queued, so that a worker never waits for the
#: sampler and the storage between two trials (the sweep's window too); constant_liar keeps the
#: sampler off both.
_TASKS_PER_WORKER = 2


@dataclass
class StudyResult:
    """What a run of a study did.

    Attributes:
        spec: the study.
        out_dir: its output folder.
        storage: the storage URL, password hidden.
        total: the trials asked for in all.
        ran: trials this process ran (finished) in this run.
        seconds: wall time of the trial loop, s.
        cpu_seconds: CPU time of this process (all its threads) in the trial loop, s: the sampler,
            the storage and the loop, which take their share of the cores the workers run on.
        backend: ``"local pool, N workers"`` or ``"dask: ..."``.
        retried: numbers of trials of dead processes that were failed and asked again.
        files: what :func:`torus_cad.optimize.results.write_results` wrote, by kind.
        summary_lines: the best designs' lines for the terminal.
        interrupted_by: the signal's name when interrupted, else ''.
    """

    spec: StudySpec
    out_dir: Path
    storage: str
    total: int
    ran: int = 0
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    backend: str = ""
    retried: list[int] = field(default_factory=list)
    files: dict[str, Path] = field(default_factory=dict)
    summary_lines: list[str] = field(default_factory=list)
    interrupted_by: str = ""

    def trials_per_minute(self) -> float:
        return 60.0 * self.ran / self.seconds if self.seconds > 0 else 0.0

    def summary(self) -> str:
        head = (
            f"study {self.spec.name!r}: {self.ran} trials run in {self.seconds:.1f} s "
            f"({self.trials_per_minute():.1f} trials/min, {self.backend}); storage {self.storage}"
        )
        lines = [
            head
            + (
                f" (INTERRUPTED by {self.interrupted_by}; rerun the same command to continue)"
                if self.interrupted_by
                else ""
            )
        ]
        if self.retried:
            lines.append(
                f"  trials {', '.join(map(str, self.retried))} of a stopped run were asked again"
            )
        lines += self.summary_lines
        lines += [f"  {kind}: {path}" for kind, path in self.files.items()]
        return "\n".join(lines)


class StudyInterrupted(Interrupted):
    """SIGINT, SIGTERM or SIGHUP during :func:`run_study`; ``result`` is the partial run (its
    outputs written)."""

    def __init__(self, signum: int, result: StudyResult) -> None:
        super().__init__(signum)
        self.result = result


def available_workers() -> int:
    """The CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_study(
    spec: StudySpec,
    out_dir: str | Path,
    *,
    trials: int | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    storage: str | None = None,
    write_results: bool = True,
    trial_job: Job = run_trial,
    progress: bool | None = None,
) -> StudyResult:
    """Run ``spec`` until it holds ``trials`` (default ``spec.trials``) finished trials, then write
    its results.

    Args:
        spec: the study (:func:`torus_cad.optimize.study_file.read_study_file`).
        out_dir: the output folder: ``trials/<number>/``, ``<name>.db``, ``results.csv``, ``best/``.
        trials: trials in all (over every run and process of the study).
        workers: local worker processes (default and cap: the CPUs available), or a LocalCluster's
            size with ``scheduler="local"``.
        scheduler: a Dask scheduler address, or ``"local"``; ``out_dir`` must be shared with its
            workers.
        storage: the storage URL (default ``spec.storage``, else SQLite ``OUT/<name>.db``).
        write_results: write the table, the history picture and the best designs at the end.
        trial_job: what a worker runs for each stage of a trial (default :func:`run_trial`: the
            build and ``torus-cad simulate``); a top-level function of a :class:`TrialTask` giving a
            DesignResult.
        progress: draw a bar of the trials (finished of all, by state, per minute, time left) and a
            line each time a one-objective study finds a better trial, on stderr; None: only when
            stderr is a terminal.

    Raises ParameterError for bad options or a study whose stored definition differs,
    StorageError / BatchError when the storage or the executor cannot be used, and
    :class:`StudyInterrupted` after a signal (the trials then running are asked again next run).
    """
    total = spec.trials if trials is None else trials
    if isinstance(total, bool) or not isinstance(total, int) or not 1 <= total <= MAX_STUDY_TRIALS:
        raise ParameterError(
            f"--trials = {total!r} is out of range; allowed [1, {MAX_STUDY_TRIALS}]"
        )
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ParameterError(f"--workers must be a whole number >= 1, got {workers!r}")
    out = Path(out_dir).resolve()
    url = storage_url(spec.storage if storage is None else storage, out, spec.name)
    from torus_cad.outputs.output_set import check_writable_folder

    check_writable_folder(out)
    (out / TRIALS_DIR).mkdir(parents=True, exist_ok=True)
    result = StudyResult(spec, out, public_url(url), total)
    runner: _Runner | None = None
    try:
        # From opening the storage to closing it, a signal only takes effect at a safe point
        # (between two trials' bookkeeping, between two files of the results): never inside a
        # commit, an import or the pool's start-up; the storage is closed on every way out (no -wal
        # / -shm left beside an SQLite file).
        with interrupts_raised(), storage_failures_named(url):
            try:
                try:
                    runner = _Runner(spec, out, url, total, trial_job, progress)
                    raise_if_interrupted()
                    runner.run(result, workers, scheduler)
                except Interrupted as interrupt:
                    result.interrupted_by = interrupt.signal_name
                    if write_results and runner is not None:
                        runner.write(result)  # the signal was raised once: this is not cut short
                    raise StudyInterrupted(interrupt.signum, result) from None
                if write_results:
                    runner.write(result, checkpoint=raise_if_interrupted)
            finally:
                if runner is not None:
                    runner.close()
    except StudyInterrupted:
        raise
    except Interrupted as interrupt:  # while the results were written (they stop at the next file)
        result.interrupted_by = interrupt.signal_name
        raise StudyInterrupted(interrupt.signum, result) from None
    return result


class _Runner:
    """One process's part of a study: its storage, sampler, trials in flight."""

    def __init__(
        self,
        spec: StudySpec,
        out: Path,
        url: str,
        total: int,
        job: Job = run_trial,
        progress: bool | None = None,
    ) -> None:
        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        self.spec, self.out, self.url, self.total = spec, out, url, total
        # SQLite: one process at a time creates the tables and the study
        with claim_lock(None, url, spec.name):
            self.rdb = open_storage(url)
            try:
                self.study = _load_study(spec, self.rdb)
            except BaseException:
                self.close()
                raise
        self.study_id = self.rdb.get_study_id_from_name(self.study.study_name)
        self.owner = owner_record()
        self.in_flight: dict[str, Trial] = {}  # design id -> optuna Trial
        self.seeded = False
        self.ran = 0
        self.heartbeat = Heartbeat(self.rdb, self.study)
        self.job = job
        self.climbs: deque[TrialTask] = deque()  # trials the pruner let climb, ahead of new trials
        self.progress_enabled = progress
        self.progress: BatchProgress | None = None
        # a one-objective study's best trial so far: (number, value)
        self.best: tuple[int, float] | None = None
        self.seconds: dict[str, float] = {}  # design id -> worker seconds of its stages so far
        # parameters -> a complete trial
        self.answered: dict[str, tuple[int, dict[str, Any], list[float]]] = {}
        from optuna.trial import TrialState

        for done in self.study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)):
            self._remember(done.params, done.number, trial_result(done), list(done.values))

    # -- the loop --------------------------------------------------------------------------------

    def run(self, result: StudyResult, workers: int | None, scheduler: str | None) -> None:
        start, cpu_start = time.perf_counter(), time.process_time()
        # of workers killed in earlier runs
        _remove_staging_debris((self.out / TRIALS_DIR).glob("*/"))
        own_client = own_cluster = None
        finished, _ = count_trials(self.rdb, self.study_id)
        self.progress = BatchProgress(
            self.total, min(finished, self.total), enabled=self.progress_enabled, label="trials"
        )
        try:
            with self.heartbeat, self.progress:
                if scheduler is not None:
                    own_client, own_cluster = cluster.connect(scheduler, workers)
                    executor = own_client.get_executor(pure=False)
                    window = _TASKS_PER_WORKER * max(
                        1, len(own_client.scheduler_info().get("workers", {})) or workers or 1
                    )
                    result.backend = f"dask: {cluster.client_label(own_client)}"
                    run_tasks(
                        _Tasks(self, result),
                        self.on_result,
                        lambda: executor,
                        window=window,
                        job=self.job,
                        check_visible=True,
                    )
                else:
                    count = min(workers or available_workers(), available_workers())
                    result.backend = f"local pool, {count} worker{'s' if count > 1 else ''}"
                    run_tasks(
                        _Tasks(self, result),
                        self.on_result,
                        lambda: LocalPool(count, self.spec.time_limit_s),
                        window=_TASKS_PER_WORKER * count,
                        job=self.job,
                    )
        except BaseException:
            self._retry_in_flight()
            raise
        finally:
            result.ran, result.seconds = self.ran, time.perf_counter() - start
            result.cpu_seconds = time.process_time() - cpu_start
            if own_client is not None:
                cluster.close_client(own_client, own_cluster)

    def claim_trial(self) -> Trial | None:
        """Ask for a trial (an enqueued retry first), or None when the study is full.

        Called by the runner's tasks (:class:`_Tasks`) under the claim lock. The trial is this
        process's from
        here: in flight, owned, on the heartbeat.

        Returns:
            The new trial, or None when the study holds its trials and no retry waits.
        """
        counted, waiting = count_trials(self.rdb, self.study_id)
        # distinct seeds for processes sharing a study, reproducible for one process
        if not self.seeded:
            self.study.sampler = _sampler(self.spec, self.spec.seed + counted)
            self.seeded = True
        if not waiting and counted >= self.total:
            return None
        with warnings.catch_warnings():
            # optuna's ExperimentalWarning for constraints_func etc.
            warnings.simplefilter("ignore")
            trial = self.study.ask(_distributions(self.spec))
        # from here an interrupt fails it and asks it again
        self.in_flight[trial_name(trial.number)] = trial
        trial.set_user_attr(OWNER, self.owner)
        self.heartbeat.add(trial)
        return trial

    def answered_by_twin(self, trial: Trial) -> bool:
        """Whether a complete trial this process knows had exactly ``trial``'s parameters; if so,
        ``trial`` is told that trial's values and takes its record (metrics, constraints, folder;
        ``same_as`` names it), and no worker builds or simulates the design again (the same
        parameters give the same design and numbers).

        Args:
            trial: a trial this process claimed (:meth:`claim_trial`).

        Returns:
            True when the trial was answered so; False when it must run.
        """
        import optuna

        twin = self.answered.get(_parameters_key(trial.params))
        if twin is None:
            return False
        number, record, values = twin
        record = {**record, SAME_AS: record.get(SAME_AS, number), SECONDS: 0.0}
        # a process took it as stale
        with contextlib.suppress(optuna.exceptions.UpdateFinishedTrialError):
            trial.set_user_attr(RESULT, record)
            self.study.tell(trial, values)
        self._finished(trial_name(trial.number), trial, values, pruned=False)
        return True

    def _remember(
        self, params: dict[str, Any], number: int, record: dict[str, Any], values: list[float]
    ) -> None:
        """A complete trial's values and record, for a later trial with the same parameters."""
        self.answered.setdefault(_parameters_key(params), (number, record, values))

    def trial_task(self, trial: Trial, stage: int = 0) -> TrialTask:
        """Trial ``trial``'s task at ``stage`` (0: build it and simulate it at the first level).

        Args:
            trial: a trial this process claimed (:meth:`claim_trial`).
            stage: the index of the simulation level the task runs.

        Returns:
            The task, its folder made.
        """
        name = trial_name(trial.number)
        folder = self.out / TRIALS_DIR / str(trial.number)
        folder.mkdir(parents=True, exist_ok=True)
        parameters = self.spec.parameters(trial.params, name)
        levels = self.spec.levels
        report_dir = performance_dir(levels[stage], len(levels)) if levels else PERFORMANCE_DIR
        return TrialTask(
            name,
            parameters,
            str(folder),
            stl=self.spec.stl,
            simulate=self.spec.stage_settings(stage),
            simulate_time_limit_s=self.spec.time_limit_s,
            simulate_dir=report_dir,
            stage=stage,
        )

    def on_result(self, task: DesignTask, result: DesignResult) -> None:
        """Tell optuna what the trial gave: its objective values and constraints, or FAIL with the
        reason; at a screening level, climb (queue the next stage) or PRUNED.

        The trial's record (outcome, reason, metrics, violations) is one user attr, one write.

        Args:
            task: the trial's task that ran (or was refused before it ran).
            result: what it gave.
        """
        import optuna
        from optuna.trial import TrialState

        trial = self.in_flight[task.design_id]
        stage = task.stage if isinstance(task, TrialTask) else 0
        outcome, reason = result.outcome, result.reason
        values: list[float] | None = None
        seconds = self.seconds.pop(task.design_id, 0.0) + result.seconds
        record: dict[str, Any] = {SECONDS: seconds, FOLDER: f"{TRIALS_DIR}/{trial.number}"}
        levels = self.spec.levels
        if outcome is Outcome.VALID:
            try:
                report_dir = task.simulate_dir if isinstance(task, TrialTask) else PERFORMANCE_DIR
                values = self._evaluate(Path(str(task.folder)), task.design_id, record, report_dir)
            except (KeyError, OSError, ValueError) as error:
                outcome, reason = Outcome.ERROR, f"the trial's report cannot be read: {error}"
        elif stage > 0:
            reason = f"at the {levels[stage]} level: {reason}"
        if len(levels) > 1 and outcome is Outcome.VALID:
            record[LEVEL] = levels[stage]
            earlier = trial.user_attrs.get(LEVELS, {})
            record[LEVEL_SECONDS] = {
                **{name: entry.get(SECONDS) for name, entry in earlier.items()},
                levels[stage]: result.seconds,
            }
            if stage + 1 < len(levels) and values is not None:
                try:
                    stops = self._stops_here(trial, stage, values, record, result.seconds)
                # a process took it as stale: asked again
                except optuna.exceptions.UpdateFinishedTrialError:
                    self._forget(task.design_id, trial)
                    return
                if not stops:
                    self.seconds[task.design_id] = seconds
                    self.climbs.append(self.trial_task(trial, stage + 1))
                    return
                record[PRUNED_AT] = levels[stage]
        record.update({OUTCOME: outcome.value, REASON: reason})
        if result.prescreened:
            record[PRESCREENED] = True
        # a worker stopped at its time limit, or killed, leaves its staging folder
        if outcome is not Outcome.VALID:
            _remove_staging_debris([Path(str(task.folder))])
        # a process took it as stale
        with contextlib.suppress(optuna.exceptions.UpdateFinishedTrialError):
            trial.set_user_attr(RESULT, record)
            if values is None:
                self.study.tell(trial, state=TrialState.FAIL)
            elif PRUNED_AT in record:
                self.study.tell(trial, state=TrialState.PRUNED)
            else:
                self.study.tell(trial, values)
                self._remember(trial.params, trial.number, record, values)
        self._finished(task.design_id, trial, values, pruned=PRUNED_AT in record)

    def _finished(
        self, design_id: str, trial: Trial, values: list[float] | None, pruned: bool
    ) -> None:
        """A trial told to optuna: no longer in flight, counted, shown."""
        self._forget(design_id, trial)
        self.ran += 1
        self._show_progress(trial.number, values, pruned)

    def _show_progress(self, number: int, values: list[float] | None, pruned: bool) -> None:
        """One finished trial on the bar, and a line when a one-objective study's best improves."""
        if self.progress is None:
            return
        self.progress.update("failed" if values is None else "pruned" if pruned else "complete")
        if values is None or pruned or len(values) != 1:
            return
        objective = self.spec.objectives[0]
        sign = 1.0 if objective.direction is Direction.MINIMIZE else -1.0
        if self.best is None or sign * values[0] < sign * self.best[1]:
            self.best = (number, values[0])
            self.progress.message(
                f"trial {number}: best so far, {objective.metric} = {values[0]:.6g}"
            )

    def _forget(self, design_id: str, trial: Trial) -> None:
        """The trial is no longer this process's to run: out of the trials in flight and the
        heartbeat."""
        del self.in_flight[design_id]
        self.seconds.pop(design_id, None)
        self.heartbeat.discard(trial)

    def _stops_here(
        self, trial: Trial, stage: int, values: list[float], record: dict[str, Any], seconds: float
    ) -> bool:
        """Whether the trial stops at screening level ``stage`` (the pruner's word, or a broken
        constraint); its values there are recorded with the trial first (``LEVELS``), where other
        processes' pruners read them."""
        level = self.spec.levels[stage]
        feasible = all(v <= 0.0 for v in record.get(CONSTRAINT, []))
        # this process's own trial: its attrs are current
        done = dict(trial.user_attrs.get(LEVELS, {}))
        done[level] = {METRICS: record[METRICS], "feasible": feasible, SECONDS: seconds}
        trial.set_user_attr(LEVELS, done)
        pruner = self.spec.pruner
        if pruner is None:
            return False
        if len(self.spec.objectives) == 1:  # optuna's pruners judge one value; a step per level
            trial.report(values[0], _step(pruner.kind, pruner.reduction_factor, stage))
        if not feasible:
            return True
        if pruner.kind in (PrunerKind.MEDIAN, PrunerKind.HALVING):
            return bool(trial.should_prune())
        if pruner.kind is PrunerKind.DOMINATED:
            others = [
                other
                for other in self.study.get_trials(deepcopy=False)
                if other.number != trial.number
            ]
            return dominated_at_level(
                values, self.spec.objectives, level, others, pruner.startup_trials
            )
        return False

    def _evaluate(
        self, folder: Path, name: str, record: dict[str, Any], report_dir: str = PERFORMANCE_DIR
    ) -> list[float]:
        """The objective values; the metrics and the constraint violations go into the trial's
        ``record``."""
        report = json.loads((folder / f"{name}.json").read_text())
        performance = None
        if self.spec.simulate is not None:
            performance = json.loads((folder / report_dir / f"{name}_performance.json").read_text())
        metrics = {
            metric: metric_value(metric, report, performance)
            for metric in dict.fromkeys(self.spec.metrics)
        }
        record[METRICS] = metrics
        if self.spec.constraints:
            record[CONSTRAINT] = [
                v for c in self.spec.constraints for v in c.violations(metrics[c.metric])
            ]
        return [metrics[objective.metric] for objective in self.spec.objectives]

    def _retry_in_flight(self) -> None:
        """After an interrupt: fail the trials this process was running and ask their parameters
        again (those it holds, and any RUNNING trial that records this process as its owner)."""
        from optuna.trial import TrialState

        mine = {trial.number for trial in self.in_flight.values()}
        # the storage is gone: the next run finds them by their owner
        with contextlib.suppress(Exception):
            mine |= {
                trial.number
                for trial in self.study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
                if trial.user_attrs.get(OWNER) == self.owner
            }
            fail_and_retry(self.study, self.rdb, mine)
        # the pool is stopped: the staging folders its workers had open are debris now (their trials
        # are asked again under new numbers, in new folders)
        _remove_staging_debris(
            self.out / TRIALS_DIR / str(trial.number) for trial in self.in_flight.values()
        )
        self.in_flight.clear()
        self.climbs.clear()
        self.seconds.clear()

    def write(self, result: StudyResult, checkpoint: Callable[[], None] | None = None) -> None:
        """The table, the pictures, the best designs and the summary; ``checkpoint`` is called
        between two of them (it raises to stop there)."""
        from torus_cad.errors import OutputError
        from torus_cad.outputs.output_set import describe_os_error

        try:
            result.files, result.summary_lines = write_results(
                self.spec, self.study, self.out, checkpoint=checkpoint
            )
        # a full disk: name the file as the user knows it, not its temp name
        except OSError as error:
            named = Path(error.filename) if isinstance(error.filename, str) else self.out
            raise OutputError(describe_os_error(error, _final_name(named))) from None

    def close(self) -> None:
        """Close the storage's connections: SQLite's last connection folds its write-ahead log into
        the database and removes ``-wal`` and ``-shm``. The study is read from the storage once more
        to write the results, which opens a connection again; this is called after that too."""
        # a storage that already failed: its error is the one reported
        with contextlib.suppress(Exception):
            self.rdb.remove_session()
        with contextlib.suppress(Exception):
            self.rdb.engine.dispose()


class _Tasks:
    """The runner's tasks: a trial that climbs to its next level first, else a new trial whenever a
    worker is free, until the study holds its trials.

    An iterator that may end and go on again: while trials in flight may still climb, it stops when
    it has nothing to give now, and :func:`~torus_cad.batch.runner.run_tasks` asks it again after
    each result."""

    def __init__(self, runner: _Runner, result: StudyResult) -> None:
        self.runner, self.result = runner, result
        self.checked = -math.inf
        self.full = False  # the study holds its trials: no new one is asked for

    def __iter__(self) -> _Tasks:
        return self

    def __next__(self) -> TrialTask:
        runner = self.runner
        while True:
            if runner.climbs:
                return runner.climbs.popleft()
            if self.full:
                raise StopIteration
            with claim_lock(runner.rdb, runner.url, runner.spec.name):
                # at the start, then once per heartbeat
                if time.monotonic() - self.checked >= HEARTBEAT_S:
                    self.result.retried += retry_stale_trials(runner.study, runner.rdb)
                    self.checked = time.monotonic()
                trial = runner.claim_trial()
            if trial is None:
                self.full = True
                continue
            if runner.answered_by_twin(trial):
                continue
            task = runner.trial_task(trial)
            # refused by the kernel-free checks: told at once, no worker needed
            refusal = prescreen(task)
            if refusal is None:
                return task
            runner.on_result(task, refusal)


def _parameters_key(params: dict[str, Any]) -> str:
    """A trial's parameters as one comparable text (values as optuna holds them)."""
    return json.dumps(params, sort_keys=True)


def _step(kind: PrunerKind, reduction_factor: int, stage: int) -> int:
    """The step at which a trial reports its value at level ``stage``: ``reduction_factor ** stage``
    for successive halving (level i is its rung i: a resource that grows by the reduction factor per
    level), else
    ``stage``."""
    return reduction_factor**stage if kind is PrunerKind.HALVING else stage


def dominated_at_level(
    values: Sequence[float],
    objectives: Sequence[Objective],
    level: str,
    others: Iterable[FrozenTrial],
    startup_trials: int,
) -> bool:
    """The pruner of several objectives: whether ``values`` (a trial's at ``level``) are dominated
    by the values at ``level`` of a feasible one of ``others`` (no worse in every objective, better
    in one), once at least ``startup_trials`` of them have values there. optuna's pruners take one
    value; this is the Pareto front's own test, on the screening level."""
    signs = [1.0 if objective.direction.value == "minimize" else -1.0 for objective in objectives]
    mine = [sign * value for sign, value in zip(signs, values)]
    seen = []
    for other in others:
        entry = other.user_attrs.get(LEVELS, {}).get(level)
        if (
            isinstance(entry, dict)
            and entry.get("feasible")
            and isinstance(entry.get(METRICS), dict)
        ):
            try:
                seen.append(
                    [sign * float(entry[METRICS][o.metric]) for sign, o in zip(signs, objectives)]
                )
            except (KeyError, TypeError, ValueError):
                continue
    if len(seen) < startup_trials:
        return False
    return any(
        all(a <= b for a, b in zip(point, mine)) and any(a < b for a, b in zip(point, mine))
        for point in seen
    )


def _pruner(spec: StudySpec) -> BasePruner | None:
    """optuna's pruner of a one-objective study of several levels; None otherwise (the study's
    default, never consulted: trials report no values)."""
    import optuna

    pruner = spec.pruner
    if pruner is None or len(spec.objectives) > 1:
        return None
    if pruner.kind is PrunerKind.MEDIAN:
        return optuna.pruners.MedianPruner(n_startup_trials=pruner.startup_trials, n_warmup_steps=0)
    if pruner.kind is PrunerKind.HALVING:
        return optuna.pruners.SuccessiveHalvingPruner(
            min_resource=1,
            reduction_factor=pruner.reduction_factor,
            bootstrap_count=pruner.startup_trials,
        )
    return optuna.pruners.NopPruner()


def _final_name(path: Path) -> Path:
    """The file a temp file of :func:`torus_cad.runtime.files.atomic_path` stands for
    (``.x.png.tmp-...`` -> ``x.png``)."""
    name, marker, _ = path.name.partition(".tmp-")
    return path.with_name(name[1:]) if marker and name.startswith(".") else path


def _remove_staging_debris(folders: Iterable[Path]) -> None:
    """Remove the staging folders that dead processes of this host left in these trial folders."""
    from torus_cad.outputs.output_set import remove_stale_staging

    for folder in folders:
        remove_stale_staging(folder)


def _distributions(spec: StudySpec) -> dict[str, BaseDistribution]:
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    distributions: dict[str, BaseDistribution] = {}
    for axis in spec.axes:
        if not axis.is_bounds:
            distributions[axis.key] = CategoricalDistribution(list(axis.values))
        elif axis.integer:
            distributions[axis.key] = IntDistribution(int(axis.low or 0), int(axis.high or 0))
        else:
            distributions[axis.key] = FloatDistribution(
                float(axis.low or 0.0), float(axis.high or 0.0)
            )
    return distributions


def _constraints(trial: FrozenTrial) -> list[float]:
    """optuna's constraints_func: the violations recorded with the trial (feasible when all <=
    0)."""
    return list(trial_result(trial).get(CONSTRAINT, [math.inf]))


def _sampler(spec: StudySpec, seed: int) -> BaseSampler:
    import optuna

    constraints = _constraints if spec.constraints else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ExperimentalWarning: constraints_func, constant_liar
        if spec.sampler is Sampler.TPE:
            return optuna.samplers.TPESampler(
                seed=seed, constraints_func=constraints, constant_liar=True
            )
        if spec.sampler is Sampler.CMAES:
            return optuna.samplers.CmaEsSampler(seed=seed, warn_independent_sampling=False)
        if spec.sampler is Sampler.NSGA2:
            return optuna.samplers.NSGAIISampler(
                seed=seed, constraints_func=constraints, population_size=spec.population
            )
        return optuna.samplers.RandomSampler(seed=seed)


def _load_study(spec: StudySpec, rdb: RDBStorage) -> optuna.Study:
    """The study in the storage (created on the first run); ParameterError if it was created from
    another file."""
    import optuna

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            directions: Any = spec.directions
            study = optuna.create_study(
                storage=rdb,
                study_name=spec.name,
                directions=directions,
                load_if_exists=True,
                sampler=_sampler(spec, spec.seed),
                pruner=_pruner(spec),
            )
        except ValueError as error:  # e.g. directions differ from the stored study's
            raise ParameterError(
                f"study {spec.name!r} in the storage does not match the study file: {error}"
            ) from None
    definition = spec.definition()
    stored = study.user_attrs.get(DEFINITION_ATTR)
    if stored is None:
        study.set_user_attr(DEFINITION_ATTR, definition)
    elif stored != definition:
        raise ParameterError(
            f"study {spec.name!r} in the storage was made from another base, [vary], objectives, "
            "constraints or [simulate]; give the study a new name (study.name) or another --out"
        )
    return study
