"""Design sweeps: many propellers from one sweep file, on a local process pool or a Dask cluster.

A sweep file is TOML with three tables::

    [base]                       # the design every variant starts from
    config = "my_prop.toml"      # optional, relative to the sweep file; inline tables override it
    [base.resolution]
    sections = 16

    [sweep]
    mode = "grid"                # "grid" | "random" | "latin_hypercube"
    samples = 20                 # random / latin_hypercube only: how many designs
    seed = 1                     # random / latin_hypercube only (default 0)
    stl = true                   # write STL files (default true)
    density_g_cm3 = 1.24         # material density for the mass (default: PLA)

    [vary]                       # dotted parameter keys; "key[i]" addresses one vector element
    "hub.radius" = [9.0, 10.0, 11.0]               # a list of values (any mode)
    blades = {start = 2, stop = 4, step = 1}       # a range, stop included (any mode)
    "centerline.p2[2]" = {low = 18.0, high = 26.0} # bounds (random / latin_hypercube only)

``grid`` takes the Cartesian product of the lists and ranges. ``random`` draws ``samples``
independent uniform points, ``latin_hypercube`` a Latin hypercube (scipy.stats.qmc), both
seeded so that rerunning the file gives the same designs. Bounds on an integer parameter
(``blades``, ``resolution.*``) give integers in ``[low, high]``; on a float parameter,
floats in ``[low, high)``. Lists and ranges in a sampled sweep are categorical: each
sample picks one of their values.

Every design gets an id, the first 12 hex digits of the SHA-256 of its canonical JSON
parameter dict (sorted keys, without ``name``, which is set to the id), and a folder
``OUT/designs/<id>/`` holding ``<id>.step``, ``<id>.stl`` and ``<id>.json`` (the report
of :meth:`torus_cad.propeller.Propeller.write`, written last and atomically). A design the
parameters or the geometry checks refuse gets a ``refusal.json`` instead; a kernel failure
or an unexpected error gets a ``failure.json``. A design is *done* when its report (with
its STEP and, if asked for, STL file) or its refusal exists: rerunning the sweep skips it,
and failed designs are tried again. ``OUT/results.csv`` (and ``OUT/results.parquet`` when
pyarrow is installed) is rebuilt from those per-design files at the end of every run, also
after an interruption, so nothing that finished is ever lost.

Designs run in a :class:`concurrent.futures.ProcessPoolExecutor` (one process per CPU by
default, started from multiprocessing's fork server, which imports the kernel once) or, with
a scheduler address, on a Dask distributed cluster through the same loop
(``Client.get_executor``). On a cluster, ``OUT`` must be on a file system every worker can
write and the client can read, and the workers need torus_cad installed. A script that calls
:func:`run_sweep` needs an ``if __name__ == "__main__":`` guard: the workers re-import it.

Units: lengths mm, areas mm^2, volumes mm^3, mass g, inertia g mm^2 (and mm^5 for the pure
geometric integral), times s, density g/cm^3, rates designs per minute.
"""

from __future__ import annotations

import csv
import difflib
import hashlib
import itertools
import json
import math
import multiprocessing
import os
import re
import signal
import sys
import threading
import time
import tomllib
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from torus_cad.errors import GeometryError, KernelError, ParameterError, TorusCadError
from torus_cad.parameters import PropellerParameters
from torus_cad.progress import is_terminal

__all__ = [
    "MODES", "Design", "DesignTask", "Progress", "SweepError", "SweepInterrupted", "SweepResult", "SweepSpec",
    "VaryAxis", "collect_rows", "design_id", "generate_designs", "load_sweep", "parse_sweep", "read_design_status",
    "run_design", "run_sweep", "table_columns", "write_table",
]

MODES = ("grid", "random", "latin_hypercube")
ID_LENGTH = 12  #: hex digits of the SHA-256 kept as the design id (48 bits)
DESIGNS_DIR = "designs"
MANIFEST_FILE = "sweep.json"
TABLE_CSV = "results.csv"
TABLE_PARQUET = "results.parquet"
REFUSAL_FILE = "refusal.json"
FAILURE_FILE = "failure.json"

STATUS_OK, STATUS_REFUSED, STATUS_FAILED, STATUS_ERROR, STATUS_PENDING = "ok", "refused", "failed", "error", "pending"

#: Stage columns of the table, in pipeline order (see :class:`torus_cad.propeller.StageTimer`).
STAGES = ("parameters", "section_math", "wires", "loft", "fuse", "check", "step_write", "stl_write")

_SWEEP_KEYS = ("mode", "samples", "seed", "name", "stl", "density_g_cm3")
_TOP_KEYS = ("base", "sweep", "vary")
_SPEC_KEYS = {"low", "high", "start", "stop", "step", "num"}
_KEY_PATTERN = re.compile(r"^(?P<path>[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*)(?:\[(?P<index>\d+)\])?$")
_RANGE_DIGITS = 12  # range values are rounded to 12 decimals so 0.1 steps give 0.3, not 0.30000000000000004
_POLL_SECONDS = 0.25
CONNECT_TIMEOUT_S = 20.0  #: how long to wait for a Dask scheduler, s


