"""Where a study lives: an SQLite file (one machine) or a PostgreSQL server (workers on many
machines).

Every process that runs trials of a study takes :func:`claim_lock` to count the trials and ask
for the next one, so that processes sharing a study never ask for more than ``--trials`` in all:
an ``flock`` on a file beside the SQLite database, a PostgreSQL advisory lock on a server.

A process that dies (SIGKILL, a power cut) leaves its trials RUNNING. Each trial records its
owner (host, pid, process start time), and its process records a heartbeat every
:data:`HEARTBEAT_S` seconds; a RUNNING trial with no owner (its process died while claiming it),
one whose owner is gone from this host, or one whose heartbeat is older than :data:`GRACE_S`
(another host), is failed and its parameters are asked
again as a new trial that records ``retry_of`` (:func:`retry_stale_trials`).

All of it is optuna's public API: heartbeats through ``RDBStorage(heartbeat_interval=...,
grace_period=..., heartbeat_stale_trial_callback=...)``, the stale trials of other hosts failed by
``optuna.storages.fail_stale_trials``, a failed trial asked again by
``RetryHeartbeatStaleTrialCallback`` (``RetryFailedTrialCallback`` before optuna 4.9); this host's
dead owners are found first, at once, by their pid. The one private name left (the trials' table,
for the one-query count) sits in :func:`_trial_tables`, pinned to optuna's version.
"""

from __future__ import annotations

import contextlib
import copy
import fcntl
import hashlib
import os
import threading
import time
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import urlsplit, urlunsplit

from torus_cad.errors import ParameterError, TorusCadError
from torus_cad.runtime.processes import host_tag, process_identity

if TYPE_CHECKING:  # optuna and SQLAlchemy are imported where they are used (the optimize extra)
    import optuna
    import sqlalchemy
    from optuna.storages import RDBStorage
    from optuna.trial import FrozenTrial, Trial

__all__ = [
    "GRACE_S",
    "HEARTBEAT_S",
    "LEVEL",
    "LEVELS",
    "LEVEL_SECONDS",
    "PRESCREENED",
    "PRUNED_AT",
    "Heartbeat",
    "StorageError",
    "claim_lock",
    "count_trials",
    "fail_and_retry",
    "open_storage",
    "owner_record",
    "public_url",
    "retry_failed_trial",
    "retry_stale_trials",
    "storage_failures_named",
    "storage_url",
    "trial_result",
]

HEARTBEAT_S = 10  #: how often a running process records that its trials are alive, s
GRACE_S = 120  #: a RUNNING trial without a heartbeat for this long belongs to a dead process, s
# : how long a writer waits for SQLite's lock (several processes share one file)
_SQLITE_TIMEOUT_S = 120
_SCHEMES = ("sqlite", "postgresql")
# : tries to open a storage whose tables another process is creating at the same moment
_OPEN_ATTEMPTS = 5

RETRY_OF = "retry_of"  #: user attr of a trial that repeats an interrupted one: that trial's number
#: User attr of a trial failed because its run stopped (set before the FAIL, so that a run stopped
#: between recording a trial's outcome and telling it is still known as stopped, not as done).
STOPPED = "stopped"
#: User attr of a finished trial, written in one transaction: ``{"outcome", "reason", "seconds",
#: "folder", "metrics", "constraint"}`` (the outcome's value, the refusal's reason, the worker's s,
#: the trial's folder under the study's out folder, the metrics by name, the constraint violations);
#: read with :func:`trial_result`.
RESULT = "result"
OUTCOME, REASON, METRICS, CONSTRAINT, FOLDER, SECONDS = (
    "outcome",
    "reason",
    "metrics",
    "constraint",
    "folder",
    "seconds",
)  #: the keys of :data:`RESULT`
#: Key of :data:`RESULT`, True when the kernel-free checks refused the trial before any worker built
#: it.
PRESCREENED = "prescreened"
#: Key of :data:`RESULT` of a trial whose parameters an earlier complete trial had (a genetic
#: sampler's offspring can repeat a parent): that trial's number, whose values, metrics and files
#: (``folder``) it takes.
SAME_AS = "same_as"
#: Keys of :data:`RESULT` in a study of several mesh levels: the level of the trial's metrics (the
#: finest it reached), and the screening level at which the pruner stopped it (absent when it was
#: not pruned).
LEVEL, PRUNED_AT = "level", "pruned_at"
#: Key of :data:`RESULT` in a study of several mesh levels: the worker's seconds at each level the
#: trial ran, by level (the first level's include the build).
LEVEL_SECONDS = "level_seconds"
#: User attr of a trial of a study of several mesh levels, written as each level finishes (other
#: processes' pruners read it): ``{level: {"metrics": {...}, "feasible": bool, "seconds": s}}``.
LEVELS = "levels"
OWNER = "owner"  #: user attr: ``{"host", "pid", "start"}`` of the process that runs the trial


