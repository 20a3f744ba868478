"""A study's results: every trial in one table, the objective's history, the best designs built.

* ``OUT/results.csv`` and ``OUT/results.parquet`` (the batch table code): one row per trial with
  its state, outcome and reason, varied values, metrics, constraint violations and folder (and, in a
  study of several mesh levels, the level of its metrics: state ``pruned`` for a trial stopped
  there);
* ``OUT/<name>_history.png``: each objective against the trial number with the best feasible
  value so far, and ``OUT/<name>_pareto.png`` for two objectives;
* ``OUT/best/<name>_best.toml`` (one objective) or ``OUT/best/<name>_pareto_<number>.toml``
  (the Pareto front): design files that ``torus-cad build`` reads unchanged, each with the output
  set its trial wrote (STEP, STL, 3MF as the design asks, JSON) copied beside it under its name: the
  files the study judged, not a rebuild. A best trial whose files cannot be published is named in
  one line and (one objective) the next best feasible trial is published instead;
* ``OUT/<name>_study.json``: counts, the best trials and their values.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from torus_cad.batch.table import write_table
from torus_cad.optimize.storage import (
    CONSTRAINT,
    FOLDER,
    LEVEL,
    LEVEL_SECONDS,
    METRICS,
    OUTCOME,
    PRESCREENED,
    PRUNED_AT,
    REASON,
    RETRY_OF,
    SAME_AS,
    SECONDS,
    trial_result,
    was_stopped,
)
from torus_cad.optimize.study_file import StudySpec
from torus_cad.optimize.trial_job import TRIALS_DIR, trial_name

if TYPE_CHECKING:  # optuna and matplotlib are imported where they are used
    import optuna
    from matplotlib.figure import Figure
    from optuna.trial import FrozenTrial

    from torus_cad.parameters import PropellerParameters

__all__ = ["BEST_DIR", "MAX_PARETO_BUILDS", "best_trials", "trial_rows", "write_results"]

BEST_DIR = "best"
MAX_PARETO_BUILDS = 20  #: Pareto designs built with their files (every one gets its TOML)
INTERRUPTED = "interrupted"


def write_results(
    spec: StudySpec, study: optuna.Study, out: Path, checkpoint: Callable[[], None] | None = None
) -> tuple[dict[str, Path], list[str]]:
    """Write the table, the pictures, the best designs and the summary JSON; the paths and summary
    lines.

    ``checkpoint`` is called before each of them: it may raise (a signal arrived) to stop there,
    each file or set written so far being whole."""
    from torus_cad.runtime.files import atomic_path

    check = checkpoint or (lambda: None)
    trials = study.get_trials(deepcopy=False)
    rows, columns = trial_rows(spec, trials)
    best = best_trials(spec, study)  # read now: the storage is not needed after this line
    check()
    files: dict[str, Path] = dict(write_table(rows, out, columns))
    check()
    files["history"] = _history_picture(spec, trials, out / f"{spec.name}_history.png")
    if len(spec.objectives) == 2:
        check()
        files["pareto"] = _pareto_picture(spec, trials, best, out / f"{spec.name}_pareto.png")
    check()
    lines, built = _publish_best(spec, trials, best, out / BEST_DIR, out)
    check()
    spent = _level_seconds(trials)
    pruned = _count(
        str(record[PRUNED_AT]) for record in map(trial_result, trials) if PRUNED_AT in record
    )
    lines = [
        _outcomes_line(rows),
        *_level_lines(spec, spent, pruned),
        *unvalued_lines(rows),
        *lines,
    ]
    published = [trial for trial in trials if trial.number in built]
    summary = {
        "name": spec.name,
        "trials": len(trials),
        "states": _count(row["state"] for row in rows),
        "outcomes": _count(row["outcome"] for row in rows),
        "prescreened": sum(1 for row in rows if row["prescreened"]),
        "pruned": pruned,
        "level_seconds": spent,
        "best": [
            {
                "number": trial.number,
                "values": list(trial.values),
                "params": dict(trial.params),
                "design": str(built[trial.number]),
            }
            for trial in published
        ],
        "not_published": [trial.number for trial in best if trial.number not in built],
    }
    files["summary"] = out / f"{spec.name}_study.json"
    with atomic_path(files["summary"]) as temp:
        temp.write_text(json.dumps(summary, indent=2, allow_nan=False, default=str) + "\n")
    return files, lines


def _outcomes_line(rows: Sequence[dict[str, Any]]) -> str:
    """``"  trials: 9 valid, 5 refused (4 before the kernel, pre-screened), 1 failed"`` and any
    other outcome; ``"9 valid (6 pruned at a screening level)"`` in a study of several mesh
    levels."""
    counts = _count(row["outcome"] for row in rows if row["outcome"])
    screened = sum(1 for row in rows if row["prescreened"])
    pruned = sum(1 for row in rows if row["state"] == "pruned")
    parts = [f"{counts.pop(name, 0)} {name}" for name in ("valid", "refused", "failed")]
    if pruned:
        parts[0] += f" ({pruned} pruned at a screening level)"
    if screened:
        parts[1] += f" ({screened} before the kernel, pre-screened)"
    return "  trials: " + ", ".join(
        parts + [f"{count} {name}" for name, count in sorted(counts.items())]
    )


def _level_seconds(trials: Sequence[FrozenTrial]) -> dict[str, dict[str, float]]:
    """By mesh level: the trials that ran it and their worker seconds there (a study of several
    levels)."""
    spent: dict[str, dict[str, float]] = {}
    for trial in trials:
        for level, seconds in trial_result(trial).get(LEVEL_SECONDS, {}).items():
            entry = spent.setdefault(level, {"trials": 0, "seconds": 0.0})
            entry["trials"] += 1
            entry["seconds"] += float(seconds or 0.0)
    return spent


def _level_lines(
    spec: StudySpec, spent: Mapping[str, Mapping[str, float]], pruned: Mapping[str, int]
) -> list[str]:
    """``"  coarse: 12 trials, 1430 s (5 pruned); medium: 7 trials, 2210 s"``: what each mesh level
    cost (``spent``: :func:`_level_seconds`; ``pruned``: trials stopped at each level)."""
    if len(spec.levels) < 2:
        return []
    parts = []
    for level in spec.levels:
        entry = spent.get(level, {"trials": 0, "seconds": 0.0})
        stopped = f" ({pruned[level]} pruned)" if pruned.get(level) else ""
        parts.append(f"{level}: {entry['trials']:.0f} trials, {entry['seconds']:.0f} s{stopped}")
    return ["  levels: " + "; ".join(parts)]


def _count(items: Any) -> dict[str, int]:
    counts: dict[str, int] = {}
    for item in items:
        counts[item] = counts.get(item, 0) + 1
    return counts


def best_trials(spec: StudySpec, study: optuna.Study) -> list[FrozenTrial]:
    """The best feasible trial (one objective) or the feasible Pareto front (several), by trial
    number; a trial that repeats another's parameters (``same_as``) is left to the trial it repeats,
    which has its values."""
    if len(spec.objectives) > 1:
        return sorted(
            (trial for trial in study.best_trials if SAME_AS not in trial_result(trial)),
            key=lambda trial: trial.number,
        )
    try:
        return [study.best_trial]
    except ValueError:  # no feasible complete trial yet
        return []


def trial_rows(
    spec: StudySpec, trials: Sequence[FrozenTrial]
) -> tuple[list[dict[str, Any]], list[str]]:
    """One row per trial and the columns, in table order."""
    metrics = list(dict.fromkeys(spec.metrics))
    levels = ["level"] if len(spec.levels) > 1 else []  # the level of the row's metrics
    columns = (
        ["number", "state", "outcome", "feasible", "reason", "prescreened"]
        + [axis.key for axis in spec.axes]
        + levels
        + metrics
        + ["violation", "retry_of", "same_as", "seconds", "folder"]
    )
    retried_by = {
        trial.user_attrs[RETRY_OF]: trial.number for trial in trials if RETRY_OF in trial.user_attrs
    }
    rows = []
    for trial in trials:
        attrs, record = trial.user_attrs, trial_result(trial)
        row: dict[str, Any] = dict.fromkeys(columns)
        state = trial.state.name.lower()
        outcome, reason = record.get(OUTCOME), record.get(REASON, "")
        if was_stopped(trial):
            outcome = INTERRUPTED
            again = retried_by.get(trial.number)
            reason = "its run stopped" + (
                f"; asked again as trial {again}" if again is not None else ""
            )
        violations = record.get(CONSTRAINT, [])
        row.update(
            number=trial.number,
            state=state,
            outcome=outcome or "",
            reason=reason,
            prescreened=record.get(PRESCREENED) is True,
            feasible=state == "complete" and all(v <= 0.0 for v in violations),
            violation=max(violations) if violations else None,
            retry_of=attrs.get(RETRY_OF),
            same_as=record.get(SAME_AS),
            seconds=record.get(SECONDS),
            folder=record.get(FOLDER),
        )
        if levels:
            row["level"] = record.get(LEVEL)
            if PRUNED_AT in record:
                reason = reason or f"pruned at the {record[PRUNED_AT]} level"
                row["reason"] = reason
        for axis in spec.axes:
            value = trial.params.get(axis.key)
            row[axis.key] = value if not isinstance(value, (list, tuple)) else json.dumps(value)
        for metric, value in record.get(METRICS, {}).items():
            if metric in row:
                row[metric] = value
        rows.append(row)
    return rows, columns


#: Trials without a value (refused, failed) the terminal summary names one by one; the rest are
#: counted.
MAX_UNVALUED_LINES = 5


def unvalued_lines(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Summary lines for the finished trials that have no objective value (a refused or failed
    design, not one whose run stopped): number, outcome and reason, so a refused design is not
    silently missing."""
    unvalued = [
        row for row in rows if row["state"] == "fail" and row["outcome"] not in ("", INTERRUPTED)
    ]
    lines = [
        f"  trial {row['number']} {row['outcome']}: {row['reason']}"
        for row in unvalued[:MAX_UNVALUED_LINES]
    ]
    if len(unvalued) > MAX_UNVALUED_LINES:
        lines.append(
            f"  and {len(unvalued) - MAX_UNVALUED_LINES} more "
            "trials without a value (see results.csv)"
        )
    return lines


