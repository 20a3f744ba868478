"""Random in-range designs and a supervised runner that classifies what each one does.

Used by ``scripts/fuzz.py`` (N random designs, tally, failures saved for replay) and by the
hypothesis properties in ``tests/test_robustness.py``; both draw designs through the same
function, :func:`design_from_unit`, which maps a point of the unit cube to a
:class:`PropellerParameters`. Every design it returns passes parameter validation, so the
only acceptable outcomes of building it are a valid closed solid or a clear refusal
(ParameterError / GeometryError, exit code 2 at the CLI).

Outcomes (:data:`OUTCOMES`):

* ``valid``     one valid closed solid (and, when files are written, files that read back).
* ``refused``   ParameterError or GeometryError: the package's own one-line refusal.
* ``kernel``    KernelError on an in-range design: OpenCascade failed where a refusal rule
                should have caught the design, or the kernel has a bug.
* ``exception`` any other exception (a traceback at the CLI).
* ``bad_file``  the solid was built but a written file is missing, partial or unreadable.
* ``timeout``   the design ran past its time limit (a hang).
* ``crash``     the worker process died (a segfault in OpenCascade, out of memory).

Only the first two are acceptable; the rest are "anything else".
"""

from __future__ import annotations

import math
import multiprocessing
import os
import shutil
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.geometry.frames import FrameKind
from torus_cad.geometry.transforms import quartic_minimum
from torus_cad.parameters import PropellerParameters

#: Length of the unit vector that :func:`design_from_unit` consumes.
UNIT_DIMENSION = 39

OUTCOMES = ("valid", "refused", "kernel", "exception", "bad_file", "timeout", "crash")
ACCEPTABLE = ("valid", "refused")


# -- sampling --------------------------------------------------------------------------------

def _lerp(u: float, low: float, high: float) -> float:
    return low + (high - low) * float(u)


def _log_lerp(u: float, low: float, high: float) -> float:
    return math.exp(_lerp(u, math.log(low), math.log(high)))


def _positive_quartic(ends: tuple[float, float], bulge: float, wiggle: float, floor: float) -> tuple[float, ...]:
    """A scale quartic (mm) that stays positive on [0, 1].

    S(s) = v0 (1 - s) + v1 s + 4 h s (1 - s) + 16 w s^2 (1 - s)^2 with end values ``ends``,
    mid-span ``bulge`` h and ``wiggle`` w; e is raised if needed so the minimum is ``floor`` > 0.
    """
    v0, v1 = ends
    h, w = bulge, wiggle
    coefficients = [16 * w, -32 * w, 16 * w - 4 * h, v1 - v0 + 4 * h, v0]  # highest power first
    low, _ = quartic_minimum(tuple(coefficients))
    if low < floor:
        coefficients[4] += floor - low
    while quartic_minimum(tuple(coefficients))[0] <= 0.0:  # guard against rounding
        coefficients[4] += floor
    return tuple(float(value) for value in coefficients)