class StorageError(TorusCadError):
    """The study's storage cannot be opened (server unreachable, database file unwritable)."""


def storage_url(given: str, out_dir: Path, name: str) -> str:
    """The storage URL: ``given`` (``--storage`` or ``study.storage``), or SQLite
    ``OUT/<name>.db``."""
    if not given:
        return f"sqlite:///{out_dir / f'{name}.db'}"
    scheme = urlsplit(given).scheme.split("+")[0]
    if scheme not in _SCHEMES:
        raise ParameterError(
            f"storage = {public_url(given)!r} is not "
            "allowed; use '' (SQLite in the output folder), "
            "sqlite:///path.db or postgresql://user@host/database"
        )
    return given


def _with_driver(url: str) -> str:
    """``postgresql://`` with the driver that is installed named (psycopg2 from the optimize extra,
    else psycopg): SQLAlchemy's default driver changed between versions."""
    if not url.startswith("postgresql://"):
        return url
    import importlib.util

    driver = "psycopg2" if importlib.util.find_spec("psycopg2") is not None else "psycopg"
    return f"postgresql+{driver}://" + url.removeprefix("postgresql://")


def public_url(url: str) -> str:
    """``url`` with any password replaced by ``***``, for messages and tables."""
    parts = urlsplit(url)
    if parts.password is None:
        return url
    netloc = parts.netloc.replace(f":{parts.password}@", ":***@")
    return urlunsplit(parts._replace(netloc=netloc))


def _is_sqlite(url: str) -> bool:
    return url.startswith("sqlite")


def open_storage(url: str) -> RDBStorage:
    """optuna's RDBStorage at ``url`` with heartbeats, a stale trial asked again by
    :func:`retry_failed_trial`; StorageError naming the (password-free) URL."""
    import optuna
    import sqlalchemy.exc

    kwargs: dict[str, Any] = (
        {"connect_args": {"timeout": _SQLITE_TIMEOUT_S}}
        if _is_sqlite(url)
        else {"pool_pre_ping": True}
    )
    for attempt in range(_OPEN_ATTEMPTS):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # optuna's ExperimentalWarning for the heartbeat
                storage = optuna.storages.RDBStorage(
                    _with_driver(url),
                    engine_kwargs=kwargs,
                    heartbeat_interval=HEARTBEAT_S,
                    grace_period=GRACE_S,
                    heartbeat_stale_trial_callback=_Retries(),
                )
            if _is_sqlite(url):
                _write_ahead_log(storage.engine)
            return storage
        # another process created the tables at the same moment
        except sqlalchemy.exc.IntegrityError:
            if attempt == _OPEN_ATTEMPTS - 1:
                raise StorageError(
                    f"cannot create the study tables in {public_url(url)!r}: other processes "
                    "keep creating them"
                ) from None
            time.sleep(0.5)
        except (sqlalchemy.exc.SQLAlchemyError, ImportError, ValueError) as error:
            cause = " ".join(str(error).split("\n")[0].split())[:300]
            raise StorageError(
                f"cannot open the study storage {public_url(url)!r}: {cause}"
            ) from None
    raise AssertionError("unreachable")  # pragma: no cover


