"""The studio's live performance numbers: the vortex solver's thrust, power and figure of merit (or
efficiency) at the rpm and airspeed entered, and its loading plot.

The rpm and airspeed are checked as ``simulate --solver vortex`` checks them
(:func:`torus_cad.simulate.settings.check_operating_point`, the design's tip diameter with its
targets); a refused value puts the one-line reason under its field and keeps the last numbers. A
good point is solved in its own process (:class:`torus_cad.studio.worker.ProcessRunner`, forked from
the builds' forkserver, running :func:`torus_cad.studio.vortex_run.run_vortex`): the event loop only
waits on a pipe, a newer request kills the process of the one it supersedes, and a message of an
older request is dropped, so only the latest point's numbers are ever shown. Its messages::

    ("result", request_id, {"report": {...}, "png": bytes})
        the numbers and the loading plot (PNG)
    ("failed", request_id, "one-line reason")
        e.g. KernelError: the solve did not converge

The solve starts once the design's exact solid is built (the studio calls
:meth:`Performance.set_design`), so it never competes with the build for the CPU, and never before
the page is served.
"""

from __future__ import annotations

import base64
import math
import multiprocessing.connection
import re
from pathlib import Path
from typing import Any

from torus_cad.errors import GeometryError, ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.studio.messages import PerformanceRequest
from torus_cad.studio.worker import (
    BUILD_MEMORY_LIMIT_BYTES,
    ProcessRunner,
    run_bounded,
    time_out_reason,
)

#: The operating point the studio starts with: the one the docs' vortex measurements use (rpm, m/s).
DEFAULT_RPM = 10000.0
DEFAULT_AIRSPEED_M_S = 0.0

#: Seconds a solve may take before its process is killed: one point is ~5 s of CPU on the default
#: design and ~20 s at load average 8 on 2 cores; a finer design's polars take longer.
PERFORMANCE_TIME_LIMIT_S = 180.0

#: What the readouts show while a point is being solved.
COMPUTING = "computing…"

#: What a readout shows when there is no number (a failed solve, or no figure of merit at rpm 0).
NO_NUMBER = "–"

#: The honest label under the numbers (the accuracy page holds the measurements).
SOLVER_LABEL = (
    "vortex solver: a screening estimate, not validated to 10 % "
    "(see docs/explanation/simulation-accuracy.md)"
)

#: The command-line option names in check_operating_point's messages, worded as the studio's fields.
_OPTION = re.compile(r"--(rpm|airspeed)\b")


