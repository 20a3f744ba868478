"""The numbers a study can optimise or constrain: those of the build's JSON report, and ``performance.*``.

A metric is a dotted key of the report that ``torus-cad build`` writes (``mass_g``,
``printability.thinnest_wall_mm``, ``balance.static_imbalance_g_mm``), or ``performance.<key>``,
a number of the ``<name>_performance.json`` that ``torus-cad simulate`` writes (thrust in N,
torque in N m, power in W, the dimensionless coefficients). Units are the report's: mm, mm^2,
mm^3, g, g mm^2, s.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from typing import Any

from torus_cad.errors import ParameterError, shown

__all__ = ["PERFORMANCE_METRICS", "PERFORMANCE_PREFIX", "REPORT_METRICS", "check_metric", "is_performance",
           "metric_value"]

#: Numbers every build report holds (dotted keys; ``printability.printable`` is 1 or 0).
REPORT_METRICS = (
    "volume_mm3", "surface_area_mm2", "mass_g", "density_g_cm3", "spin_axis_inertia_g_mm2", "spin_axis_inertia_mm5",
    "section_fit_error_mm",
    "balance.static_imbalance_g_mm", "balance.centroid_offset_mm", "balance.products_of_inertia_g_mm2.xz",
    "balance.products_of_inertia_g_mm2.yz", "balance.products_of_inertia_g_mm2.xy",
    "printability.thinnest_wall_mm", "printability.thinnest_wall_s", "printability.thinnest_wall_chord_fraction",
    "printability.trailing_edge_thickness_mm", "printability.trailing_edge_thinnest_s", "printability.min_wall_mm",
    "printability.printable",
)

PERFORMANCE_PREFIX = "performance."

#: Numbers of ``torus-cad simulate``'s performance report (N, N m, W; ct, cp, efficiency and figure of merit
#: dimensionless; ``converged`` is 1 or 0).
PERFORMANCE_METRICS = ("thrust_n", "torque_nm", "power_w", "ct", "cp", "efficiency", "figure_of_merit", "converged")


def is_performance(metric: str) -> bool:
    """Whether ``metric`` needs ``torus-cad simulate`` (a ``performance.*`` key)."""
    return metric.startswith(PERFORMANCE_PREFIX)


def check_metric(metric: str, where: str) -> None:
    """ParameterError naming ``where`` unless ``metric`` is a known report or performance number."""
    known = [PERFORMANCE_PREFIX + key for key in PERFORMANCE_METRICS] if is_performance(metric) else list(REPORT_METRICS)
    if metric in known:
        return
    close = difflib.get_close_matches(metric, known + [PERFORMANCE_PREFIX + k for k in PERFORMANCE_METRICS]
                                      + list(REPORT_METRICS), n=1, cutoff=0.5)
    hint = f"; did you mean {close[0]!r}?" if close else f"; known: {', '.join(REPORT_METRICS)}, performance.*"
    raise ParameterError(f"{where} = {shown(metric)} is not a number of the build report nor performance.*{hint}")


def metric_value(metric: str, report: Mapping[str, Any], performance: Mapping[str, Any] | None) -> float:
    """The finite number ``metric`` names in ``report`` (or ``performance`` for ``performance.*``).

    Raises KeyError naming the metric when it is absent, not a number or not finite.
    """
    source: Any = performance if is_performance(metric) else report
    parts = metric.removeprefix(PERFORMANCE_PREFIX).split(".") if is_performance(metric) else metric.split(".")
    for part in parts:
        source = source.get(part) if isinstance(source, Mapping) else None
    if isinstance(source, bool):
        return 1.0 if source else 0.0
    if not isinstance(source, (int, float)) or not math.isfinite(source):
        raise KeyError(f"{metric} is not a finite number in the report (got {source!r})")
    return float(source)