def _feasible(trial: FrozenTrial) -> bool:
    return trial.state.name == "COMPLETE" and all(
        v <= 0.0 for v in trial_result(trial).get(CONSTRAINT, [])
    )


def _history_picture(spec: StudySpec, trials: Sequence[FrozenTrial], path: Path) -> Path:
    """Each objective against the trial number: feasible, infeasible, and the best so far."""
    return _save_png(history_figure(spec, trials), path)


def history_figure(spec: StudySpec, trials: Sequence[FrozenTrial]) -> Figure:
    """The history picture's matplotlib figure: each objective against the trial number (feasible,
    infeasible, the best so far), and the trials without a value (refused, failed) as marks along
    the bottom of each panel."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    unvalued = [
        trial.number
        for trial in trials
        if trial.state.name == "FAIL"
        and not was_stopped(trial)
        and trial_result(trial).get(OUTCOME)
    ]

    figure, axes = plt.subplots(
        len(spec.objectives), 1, figsize=(8, 3.2 * len(spec.objectives)), squeeze=False
    )
    complete = [trial for trial in trials if trial.state.name == "COMPLETE"]
    for index, (objective, axis) in enumerate(zip(spec.objectives, axes[:, 0])):
        good = [(t.number, t.values[index]) for t in complete if _feasible(t)]
        bad = [(t.number, t.values[index]) for t in complete if not _feasible(t)]
        pruned = [(t.number, value[index]) for t, value in _pruned_values(spec, trials)]
        if pruned:
            axis.scatter(
                *zip(*pruned),
                marker="^",
                color="0.75",
                label="pruned (its value at a screening level)",
            )
        if bad:
            axis.scatter(
                *zip(*bad), marker="x", color="0.6", label="infeasible (a constraint is broken)"
            )
        if good:
            axis.scatter(*zip(*good), color="tab:blue", label="feasible")
            pick = min if objective.direction.value == "minimize" else max
            best, steps = math.nan, []
            for number, value in good:
                best = value if math.isnan(best) else pick(best, value)
                steps.append((number, best))
            axis.step(*zip(*steps), where="post", color="tab:red", label="best so far")
        if unvalued:  # no value to plot: a mark at the bottom of the panel, at its trial number
            axis.plot(
                unvalued,
                [0.02] * len(unvalued),
                "v",
                color="tab:orange",
                transform=axis.get_xaxis_transform(),
                label="refused or failed (no value; see results.csv)",
            )
        axis.set_xlabel("trial")
        axis.xaxis.set_major_locator(MaxNLocator(integer=True))
        axis.set_ylabel(objective.metric)
        axis.set_title(f"{spec.name}: {objective.direction.value} {objective.metric}")
        axis.grid(alpha=0.3)
        if good or bad or unvalued or pruned:
            axis.legend(loc="best", fontsize="small")
    return figure


def _pruned_values(
    spec: StudySpec, trials: Sequence[FrozenTrial]
) -> list[tuple[FrozenTrial, list[float]]]:
    """The pruned trials with their objective values at the screening level they stopped at."""
    pruned = []
    for trial in trials:
        metrics = trial_result(trial).get(METRICS, {}) if trial.state.name == "PRUNED" else {}
        try:
            pruned.append(
                (trial, [float(metrics[objective.metric]) for objective in spec.objectives])
            )
        except (KeyError, TypeError, ValueError):
            continue
    return pruned


def _save_png(figure: Figure, path: Path) -> Path:
    """Write a matplotlib figure as a PNG, atomically, and close it."""
    import matplotlib.pyplot as plt

    from torus_cad.runtime.files import atomic_path

    figure.tight_layout()
    with atomic_path(path) as temp:
        figure.savefig(temp, format="png", dpi=100)
    plt.close(figure)
    return path


def _pareto_picture(
    spec: StudySpec, trials: Sequence[FrozenTrial], front: Sequence[FrozenTrial], path: Path
) -> Path:
    """The two objectives of every complete trial, the feasible Pareto front highlighted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(6, 5))
    complete = [trial for trial in trials if trial.state.name == "COMPLETE"]
    pruned = _pruned_values(spec, trials)
    if pruned:
        axis.scatter(
            [v[0] for _, v in pruned],
            [v[1] for _, v in pruned],
            marker="^",
            color="0.75",
            label=f"pruned (at {'/'.join(spec.levels[:-1])})",
        )
    styles: list[tuple[str, list[Any], dict[str, Any]]] = [
        ("infeasible", [t for t in complete if not _feasible(t)], {"marker": "x", "color": "0.6"}),
        ("feasible", [t for t in complete if _feasible(t)], {"color": "tab:blue"}),
        ("Pareto front", sorted(front, key=lambda t: t.values[0]), {"color": "tab:red"}),
    ]
    for label, group, style in styles:
        if group:
            axis.scatter(
                [t.values[0] for t in group], [t.values[1] for t in group], label=label, **style
            )
    first, second = spec.objectives
    axis.set_xlabel(f"{first.metric} ({first.direction.value})")
    axis.set_ylabel(f"{second.metric} ({second.direction.value})")
    axis.set_title(f"{spec.name}: Pareto front")
    axis.grid(alpha=0.3)
    if complete or pruned:
        axis.legend(loc="best", fontsize="small")
    return _save_png(figure, path)


