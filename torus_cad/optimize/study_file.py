"""The study file: TOML naming a base design, the keys to vary, the objectives and the constraints.

::

    [study]
    name = "light_prop"
    base = "my_prop.toml"        # optional, relative to this file (default: the built-in design)
    trials = 40
    sampler = "tpe"              # tpe | cmaes | nsga2 | random
    seed = 0
    storage = ""                 # "": SQLite file OUT/<name>.db; or postgresql://user@host/db

    [vary]                       # dotted design keys; [i] picks a vector element
    "airfoil.thickness" = [0.2, 0.6]     # two numbers: a range (whole numbers stay whole numbers)
    "handedness" = ["cw", "ccw"]         # strings (or true / false): a choice

    [[objective]]
    metric = "mass_g"  # a number of the build report (dotted), or performance.* (runs simulate)
    direction = "minimize"

    [constraints]
    "printability.thinnest_wall_mm" = { min = 0.8 }

    [simulate]         # only with a performance.* metric
    rpm = 8000.0       # or thrust = 1.0 (N): each trial solved to that thrust, as simulate --thrust
    airspeed = 0.0     # m/s
    level = "coarse"   # or levels = ["coarse", "medium"]: cheap levels screen, good designs climb

    [pruner]           # only with two or more levels: which trials climb
    kind = "median"    # median | halving (one objective) | dominated | none

The tables are checked by pydantic models of the design schema's kind (strict types, no
unknown keys, one line naming the key); the varied keys and their ranges by the schema itself,
as a sweep's are. Every problem is a ParameterError (exit code 2 at the command line).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

from pydantic import Field, ValidationError

from torus_cad.batch.designs import apply_axis_values
from torus_cad.batch.sweep_file import (
    VaryAxis,
    axis_paths_relative_to,
    check_distinct_axes,
    checked_value,
    flatten_vary,
    resolve_leaf,
)
from torus_cad.design.described_geometry import sampled_blade_surface
from torus_cad.errors import ParameterError, shown
from torus_cad.optimize.metrics import (
    PERFORMANCE_PREFIX,
    check_metric,
    is_performance,
    noise_observers,
)
from torus_cad.optimize.trial_simulation import VORTEX_LEVEL
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.config_file import read_config_table
from torus_cad.parameters.schema import Section, param, parameter_error
from torus_cad.simulate.settings import Level
from torus_cad.simulate.thrust_target import DEFAULT_MAX_RUNS, DEFAULT_TOLERANCE
from torus_cad.tolerances import (
    DESIGN_TIME_LIMIT_MAX_S,
    MAX_STUDY_TRIALS,
    NOISE_MAX_OBSERVERS,
    SIMULATE_AIRSPEED_LIMIT_M_S,
    SIMULATE_MAX_ITERATIONS,
    SIMULATE_RPM_LIMIT,
    SIMULATE_THRUST_LIMIT_N,
    THRUST_RUNS_RANGE,
    THRUST_TOLERANCE_RANGE,
)

__all__ = [
    "Direction",
    "Objective",
    "Pruner",
    "PrunerKind",
    "Sampler",
    "StudySpec",
    "parse_study",
    "read_study_file",
]

_NAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}$")


class Sampler(StrEnum):
    """The search: optuna's samplers."""

    TPE = "tpe"  #: tree-structured Parzen estimator (one or more objectives)
    CMAES = "cmaes"  #: CMA-ES (one objective, no constraints)
    NSGA2 = "nsga2"  #: NSGA-II, the Pareto front of several objectives
    RANDOM = "random"  #: independent uniform samples


class Direction(StrEnum):
    MINIMIZE = "minimize"
    MAXIMIZE = "maximize"


class PrunerKind(StrEnum):
    """Which trials of a study of several mesh levels climb from one level to the next."""

    # : optuna's MedianPruner: worse than the median of the complete trials at that level stops
    MEDIAN = "median"
    # : optuna's SuccessiveHalvingPruner: the best 1/reduction_factor at each level climb
    HALVING = "halving"
    # : several objectives: stops when another trial's values at that level dominate its own
    DOMINATED = "dominated"
    NONE = "none"  #: every trial climbs (the screening levels' values are only recorded)