class SweepError(TorusCadError):
    """The sweep machinery failed (e.g. the Dask scheduler is unreachable), not a design."""


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run_sweep`; ``result`` is the partial run (its table is written)."""

    def __init__(self, result: "SweepResult") -> None:
        super().__init__("sweep interrupted")
        self.result = result


# -- the sweep file --------------------------------------------------------------------------

@dataclass(frozen=True)
class VaryAxis:
    """One varied parameter.

    Attributes:
        key: the key as written in ``[vary]``, e.g. ``"centerline.p2[2]"``; also its table column.
        path: the dotted parameter path split at the dots, e.g. ``("centerline", "p2")``.
        index: the vector element addressed by ``[i]``, or None for the whole value.
        values: the candidate values of a list or range (empty for bounds).
        low, high: the bounds for random / Latin-hypercube sampling (None for lists and ranges),
            in the parameter's unit (mm, degrees, ...).
        integer: True when the parameter is a whole number (bounds then give ints, ``high`` included).
    """

    key: str
    path: tuple[str, ...]
    index: int | None
    values: tuple[Any, ...] = ()
    low: float | None = None
    high: float | None = None
    integer: bool = False

    @property
    def is_bounds(self) -> bool:
        """True for ``{low, high}`` bounds, False for a list or range of values."""
        return self.low is not None

    def pick(self, unit: float) -> Any:
        """The value at ``unit`` in [0, 1): a point between the bounds or one of the values."""
        if self.is_bounds:
            assert self.low is not None and self.high is not None
            if self.integer:
                low, high = int(self.low), int(self.high)
                return min(high, low + int(math.floor(unit * (high - low + 1))))
            return float(self.low + unit * (self.high - self.low))
        return self.values[min(len(self.values) - 1, int(math.floor(unit * len(self.values))))]


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file.

    Attributes:
        name: the sweep's name (``[sweep] name``, default the file's stem).
        base: the design every variant starts from.
        mode: ``"grid"``, ``"random"`` or ``"latin_hypercube"``.
        axes: the varied parameters, in file order.
        samples: designs to draw (random / latin_hypercube), None for a grid.
        seed: the random seed (random / latin_hypercube).
        stl: write an STL file for each design.
        density_g_cm3: material density for the mass, g/cm^3 (None: the package default, PLA).
        source: where the sweep came from (a path or ``"<dict>"``), for messages.
    """

    name: str
    base: PropellerParameters
    mode: str = "grid"
    axes: tuple[VaryAxis, ...] = ()
    samples: int | None = None
    seed: int = 0
    stl: bool = True
    density_g_cm3: float | None = None
    source: str = "<dict>"


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file; any problem raises a one-line ParameterError naming the key."""
    path = Path(path)
    source = f"sweep file {str(path)!r}"
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as error:
        raise ParameterError(f"cannot read sweep file {str(path)!r}: {error.strerror}") from None
    except UnicodeDecodeError:
        raise ParameterError(f"{source} is not a UTF-8 text file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ParameterError(f"{source} is not valid TOML: {error}") from None
    return parse_sweep(data, base_dir=path.parent, name=path.stem, source=source)


def parse_sweep(data: Mapping[str, Any], base_dir: str | Path = ".", name: str = "sweep",
                source: str = "sweep") -> SweepSpec:
    """Check a sweep given as a mapping (the parsed TOML); ``base.config`` is relative to ``base_dir``."""

    def fail(message: str) -> ParameterError:
        return ParameterError(f"{source}: {message}")

    if not isinstance(data, Mapping):
        raise fail(f"must be a table, got {type(data).__name__}")
    for key in data:
        if key not in _TOP_KEYS:
            raise fail(f"unknown table [{key}]{_did_you_mean(str(key), _TOP_KEYS)}")
    base = _parse_base(data.get("base", {}), Path(base_dir), fail)
    settings = data.get("sweep", {})
    if not isinstance(settings, Mapping):
        raise fail("[sweep] must be a table")
    for key in settings:
        if key not in _SWEEP_KEYS:
            raise fail(f"unknown key sweep.{key}{_did_you_mean(str(key), _SWEEP_KEYS, 'sweep.')}")
    mode = settings.get("mode", "grid")
    if mode not in MODES:
        raise fail(f"sweep.mode = {mode!r} is not allowed; choose one of {', '.join(MODES)}")
    samples = settings.get("samples")
    if mode == "grid":
        if samples is not None:
            raise fail("sweep.samples applies to mode = 'random' or 'latin_hypercube', not 'grid'")
    elif not _is_int(samples) or samples < 1:
        raise fail(f"sweep.samples must be a whole number >= 1 for mode = {mode!r}, got {samples!r}")
    seed = settings.get("seed", 0)
    if not _is_int(seed) or seed < 0:
        raise fail(f"sweep.seed must be a whole number >= 0, got {seed!r}")
    sweep_name = settings.get("name", name)
    if not isinstance(sweep_name, str) or not sweep_name:
        raise fail(f"sweep.name must be a non-empty string, got {sweep_name!r}")
    stl = settings.get("stl", True)
    if not isinstance(stl, bool):
        raise fail(f"sweep.stl must be true or false, got {stl!r}")
    density = settings.get("density_g_cm3")
    if density is not None and (not _is_number(density) or not 0.0 < density <= 25.0):
        raise fail(f"sweep.density_g_cm3 = {density!r} is out of range; allowed (0, 25] g/cm^3")

    vary = data.get("vary", {})
    if not isinstance(vary, Mapping):
        raise fail("[vary] must be a table of parameter keys")
    base_dict = base.to_dict()
    axes = tuple(_parse_axis(key, spec, base_dict, mode, fail) for key, spec in _flatten_vary(vary))
    seen: dict[tuple[str, ...], list[VaryAxis]] = {}
    for axis in axes:
        for other in seen.get(axis.path, []):
            if other.index is None or axis.index is None or other.index == axis.index:
                raise fail(f"vary.{axis.key!r} and vary.{other.key!r} set the same parameter")
        seen.setdefault(axis.path, []).append(axis)
    return SweepSpec(name=sweep_name, base=base, mode=mode, axes=axes, samples=samples, seed=seed, stl=stl,
                     density_g_cm3=None if density is None else float(density), source=source)


def _parse_base(table: Any, base_dir: Path, fail: Callable[[str], ParameterError]) -> PropellerParameters:
    if not isinstance(table, Mapping):
        raise fail("[base] must be a table of design parameters (or config = \"path.toml\")")
    inline = dict(table)
    config = inline.pop("config", None)
    if config is None:
        merged: dict[str, Any] = PropellerParameters().to_dict()
    elif isinstance(config, str):
        config_path = Path(config) if Path(config).is_absolute() else base_dir / config
        try:
            merged = PropellerParameters.from_toml(config_path).to_dict()
        except ParameterError as error:
            raise fail(f"base.config: {error}") from None
    else:
        raise fail(f"base.config must be a path string, got {config!r}")
    _deep_merge(merged, inline)
    try:
        return PropellerParameters.from_dict(merged)
    except ParameterError as error:
        raise fail(f"[base] {error}") from None


def _deep_merge(target: dict[str, Any], changes: Mapping[str, Any]) -> None:
    for key, value in changes.items():
        if isinstance(value, Mapping) and isinstance(target.get(key), dict):
            _deep_merge(target[key], value)
        else:
            target[key] = value


def _flatten_vary(vary: Mapping[str, Any], prefix: str = "") -> Iterable[tuple[str, Any]]:
    """``hub.radius = [..]`` (a nested TOML table) and ``"hub.radius" = [..]`` mean the same."""
    for key, value in vary.items():
        if isinstance(value, Mapping) and not set(value) <= _SPEC_KEYS:
            yield from _flatten_vary(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", value


def _parse_axis(key: str, spec: Any, base: Mapping[str, Any], mode: str,
                fail: Callable[[str], ParameterError]) -> VaryAxis:
    where = f"vary.{key!r}"
    match = _KEY_PATTERN.match(key)
    if not match:
        raise fail(f"{where} is not a parameter key; write e.g. \"hub.radius\" or \"centerline.p2[2]\"")
    path = tuple(match["path"].split("."))
    index = None if match["index"] is None else int(match["index"])
    if path == ("name",):
        raise fail(f"{where}: the name cannot be varied; each design is named by its id")
    table: Any = base
    for depth, part in enumerate(path):
        if not isinstance(table, Mapping) or part not in table:
            known = list(table) if isinstance(table, Mapping) else []
            prefix = ".".join(path[:depth]) + "." if depth else ""
            raise fail(f"{where}: unknown key {prefix + part!r}{_did_you_mean(part, known, prefix)}")
        table = table[part]
    if isinstance(table, Mapping):
        raise fail(f"{where} is a table; vary one of its keys, e.g. {key + '.' + next(iter(table))!r}")
    leaf = table
    if index is not None:
        if not isinstance(leaf, list):
            raise fail(f"{where}: {match['path']} is not a vector, so [{index}] does not apply")
        if index >= len(leaf):
            raise fail(f"{where}: index {index} is out of range; {match['path']} has {len(leaf)} elements")
        leaf = leaf[index]

    def value_of(item: Any, what: str) -> Any:
        return _coerce_value(item, leaf, f"{where} {what}", fail)

    if isinstance(spec, list):
        if not spec:
            raise fail(f"{where} is an empty list")
        values = tuple(value_of(item, f"item {i}") for i, item in enumerate(spec))
        return VaryAxis(key, path, index, values=values, integer=_is_int(leaf))
    if not isinstance(spec, Mapping):
        raise fail(f"{where} must be a list, {{start, stop, step}} / {{start, stop, num}} or {{low, high}}, "
                   f"got {spec!r}")
    keys = set(spec)
    if not _is_number(leaf):
        raise fail(f"{where}: ranges and bounds need a number parameter; give a list of values")
    if keys == {"low", "high"}:
        if mode == "grid":
            raise fail(f"{where}: bounds {{low, high}} need sweep.mode = 'random' or 'latin_hypercube'; "
                       "a grid takes a list or {start, stop, step}")
        low, high = value_of(spec["low"], "low"), value_of(spec["high"], "high")
        if not low < high:
            raise fail(f"{where}: low = {low!r} must be below high = {high!r}")
        return VaryAxis(key, path, index, low=low, high=high, integer=_is_int(leaf))
    if keys in ({"start", "stop", "step"}, {"start", "stop", "num"}):
        start, stop = value_of(spec["start"], "start"), value_of(spec["stop"], "stop")
        return VaryAxis(key, path, index, values=_range_values(spec, start, stop, leaf, where, fail),
                        integer=_is_int(leaf))
    raise fail(f"{where} has keys {sorted(keys)}; use {{start, stop, step}}, {{start, stop, num}} or {{low, high}}")


def _range_values(spec: Mapping[str, Any], start: Any, stop: Any, leaf: Any, where: str,
                  fail: Callable[[str], ParameterError]) -> tuple[Any, ...]:
    """The values of ``{start, stop, step}`` (stop included when it falls on a step) or ``{start, stop, num}``."""
    if stop < start:
        raise fail(f"{where}: stop = {stop!r} must not be below start = {start!r}")
    if "num" in spec:
        num = spec["num"]
        if not _is_int(num) or num < 1:
            raise fail(f"{where}: num must be a whole number >= 1, got {num!r}")
        if _is_int(leaf):
            raise fail(f"{where}: {{start, stop, num}} is for float parameters; use {{start, stop, step}}")
        values = [start] if num == 1 else [round(start + (stop - start) * i / (num - 1), _RANGE_DIGITS)
                                           for i in range(num)]
    else:
        step = _coerce_value(spec["step"], leaf, f"{where} step", fail)
        if not step > 0:
            raise fail(f"{where}: step must be positive, got {step!r}")
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        if count > 100_000:
            raise fail(f"{where}: the range has {count} values; at most 100000")
        values = [start + i * step if _is_int(leaf) else round(start + i * step, _RANGE_DIGITS)
                  for i in range(count)]
    return tuple(values)


def _coerce_value(item: Any, leaf: Any, where: str, fail: Callable[[str], ParameterError]) -> Any:
    """Check ``item`` against the base value's type: ints stay ints, ints become floats for float keys."""
    if isinstance(leaf, bool):
        if not isinstance(item, bool):
            raise fail(f"{where} must be true or false, got {item!r}")
        return item
    if _is_int(leaf):
        if not _is_int(item):
            raise fail(f"{where} must be a whole number, got {item!r}")
        return item
    if isinstance(leaf, float):
        if not _is_number(item):
            raise fail(f"{where} must be a number, got {item!r}")
        return float(item)
    if isinstance(leaf, str):
        if not isinstance(item, str):
            raise fail(f"{where} must be a string, got {item!r}")
        return item
    if isinstance(leaf, list):
        if not isinstance(item, list) or len(item) != len(leaf) or not all(_is_number(x) for x in item):
            raise fail(f"{where} must be a list of {len(leaf)} numbers (a whole vector), got {item!r}")
        return [float(x) for x in item]
    raise fail(f"{where}: cannot vary this parameter")  # pragma: no cover - schema has no other leaf types


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _did_you_mean(key: str, known: Iterable[str], prefix: str = "") -> str:
    known = list(known)
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.5)
    if close:
        return f"; did you mean {prefix + close[0]!r}?"
    return f"; known keys: {', '.join(prefix + k for k in sorted(known))}" if known else ""


# -- designs ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Design:
    """One variant of the sweep.

    Attributes:
        index: its position in the sweep (0-based), the table's row order.
        design_id: the short SHA-256 of its parameters (see :func:`design_id`).
        varied: the varied values by ``[vary]`` key.
        parameters: the full parameter dict (the TOML layout), ``name`` set to the id; not yet
            validated, so an out-of-range value is refused when the design runs.
    """

    index: int
    design_id: str
    varied: dict[str, Any]
    parameters: dict[str, Any]


def design_id(parameters: Mapping[str, Any]) -> str:
    """First :data:`ID_LENGTH` hex digits of the SHA-256 of the canonical JSON of ``parameters``.

    Canonical: sorted keys, no spaces, tuples as lists, the ``name`` key left out (it only
    names the files, and a design's files are named by this id).
    """
    data = {key: value for key, value in parameters.items() if key != "name"}
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=list)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:ID_LENGTH]


def _unit_samples(spec: SweepSpec, dimensions: int) -> np.ndarray:
    """``(samples, dimensions)`` points in [0, 1), uniform or a Latin hypercube, from the seed."""
    assert spec.samples is not None
    rng = np.random.default_rng(spec.seed)
    if spec.mode == "random":
        return rng.random((spec.samples, dimensions))
    from scipy.stats import qmc

    try:
        sampler = qmc.LatinHypercube(d=dimensions, rng=rng)
    except TypeError:  # scipy < 1.15 names it seed
        sampler = qmc.LatinHypercube(d=dimensions, seed=rng)
    return sampler.random(spec.samples)


def generate_designs(spec: SweepSpec) -> list[Design]:
    """Every design of the sweep, in order, duplicates (same id) dropped after their first appearance."""
    if spec.mode == "grid":
        combos: Iterable[tuple[Any, ...]] = itertools.product(*(axis.values for axis in spec.axes))
    else:
        units = _unit_samples(spec, max(1, len(spec.axes)))
        combos = (tuple(axis.pick(float(u)) for axis, u in zip(spec.axes, row)) for row in units)
    base = spec.base.to_dict()
    designs: list[Design] = []
    seen: set[str] = set()
    for combo in combos:
        parameters = json.loads(json.dumps(base))  # a deep copy of plain data
        for axis, value in zip(spec.axes, combo):
            table = parameters
            for part in axis.path[:-1]:
                table = table[part]
            if axis.index is None:
                table[axis.path[-1]] = value
            else:
                table[axis.path[-1]][axis.index] = value
        ident = design_id(parameters)
        if ident in seen:
            continue
        seen.add(ident)
        parameters["name"] = ident
        designs.append(Design(len(designs), ident, {axis.key: value for axis, value in zip(spec.axes, combo)},
                              parameters))
    return designs


# -- one design (runs in a worker process) --------------------------------------------------------

@dataclass(frozen=True)
class DesignTask:
    """What a worker needs to build one design; plain data, so it pickles to any worker.

    Attributes:
        design_id: the design's id (also its ``name`` and its files' stem).
        parameters: the full parameter dict.
        folder: absolute path of the design's folder (on a cluster: on the shared file system).
        stl: write the STL file.
        density_g_cm3: material density, g/cm^3 (None: the package default).
    """

    design_id: str
    parameters: dict[str, Any]
    folder: str
    stl: bool = True
    density_g_cm3: float | None = None


# OpenCascade keeps global state (e.g. the STEP writer's schema and product name), so designs
# in one process never run concurrently, even on a Dask worker with several threads.
_KERNEL_LOCK = threading.Lock()


def run_design(task: DesignTask) -> dict[str, Any]:
    """Build and write one design; never raises for a bad design.

    Returns the outcome ``{"id", "status", "reason", "seconds"}``: status ``"ok"`` (STEP/STL/JSON
    written), ``"refused"`` (ParameterError or GeometryError; ``refusal.json`` written),
    ``"failed"`` (KernelError) or ``"error"`` (any other exception), both with ``failure.json``.
    ``seconds`` is the wall time of the build and the writes.
    """
    from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, build_propeller  # once per process, not timed

    start = time.perf_counter()
    folder = Path(task.folder)
    status, reason, kind = STATUS_OK, "", ""
    try:
        with _KERNEL_LOCK:
            params = PropellerParameters.from_dict(task.parameters)
            propeller = build_propeller(params)
            density = DEFAULT_DENSITY_G_CM3 if task.density_g_cm3 is None else task.density_g_cm3
            propeller.write(folder, density_g_cm3=density, stl=task.stl)
    except (ParameterError, GeometryError) as error:
        status, reason, kind = STATUS_REFUSED, str(error), type(error).__name__
    except KernelError as error:
        status, reason, kind = STATUS_FAILED, str(error), type(error).__name__
    except Exception as error:  # noqa: BLE001 - a sweep records every failure and carries on
        status, reason, kind = STATUS_ERROR, f"{type(error).__name__}: {error}", type(error).__name__
    seconds = time.perf_counter() - start
    outcome = {"id": task.design_id, "status": status, "reason": reason, "seconds": seconds}
    try:
        _record_outcome(task, outcome, kind)
    except OSError as error:  # the outcome still reaches the parent and its table
        outcome["reason"] = (reason + "; " if reason else "") + f"could not record the outcome: {error}"
    return outcome


def _record_outcome(task: DesignTask, outcome: Mapping[str, Any], kind: str) -> None:
    """Leave exactly one status file in the folder: the report, ``refusal.json`` or ``failure.json``."""
    from torus_cad.kernel.export import atomic_path

    folder = Path(task.folder)
    status = outcome["status"]
    stale = [folder / FAILURE_FILE, folder / REFUSAL_FILE]
    if status != STATUS_OK:
        stale = [folder / (FAILURE_FILE if status == STATUS_REFUSED else REFUSAL_FILE)]
        stale += [folder / f"{task.design_id}.{suffix}" for suffix in ("json", "step", "stl")]
        record = {"id": task.design_id, "status": status, "error": kind, "reason": outcome["reason"],
                  "seconds": outcome["seconds"], "parameters": task.parameters}
        with atomic_path(folder / (REFUSAL_FILE if status == STATUS_REFUSED else FAILURE_FILE)) as temp:
            temp.write_text(json.dumps(record, indent=2) + "\n")
    for path in stale:
        path.unlink(missing_ok=True)


def _write_failure_here(task: DesignTask, status: str, reason: str) -> dict[str, Any]:
    """Record a failure noticed by the parent (a worker died, or its files are not visible here)."""
    outcome = {"id": task.design_id, "status": status, "reason": reason, "seconds": 0.0}
    try:
        _record_outcome(task, outcome, "WorkerError")
    except OSError:
        pass
    return outcome


def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def read_design_status(folder: Path, design: Design, stl: bool) -> dict[str, Any] | None:
    """The design's recorded outcome, or None when it is not done.

    Done: the report ``<id>.json`` (for these exact parameters) with its STEP file, and its STL
    when ``stl``, or a ``refusal.json``. A ``failure.json`` is returned too (with status
    ``failed``/``error``) but does not count as done: failed designs are tried again.
    """
    report = _read_json(folder / f"{design.design_id}.json")
    if report is not None and report.get("parameters") == design.parameters:
        files = [folder / f"{design.design_id}.step"] + ([folder / f"{design.design_id}.stl"] if stl else [])
        if all(path.is_file() for path in files):
            return {"status": STATUS_OK, "report": report}
    for name in (REFUSAL_FILE, FAILURE_FILE):
        record = _read_json(folder / name)
        if record is not None and record.get("parameters") == design.parameters:
            return {"status": record.get("status", STATUS_ERROR), "reason": record.get("reason", ""),
                    "seconds": record.get("seconds")}
    return None


def _is_done(status: Mapping[str, Any] | None) -> bool:
    return status is not None and status["status"] in (STATUS_OK, STATUS_REFUSED)


# -- progress ---------------------------------------------------------------------------------

class Progress:
    """A one-line progress bar on a TTY: designs done / total, ok, refused, failed, rate, ETA.

    Draws only when ``enabled`` (default: when ``stream`` is a TTY), at most 10 times a second.
    """

    def __init__(self, total: int, already_done: int = 0, stream: TextIO | None = None,
                 enabled: bool | None = None, width: int = 24) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.enabled = is_terminal(self.stream) if enabled is None else enabled
        self.total, self.already_done, self.width = total, already_done, width
        self.counts = {STATUS_OK: 0, STATUS_REFUSED: 0, STATUS_FAILED: 0, STATUS_ERROR: 0}
        self.start = time.perf_counter()
        self._last_draw = 0.0
        self._drawn = False

    @property
    def built(self) -> int:
        """Designs finished in this run (any status)."""
        return sum(self.counts.values())

    def rate_per_minute(self) -> float:
        """Designs finished in this run per minute of wall time so far."""
        elapsed = time.perf_counter() - self.start
        return 60.0 * self.built / elapsed if elapsed > 0 else 0.0

    def update(self, status: str) -> None:
        """Count one finished design and redraw."""
        self.counts[status] = self.counts.get(status, 0) + 1
        self.draw(force=self.already_done + self.built >= self.total)

    def draw(self, force: bool = False) -> None:
        """Redraw the line (rate and ETA change with time even when no design finishes)."""
        now = time.perf_counter()
        if not self.enabled or (not force and now - self._last_draw < 0.1):
            return
        self._last_draw = now
        done = self.already_done + self.built
        filled = int(self.width * done / self.total) if self.total else self.width
        rate = self.rate_per_minute()
        remaining = self.total - done
        eta = f"ETA {_duration(60.0 * remaining / rate)}" if rate > 0 and remaining else ""
        failed = self.counts[STATUS_FAILED] + self.counts[STATUS_ERROR]
        line = (f"[{'#' * filled}{'.' * (self.width - filled)}] {done}/{self.total} done  "
                f"ok {self.counts[STATUS_OK]}  refused {self.counts[STATUS_REFUSED]}  failed {failed}  "
                f"{rate:.1f}/min  {eta}")
        self.stream.write("\r" + line.ljust(100)[:100])
        self.stream.flush()
        self._drawn = True

    def message(self, text: str) -> None:
        """Print one line of news under the bar (only when the bar is drawn)."""
        if self.enabled:
            self.stream.write(("\n" if self._drawn else "") + text + "\n")
            self.stream.flush()
            self._drawn = False

    def close(self) -> None:
        """End the progress line."""
        if self._drawn:
            self.draw(force=True)
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False


def _duration(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s" if minutes else f"{secs}s"


# -- running ----------------------------------------------------------------------------------

@dataclass
class SweepResult:
    """What a sweep run did.

    Attributes:
        spec: the sweep.
        out_dir: its output folder.
        designs: every design, in order.
        rows: the results table, one dict per design (see :func:`collect_rows`).
        tables: the written table files (``csv``, and ``parquet`` when pyarrow is present).
        skipped: designs already done before this run.
        built: designs run in this run.
        seconds: wall time of this run, s.
        backend: ``"local (N workers)"`` or ``"dask (ADDRESS)"``.
        interrupted: True when the run was stopped before every design ran.
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
    interrupted: bool = False

    def counts(self) -> dict[str, int]:
        """Designs by status over the whole table (ok, refused, failed, error, pending)."""
        counts = {status: 0 for status in (STATUS_OK, STATUS_REFUSED, STATUS_FAILED, STATUS_ERROR, STATUS_PENDING)}
        for row in self.rows:
            counts[row["status"]] = counts.get(row["status"], 0) + 1
        return counts

    def designs_per_minute(self) -> float:
        """Designs run in this run per minute of wall time."""
        return 60.0 * self.built / self.seconds if self.seconds > 0 else 0.0

    def summary(self) -> str:
        """A few lines for the terminal: counts, rate, the table, the first refusals and failures."""
        counts = self.counts()
        lines = [f"sweep {self.spec.name!r}: {len(self.designs)} designs in {self.out_dir}"
                 + (" (INTERRUPTED; rerun the same command to resume)" if self.interrupted else ""),
                 f"  {counts['ok']} ok, {counts['refused']} refused, {counts['failed']} failed, "
                 f"{counts['error']} errors" + (f", {counts['pending']} not run" if counts["pending"] else ""),
                 f"  {self.built} built in {_duration(self.seconds)} ({self.designs_per_minute():.1f} designs/min, "
                 f"{self.backend}); {self.skipped} already done"]
        if self.tables:
            lines.append("  table: " + ", ".join(str(path) for path in self.tables.values()))
        problems = [row for row in self.rows if row["status"] in (STATUS_REFUSED, STATUS_FAILED, STATUS_ERROR)]
        for row in problems[:5]:
            lines.append(f"  {row['status']} {row['id']}: {row['reason']}")
        if len(problems) > 5:
            lines.append(f"  ... and {len(problems) - 5} more (see the table's reason column)")
        return "\n".join(lines)


def run_sweep(spec: SweepSpec, out_dir: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              client: Any = None, stl: bool | None = None, density_g_cm3: float | None = None,
              rebuild: bool = False, progress: bool | None = None, stream: TextIO | None = None) -> SweepResult:
    """Run every design of ``spec`` that is not done yet and write the results table.

    Args:
        spec: the sweep (see :func:`load_sweep`).
        out_dir: output folder; ``designs/<id>/`` per design, ``results.csv``, ``sweep.json``.
        workers: local processes (default: ``os.cpu_count()``); ignored with a scheduler or client.
        scheduler: a Dask scheduler address (``"tcp://host:8786"``), or ``"local"`` for a
            LocalCluster of ``workers`` single-threaded processes on this machine.
        client: an existing ``dask.distributed.Client`` to use instead of ``scheduler``.
        stl, density_g_cm3: override the sweep file's ``stl`` and ``density_g_cm3`` (g/cm^3).
        rebuild: run every design again, even those already done.
        progress: draw the progress bar (default: when ``stream`` is a TTY).
        stream: where the progress bar goes (default: stderr).

    A design never stops the sweep: refusals and failures are recorded in its folder and its
    row. On KeyboardInterrupt the table is still written (unfinished designs as ``pending``)
    and the interrupt is raised again. Raises SweepError when the Dask scheduler cannot be used.
    """
    if workers is not None and (not _is_int(workers) or workers < 1):
        raise ParameterError(f"--workers must be a whole number >= 1, got {workers!r}")
    out_dir = Path(out_dir).resolve()
    stl = spec.stl if stl is None else stl
    density = spec.density_g_cm3 if density_g_cm3 is None else density_g_cm3
    designs = generate_designs(spec)
    result = SweepResult(spec, out_dir, designs)
    _write_manifest(spec, designs, out_dir, stl, density)
    outcomes: dict[str, dict[str, Any]] = {}
    pending: list[DesignTask] = []
    for design in designs:
        folder = out_dir / DESIGNS_DIR / design.design_id
        if not rebuild and _is_done(read_design_status(folder, design, stl)):
            continue
        pending.append(DesignTask(design.design_id, design.parameters, str(folder), stl, density))
    result.skipped = len(designs) - len(pending)
    bar = Progress(len(designs), result.skipped, stream, progress)

    def on_outcome(task: DesignTask, outcome: dict[str, Any]) -> None:
        outcomes[task.design_id] = outcome
        bar.update(outcome["status"])

    start = time.perf_counter()
    own_client = None
    try:
        if not pending:
            result.backend = "nothing to run"
        elif client is not None or scheduler is not None:
            if client is None:
                assert scheduler is not None
                own_client = client = _connect(scheduler, workers)
            dask_client = client
            result.backend = f"dask: {_client_label(dask_client)}"
            _drive(lambda: dask_client.get_executor(pure=False), pending, None, on_outcome, bar, check_files=True)
        else:
            count = max(1, min(workers or os.cpu_count() or 1, len(pending)))
            result.backend = f"local pool, {count} worker{'s' if count > 1 else ''}"
            _drive(lambda: _local_pool(count), pending, count, on_outcome, bar, check_files=False)
    except KeyboardInterrupt as interrupt:
        result.interrupted = True
        raise SweepInterrupted(result) from interrupt
    finally:
        bar.close()
        result.built = len(outcomes)
        result.seconds = time.perf_counter() - start
        if own_client is not None:
            _close_client(own_client)
        result.rows = collect_rows(designs, spec.axes, out_dir, stl, outcomes)
        result.tables = write_table(result.rows, out_dir, table_columns(spec.axes))
    return result


def _local_pool(workers: int) -> ProcessPoolExecutor:
    """A process pool whose workers start from a clean process, never by forking this one.

    Forking the caller is unsafe when it holds threads (a Dask client, a GUI, a test runner).
    Where available, the workers fork from multiprocessing's fork server, which imports the
    kernel once (cadquery takes seconds to import), so every worker starts at once and later
    pools in this process start at once too; elsewhere they are spawned.
    """
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["torus_cad.sweep", "torus_cad.propeller"])
    else:  # pragma: no cover - Windows
        context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_ignore_interrupts)


def _ignore_interrupts() -> None:
    """In a pool worker: leave Ctrl-C to the parent, so the designs being built finish and are kept."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _connect(scheduler: str, workers: int | None) -> Any:
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise SweepError("--scheduler needs dask.distributed: pip install 'dask[distributed]'") from None
    try:
        if scheduler == "local":
            cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                   processes=True, dashboard_address=None)
            client = Client(cluster)
            client._torus_cad_cluster = cluster  # closed with the client
            return client
        return Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
    except (OSError, TimeoutError, ValueError) as error:
        raise SweepError(f"cannot connect to the Dask scheduler at {scheduler!r}: {error}") from None


def _close_client(client: Any) -> None:
    cluster = getattr(client, "_torus_cad_cluster", None)
    client.close()
    if cluster is not None:
        cluster.close()


def _client_label(client: Any) -> str:
    try:
        info = client.scheduler_info()
        workers = info.get("workers", {})
        threads = sum(worker.get("nthreads", 1) for worker in workers.values())
        return f"{info.get('address', '?')}, {len(workers)} workers, {threads} threads"
    except Exception:  # noqa: BLE001 - only a label
        return "cluster"


def _drive(make_executor: Callable[[], Executor], tasks: Sequence[DesignTask], window: int | None,
           on_outcome: Callable[[DesignTask, dict[str, Any]], None], bar: Progress, check_files: bool,
           function: Callable[[DesignTask], dict[str, Any]] | None = None) -> None:
    """Run ``tasks`` on an executor (a process pool or Dask's), calling ``on_outcome`` as each finishes.

    ``window`` caps the tasks in flight (the pool's size; None: submit all, for Dask's scheduler).
    When a worker process dies (a crash inside OpenCascade), the pool is replaced; the designs
    that were in flight run again one at a time, and one that kills its worker alone is
    recorded as an error. ``check_files``: verify that an ok design's report is visible here
    (a cluster writing to a disk the client cannot see is recorded as an error). ``function``
    replaces :func:`run_design` (a top-level function, for tests).
    """
    function = run_design if function is None else function
    queue: deque[DesignTask] = deque(tasks)
    suspects: deque[DesignTask] = deque()
    executor = make_executor()
    in_flight: dict[Future, DesignTask] = {}
    alone: DesignTask | None = None  # a suspect running by itself
    finished_any = False  # a design came back from a worker (so the workers can start)
    lone_crashes = idle_breaks = 0

    def submit(task: DesignTask) -> bool:
        try:
            in_flight[executor.submit(function, task)] = task
        except BrokenProcessPool:  # a worker just died: its futures tell which designs were hit
            return False
        return True

    try:
        while queue or suspects or in_flight:
            if suspects and not in_flight:
                alone = suspects[0]
                if submit(alone):
                    suspects.popleft()
                else:  # the fresh pool cannot start a worker
                    raise SweepError("the process pool's workers cannot start")
            elif not suspects:
                while queue and (window is None or len(in_flight) < window) and submit(queue[0]):
                    queue.popleft()
                if queue and not in_flight:  # the pool broke while idle (a worker was killed): replace it
                    idle_breaks += 1
                    if idle_breaks > 3:
                        raise SweepError("the process pool keeps breaking before it runs a design")
                    _shutdown(executor, wait=False)
                    executor = make_executor()
                    continue
            done, _ = wait(list(in_flight), timeout=_POLL_SECONDS, return_when=FIRST_COMPLETED)
            bar.draw()
            broken: list[DesignTask] = []
            if any(isinstance(future.exception(), BrokenProcessPool) for future in done):
                done, _ = wait(list(in_flight))  # every other task of the dead pool fails now too
            for future in done:
                task = in_flight.pop(future)
                error = future.exception()
                if isinstance(error, BrokenProcessPool):
                    broken.append(task)
                    continue
                if error is not None:  # e.g. Dask's KilledWorker, or the task could not be sent
                    outcome = _write_failure_here(task, STATUS_ERROR, f"{type(error).__name__}: {error}")
                else:
                    outcome = future.result()
                    finished_any = True
                    if check_files and outcome["status"] == STATUS_OK and not (
                            Path(task.folder) / f"{task.design_id}.json").is_file():
                        outcome = _write_failure_here(
                            task, STATUS_ERROR, f"the worker wrote {task.folder} but it is not visible here; "
                            "the output folder must be on a file system shared by the workers and the client")
                if task is alone:
                    alone = None
                on_outcome(task, outcome)
            if broken:
                _shutdown(executor, wait=False)
                executor = make_executor()
                if alone is not None and broken == [alone]:
                    lone_crashes += 1
                    if not finished_any and lone_crashes >= 2:
                        raise SweepError(
                            "the worker processes die before finishing any design; they may fail to start "
                            "(a script that calls run_sweep needs an `if __name__ == \"__main__\":` guard, "
                            "as the workers re-import it)")
                    on_outcome(alone, _write_failure_here(
                        alone, STATUS_ERROR, "the worker process died while building this design "
                        "(a crash inside OpenCascade?)"))
                else:
                    suspects.extend(broken)
                alone = None
    except KeyboardInterrupt:
        for future in in_flight:
            future.cancel()
        running = [task for future, task in in_flight.items() if not future.done()]
        if isinstance(executor, ProcessPoolExecutor) and running:
            # the workers ignore Ctrl-C: let the designs being built finish, so they are kept and tabulated
            bar.message(f"interrupted: finishing the {len(running)} designs in progress (Ctrl-C again to leave "
                        "them to finish in the background)")
            _shutdown(executor, wait=True)
            for future, task in in_flight.items():
                if future.done() and not future.cancelled() and future.exception() is None:
                    on_outcome(task, future.result())
        else:
            _shutdown(executor, wait=False)
        raise
    except BaseException:
        _shutdown(executor, wait=False)
        raise
    _shutdown(executor, wait=True)


