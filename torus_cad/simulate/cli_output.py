"""What ``torus-cad simulate`` prints: a progress line during the run, the numbers at the end."""

from __future__ import annotations

import sys
from typing import Any, TextIO

from torus_cad.runtime.progress import is_terminal
from torus_cad.simulate.coefficients import SPREAD_SAFETY_FACTOR
from torus_cad.simulate.pipeline import Result
from torus_cad.simulate.run import Status


class IterationLine:
    """One line on a terminal (stderr), rewritten at each iteration: iteration, residuals, thrust,
    torque."""

    def __init__(self, enabled: bool, stream: TextIO | None = None) -> None:
        self.enabled, self.stream = enabled, stream if stream is not None else sys.stderr
        self._open = False

    @classmethod
    def for_terminal(cls, quiet: bool = False) -> IterationLine:
        return cls(not quiet and is_terminal(sys.stderr))

    def __call__(self, status: Status) -> None:
        if not self.enabled:
            return
        self.stream.write("\r\x1b[K" + status_text(status))
        self.stream.flush()
        self._open = True

    def close(self) -> None:
        if self._open:
            self.stream.write("\n")
            self.stream.flush()
            self._open = False


def status_text(status: Status) -> str:
    """``simpleFoam 120/300  Ux 2.1e-03 ... | force z 0.512 N, moment z 1.23 N mm``"""
    residuals = " ".join(f"{name} {value:.1e}" for name, value in status.residuals.items())
    return (
        f"simpleFoam {status.iteration}/{status.total}  "
        f"{residuals} | force z {status.force_n[2]:.4g} N, "
        f"moment z {status.moment_nm[2] * 1000:.4g} N mm"
    )


def _number(value: float | None, digits: int = 4) -> str:
    return "-" if value is None else f"{value:.{digits}g}"


def _percent(fraction: float | None, digits: int = 2) -> str:
    return "-" if fraction is None else f"{100.0 * fraction:.{digits}g} %"


#: What the terminal shows of each force: its name, its factor from the report's SI unit, its unit.
#: Torque is in N mm on the terminal everywhere (the progress line, the plot), N m in the reports.
_SHOWN = {"thrust_n": ("thrust", 1.0, "N"), "torque_nm": ("torque", 1000.0, "N mm")}


def summary_lines(result: Result, convergence: bool = False) -> list[str]:
    """The paths written and the designer's numbers (torque in N mm, variations in percent)."""
    lines = [f"wrote {path}" for path in result.paths.values()]
    report = result.report
    if convergence:
        return (
            lines
            + convergence_lines(report)
            + [
                f"warning: {level} level: {flag}"
                for level, values in report.get("levels", {}).items()
                for flag in values.get("validity") or []
            ]
        )
    if "step" in report:
        step = report["step"]
        lines.append(
            f"STEP {step['file']}: axis {step['axis']}, turning {step['turning']}; tip diameter "
            f"{step['tip_diameter_mm']:.2f} mm, hub radius "
            f"{step['hub_radius_mm']:.2f} mm, hub length "
            f"{step['hub_length_mm']:.2f} mm"
        )
    if "thrust_n" not in report:  # --case-only
        cells = f"{report['cells']:,} cells" if report.get("cells") else "meshed by Allrun"
        lines.append(f"case written ({cells}, level {report['level']}); run it with its Allrun")
        return lines + warning_lines(report)
    if "thrust_search" in report:
        lines += thrust_search_lines(report["thrust_search"])
    variation = report["force_variation_last_10_percent"]
    state = "converged" if report["converged"] else "NOT converged"
    merit = (
        f"efficiency {_number(report['efficiency'], 3)}"
        if report["efficiency"] is not None
        else f"figure of merit {_number(report['figure_of_merit'], 3)}"
    )
    lines.append(
        f"thrust {report['thrust_n']:.4g} N, torque {report['torque_nm'] * 1000.0:.4g} N mm, power "
        f"{report['power_w']:.4g} W at {report['rpm']:g} rpm, {report['airspeed_m_s']:g} m/s (J "
        f"{_number(report['advance_ratio'], 3)}): CT "
        f"{_number(report['ct'])}, CP {_number(report['cp'])}, {merit}"
    )
    lines.append(
        f"{state}: thrust varies {_percent(variation['thrust'])}, "
        f"torque {_percent(variation['torque'])} "
        f"over the last 10 % of {report['iterations']} iterations; {report['cells']:,} "
        f"cells, level {report['level']}, {report['wall_seconds']:.0f} s; {report['fluid']['name']}"
    )
    y_plus = report.get("y_plus")
    if y_plus:
        mesh = report["mesh"]
        sizing = f"first layer sized for y+ {mesh.get('y_plus_target', '-')}"
        wanted, first = mesh.get("first_layer_for_y_plus_target_m"), mesh.get("first_layer_m")
        if wanted and first and first > wanted * 1.0001:
            sizing = (
                f"first layer {first * 1e6:.3g} um, raised from the {wanted * 1e6:.3g} um of y+ "
                f"{mesh['y_plus_target']} so that the layers meet the surface cells"
            )
        lines.append(
            f"y+ on the propeller: min {y_plus['min']:.3g}, "
            f"mean {y_plus['mean']:.3g}, max {y_plus['max']:.3g} "
            f"({report['mesher']} mesh, {sizing})"
        )
    viscous = report.get("viscous")
    if viscous and viscous["torque_share"] is not None and viscous["thrust_share"] is not None:
        lines.append(
            f"wall shear: {_percent(viscous['torque_share'])} of the torque, "
            f"{_percent(viscous['thrust_share'])} of the thrust (the rest is pressure)"
        )
    if report.get("noise"):
        lines.append(noise_line(report["noise"]))
    return lines + warning_lines(report)