#: The pruners of optuna, which judge one value (Trial.report and should_prune take one objective).
ONE_OBJECTIVE_PRUNERS = (PrunerKind.MEDIAN, PrunerKind.HALVING)
#: Study-file keys of [simulate] for a target thrust (given without ``thrust``, they are refused).
_THRUST_KEYS = ("thrust_tolerance", "thrust_runs")


class StudyTable(Section):
    """[study]: the study's name, size, sampler and storage."""

    name: str = param(
        "",
        doc=(
            "the study's name (files OUT/<name>.db, "
            "OUT/best/<name>_best.toml); default: the file's stem"
        ),
    )
    base: str = param(
        "",
        doc="the design file every trial starts from, relative to the study file ('' = defaults)",
    )
    trials: int = param(
        20, ge=1, le=MAX_STUDY_TRIALS, doc="trials in the study in all (--trials overrides it)"
    )
    sampler: Sampler = param(Sampler.TPE, strict=False, doc="tpe | cmaes | nsga2 | random")
    seed: int = param(0, ge=0, le=2**31 - 1, doc="the sampler's random seed")
    storage: str = param("", doc="'' = SQLite file OUT/<name>.db; or a postgresql:// URL")
    population: int = param(20, ge=2, le=10000, doc="nsga2: designs per generation")
    stl: bool = param(
        True,
        doc="each trial writes its STL, so it is judged on every file its best set holds "
        "(false: trials and best sets without STL)",
    )
    time_limit_s: float = param(
        0.0,
        unit="s",
        ge=0.0,
        le=DESIGN_TIME_LIMIT_MAX_S,
        doc="per trial on the local pool (0 = 300 s, or 3600 s with simulate)",
    )


class ObjectiveTable(Section):
    """One [[objective]]."""

    metric: str = param("", doc="a number of the build report (dotted) or performance.*")
    direction: Direction = param(Direction.MINIMIZE, strict=False, doc="minimize | maximize")


class BoundTable(Section):
    """One constraint: the metric's allowed interval."""

    min: float | None = None
    max: float | None = None


class StudyLevel(StrEnum):
    """The fidelity a trial is evaluated at, cheapest first: the vortex solver (``simulate --solver
    vortex``, seconds) or one of OpenFOAM's mesh levels (``simulate --level``)."""

    VORTEX = VORTEX_LEVEL
    COARSE = Level.COARSE.value
    MEDIUM = Level.MEDIUM.value
    FINE = Level.FINE.value


class SimulateTable(Section):
    """[simulate]: how ``torus-cad simulate`` runs each trial."""

    rpm: float = param(0.0, ge=0.0, le=SIMULATE_RPM_LIMIT, doc="rotational speed, rpm (or thrust)")
    thrust: float = param(
        0.0,
        unit="N",
        ge=0.0,
        le=SIMULATE_THRUST_LIMIT_N,
        doc="target thrust: each trial solved to it as simulate --thrust does (or rpm)",
    )
    thrust_tolerance: float = param(
        DEFAULT_TOLERANCE,
        ge=THRUST_TOLERANCE_RANGE[0],
        le=THRUST_TOLERANCE_RANGE[1],
        doc="the target thrust's tolerance, a fraction (simulate --thrust-tolerance)",
    )
    thrust_runs: int = param(
        DEFAULT_MAX_RUNS,
        ge=THRUST_RUNS_RANGE[0],
        le=THRUST_RUNS_RANGE[1],
        doc="solver runs of a trial's rpm search at most (simulate --thrust-runs)",
    )
    airspeed: float = param(
        0.0,
        unit="m/s",
        ge=0.0,
        le=SIMULATE_AIRSPEED_LIMIT_M_S,
        doc="axial inflow speed (simulate --airspeed's range)",
    )
    level: StudyLevel = param(
        StudyLevel.COARSE,
        strict=False,
        doc="vortex (the vortex solver) or the mesh level of the simulation",
    )
    levels: list[Annotated[StudyLevel, Field(strict=False)]] = Field(
        default_factory=list,
        json_schema_extra={"unit": ""},
        description="levels, cheapest first (vortex, coarse, "
        "medium, fine): every trial runs the first, those the "
        "pruner keeps climb to the next (instead of level)",
    )
    iterations: int = param(
        0, ge=0, le=SIMULATE_MAX_ITERATIONS, doc="SIMPLE iterations (0: the level's own)"
    )
    processes: int = param(0, ge=0, le=2, doc="MPI processes of each simulation (0: one per CPU)")


