"""The noise entry of a simulation's report, its pressure signals (CSV) and its picture
(directivity, spectrum, signal over one revolution)."""

from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from torus_cad.acoustics.fwh import Medium, ObserverSignal, RotatingSurface, observer_signal
from torus_cad.acoustics.observers import Observer
from torus_cad.acoustics.spectrum import REFERENCE_PRESSURE_PA, harmonic_rms, overall_db, spl_db

if TYPE_CHECKING:
    from matplotlib.projections.polar import PolarAxes

#: Blade-passing harmonics listed per observer.
HARMONICS = 10
#: Fewest samples per revolution; more when 4 per period of the highest listed harmonic need more
#: (the levels of the harmonics above fall by tens of dB each, so what folds back below the Nyquist
#: frequency is negligible).
MIN_SAMPLES = 64
#: The picture shows levels down to this far below its loudest (lower ones, such as the round-off of
#: the axis, where a steady rotor makes no tone, at this floor).
PICTURE_RANGE_DB = 60.0
#: The picture's directivity: observers every this many degrees from 0 to 180 at the first
#: observer's distance.
DIRECTIVITY_STEP_DEG = 15.0
METHOD = (
    "Ffowcs Williams-Hawkings, Farassat formulation 1A, "
    "impermeable rotating blade surface (each face of "
    "the propeller patch a source on its circle), steady "
    "pressure loading of the frozen-rotor solution "
    "(viscous stress left out), medium at rest relative "
    "to the hub; tones only: no broadband, tip-vortex or "
    "unsteady-loading noise"
)


def samples_per_revolution(blades: int, harmonics: int = HARMONICS) -> int:
    """A power of two, at least MIN_SAMPLES and 4 samples per period of harmonic ``harmonics`` x
    ``blades``."""
    return max(MIN_SAMPLES, 1 << math.ceil(math.log2(4 * harmonics * blades)))


@dataclass(frozen=True)
class Noise:
    """The report entry (``report``), each observer's signal, and the directivity sweep (angle deg,
    OASPL dB, dB(A)) at the first observer's distance."""

    report: dict[str, Any]
    observers: tuple[Observer, ...]
    signals: tuple[ObserverSignal, ...]
    directivity: tuple[tuple[float, float, float], ...]


#: A level below this (dB re 20 uPa, 2e-14 Pa) is the round-off of a sound that cancels (a steady
#: rotor's tones on its axis come out near -260 dB; a weak high harmonic off the axis is a real -150
#: dB): reported as silent (None), not as a level.
SILENT_BELOW_DB = -200.0


def _level_db(value: float) -> float | None:
    """``value`` (dB) if it is a level; None for silence (-inf) and for round-off below
    SILENT_BELOW_DB."""
    return float(value) if math.isfinite(value) and value > SILENT_BELOW_DB else None


def _overall(rms: np.ndarray, blades: int, rotation_hz: float) -> tuple[float, float, float]:
    """(OASPL dB, dB(A)) of the blade-passing harmonics among the rotation harmonics ``rms`` (Pa;
    index 0 the first), and the overall SPL dB of the others."""
    frequency = rotation_hz * np.arange(1, len(rms) + 1)
    passing = np.arange(1, len(rms) + 1) % blades == 0
    return (
        overall_db(rms[passing]),
        overall_db(rms[passing], frequency[passing]),
        overall_db(rms[~passing]),
    )


def _levels(
    signal: ObserverSignal, blades: int, rotation_hz: float, harmonics: int
) -> dict[str, Any]:
    total, thickness, loading = (
        harmonic_rms(part) for part in (signal.total_pa, signal.thickness_pa, signal.loading_pa)
    )
    frequency = rotation_hz * np.arange(1, len(total) + 1)
    oaspl, oaspl_a, others = _overall(total, blades, rotation_hz)
    listed = []
    for m in range(1, harmonics + 1):
        k = m * blades - 1
        if k >= len(total):
            break
        listed.append(
            {
                "harmonic": m,
                "frequency_hz": float(frequency[k]),
                "spl_db": _level_db(float(spl_db(total[k]))),
                "thickness_spl_db": _level_db(float(spl_db(thickness[k]))),
                "loading_spl_db": _level_db(float(spl_db(loading[k]))),
            }
        )
    return {
        "oaspl_db": _level_db(oaspl),
        "oaspl_dba": _level_db(oaspl_a),
        "silent": _level_db(oaspl) is None,
        "other_harmonics_spl_db": _level_db(others),
        "peak_to_peak_pa": float(np.ptp(signal.total_pa)),
        "harmonics": listed,
    }