def _publish_best(
    spec: StudySpec,
    trials: Sequence[FrozenTrial],
    best: Sequence[FrozenTrial],
    folder: Path,
    out: Path,
) -> tuple[list[str], dict[int, Path]]:
    """Write each best design's TOML and publish beside it, as an output set, the files its trial
    wrote (copied, not rebuilt: the study judged the trial on them). A trial whose set cannot be
    published is named in one line; for one objective the next best feasible trial takes its
    place."""
    from torus_cad.errors import TorusCadError

    if not best:
        return ["  no feasible trial yet: no best design"], {}
    folder.mkdir(parents=True, exist_ok=True)
    single = len(spec.objectives) == 1
    if single:
        ranked = [best[0]] + [
            trial for trial in _ranked_feasible(spec, trials) if trial.number != best[0].number
        ]
        slots = [(f"{spec.name}_best", ranked)]
    else:
        slots = [(f"{spec.name}_pareto_{trial.number}", [trial]) for trial in best]
        _remove_stale_pareto(spec, folder, {name for name, _ in slots})
    lines, built = [], {}
    for position, (name, candidates) in enumerate(slots):
        for rank, trial in enumerate(candidates):
            try:
                path = _publish_trial(
                    spec, trial, name, folder, out, with_files=position < MAX_PARETO_BUILDS
                )
            except (TorusCadError, OSError) as error:
                lines.append(
                    f"  trial {trial.number} is not published: {' '.join(str(error).split())}"
                )
                continue
            built[trial.number] = path
            values = ", ".join(
                f"{o.metric} = {v:.6g}" for o, v in zip(spec.objectives, trial.values)
            )
            which = "best" if rank == 0 else "next best"
            lines.append(f"  {which} trial {trial.number}: {values}; design {path}")
            break
    return lines, built