class PrunerTable(Section):
    """[pruner]: which trials climb from one mesh level to the next."""

    kind: PrunerKind | None = param(
        None,
        strict=False,
        doc="median | halving (one objective) | dominated | none; "
        "default median for one objective, dominated for several",
    )
    startup_trials: int = param(
        4,
        ge=0,
        le=MAX_STUDY_TRIALS,
        doc="trials that reach a level before any is stopped there (median: complete trials)",
    )
    reduction_factor: int = param(
        3, ge=2, le=100, doc="halving: 1 in this many trials climbs at each level"
    )


class StudyFile(Section):
    """A whole study file."""

    study: StudyTable = Field(default_factory=StudyTable)
    vary: dict[str, list[int | float | bool | str]] = Field(default_factory=dict)
    objective: list[ObjectiveTable] = Field(default_factory=list)
    constraints: dict[str, BoundTable] = Field(default_factory=dict)
    simulate: SimulateTable = Field(default_factory=SimulateTable)
    pruner: PrunerTable = Field(default_factory=PrunerTable)


@dataclass(frozen=True)
class Pruner:
    """Which trials climb from one mesh level to the next (:class:`PrunerKind`); ``startup_trials``:
    trials that reach a level before any is stopped there; ``reduction_factor``: halving's."""

    kind: PrunerKind
    startup_trials: int = 4
    reduction_factor: int = 3


@dataclass(frozen=True)
class Objective:
    metric: str
    direction: Direction


@dataclass(frozen=True)
class Constraint:
    """``low <= metric <= high`` (either may be None)."""

    metric: str
    low: float | None
    high: float | None

    def violations(self, value: float) -> list[float]:
        """optuna's convention: a number per bound, feasible when <= 0."""
        return ([self.low - value] if self.low is not None else []) + (
            [value - self.high] if self.high is not None else []
        )