def warning_lines(report: dict[str, Any]) -> list[str]:
    """``warning: ...`` for each of the report's ``validity`` flags
    (torus_cad.simulate.validity)."""
    return [f"warning: {flag}" for flag in report.get("validity") or []]


def _level(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def noise_line(noise: dict[str, Any]) -> str:
    """``tonal noise (BPF 500 Hz): 1 m 0 deg silent (no tonal noise); 1 m 90 deg 61.2 dB ...``: each
    observer's overall SPL and dB(A), or that it hears no tone (a steady rotor on its axis)."""
    heard = "; ".join(
        f"{entry['distance_m']:g} m {entry['angle_deg']:g} deg "
        + (
            "silent (no tonal noise)"
            if entry.get("silent")
            else f"{_level(entry['oaspl_db'])} dB ({_level(entry['oaspl_dba'])} dB(A))"
        )
        for entry in noise["observers"]
    )
    passing = (
        f"BPF {noise['blade_passing_frequency_hz']:.4g} Hz"
        if noise.get("blades")
        else f"rotation {noise['rotation_hz']:.4g} Hz"
    )
    return f"tonal noise ({passing}, steady loading and thickness, FW-H): {heard}"


def thrust_search_lines(search: dict[str, Any]) -> list[str]:
    """``--thrust``: every run, then the rpm found (or the closest run, when none was within the
    tolerance)."""
    runs = "; ".join(f"{run['rpm']:.0f} rpm {run['thrust_n']:.4g} N" for run in search["runs"])
    verdict = (
        f"within {_percent(search['tolerance'])}"
        if search["within_tolerance"]
        else (
            f"NOT within {_percent(search['tolerance'])} after "
            f"{len(search['runs'])} runs: the closest run"
        )
    )
    return [
        f"thrust search, {len(search['runs'])} runs on one mesh: {runs}",
        f"rpm for {search['target_thrust_n']:.4g} N: "
        f"{search['rpm']:.0f} rpm ({search['thrust_n']:.4g} N, "
        f"{verdict})",
    ]


def _spread_bound(entry: dict[str, Any]) -> str:
    """The uncertainty a study without a GCI still has: a multiple of the levels' spread (empty if
    unknown)."""
    if entry.get("uncertainty_fine") is None or entry.get("spread") is None:
        return ""
    return (
        "; uncertainty of the fine value "
        f"{_percent(entry['uncertainty_fine'])} (the levels spread over "
        f"{_percent(entry['spread'])} of it; "
        f"{SPREAD_SAFETY_FACTOR:g} times that bounds the error without an "
        "observed order)"
    )


def convergence_lines(report: dict[str, Any]) -> list[str]:
    """The convergence study: each force on the three levels, Richardson's extrapolation, the
    observed order and Roache's grid convergence index (or why there is none)."""
    lines = []
    for key, (label, factor, unit) in _SHOWN.items():
        entry = report[key]
        levels = ", ".join(
            f"{level} {_number(values[key] * factor)}" for level, values in report["levels"].items()
        )
        if entry["converges_monotonically"]:
            asymptotic = (
                "in the asymptotic range"
                if entry.get("in_asymptotic_range")
                else "NOT in the asymptotic range"
            )
            lines.append(
                f"{label}: {levels} {unit}; Richardson "
                f"{_number(entry['extrapolated'] * factor)} {unit}, "
                f"observed order {_number(entry['observed_order'], 3)}; GCI fine "
                f"{_percent(entry.get('gci_fine'))}, medium {_percent(entry.get('gci_medium'))}, "
                "GCI_medium / (r^p GCI_fine) "
                f"{_number(entry.get('gci_asymptotic_ratio'), 3)} ({asymptotic})"
            )
        else:
            lines.append(
                f"{label}: {levels} {unit}; no Richardson "
                "extrapolation and no grid convergence index: the "
                "levels do not converge monotonically (the "
                "change from medium to fine is not smaller than "
                "from coarse to medium), so they are not in the asymptotic range"
                + _spread_bound(entry)
            )
    return lines