def evaluate_noise(
    surface: RotatingSurface,
    omega_rad_s: float,
    blades: int,
    medium: Medium,
    observers: tuple[Observer, ...],
    harmonics: int = HARMONICS,
    directivity: bool = True,
) -> Noise:
    """The tonal noise of ``surface`` (``blades`` blades, turning at ``omega_rad_s`` about +z) at
    ``observers``."""
    start = time.perf_counter()
    samples = samples_per_revolution(blades, harmonics)
    rotation_hz = abs(omega_rad_s) / (2.0 * math.pi)
    computed: dict[Observer, ObserverSignal] = {}

    def signal_at(observer: Observer) -> ObserverSignal:
        if observer not in computed:
            computed[observer] = observer_signal(
                surface, omega_rad_s, observer.position_m, medium, samples
            )
        return computed[observer]

    signals = tuple(signal_at(observer) for observer in observers)
    entries = [
        {**observer.to_dict(), **_levels(signal, blades, rotation_hz, harmonics)}
        for observer, signal in zip(observers, signals)
    ]
    sweep: list[tuple[float, float, float]] = []
    if directivity and observers:
        distance = observers[0].distance_m
        for angle in np.arange(0.0, 180.0 + 0.5 * DIRECTIVITY_STEP_DEG, DIRECTIVITY_STEP_DEG):
            rms = harmonic_rms(signal_at(Observer(distance, float(angle))).total_pa)
            sweep.append((float(angle), *_overall(rms, blades, rotation_hz)[:2]))
    force = surface.pressure_force_n
    report = {
        "method": METHOD,
        "blades": blades,
        "rotation_hz": rotation_hz,
        "blade_passing_frequency_hz": blades * rotation_hz,
        "samples_per_revolution": samples,
        "faces": surface.face_count,
        "density_kg_m3": medium.density_kg_m3,
        "speed_of_sound_m_s": medium.speed_of_sound_m_s,
        "reference_pressure_pa": REFERENCE_PRESSURE_PA,
        "surface_pressure_thrust_n": float(force[2]),
        "conventions": "observer angle from +z (the thrust's "
        "direction, ahead of the propeller; 90 = the rotor "
        "plane) in the plane x-z, distance from the hub; "
        "SPL dB re 20 uPa of the rms pressure of each "
        "blade-passing harmonic; oaspl_db sums every blade-passing harmonic the samples resolve, "
        "oaspl_dba weights each by IEC 61672-1 A-weighting; other_harmonics_spl_db sums the other "
        "harmonics of the rotation frequency (the blades' loads differ: for identical blades, the "
        "mesh's asymmetry)",
        "observers": entries,
        "seconds": time.perf_counter() - start,
    }
    return Noise(report, tuple(observers), signals, tuple(sweep))


def write_noise_csv(noise: Noise, path: Path) -> Path:
    """The acoustic pressure (Pa) at each observer over one revolution: time_s, then one column per
    observer."""
    with path.open("w", newline="", encoding="utf-8") as stream:
        writer = csv.writer(stream)
        writer.writerow(
            ["time_s"] + [f"p_pa_{o.distance_m:g}m_{o.angle_deg:g}deg" for o in noise.observers]
        )
        for row, time_s in enumerate(noise.signals[0].time_s if noise.signals else []):
            writer.writerow(
                [f"{time_s:.9g}"] + [f"{signal.total_pa[row]:.9g}" for signal in noise.signals]
            )
    return path


def write_noise_plot(noise: Noise, path: Path, title: str) -> Path:
    """The picture (matplotlib, Agg): directivity (OASPL and dB(A) against the angle from the axis),
    SPL per blade-passing harmonic at each observer (both down to PICTURE_RANGE_DB below the
    loudest), and the signal over one revolution (less its mean: the steady near field of the
    thrust)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    levels = [row[1] for row in noise.directivity] + [
        row["spl_db"]
        for entry in noise.report["observers"]
        for row in entry["harmonics"]
        if row["spl_db"] is not None
    ]
    floor = max((level for level in levels if math.isfinite(level)), default=0.0) - PICTURE_RANGE_DB

    def shown(values: list[float | None]) -> np.ndarray:
        return np.array(
            [floor if value is None or not value > floor else value for value in values]
        )

    figure = plt.figure(figsize=(12, 8))
    try:
        polar = cast("PolarAxes", figure.add_subplot(2, 2, 1, projection="polar"))
        if noise.directivity:
            angles = np.radians([row[0] for row in noise.directivity])
            polar.plot(
                angles, shown([row[1] for row in noise.directivity]), label="overall SPL, dB"
            )
            polar.plot(angles, shown([row[2] for row in noise.directivity]), label="dB(A)")
            polar.set_rorigin(floor - 0.1 * PICTURE_RANGE_DB)
            polar.set_rmin(floor)
            polar.set_thetamin(0.0)
            polar.set_thetamax(180.0)
            polar.set_theta_zero_location("N")
            polar.set_theta_direction(-1)
            polar.legend(loc="lower left", fontsize="small")
        distance = noise.observers[0].distance_m if noise.observers else 1.0
        polar.set_title(
            f"directivity at {distance:g} m (0 deg = +z, ahead; floor {floor:.0f} dB)",
            fontsize="medium",
        )
        spectrum = figure.add_subplot(2, 2, 2)
        width = 0.8 / max(1, len(noise.observers))
        for index, entry in enumerate(noise.report["observers"]):
            harmonics = [row["harmonic"] for row in entry["harmonics"]]
            heights = shown([row["spl_db"] for row in entry["harmonics"]]) - floor
            spectrum.bar(
                np.array(harmonics) + (index - (len(noise.observers) - 1) / 2) * width,
                heights,
                width,
                bottom=floor,
                label=f"{entry['distance_m']:g} m, {entry['angle_deg']:g} deg",
            )
        spectrum.set_xlabel(
            "harmonic of the blade-passing frequency "
            f"({noise.report['blade_passing_frequency_hz']:.4g} Hz)"
        )
        spectrum.set_ylabel("SPL, dB re 20 uPa")
        spectrum.grid(True, alpha=0.3)
        spectrum.legend(fontsize="small")
        signal_axes = figure.add_subplot(2, 1, 2)
        for observer, signal in zip(noise.observers, noise.signals):
            signal_axes.plot(
                signal.time_s * 1000.0,
                signal.total_pa - np.mean(signal.total_pa),
                label=f"{observer.distance_m:g} m, {observer.angle_deg:g} deg",
            )
        signal_axes.set_xlabel("observer time over one revolution, ms")
        signal_axes.set_ylabel("acoustic pressure less its mean, Pa")
        signal_axes.grid(True, alpha=0.3)
        signal_axes.legend(fontsize="small")
        figure.suptitle(title)
        figure.tight_layout()
        figure.savefig(path, dpi=100)
    finally:
        plt.close(figure)
    return path