def _shutdown(executor: Executor, wait: bool) -> None:
    """Shut an executor down; without waiting, queued tasks are cancelled (Dask's executor cancels its own)."""
    if isinstance(executor, ProcessPoolExecutor):
        executor.shutdown(wait=wait, cancel_futures=not wait)
    else:
        executor.shutdown(wait=wait)


# -- the results table ------------------------------------------------------------------------

_PROPERTY_COLUMNS = ("volume_mm3", "surface_area_mm2", "mass_g", "density_g_cm3", "spin_axis_inertia_g_mm2",
                     "spin_axis_inertia_mm5", "centroid_x_mm", "centroid_y_mm", "centroid_z_mm",
                     "section_fit_error_mm")


def table_columns(axes: Sequence[VaryAxis]) -> list[str]:
    """The table's columns: id and status, the varied keys, mass properties, stage times (s), folder."""
    return (["index", "id", "status", "valid", "reason"] + [axis.key for axis in axes] + list(_PROPERTY_COLUMNS)
            + [f"time_{stage}_s" for stage in STAGES] + ["time_total_s", "folder"])


def collect_rows(designs: Sequence[Design], axes: Sequence[VaryAxis], out_dir: str | Path, stl: bool = True,
                 outcomes: Mapping[str, Mapping[str, Any]] | None = None) -> list[dict[str, Any]]:
    """The results table, rebuilt from the per-design files (``outcomes`` fill in designs with no file).

    Vector values of varied keys are JSON strings (``"[25.0, 3.0, 22.0]"``); numbers stay numbers;
    a column that does not apply (e.g. the volume of a refused design) is None.
    """
    out_dir = Path(out_dir)
    columns = table_columns(axes)
    rows = []
    for design in designs:
        folder = out_dir / DESIGNS_DIR / design.design_id
        status = read_design_status(folder, design, stl)
        if status is None and outcomes and design.design_id in outcomes:
            status = dict(outcomes[design.design_id])
        row: dict[str, Any] = dict.fromkeys(columns)
        row.update(index=design.index, id=design.design_id, status=STATUS_PENDING, valid=False, reason="",
                   folder=f"{DESIGNS_DIR}/{design.design_id}")
        for key, value in design.varied.items():
            row[key] = json.dumps(value) if isinstance(value, list) else value
        if status is not None:
            row["status"] = status["status"]
            report = status.get("report")
            if report is not None:
                row["valid"] = bool(report.get("valid", False))
                for column in _PROPERTY_COLUMNS:
                    if column in report:
                        row[column] = report[column]
                centroid = report.get("centroid_mm") or [None, None, None]
                row["centroid_x_mm"], row["centroid_y_mm"], row["centroid_z_mm"] = centroid
                stages = report.get("stage_seconds", {})
                for stage in STAGES:
                    row[f"time_{stage}_s"] = stages.get(stage)
                row["time_total_s"] = float(sum(stages.values()))
            else:
                row["reason"] = status.get("reason", "")
                row["time_total_s"] = status.get("seconds")
        rows.append(row)
    return rows