def _ranked_feasible(spec: StudySpec, trials: Sequence[FrozenTrial]) -> list[FrozenTrial]:
    """The feasible complete trials of a one-objective study, best first."""
    sign = -1.0 if spec.objectives[0].direction.value == "maximize" else 1.0
    return sorted(
        (trial for trial in trials if _feasible(trial)),
        key=lambda trial: (sign * trial.values[0], trial.number),
    )


def _publish_trial(
    spec: StudySpec, trial: FrozenTrial, name: str, folder: Path, out: Path, with_files: bool = True
) -> Path:
    """``folder/<name>.toml`` (the trial's design under ``name``) and, with ``with_files``, the
    trial's own output set copied beside it as the set ``name`` (unless that set is already
    current).

    Raises IncompleteOutputError when the trial's set is incomplete or lacks a format its design
    writes (a trial run before trials wrote every format), OSError when a copy cannot be written."""
    from torus_cad.parameters import PropellerParameters
    from torus_cad.runtime.files import atomic_path

    parameters = PropellerParameters.from_dict(spec.parameters(trial.params, name))
    toml = parameters.to_toml()
    path = folder / f"{name}.toml"
    if path.is_file() and path.read_text() == toml and (not with_files or _complete(folder, name)):
        return path
    if with_files:
        _copy_trial_set(trial, parameters, name, folder, out, stl=spec.stl)
    with atomic_path(path) as temp:
        temp.write_text(toml)
    return path


