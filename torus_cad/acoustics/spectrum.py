"""Levels of a periodic signal: SPL per harmonic, overall SPL and A-weighted level (dB re 20 uPa).

A signal sampled uniformly over one period T has harmonics at k / T (k = 1, 2, ...); the rms
pressure of harmonic k is sqrt(2) |X_k| / S, with X the discrete Fourier transform of the S samples.
The overall SPL sums the squares of every harmonic the samples resolve (below the Nyquist
frequency); the A-weighted level weights each harmonic by A(f) of IEC 61672-1 (closed form, A(1
kHz) = 0 dB).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

#: Reference pressure of sound pressure levels in air, Pa.
REFERENCE_PRESSURE_PA = 20e-6
#: IEC 61672-1 pole frequencies of the A-weighting, Hz, and its normalisation (A(1000 Hz) = 0 dB).
_F1, _F2, _F3, _F4 = 20.598997, 107.65265, 737.86223, 12194.217
_A_1000_DB = 2.0


def harmonic_rms(signal_pa: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rms pressure (Pa) of harmonics 1 .. S/2 - 1 of a signal sampled at S uniform times over
    one period (index 0 is harmonic 1)."""
    samples = len(signal_pa)
    spectrum = np.fft.rfft(signal_pa) / samples
    return np.asarray(math.sqrt(2.0) * np.abs(spectrum[1 : (samples + 1) // 2]))


def spl_db(rms_pa: float | NDArray[np.float64]) -> NDArray[np.float64]:
    """Sound pressure level, dB re 20 uPa, of rms pressures in Pa (-inf for 0)."""
    with np.errstate(divide="ignore"):
        return np.asarray(20.0 * np.log10(np.asarray(rms_pa, dtype=float) / REFERENCE_PRESSURE_PA))


def a_weighting_db(frequency_hz: float | NDArray[np.float64]) -> NDArray[np.float64]:
    """A-weighting in dB at ``frequency_hz`` (> 0), IEC 61672-1 closed form."""
    f2 = np.asarray(frequency_hz, dtype=float) ** 2
    gain = (_F4**2 * f2**2) / (
        (f2 + _F1**2) * np.sqrt((f2 + _F2**2) * (f2 + _F3**2)) * (f2 + _F4**2)
    )
    return np.asarray(20.0 * np.log10(gain) + _A_1000_DB)


def overall_db(
    rms_pa: NDArray[np.float64], frequency_hz: NDArray[np.float64] | None = None
) -> float:
    """Overall SPL (dB) of harmonics of rms pressures ``rms_pa``; A-weighted (dB(A)) when their
    frequencies (Hz) are given. -inf when all are 0."""
    energy = np.asarray(rms_pa, dtype=float) ** 2
    if frequency_hz is not None:
        energy = energy * 10.0 ** (a_weighting_db(frequency_hz) / 10.0)
    total = float(np.sum(energy))
    return 10.0 * math.log10(total / REFERENCE_PRESSURE_PA**2) if total > 0.0 else -math.inf