class PointRefused(ParameterError):
    """An rpm or airspeed the vortex solver refuses; ``field`` is ``"rpm"`` or ``"airspeed"``."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


def state_defaults() -> dict[str, Any]:
    """The page state of the performance card before anything is solved."""
    return {
        "perf_rpm": DEFAULT_RPM,
        "perf_airspeed": DEFAULT_AIRSPEED_M_S,
        "perf_rpm_error": "",
        "perf_airspeed_error": "",
        "perf_thrust_text": "…",
        "perf_power_text": "…",
        "perf_merit_label": "figure of merit",
        "perf_merit_text": "…",
        "perf_point_text": "",
        "perf_failure": "",
        "perf_plot": "",
        "perf_computing": False,
    }


def check_point(rpm: Any, airspeed: Any, params: PropellerParameters) -> tuple[float, float]:
    """(rpm, airspeed m/s) from the page's values, in ``simulate --solver vortex``'s ranges for
    ``params``; :class:`PointRefused` naming the field, the value and the allowed range
    otherwise."""
    from torus_cad.simulate.settings import OperatingPoint, check_operating_point
    from torus_cad.vortex.pipeline import tip_diameter_m

    values = {
        name: _number(name, value, unit)
        for name, value, unit in (("rpm", rpm, "rpm"), ("airspeed", airspeed, "m/s"))
    }
    try:
        check_operating_point(
            OperatingPoint(values["rpm"], values["airspeed"]), tip_diameter_m(params), params
        )
    except ParameterError as error:
        message = _OPTION.sub(r"\1", str(error))
        raise PointRefused("rpm" if message.startswith("rpm") else "airspeed", message) from None
    return values["rpm"], values["airspeed"]


def _number(name: str, value: Any, unit: str) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise PointRefused(name, f"{name} must be a number in {unit}, got {value!r}") from None


def readouts(
    report: dict[str, Any], rpm: float, airspeed_m_s: float, strips: int
) -> dict[str, Any]:
    """The card's texts for a solved point: thrust N, power W, figure of merit (still air) or
    efficiency."""
    axial = airspeed_m_s > 0.0
    merit = report["efficiency"] if axial else report["figure_of_merit"]
    doubtful = report["low_confidence_strips"]
    point = f"at {rpm:g} rpm, {airspeed_m_s:g} m/s"
    if doubtful:
        point += f"; NeuralFoil unsure of its polars on {doubtful} of {strips} strips"
    return {
        "perf_thrust_text": f"{report['thrust_n']:.4g} N",
        "perf_power_text": f"{report['power_w']:.4g} W",
        "perf_merit_label": "efficiency" if axial else "figure of merit",
        "perf_merit_text": NO_NUMBER
        if merit is None or not math.isfinite(merit)
        else f"{merit:.3f}",
        "perf_point_text": point,
    }


class Performance:
    """The performance card's state and its solves, for one studio page (module doc).

    ``state``: the trame state holding :func:`state_defaults`' keys; ``workdir``: the studio's
    folder.
    """

    def __init__(self, state: Any, workdir: Path) -> None:
        self.state, self.workdir = state, workdir
        self._runner = ProcessRunner(
            self._on_message,
            _child_main,
            ("result", "failed"),
            _time_out_reason,
            "vortex solver",
            PERFORMANCE_TIME_LIMIT_S,
            BUILD_MEMORY_LIMIT_BYTES,
        )
        self._design: PropellerParameters | None = None
        self._request_id = 0
        self._solving: tuple[float, float] | None = None  # the point of the request running

    @property
    def running(self) -> bool:
        """A solve is running."""
        return self._runner.running

    def set_design(self, params: PropellerParameters) -> None:
        """Solve ``params`` (the design whose exact solid is on screen) at the page's point."""
        self._design = params
        self.solve()

    def hold(self) -> None:
        """A new design is being built: stop the solve of the old one and show that numbers are
        coming."""
        self._runner.cancel()
        self._show_computing()

    def on_operating_point(self, **_: Any) -> None:
        """The rpm or airspeed changed (a trame state callback)."""
        self.solve()

    def solve(self) -> None:
        """Check the page's point; solve it in a new process, or put the refusal under its field."""
        if self._design is None:
            return
        try:
            rpm, airspeed = check_point(self.state.perf_rpm, self.state.perf_airspeed, self._design)
        except PointRefused as refusal:
            with self.state:
                self.state.perf_rpm_error = str(refusal) if refusal.field == "rpm" else ""
                self.state.perf_airspeed_error = str(refusal) if refusal.field == "airspeed" else ""
            return
        # the design itself; the build would refuse it
        except (ParameterError, GeometryError) as error:
            self._show_failure(str(error))
            return
        self._request_id += 1
        self._solving = (rpm, airspeed)
        request = PerformanceRequest(
            self._request_id, self._design.to_dict(), rpm, airspeed, self.workdir / "performance"
        )
        request.out_dir.mkdir(parents=True, exist_ok=True)
        self._runner.start(self._request_id, request)
        with self.state:
            self.state.perf_rpm_error = self.state.perf_airspeed_error = ""
        self._show_computing()

    def cancel(self) -> None:
        """Kill the running solve, if any (the server is stopping)."""
        self._runner.cancel()

    def _on_message(self, kind: str, request_id: int, payload: Any) -> None:
        if request_id != self._request_id or self._solving is None:
            return  # a superseded request's: dropped
        rpm, airspeed = self._solving
        if kind == "result":
            encoded = base64.b64encode(payload["png"]).decode("ascii")
            with self.state:
                self.state.update(readouts(payload["report"], rpm, airspeed, payload["strips"]))
                self.state.perf_plot = f"data:image/png;base64,{encoded}"
                self.state.perf_failure, self.state.perf_computing = "", False
        elif kind == "failed":
            self._show_failure(f"{payload} (at {rpm:g} rpm, {airspeed:g} m/s)")

    def _show_computing(self) -> None:
        with self.state:
            for name in ("perf_thrust_text", "perf_power_text", "perf_merit_text"):
                self.state[name] = COMPUTING
            self.state.perf_computing = True

    def _show_failure(self, message: str) -> None:
        with self.state:
            for name in ("perf_thrust_text", "perf_power_text", "perf_merit_text"):
                self.state[name] = NO_NUMBER
            self.state.perf_failure, self.state.perf_computing = message, False


_time_out_reason = time_out_reason(
    "the vortex solve", "run it with torus-cad simulate --solver vortex"
)


def _child_main(
    request: PerformanceRequest,
    connection: multiprocessing.connection.Connection,
    memory_limit_bytes: int,
) -> None:
    """The solve's process (forked from the forkserver): bounded in data memory as a build is."""
    from torus_cad.studio.vortex_run import run_vortex

    run_bounded(run_vortex, request, connection, memory_limit_bytes)