def _storage_cause(error: BaseException) -> str:
    """The cause of a storage failure in the database's own words ("database or disk is full"), from
    the driver's exception that optuna and SQLAlchemy wrap, on one line and cut to 300
    characters."""
    seen: set[int] = set()
    current: BaseException | None = error
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        original = getattr(current, "orig", None)  # SQLAlchemy's DBAPIError: the driver's exception
        if isinstance(original, BaseException) and str(original).strip():
            return " ".join(str(original).split())[:300]
        current = current.__cause__ or current.__context__
    return " ".join(str(error).split("\n")[0].split())[:300] or type(error).__name__


@contextlib.contextmanager
def storage_failures_named(url: str) -> Iterator[None]:
    """Within the block, a failure of the study storage (optuna's StorageInternalError, any
    SQLAlchemy error: a full disk, a file that became unwritable, a server that went away) becomes a
    :class:`StorageError` naming the storage (its URL, password hidden: for SQLite, the database
    file) and the cause."""
    import optuna
    import sqlalchemy.exc

    try:
        yield
    except (optuna.exceptions.StorageInternalError, sqlalchemy.exc.SQLAlchemyError) as error:
        raise StorageError(
            f"the study storage {public_url(url)!r} failed: {_storage_cause(error)}"
        ) from None


def _write_ahead_log(engine: sqlalchemy.engine.Engine) -> None:
    """SQLite in write-ahead-log mode with NORMAL synchronisation on every connection of ``engine``:
    a commit then costs no fsync (a trial's records take several), and a killed process still loses
    nothing it committed; only a power cut can undo the last commits (those trials are asked
    again)."""
    import sqlalchemy

    def configure(connection: Any, _record: Any) -> None:
        cursor = connection.cursor()
        cursor.execute("PRAGMA journal_mode=WAL")
        cursor.execute("PRAGMA synchronous=NORMAL")
        cursor.close()

    sqlalchemy.event.listen(engine, "connect", configure)
    engine.dispose()  # the connections opened to create the tables: new ones get the settings


@contextlib.contextmanager
def claim_lock(storage: RDBStorage | None, url: str, name: str) -> Iterator[None]:
    """Hold the study's lock (flock beside an SQLite file, an advisory lock on PostgreSQL) in the
    block.

    ``storage`` (the RDBStorage) is needed for PostgreSQL only; without it there is no lock there.
    """
    if _is_sqlite(url):
        database = url.split(":///", 1)[1].split("?")[0] if ":///" in url else ""
        if not database or database == ":memory:":
            yield
            return
        lock_path = Path(database).with_name(f".{Path(database).name}.lock")
        descriptor = os.open(lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(descriptor, fcntl.LOCK_EX)
            yield
        finally:
            os.close(descriptor)
        return
    if storage is None:
        yield
        return
    import sqlalchemy

    key = int.from_bytes(
        hashlib.sha256(f"torus_cad optimize {name}".encode()).digest()[:8], "big", signed=True
    )
    with storage.engine.connect() as connection:
        connection.execute(sqlalchemy.text("SELECT pg_advisory_lock(:key)"), {"key": key})
        connection.commit()
        try:
            yield
        finally:
            connection.execute(sqlalchemy.text("SELECT pg_advisory_unlock(:key)"), {"key": key})
            connection.commit()


def owner_record() -> dict[str, Any]:
    """This process: host, pid and start time (a successor with the same pid is told apart)."""
    return {"host": host_tag(), "pid": os.getpid(), "start": process_identity(os.getpid())}


def _owner_gone(owner: object) -> bool:
    """Whether ``owner`` (an :func:`owner_record`) is a process of this host that no longer runs."""
    if (
        not isinstance(owner, dict)
        or owner.get("host") != host_tag()
        or not isinstance(owner.get("pid"), int)
    ):
        return False
    return process_identity(owner["pid"]) != owner.get("start")


def retry_stale_trials(study: optuna.Study, rdb: RDBStorage) -> list[int]:
    """Fail the RUNNING trials of dead processes and ask their parameters again; the failed trials'
    numbers.

    Call under :func:`claim_lock`; ``rdb`` is the study's RDBStorage (:func:`open_storage`). A
    first, fast pass finds dead owners on this host by their pid, and a trial with no owner (its
    process died while claiming it); then optuna's ``fail_stale_trials`` fails the trials whose
    heartbeat is :data:`GRACE_S` old (owners on other hosts) and asks them again through
    :func:`retry_failed_trial`.
    """
    from optuna.storages import fail_stale_trials
    from optuna.trial import TrialState

    # Every process asks for a trial and records its owner under the claim lock, so a RUNNING trial
    # without an owner, seen under that lock, was being claimed by a process that died in between.
    stale = [
        trial.number
        for trial in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,))
        if OWNER not in trial.user_attrs or _owner_gone(trial.user_attrs[OWNER])
    ]
    retried = fail_and_retry(study, rdb, stale)
    recorder = rdb.get_heartbeat_stale_trial_callback()
    seen = len(recorder.numbers) if isinstance(recorder, _Retries) else 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # optuna's ExperimentalWarning for fail_stale_trials
        fail_stale_trials(study)
    return retried + (sorted(recorder.numbers[seen:]) if isinstance(recorder, _Retries) else [])