def design_dict_from_unit(u: Sequence[float], name: str = "fuzz",
                          sections: tuple[int, int] = (16, 36), points: tuple[int, int] = (24, 48)
                          ) -> dict[str, Any]:
    """Map ``u`` in [0, 1]^UNIT_DIMENSION to a design as a nested dict (the TOML layout).

    The first number sets a *wildness* w in [0, 1]: every geometric quantity is the default
    design's (scaled to the sampled hub) perturbed by up to w times its own range, so a run
    covers near-default propellers (mostly valid) through wild ones (mostly refused). Ranges
    at w = 1: 1-8 blades; hub radius 4-25 mm, length 8-50 mm; any NACA camber / position,
    thickness 0.06-1, pivot 0-1; blade span 0.3-1.15 of the blade pitch, control-point heights
    0.1-6.6 R and y_L from far above to below the hub; both frame kinds; angle of attack
    +-90 degrees plus quartic terms up to +-250 degrees; chord and thickness scales whose
    ends, bulge and wiggle vary by factors of 3 (kept positive). Every value lies in its
    field's range; rules that tie fields together (an airfoil too thick for its camber, ...)
    may still refuse the design with ParameterError, which counts as a clear refusal.
    ``sections`` and ``points`` bound the (low) sampling resolution, inclusive.
    """
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    if u.shape != (UNIT_DIMENSION,):
        raise ValueError(f"design_dict_from_unit needs {UNIT_DIMENSION} numbers in [0, 1], got shape {u.shape}")
    it: Iterator[float] = iter(u.tolist())

    def take() -> float:
        return next(it)

    wild = take()

    def vary(value: float, factor: float) -> float:
        """``value`` times a factor in [1/factor, factor]^wild (log-uniform)."""
        return value * math.exp(wild * _lerp(take(), -1.0, 1.0) * math.log(factor))

    def shift(value: float, spread: float) -> float:
        """``value`` plus up to +-wild * spread (offsets below 1e-9 of the spread snap to 0)."""
        offset = wild * _lerp(take(), -1.0, 1.0) * spread
        # Subnormal coefficients (hypothesis finds them) break np.roots in quartic_minimum; that bug
        # has its own regression test in tests/test_malformed_config.py; here they would only mask
        # the geometry this sampler is for.
        return value + (offset if abs(offset) > 1e-9 * spread else 0.0)

    blades = 1 + min(7, int(take() * 8))
    radius = float(np.clip(vary(10.0, 2.5), 4.0, 25.0))
    length = float(np.clip(vary(20.0, 2.5), 8.0, 50.0))
    size = radius / 10.0  # the default design is drawn for R = 10 mm
    phase = _lerp(take(), -180.0, 180.0)

    symmetric, camber = take() < 0.2, take()  # one design in five has a symmetric section
    max_camber = 0.0 if symmetric else _lerp(camber, 0.0, 0.095)
    camber_position = _lerp(take(), 0.1, 0.9)
    thickness = float(np.clip(vary(0.5, 8.0), 0.06, 1.0))
    camber_normal = take() < 0.5
    pivot = float(np.clip(wild * take(), 0.0, 1.0))

    pitch = 360.0 if blades == 1 else 360.0 / blades
    span = pitch * (0.83 if blades > 1 else 100.0 / 360.0) * math.exp(wild * _lerp(take(), -1.0, 0.33))
    span = float(np.clip(span, 10.0, 1.15 * pitch if blades > 1 else 340.0))
    x2 = span * shift(0.25, 0.6)
    x3 = span * shift(0.75, 0.6)
    x4 = span * (-1.0 if take() < 0.15 * wild else 1.0)
    y_span = length - 2.0  # y_L in [0, L - 2] keeps a point between the end faces
    y2 = y_span * shift(3.0 / 18.0, 0.7)
    y3 = y_span * shift(15.0 / 18.0, 0.7)
    y4 = y_span * float(np.clip(shift(1.0, 1.0), 0.0, 1.0))
    inset = radius - radius / 8.0
    z2 = max(vary(22.0 * size, 3.0), -0.9 * inset)
    z3 = max(vary(22.0 * size, 3.0), -0.9 * inset)
    x2, x3 = (float(np.clip(x, -359.0, 359.0)) for x in (x2, x3))
    frame = (FrameKind.FRENET if take() < 0.5 else FrameKind.ROTATION_MINIMIZING).value

    alpha = (shift(0.0, 250.0), shift(0.0, 250.0), shift(0.0, 250.0), shift(0.0, 250.0), shift(20.0, 90.0))
    # Sections shrink with the span (a shorter blade bends tighter); ends start at half the default's.
    chord = size * min(1.0, span / 100.0)
    scale_x = _positive_quartic((vary(3.0 * chord, 3.0), vary(3.0 * chord, 3.0)), vary(5.0 * chord, 3.0),
                                shift(0.0, 3.0 * chord), 0.02 * radius)
    scale_y = _positive_quartic((vary(1.0 * chord, 3.0), vary(1.0 * chord, 3.0)), vary(1.5 * chord, 3.0),
                                shift(0.0, 1.0 * chord), 0.02 * radius)

    section_count = int(round(_lerp(take(), sections[0], sections[1])))
    point_count = int(round(_lerp(take(), points[0], points[1])))
    linear_deflection = _log_lerp(take(), 0.02, 0.5)
    angular_deflection = _lerp(take(), 0.2, 0.8)
    schema = "AP214" if take() < 0.5 else "AP242"
    assert next(it, None) is None, "UNIT_DIMENSION does not match the numbers design_dict_from_unit takes"

    return {
        "name": name,
        "blades": blades,
        "phase_deg": phase,
        "hub": {"radius": radius, "length": length},
        "airfoil": {"max_camber": max_camber, "camber_position": camber_position, "thickness": thickness,
                    "camber_normal": camber_normal, "pivot": pivot},
        "centerline": {"p2": [x2, y2, z2], "p3": [x3, y3, z3], "p4": [x4, y4], "frame": frame},
        "transforms": {"angle_of_attack": list(alpha), "scale_x": list(scale_x), "scale_y": list(scale_y)},
        "resolution": {"sections": section_count, "points": point_count},
        "export": {"stl_linear_deflection": linear_deflection, "stl_angular_deflection": angular_deflection,
                   "step_schema": schema},
    }