def _copy_trial_set(
    trial: FrozenTrial,
    parameters: PropellerParameters,
    name: str,
    folder: Path,
    out: Path,
    stl: bool = True,
) -> None:
    """Publish the trial's verified output set (renamed ``name``: its files and its report, which
    names the trial it came from) in ``folder``; the copies are checked against the trial's SHA-256.
    The set must hold every format of the design's ``export.formats`` (STL only if ``stl``)."""
    import shutil

    from torus_cad.errors import IncompleteOutputError
    from torus_cad.outputs.output_set import FILES_KEY, OutputSet, file_entry, verify_set

    source = out / str(trial_result(trial).get(FOLDER, f"{TRIALS_DIR}/{trial.number}"))
    # a trial's twin's files are its own
    design = trial_name(int(trial_result(trial).get(SAME_AS, trial.number)))
    report = json.loads(verify_set(source, design).report.read_text(encoding="utf-8"))
    files: dict[str, dict[str, Any]] = report[FILES_KEY]
    formats = {fmt.value for fmt in parameters.export.formats if stl or fmt.value != "stl"}
    missing = sorted(formats - set(files))
    if missing:
        raise IncompleteOutputError(f"{design}: its output set has no {', '.join(missing)} file")

    def copy(kind: str, entry: dict[str, Any]) -> Any:
        renamed = (
            name + entry["file"][len(design) :]
            if entry["file"].startswith(design)
            else entry["file"]
        )

        def write(staging: Path) -> dict[str, Path]:
            copied = Path(shutil.copyfile(source / entry["file"], staging / renamed))
            if file_entry(copied)["sha256"] != entry["sha256"]:
                raise IncompleteOutputError(
                    f"{design}: the copy of {entry['file']} differs from the trial's"
                )
            return {kind: copied}

        return write

    with OutputSet(folder, name) as output:
        for kind, entry in files.items():
            output.write_files(copy(kind, entry))
        sealed = {key: value for key, value in report.items() if key != FILES_KEY}
        sealed.update(
            name=name,
            study_trial={
                "number": trial.number,
                "design": design,
                "folder": source.relative_to(out).as_posix(),
            },
        )
        output.publish(sealed)


def _complete(folder: Path, name: str) -> bool:
    from torus_cad.errors import IncompleteOutputError
    from torus_cad.outputs.output_set import verify_set

    try:
        verify_set(folder, name)
    except IncompleteOutputError:
        return False
    return True


def _remove_stale_pareto(spec: StudySpec, folder: Path, keep: set[str]) -> None:
    """Designs of an earlier Pareto front that the current one no longer holds."""
    prefix = f"{spec.name}_pareto_"
    for path in folder.iterdir():
        stem = path.name.split(".")[0]
        if path.is_file() and stem.startswith(prefix) and stem not in keep:
            path.unlink(missing_ok=True)