def retry_failed_trial(study: optuna.Study, trial: FrozenTrial) -> None:
    """Ask a failed trial's parameters again as a new WAITING trial that records ``retry_of``
    (optuna's ``RetryHeartbeatStaleTrialCallback``, given the trial with that one user attr: the
    failed run's own records, owner, result and stopped, stay with the failed trial)."""
    from optuna.storages import RetryHeartbeatStaleTrialCallback

    retry = copy.copy(trial)
    retry.user_attrs = {RETRY_OF: trial.number}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # optuna's ExperimentalWarning for the callback
        RetryHeartbeatStaleTrialCallback()(study, retry)


class _Retries:
    """The storage's ``heartbeat_stale_trial_callback``: :func:`retry_failed_trial`, keeping the
    numbers of the trials it asked again (``fail_stale_trials`` returns none)."""

    def __init__(self) -> None:
        self.numbers: list[int] = []

    def __call__(self, study: optuna.Study, trial: FrozenTrial) -> None:
        retry_failed_trial(study, trial)
        self.numbers.append(trial.number)


def trial_result(trial: FrozenTrial) -> dict[str, Any]:
    """The :data:`RESULT` record of a (frozen) trial; empty while it runs or when its run stopped
    first."""
    record = trial.user_attrs.get(RESULT)
    return record if isinstance(record, dict) else {}


def count_trials(rdb: RDBStorage, study_id: int) -> tuple[int, bool]:
    """The trials that count toward ``--trials`` (COMPLETE, PRUNED, RUNNING, WAITING, and FAIL with
    a recorded result and not stopped) and whether any is WAITING, in one query.

    One aggregate over optuna's tables, not a read of every trial: asking for a trial reads them
    anyway, and this count is made under :func:`claim_lock` before every ask. The FAIL rule is
    :func:`was_stopped`'s, in SQL: change them together."""
    import sqlalchemy
    from optuna.trial import TrialState

    trial, attr = _trial_tables()

    def has_attr(key: str) -> sqlalchemy.Exists:
        return sqlalchemy.exists().where(attr.trial_id == trial.trial_id, attr.key == key)

    counted = sqlalchemy.or_(
        trial.state.in_(
            [TrialState.COMPLETE, TrialState.PRUNED, TrialState.RUNNING, TrialState.WAITING]
        ),
        sqlalchemy.and_(trial.state == TrialState.FAIL, has_attr(RESULT), ~has_attr(STOPPED)),
    )
    query = sqlalchemy.select(
        sqlalchemy.func.count().filter(counted),
        sqlalchemy.func.count().filter(trial.state == TrialState.WAITING),
    ).where(trial.study_id == study_id)
    with rdb.engine.connect() as connection:
        total, waiting = connection.execute(query).one()
    return int(total or 0), bool(waiting)


