"""The numbers a study can optimise or constrain: those of the build's JSON report, and
``performance.*``.

A metric is a dotted key of the report that ``torus-cad build`` writes (``mass_g``,
``printability.thinnest_wall_mm``, ``balance.static_imbalance_g_mm``), or ``performance.<key>``,
a number of the ``<name>_performance.json`` that ``torus-cad simulate`` writes (thrust in N,
torque in N m, power in W, the dimensionless coefficients, and ``rpm``: the one asked for, or the
one found for a target thrust). ``performance.noise[DIST_M:ANGLE_DEG].<key>`` is a number of the
tonal noise at one observer (the ``noise.observers`` entry of that distance and angle, spelt as
``simulate --observer`` spells it): ``oaspl_db``, ``oaspl_dba`` (dB re 20 uPa),
``other_harmonics_spl_db``, ``peak_to_peak_pa``. Units are the report's: mm, mm^2, mm^3, g, g mm^2,
s, dB, Pa.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Iterable, Mapping
from typing import Any

from torus_cad.errors import ParameterError, shown

__all__ = [
    "NOISE_METRICS",
    "PERFORMANCE_METRICS",
    "PERFORMANCE_PREFIX",
    "REPORT_METRICS",
    "check_metric",
    "is_performance",
    "metric_value",
    "noise_observers",
]

#: Numbers every build report holds (dotted keys; ``printability.printable`` is 1 or 0).
REPORT_METRICS = (
    "volume_mm3",
    "surface_area_mm2",
    "mass_g",
    "density_g_cm3",
    "spin_axis_inertia_g_mm2",
    "spin_axis_inertia_mm5",
    "section_fit_error_mm",
    "balance.static_imbalance_g_mm",
    "balance.centroid_offset_mm",
    "balance.products_of_inertia_g_mm2.xz",
    "balance.products_of_inertia_g_mm2.yz",
    "balance.products_of_inertia_g_mm2.xy",
    "printability.thinnest_wall_mm",
    "printability.thinnest_wall_s",
    "printability.thinnest_wall_chord_fraction",
    "printability.trailing_edge_thickness_mm",
    "printability.trailing_edge_thinnest_s",
    "printability.min_wall_mm",
    "printability.printable",
)

PERFORMANCE_PREFIX = "performance."

#: Numbers of ``torus-cad simulate``'s performance report (N, N m, W; ct, cp, efficiency and figure
#: of merit dimensionless; ``converged`` is 1 or 0).
PERFORMANCE_METRICS = (
    "thrust_n",
    "torque_nm",
    "power_w",
    "ct",
    "cp",
    "efficiency",
    "figure_of_merit",
    "converged",
    "rpm",
)

#: Numbers of one observer's entry of the performance report's ``noise.observers`` (dB re 20 uPa;
#: Pa).
NOISE_METRICS = ("oaspl_db", "oaspl_dba", "other_harmonics_spl_db", "peak_to_peak_pa")
_NOISE = re.compile(r"^performance\.noise\[(?P<observer>[^\]]*)\]\.(?P<key>[A-Za-z0-9_]+)$")
_NOISE_EXAMPLE = "performance.noise[1:90].oaspl_dba"


def is_performance(metric: str) -> bool:
    """Whether ``metric`` needs ``torus-cad simulate`` (a ``performance.*`` key)."""
    return metric.startswith(PERFORMANCE_PREFIX)


def _noise_parts(metric: str) -> tuple[str, str] | None:
    """(observer text, key) of a ``performance.noise[DIST_M:ANGLE_DEG].<key>`` metric; None for any
    other metric."""
    match = _NOISE.match(metric)
    return (match["observer"], match["key"]) if match else None


def noise_observers(metrics: Iterable[str]) -> tuple[str, ...]:
    """The observers (``DIST_M:ANGLE_DEG``, as ``simulate --observer`` takes them) that ``metrics``
    name, in order."""
    named = (_noise_parts(metric) for metric in metrics)
    return tuple(dict.fromkeys(parts[0] for parts in named if parts is not None))


def _check_noise_metric(metric: str, observer: str, key: str, where: str) -> None:
    from torus_cad.acoustics.observers import observer_ranges, parse_observer

    if key not in NOISE_METRICS:
        close = difflib.get_close_matches(key, NOISE_METRICS, n=1, cutoff=0.5)
        hint = f"did you mean {close[0]!r}?" if close else f"known: {', '.join(NOISE_METRICS)}"
        raise ParameterError(
            f"{where} = {shown(metric)}: {key!r} is not a number of an observer's noise; {hint}"
        )
    try:
        parse_observer(observer)
    except ParameterError:
        raise ParameterError(
            f"{where} = {shown(metric)}: the observer {observer!r} is out of range or malformed; "
            f"allowed {observer_ranges()}, e.g. {_NOISE_EXAMPLE}"
        ) from None


def check_metric(metric: str, where: str) -> None:
    """ParameterError naming ``where`` unless ``metric`` is a known report or performance number."""
    noise = _noise_parts(metric)
    if noise is not None:
        _check_noise_metric(metric, *noise, where)
        return
    if metric.startswith(PERFORMANCE_PREFIX + "noise"):
        raise ParameterError(
            f"{where} = {shown(metric)} is not a noise number; name the observer as "
            f"simulate --observer does, e.g. {_NOISE_EXAMPLE} (keys: {', '.join(NOISE_METRICS)})"
        )
    known = (
        [PERFORMANCE_PREFIX + key for key in PERFORMANCE_METRICS]
        if is_performance(metric)
        else list(REPORT_METRICS)
    )
    if metric in known:
        return
    close = difflib.get_close_matches(
        metric,
        known + [PERFORMANCE_PREFIX + k for k in PERFORMANCE_METRICS] + list(REPORT_METRICS),
        n=1,
        cutoff=0.5,
    )
    hint = (
        f"; did you mean {close[0]!r}?"
        if close
        else f"; known: {', '.join(REPORT_METRICS)}, performance.*"
    )
    raise ParameterError(
        f"{where} = {shown(metric)} is not a number of the build report nor performance.*{hint}"
    )


def metric_value(
    metric: str, report: Mapping[str, Any], performance: Mapping[str, Any] | None
) -> float:
    """The finite number ``metric`` names in ``report`` (or ``performance`` for ``performance.*``).

    Raises KeyError naming the metric when it is absent, not a number or not finite.
    """
    noise = _noise_parts(metric)
    if noise is not None:
        return _noise_value(metric, *noise, performance)
    source: Any = performance if is_performance(metric) else report
    parts = (
        metric.removeprefix(PERFORMANCE_PREFIX).split(".")
        if is_performance(metric)
        else metric.split(".")
    )
    for part in parts:
        source = source.get(part) if isinstance(source, Mapping) else None
    if isinstance(source, bool):
        return 1.0 if source else 0.0
    if not isinstance(source, (int, float)) or not math.isfinite(source):
        raise KeyError(f"{metric} is not a finite number in the report (got {source!r})")
    return float(source)


def _noise_value(
    metric: str, observer: str, key: str, performance: Mapping[str, Any] | None
) -> float:
    """The ``key`` of the entry of ``performance["noise"]["observers"]`` at the observer
    ``DIST_M:ANGLE_DEG``."""
    from torus_cad.acoustics.observers import parse_observer

    wanted = parse_observer(observer)
    noise = performance.get("noise") if isinstance(performance, Mapping) else None
    entries = noise.get("observers") if isinstance(noise, Mapping) else None
    for entry in entries if isinstance(entries, list) else []:
        if not isinstance(entry, Mapping):
            continue
        distance, angle = entry.get("distance_m"), entry.get("angle_deg")
        if (
            isinstance(distance, (int, float))
            and isinstance(angle, (int, float))
            and math.isclose(distance, wanted.distance_m)
            and math.isclose(angle, wanted.angle_deg, abs_tol=1e-9)
        ):
            value = entry.get(key)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not math.isfinite(value)
            ):
                raise KeyError(f"{metric} is not a finite number in the report (got {value!r})")
            return float(value)
    raise KeyError(f"{metric}: the performance report has no noise at the observer {observer}")