def design_from_unit(u: Sequence[float], name: str = "fuzz", **kwargs: Any) -> PropellerParameters:
    """:func:`design_dict_from_unit` as validated parameters (may raise ParameterError)."""
    return PropellerParameters.from_dict(design_dict_from_unit(u, name, **kwargs))


def random_design_dict(seed: int, **kwargs: Any) -> dict[str, Any]:
    """The design of ``seed`` as a dict: unit vector from numpy's default_rng(seed); named fuzz_<seed>."""
    rng = np.random.default_rng(seed)
    return design_dict_from_unit(rng.random(UNIT_DIMENSION), name=f"fuzz_{seed}", **kwargs)


def random_design(seed: int, **kwargs: Any) -> PropellerParameters:
    """:func:`random_design_dict` as validated parameters (may raise ParameterError)."""
    return PropellerParameters.from_dict(random_design_dict(seed, **kwargs))


# -- running one design ----------------------------------------------------------------------

@dataclass
class Outcome:
    """What building (and writing) one design did."""

    kind: str
    message: str = ""
    seconds: float = 0.0
    detail: str = ""  # traceback or extra text for anything unacceptable

    @property
    def acceptable(self) -> bool:
        return self.kind in ACCEPTABLE


def _check_files(paths: dict[str, Path]) -> str:
    """'' when every written file is complete and reads back; otherwise what is wrong."""
    import json

    from torus_cad.kernel.checks import is_valid_closed_solid
    from torus_cad.kernel.export import read_step

    for kind, path in paths.items():
        if not path.is_file() or path.stat().st_size == 0:
            return f"{kind} file {path.name} is missing or empty"
    leftovers = [p.name for p in next(iter(paths.values())).parent.glob(".*.tmp-*")]
    if leftovers:
        return f"temporary files left behind: {leftovers}"
    if not is_valid_closed_solid(read_step(paths["step"])):
        return "the STEP file does not read back as one valid closed solid"
    if "stl" in paths:
        data = paths["stl"].read_bytes()
        count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0]) if len(data) >= 84 else -1
        if count <= 0 or len(data) != 84 + 50 * count:
            return f"the STL file is truncated or empty ({len(data)} bytes for {count} triangles)"
        vertices = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                                 count=count, offset=84)["v"]
        if not np.all(np.isfinite(vertices)):
            return "the STL file holds non-finite coordinates"
    report = json.loads(paths["json"].read_text())
    if not report.get("valid") or not report.get("volume_mm3", 0) > 0:
        return "the JSON report does not describe a valid solid"
    return ""


def run_design(design: PropellerParameters | Mapping[str, Any], out_dir: str | Path | None = None,
               stl: bool = True) -> Outcome:
    """Build ``design`` (parameters or a dict) in this process and classify the result.

    Files are written to ``out_dir`` (and read back) when it is given.
    """
    from torus_cad.errors import GeometryError, KernelError, ParameterError
    from torus_cad.kernel.checks import is_valid_closed_solid
    from torus_cad.propeller import build_propeller

    start = time.perf_counter()
    try:
        params = design if isinstance(design, PropellerParameters) else PropellerParameters.from_dict(design)
        propeller = build_propeller(params)
        if not is_valid_closed_solid(propeller.solid):
            return Outcome("kernel", "build_propeller returned a shape that is not one valid closed solid",
                           time.perf_counter() - start)
        if out_dir is not None:
            paths = propeller.write(out_dir, stl=stl)
            problem = _check_files(paths)
            if problem:
                return Outcome("bad_file", problem, time.perf_counter() - start)
    except (ParameterError, GeometryError) as error:
        return Outcome("refused", str(error), time.perf_counter() - start)
    except KernelError as error:
        return Outcome("kernel", str(error), time.perf_counter() - start, traceback.format_exc())
    except Exception as error:  # noqa: BLE001 - the point is to catch everything
        return Outcome("exception", f"{type(error).__name__}: {error}", time.perf_counter() - start,
                       traceback.format_exc())
    return Outcome("valid", "", time.perf_counter() - start)


# -- supervised pool: time limits and crash isolation ------------------------------------------

def _die_with_parent() -> None:
    """Linux: have the kernel SIGKILL this worker when its parent dies (no orphans after a kill)."""
    try:
        import ctypes
        import signal

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: workers still stop when their pipe closes
        pass


#: A design dict holding this key makes the worker hang ("hang") or die ("crash") instead of
#: building: the supervisor's own test uses it to check that both are counted, not fatal.
TEST_ACTION_KEY = "__fuzz_self_test__"