def _trial_tables() -> tuple[Any, Any]:
    """optuna's trial and trial-user-attribute tables (SQLAlchemy models), for :func:`count_trials`.

    The one private name of optuna this package uses, read as of optuna 5.0.0 (constraints.txt): the
    public API has no aggregate over a study's trials. A new optuna: check the models' names and
    columns (``trial_id``, ``study_id``, ``state``; ``trial_id``, ``key``)."""
    # private: optuna's public API counts no trials in one query; read as of optuna==5.0.0
    # (constraints.txt)
    from optuna.storages._rdb import models

    return models.TrialModel, models.TrialUserAttributeModel


def was_stopped(trial: FrozenTrial) -> bool:
    """A FAIL trial whose run stopped (asked again), not one failed for a reason of its design."""
    from optuna.trial import TrialState

    return trial.state is TrialState.FAIL and (
        RESULT not in trial.user_attrs or STOPPED in trial.user_attrs
    )


def fail_and_retry(study: optuna.Study, rdb: RDBStorage, trial_numbers: Iterable[int]) -> list[int]:
    """Fail each of these trials that is still RUNNING, marked :data:`STOPPED` first, and ask its
    parameters again (:func:`retry_failed_trial`); the numbers of the trials failed (one that
    another process finished is skipped)."""
    import optuna
    from optuna.trial import TrialState

    study_id = rdb.get_study_id_from_name(study.study_name)
    retried = []
    for number in sorted(set(trial_numbers)):
        trial_id = rdb.get_trial_id_from_study_id_trial_number(study_id, number)
        try:
            rdb.set_trial_user_attr(trial_id, STOPPED, True)
            if not rdb.set_trial_state_values(trial_id, state=TrialState.FAIL):
                continue
        except optuna.exceptions.UpdateFinishedTrialError:
            continue  # another process finished or failed it first
        retry_failed_trial(study, rdb.get_trial(trial_id))
        retried.append(number)
    return retried


class Heartbeat:
    """A thread that records the heartbeat of the trials this process runs, every
    :data:`HEARTBEAT_S` s (optuna's ``RDBStorage.record_heartbeat``; optuna's own thread runs inside
    ``Study.optimize`` only)."""

    def __init__(self, storage: RDBStorage, study: optuna.Study) -> None:
        self._storage = storage
        self._study_id = storage.get_study_id_from_name(study.study_name)
        self._trial_ids: dict[int, int] = {}  # trial number -> trial id
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(
            target=self._run, name="torus-cad study heartbeat", daemon=True
        )

    def __enter__(self) -> Heartbeat:
        self._thread.start()
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def add(self, trial: Trial) -> None:
        trial_id = self._storage.get_trial_id_from_study_id_trial_number(
            self._study_id, trial.number
        )
        with self._lock:
            self._trial_ids[trial.number] = trial_id
        self._beat([trial_id])

    def discard(self, trial: Trial) -> None:
        with self._lock:
            self._trial_ids.pop(trial.number, None)

    def _beat(self, trial_ids: list[int]) -> None:
        for trial_id in trial_ids:
            with contextlib.suppress(Exception):  # a lost heartbeat is retried; the trial goes on
                self._storage.record_heartbeat(trial_id)

    def _run(self) -> None:
        while not self._stop.wait(HEARTBEAT_S):
            with self._lock:
                trial_ids = sorted(self._trial_ids.values())
            self._beat(trial_ids)