def write_table(rows: Sequence[Mapping[str, Any]], out_dir: str | Path,
                columns: Sequence[str] | None = None) -> dict[str, Path]:
    """Write ``results.csv`` (and ``results.parquet`` when pyarrow is installed) atomically."""
    from torus_cad.kernel.export import atomic_path

    out_dir = Path(out_dir)
    columns = list(columns if columns is not None else (rows[0].keys() if rows else []))
    paths = {"csv": out_dir / TABLE_CSV}
    with atomic_path(paths["csv"]) as temp:
        with temp.open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=columns, extrasaction="ignore")
            writer.writeheader()
            for row in rows:
                writer.writerow({key: "" if row.get(key) is None else row[key] for key in columns})
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        return paths
    paths["parquet"] = out_dir / TABLE_PARQUET
    table = pyarrow.Table.from_pylist([{key: row.get(key) for key in columns} for row in rows]) if rows \
        else pyarrow.table({key: [] for key in columns})
    with atomic_path(paths["parquet"]) as temp:
        pyarrow.parquet.write_table(table, temp)
    return paths


def _write_manifest(spec: SweepSpec, designs: Sequence[Design], out_dir: Path, stl: bool,
                    density_g_cm3: float | None) -> None:
    """``sweep.json``: the sweep's settings and every design's id and varied values."""
    from torus_cad.kernel.export import atomic_path

    manifest = {
        "name": spec.name, "source": spec.source, "mode": spec.mode, "samples": spec.samples, "seed": spec.seed,
        "stl": stl, "density_g_cm3": density_g_cm3,
        "vary": {axis.key: ({"low": axis.low, "high": axis.high} if axis.is_bounds else list(axis.values))
                 for axis in spec.axes},
        "base": spec.base.to_dict(),
        "designs": [{"index": d.index, "id": d.design_id, "varied": d.varied} for d in designs],
    }
    with atomic_path(out_dir / MANIFEST_FILE) as temp:
        temp.write_text(json.dumps(manifest, indent=2) + "\n")