@dataclass(frozen=True)
class StudySpec:
    """A checked study.

    Attributes:
        name: the study's name (storage and file names).
        base: the design every trial starts from.
        axes: the varied keys: ``low``/``high`` for a range (``integer`` for whole numbers),
            ``values`` for a choice.
        objectives: what to optimise, in order.
        constraints: the allowed intervals of metrics.
        trials: trials in all.
        sampler, seed, population: the search.
        storage: the storage URL from the file ('' = SQLite in the output folder).
        simulate: ``{"rpm", "airspeed", "level"}`` when a metric is ``performance.*``, else None;
            with ``"thrust"`` (N, rpm 0), ``"thrust_tolerance"``, ``"thrust_runs"`` for a target
            thrust, and ``"iterations"``, ``"processes"``, ``"observers"`` (``DIST_M:ANGLE_DEG``
            texts) when given.
        levels: the mesh levels a trial climbs, coarse to fine (one: no climbing); () without
            simulate.
        pruner: which trials climb (two or more levels), else None.
        stl: trials (and so the best sets copied from them) write STL files.
        time_limit_s: per trial, s.
        source: where it came from, for messages.
    """

    name: str
    base: PropellerParameters
    axes: tuple[VaryAxis, ...]
    objectives: tuple[Objective, ...]
    constraints: tuple[Constraint, ...] = ()
    trials: int = 20
    sampler: Sampler = Sampler.TPE
    seed: int = 0
    population: int = 20
    storage: str = ""
    simulate: dict[str, Any] | None = None
    stl: bool = True
    time_limit_s: float = 300.0
    source: str = "<dict>"
    metrics: tuple[str, ...] = field(default=())
    levels: tuple[str, ...] = ()
    pruner: Pruner | None = None

    def stage_settings(self, stage: int) -> dict[str, Any] | None:
        """The simulation settings of stage ``stage`` (its level ``levels[stage]``); None without
        simulate."""
        if self.simulate is None:
            return None
        settings = {key: value for key, value in self.simulate.items() if key != "levels"}
        settings["level"] = self.levels[stage]
        return settings

    @property
    def directions(self) -> list[str]:
        return [objective.direction.value for objective in self.objectives]

    def parameters(self, values: Mapping[str, Any], name: str) -> dict[str, Any]:
        """The full design (TOML layout) of the trial with ``values`` by vary key, named
        ``name``."""
        parameters = apply_axis_values(
            self.base.to_dict(), self.axes, tuple(values[axis.key] for axis in self.axes)
        )
        parameters["name"] = name
        return parameters

    def definition(self) -> str:
        """What must not change between runs of one study: a digest of base, axes, objectives,
        constraints and [simulate] (the [pruner] may change: it only decides which trials climb)."""
        data = {
            "base": self.base.to_dict(),
            "axes": [[a.key, a.low, a.high, list(a.values)] for a in self.axes],
            "objectives": [[o.metric, o.direction.value] for o in self.objectives],
            "constraints": [[c.metric, c.low, c.high] for c in self.constraints],
            "simulate": self.simulate,
        }
        text = json.dumps(data, sort_keys=True, default=str, allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def read_study_file(path: str | Path) -> StudySpec:
    """Read and check a study file; any problem is a one-line ParameterError naming the key."""
    path = Path(path)
    source = f"study file {str(path)!r}"
    # the readers of every file: shape, size, nesting, digits
    data = read_config_table(path, "study file")
    return parse_study(data, base_dir=path.parent, name=path.stem, source=source)


def parse_study(
    data: Mapping[str, Any], base_dir: str | Path = ".", name: str = "study", source: str = "study"
) -> StudySpec:
    """Check a study given as the parsed TOML; ``study.base`` and file values are relative to
    ``base_dir``."""

    def fail(message: str) -> ParameterError:
        return ParameterError(f"{source}: {message}")

    data = dict(data)
    if isinstance(data.get("vary"), Mapping):
        data["vary"] = dict(flatten_vary(data["vary"]))
        _refuse_non_finite(data["vary"], fail)
    if isinstance(data.get("constraints"), Mapping):
        data["constraints"] = dict(_flatten_bounds(data["constraints"]))
        for key, bound in data["constraints"].items():
            if isinstance(bound, Mapping) and not set(bound) <= {"min", "max"}:
                raise fail(
                    f"constraints.{shown(key)} has keys {sorted(bound)}; "
                    f"give min, max or both, e.g. {{ min = 0.8 }}"
                )
    try:
        model = StudyFile.model_validate(data)
    except ValidationError as error:
        raise fail(str(parameter_error(StudyFile, error))) from None
    folder = Path(base_dir).resolve()
    table = model.study
    study_name = table.name or name
    if not _NAME_PATTERN.match(study_name):
        raise fail(
            f"study.name = {study_name!r} must be 1-100 "
            "letters, digits, '_', '.' or '-' (it names files)"
        )
    axes = tuple(_axis(key, values, folder, fail) for key, values in model.vary.items())
    if not axes:
        raise fail(
            "[vary] is empty; name at least one design key "
            'to vary, e.g. "airfoil.thickness" = [0.2, 0.6]'
        )
    check_distinct_axes(axes, fail)
    objectives, constraints = _goals(model, fail)
    metrics = tuple(o.metric for o in objectives) + tuple(c.metric for c in constraints)
    base = _base(table.base, folder, fail)
    simulate = _simulate(
        model, any(is_performance(metric) for metric in metrics), metrics, base, fail
    )
    levels = _levels(model, simulate, fail)
    pruner = _pruner(model, levels, len(objectives), fail)
    if simulate is not None and simulate.get("thrust"):
        if table.sampler is Sampler.CMAES:
            raise fail(
                "study.sampler = 'cmaes' cannot take [simulate] "
                "thrust (each trial's thrust is constrained to "
                "the target within thrust_tolerance, and optuna's "
                "CMA-ES has no constraints_func); use 'tpe'"
            )
        target, tolerance = simulate["thrust"], simulate["thrust_tolerance"]
        constraints += (
            Constraint(THRUST_METRIC, target * (1.0 - tolerance), target * (1.0 + tolerance)),
        )
        metrics += (THRUST_METRIC, RPM_METRIC)
    _check_sampler(table.sampler, objectives, constraints, fail)
    return StudySpec(
        name=study_name,
        base=base,
        axes=axes,
        objectives=objectives,
        constraints=constraints,
        trials=table.trials,
        sampler=table.sampler,
        seed=table.seed,
        population=table.population,
        storage=table.storage,
        simulate=simulate,
        stl=table.stl,
        time_limit_s=table.time_limit_s or (3600.0 if simulate else 300.0),
        source=source,
        metrics=metrics,
        levels=levels,
        pruner=pruner,
    )


#: With a target thrust: the metrics every trial records (the thrust at the rpm found, and that
#: rpm).
THRUST_METRIC = PERFORMANCE_PREFIX + "thrust_n"
RPM_METRIC = PERFORMANCE_PREFIX + "rpm"


def _flatten_bounds(table: Mapping[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``a.b = {min = 1}`` unquoted (nested tables) means ``"a.b" = {min = 1}``."""
    items: list[tuple[str, Any]] = []
    for key, value in table.items():
        if (
            isinstance(value, Mapping)
            and value
            and all(isinstance(item, Mapping) for item in value.values())
        ):
            items += _flatten_bounds(value, f"{prefix}{key}.")
        else:
            items.append((f"{prefix}{key}", value))
    return items


def _refuse_non_finite(vary: Mapping[str, Any], fail: Any) -> None:
    """A NaN or infinite bound of a [vary] range, named with the parameter's range (before the
    file's schema, whose own message would name only the type it tried)."""
    for key, values in vary.items():
        if not isinstance(values, list):
            continue
        for end, value in zip(("low", "high"), values):
            if isinstance(value, float) and not math.isfinite(value):
                _, _, leaf = resolve_leaf(key, fail)
                checked_value(value, leaf, f"vary.{shown(key)} {end}", fail)


def _axis(key: str, values: list[Any], folder: Path, fail: Any) -> VaryAxis:
    """A range (two numbers) or a choice (strings or booleans), checked against the schema's
    ranges."""
    where = f"vary.{shown(key)}"
    path, index, leaf = resolve_leaf(key, fail)
    numbers = [v for v in values if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if numbers and len(numbers) == len(values):
        if len(values) != 2:
            raise fail(
                f"{where} must be [low, high], two numbers (a range), got {len(values)} numbers"
            )
        low, high = (
            checked_value(value, leaf, f"{where} {end}", fail)
            for value, end in zip(values, ("low", "high"))
        )
        if isinstance(low, list) or not low < high:
            raise fail(f"{where}: low = {low!r} must be below high = {high!r}")
        return VaryAxis(key, path, index, low=low, high=high, integer=leaf.kind is int)
    if numbers or not values:
        raise fail(
            f"{where} must be two numbers (a range) or a list of "
            f"strings or booleans (a choice), got {shown(values)}"
        )
    checked = tuple(
        checked_value(value, leaf, f"{where} item {i}", fail) for i, value in enumerate(values)
    )
    if len(set(map(repr, checked))) != len(checked):
        raise fail(f"{where} lists a choice twice")
    return axis_paths_relative_to(VaryAxis(key, path, index, values=checked), folder)


def _goals(model: StudyFile, fail: Any) -> tuple[tuple[Objective, ...], tuple[Constraint, ...]]:
    if not model.objective:
        raise fail(
            'no [[objective]]; add one, e.g. [[objective]] metric = "mass_g" direction = "minimize"'
        )
    objectives = []
    for number, item in enumerate(model.objective):
        try:
            check_metric(item.metric, f"objective[{number}].metric")
        except ParameterError as error:
            raise fail(str(error)) from None
        objectives.append(Objective(item.metric, item.direction))
    if len({o.metric for o in objectives}) != len(objectives):
        raise fail("two [[objective]] tables name the same metric")
    constraints = []
    for metric, bound in model.constraints.items():
        try:
            check_metric(metric, "constraints key")
        except ParameterError as error:
            raise fail(str(error)) from None
        if bound.min is None and bound.max is None:
            raise fail(f"constraints.{metric!r} needs min, max or both, e.g. {{ min = 0.8 }}")
        if bound.min is not None and bound.max is not None and not bound.min <= bound.max:
            raise fail(
                f"constraints.{metric!r}: min = {bound.min:g} must not be above max = {bound.max:g}"
            )
        constraints.append(Constraint(metric, bound.min, bound.max))
    return tuple(objectives), tuple(constraints)


def _simulate(
    model: StudyFile, needed: bool, metrics: tuple[str, ...], base: PropellerParameters, fail: Any
) -> dict[str, Any] | None:
    given = "simulate" in model.model_fields_set
    if not needed:
        if given:
            raise fail(
                "[simulate] applies only when an objective or constraint is a performance.* metric"
            )
        return None
    table = model.simulate
    keys = table.model_fields_set
    if not given or (table.rpm <= 0.0 and table.thrust <= 0.0):
        raise fail(
            "a performance.* metric runs torus-cad simulate: give [simulate] rpm = ... (> 0) or "
            "thrust = ... (N, > 0)"
        )
    if table.rpm > 0.0 and table.thrust > 0.0:
        raise fail(
            f"simulate.rpm = {table.rpm:g} and simulate.thrust "
            f"= {table.thrust:g} N: give one (thrust finds "
            "each trial's rpm)"
        )
    if table.thrust <= 0.0 and keys & set(_THRUST_KEYS):
        raise fail(
            f"simulate.{sorted(keys & set(_THRUST_KEYS))[0]} applies "
            "only with simulate.thrust (a target thrust)"
        )
    if "level" in keys and "levels" in keys:
        raise fail(
            'simulate.level and simulate.levels: give one (levels = ["coarse", "medium"] climbs)'
        )
    settings: dict[str, Any] = {
        "rpm": table.rpm,
        "airspeed": table.airspeed,
        "level": table.level.value,
    }
    if table.rpm > 0.0:
        _check_rpm(table.rpm, table.airspeed, base, fail)
    if table.thrust > 0.0:
        _check_thrust(table.thrust, table.airspeed, base, fail)
        settings.update(
            thrust=table.thrust,
            thrust_tolerance=table.thrust_tolerance,
            thrust_runs=table.thrust_runs,
        )
    if table.iterations:
        settings["iterations"] = table.iterations
    if table.processes:
        settings["processes"] = table.processes
    observers = noise_observers(metrics)
    if observers:
        _check_observers(observers, base, fail)
        settings["observers"] = list(observers)
    if "levels" in keys:
        settings["levels"] = [level.value for level in table.levels]
        settings["level"] = settings["levels"][0] if settings["levels"] else settings["level"]
    return settings


def _check_rpm(rpm: float, airspeed_m_s: float, base: PropellerParameters, fail: Any) -> None:
    """An rpm above simulate's tip-Mach limit for the base design's tip diameter is refused here,
    before the first trial, with simulate's own range (each trial's simulate checks its own design
    again)."""
    from torus_cad.simulate.settings import AIR_15C, rpm_limit

    diameter_mm = base.diameter if base.diameter > 0.0 else _tip_diameter_mm(base)
    limit = rpm_limit(diameter_mm / 1000.0, airspeed_m_s, AIR_15C)
    if rpm > limit:
        raise fail(
            f"simulate.rpm = {rpm:g} is out of range; allowed "
            f"(0, {limit:.0f}] rpm (simulate's helical tip "
            f"Mach limit for the base's D = {diameter_mm:.1f} mm at {airspeed_m_s:g} m/s)"
        )


def _tip_diameter_mm(base: PropellerParameters) -> float:
    """Twice the largest radius of the base design's blade surface (kernel-free)."""
    import numpy as np

    points = sampled_blade_surface(base).points
    return 2.0 * float(np.hypot(points[..., 0], points[..., 1]).max())


def _check_thrust(
    target_n: float, airspeed_m_s: float, base: PropellerParameters, fail: Any
) -> None:
    """A target no propeller of the base's diameter reaches (CT 1 at the rpm limit) is refused here,
    once, not in every trial (a base without a ``diameter`` target: each trial's simulate checks its
    own)."""
    from torus_cad.simulate.settings import AIR_15C, rpm_limit
    from torus_cad.simulate.thrust_target import PLAUSIBLE_CT_LIMIT, thrust_ceiling

    if base.diameter <= 0.0:
        return
    diameter_m = base.diameter / 1000.0
    limit = rpm_limit(diameter_m, airspeed_m_s, AIR_15C)
    ceiling = thrust_ceiling(limit, diameter_m, AIR_15C.density_kg_m3)
    if target_n > ceiling:
        raise fail(
            f"simulate.thrust = {target_n:g} N is out of range; allowed (0, {ceiling:.4g}] N (CT "
            f"{PLAUSIBLE_CT_LIMIT:g} at the rpm limit "
            f"{limit:.0f} rpm for the base's D = {base.diameter:g} mm)"
        )


def _check_observers(observers: tuple[str, ...], base: PropellerParameters, fail: Any) -> None:
    """At most NOISE_MAX_OBSERVERS, each outside the base's tip radius (when it has a ``diameter``
    target)."""
    from torus_cad.acoustics.observers import parse_observer

    if len(observers) > NOISE_MAX_OBSERVERS:
        raise fail(
            f"the metrics name {len(observers)} noise "
            f"observers; allowed at most {NOISE_MAX_OBSERVERS}"
        )
    for text in observers:
        observer = parse_observer(text)
        if base.diameter > 0.0 and observer.distance_m * 1000.0 <= base.diameter / 2.0:
            raise fail(
                f"performance.noise[{text}]: the observer is "
                "inside the rotor; allowed a distance above the "
                f"base's tip radius {base.diameter / 2000.0:g} m"
            )


def _levels(model: StudyFile, simulate: dict[str, Any] | None, fail: Any) -> tuple[str, ...]:
    """The mesh levels a trial climbs, coarse to fine, each once."""
    if simulate is None:
        return ()
    if "levels" not in simulate:
        return (str(simulate["level"]),)
    levels = tuple(simulate["levels"])
    order = [level.value for level in StudyLevel]
    if not levels or list(levels) != sorted(set(levels), key=order.index):
        raise fail(
            f"simulate.levels = {list(levels)!r} must name "
            "levels from the cheapest to the finest (vortex, "
            'coarse, medium, fine), each once, e.g. ["vortex", "medium"]'
        )
    return levels


def _pruner(model: StudyFile, levels: tuple[str, ...], objectives: int, fail: Any) -> Pruner | None:
    """The pruner of a study of two or more levels (default median for one objective, dominated for
    several)."""
    table = model.pruner
    if len(levels) < 2:
        if "pruner" in model.model_fields_set:
            raise fail(
                "[pruner] applies only with [simulate] levels "
                'of two or more, e.g. levels = ["coarse", '
                '"medium"]'
            )
        return None
    kind = table.kind or (PrunerKind.MEDIAN if objectives == 1 else PrunerKind.DOMINATED)
    if kind in ONE_OBJECTIVE_PRUNERS and objectives > 1:
        raise fail(
            f"pruner.kind = {kind.value!r} judges one "
            "objective (optuna's pruners take one value); with "
            f"{objectives} objectives use 'dominated' or 'none'"
        )
    return Pruner(kind, table.startup_trials, table.reduction_factor)


def _check_sampler(
    sampler: Sampler,
    objectives: tuple[Objective, ...],
    constraints: tuple[Constraint, ...],
    fail: Any,
) -> None:
    if sampler is Sampler.CMAES and len(objectives) > 1:
        raise fail(
            "study.sampler = 'cmaes' takes one objective; use 'nsga2' (or 'tpe') for several"
        )
    if sampler is Sampler.CMAES and constraints:
        raise fail(
            "study.sampler = 'cmaes' takes no [constraints] "
            "(optuna's CMA-ES has no constraints_func); "
            "use 'tpe'"
        )


def _base(base: str, folder: Path, fail: Any) -> PropellerParameters:
    if not base:
        return PropellerParameters()
    path = Path(base).expanduser()
    path = path if path.is_absolute() else folder / path
    try:
        return PropellerParameters.from_toml(path)
    except ParameterError as error:
        raise fail(f"study.base: {error}") from None