def _test_action(action: str) -> None:
    import signal

    if action == "hang":
        time.sleep(3600)
    elif action == "crash":
        os.kill(os.getpid(), signal.SIGKILL)


def _worker(connection: Connection, write: bool, stl: bool) -> None:
    """Worker loop: receive (index, design dict), build, send (index, Outcome); None stops it."""
    _die_with_parent()
    while True:
        try:
            task = connection.recv()
        except EOFError:
            return
        if task is None:
            return
        index, design = task
        if isinstance(design, Mapping) and TEST_ACTION_KEY in design:  # self-test of the supervisor
            _test_action(design[TEST_ACTION_KEY])
        scratch = Path(tempfile.mkdtemp(prefix="torus_fuzz_")) if write else None
        try:
            outcome = run_design(design, scratch, stl)
        finally:
            if scratch is not None:
                shutil.rmtree(scratch, ignore_errors=True)
        connection.send((index, outcome))


@dataclass
class _Slot:
    process: multiprocessing.process.BaseProcess
    connection: Connection
    task: tuple[int, Any] | None = None
    started: float = 0.0


@dataclass
class SupervisedPool:
    """Runs designs in worker processes, each with a wall-clock limit; a hang or a crash is an outcome.

    A worker that overruns its limit is killed (SIGKILL) and replaced; one that dies is
    replaced too. Workers are started with the 'spawn' method (OpenCascade is not fork-safe).
    """

    workers: int = 2
    time_limit: float = 60.0
    write: bool = True
    stl: bool = True
    _slots: list[_Slot] = field(default_factory=list)

    def _start(self) -> _Slot:
        context = multiprocessing.get_context("spawn")
        parent, child = context.Pipe()
        process = context.Process(target=_worker, args=(child, self.write, self.stl), daemon=True)
        process.start()
        child.close()
        return _Slot(process, parent)

    def _stop(self, slot: _Slot) -> None:
        if slot.process.is_alive():
            slot.process.kill()
        slot.process.join(5)
        slot.connection.close()

    def run(self, designs: Sequence[PropellerParameters | Mapping[str, Any]],
            on_result: Callable[[int, Outcome], None] | None = None) -> list[Outcome]:
        """Outcomes of ``designs`` in order; ``on_result(index, outcome)`` as each one finishes."""
        results: list[Outcome | None] = [None] * len(designs)
        pending = list(reversed(range(len(designs))))
        self._slots = [self._start() for _ in range(max(1, min(self.workers, len(designs))))]

        def finish(index: int, outcome: Outcome) -> None:
            results[index] = outcome
            if on_result is not None:
                on_result(index, outcome)

        try:
            while pending or any(slot.task is not None for slot in self._slots):
                for slot in self._slots:
                    if slot.task is None and pending:
                        index = pending.pop()
                        design = designs[index]
                        slot.task = (index, design.to_dict() if isinstance(design, PropellerParameters) else design)
                        slot.started = time.perf_counter()
                        slot.connection.send(slot.task)
                busy = [slot for slot in self._slots if slot.task is not None]
                deadline = min(slot.started + self.time_limit for slot in busy)
                ready = wait([slot.connection for slot in busy], timeout=max(0.0, deadline - time.perf_counter()))
                for position, slot in enumerate(self._slots):
                    if slot.task is None:
                        continue
                    index = slot.task[0]
                    if slot.connection in ready:
                        try:
                            got_index, outcome = slot.connection.recv()
                        except (EOFError, OSError):
                            slot.process.join(5)
                            code = slot.process.exitcode
                            finish(index, Outcome("crash", f"worker died (exit code {code})",
                                                  time.perf_counter() - slot.started))
                            self._stop(slot)
                            self._slots[position] = self._start()
                            continue
                        slot.task = None
                        finish(got_index, outcome)
                    elif time.perf_counter() - slot.started >= self.time_limit:
                        finish(index, Outcome("timeout", f"no result within {self.time_limit:g} s",
                                              time.perf_counter() - slot.started))
                        self._stop(slot)
                        self._slots[position] = self._start()
        finally:
            for slot in self._slots:
                try:
                    slot.connection.send(None)
                except (OSError, BrokenPipeError):
                    pass
            for slot in self._slots:
                slot.process.join(2)
                self._stop(slot)
        return [result for result in results if result is not None]


def tally(outcomes: Sequence[Outcome]) -> dict[str, int]:
    """Counts per outcome kind, every kind present (zeros included)."""
    counts = {kind: 0 for kind in OUTCOMES}
    for outcome in outcomes:
        counts[outcome.kind] += 1
    return counts


def default_workers() -> int:
    """One worker per core."""
    return max(1, os.cpu_count() or 1)
