"""Monte Carlo function-space study of spec §2.4–§2.5 (which transform family to use).

The spec picks quartic polynomials for the angle of attack and the two scale factors of
§2.1–§2.2 on the strength of a Monte Carlo study: random functions are drawn from four
generators (§2.4.2), each is fitted by five candidate families (§2.4.3) by least squares
(§2.4.4), and the mean error per family is reported in Table 1 (§2.5).  This module
re-runs that study, seeded, and lets the open details be varied.

What the spec leaves open, and what this module does by default (each one is a field of
:class:`StudyConfig`):

* ``points`` – the number n of sample points, default 100, on an evenly spaced grid over
  [0, 1] (``numpy.linspace(0, 1, n)``), shared by all samples.
* ``generator_draw`` – ``"random"`` (default): each sample's generator is drawn uniformly
  among the four, as in the original code; ``"balanced"``: sample i uses generator i mod 4.
* ``knot_placement`` – where the 3–8 knots of the piecewise-linear generator sit:
  ``"even"`` (default): evenly spaced over [0, 1] including both ends (the "down-sampled"
  reading of §2.4.2); ``"random"``: sorted U(0, 1) positions, held constant outside the
  outermost knots (the literal "uniformly sampled" reading).
* ``sinusoid_start`` – the start of the nonlinear fit of A sin(Bs + C) + D:
  ``"fft"`` (default): a handful of trial frequencies around the peak of the FFT plus three
  low ones (0.25, 0.5, 0.75 cycles), each scored by solving for A, C, D linearly, and the
  best one started from; ``"ones"``: A = B = C = D = 1, the start of the spec author's code.
* ``sinusoid_max_evaluations`` – the Levenberg–Marquardt budget per sinusoid fit; fits that
  stop on it (or end non-finite) are counted as not converged.

Two errors are computed for every fit (docs/function_space_study.md explains why both):

* ``mse`` – the mean squared error that §2.4.4 defines, (1/n) Σ (y_i − f(s_i))²;
* ``range_normalised_sse`` – Σ ((y_i − f(s_i)) / (max y − min y))², the quantity the
  spec's Table 1 actually averages.

The four linear candidates are fitted exactly, all N samples in one batched
``numpy.linalg.lstsq`` call per candidate (the samples share one grid, hence one design
matrix); the sinusoid is fitted per sample with ``scipy.optimize.least_squares``
(``method="lm"``, analytic Jacobian).
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from torus_cad.errors import ParameterError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

SinusoidStart = Literal["fft", "ones"]
GeneratorDraw = Literal["random", "balanced"]
KnotPlacement = Literal["even", "random"]

#: Generator names, in the order of spec §2.4.2.
GENERATOR_NAMES: Final[tuple[str, ...]] = ("sinusoid", "polynomial", "logistic", "piecewise_linear")

SINUSOID_STARTS: Final[tuple[str, ...]] = ("fft", "ones")
GENERATOR_DRAWS: Final[tuple[str, ...]] = ("random", "balanced")
KNOT_PLACEMENTS: Final[tuple[str, ...]] = ("even", "random")

#: Smallest number of sample points: one more than the largest candidate's parameter count (7).
MIN_POINTS: Final[int] = 8
#: Largest accepted values, to keep a typo from asking for hours of work or gigabytes of memory.
MAX_SAMPLES: Final[int] = 10_000_000
MAX_POINTS: Final[int] = 100_000
MAX_SINUSOID_EVALUATIONS: Final[int] = 1_000_000

#: Errors below this value are drawn at this value on the log-scale figure (exact fits give ~1e-30).
PLOT_ERROR_FLOOR: Final[float] = 1e-12


@dataclass(frozen=True)
class Candidate:
    """One candidate family of spec §2.4.3."""

    name: str
    """Short identifier used in tables, CSV and JSON."""
    label: str
    """Name as printed in the spec's Table 1."""
    parameter_names: tuple[str, ...]
    """Names of the fitted parameters, in the order they are stored."""
    is_linear: bool
    """True when the family is linear in its parameters (fitted exactly by linear least squares)."""
    spec_table_value: float
    """The value the spec's Table 1 gives for this family."""

    @property
    def parameter_count(self) -> int:
        """Number of free parameters."""
        return len(self.parameter_names)


#: The five candidates of spec §2.4.3 with the spec's Table 1 values.
CANDIDATES: Final[tuple[Candidate, ...]] = (
    Candidate("poly4", "4th-Degree Polynomial", tuple(f"a{i}" for i in range(5)), True, 2.064),
    Candidate("poly6", "6th-Degree Polynomial", tuple(f"a{i}" for i in range(7)), True, 0.845),
    Candidate("fourier2", "Fourier Series (Order 2)", ("A0", "A1", "B1", "A2", "B2"), True, 2.441),
    Candidate(
        "fourier3",
        "Fourier Series (Order 3)",
        ("A0", "A1", "B1", "A2", "B2", "A3", "B3"),
        True,
        1.193,
    ),
    Candidate("sinusoid", "Sinusoidal Function", ("A", "B", "C", "D"), False, 5.748),
)
CANDIDATE_NAMES: Final[tuple[str, ...]] = tuple(candidate.name for candidate in CANDIDATES)
_CANDIDATE_BY_NAME: Final[dict[str, Candidate]] = {
    candidate.name: candidate for candidate in CANDIDATES
}


def candidate_by_name(name: str) -> Candidate:
    """Return the candidate called ``name`` (one of :data:`CANDIDATE_NAMES`)."""
    try:
        return _CANDIDATE_BY_NAME[name]
    except KeyError:
        raise ParameterError(
            f"candidate = {name!r} is unknown; allowed: {', '.join(CANDIDATE_NAMES)}"
        ) from None


# --------------------------------------------------------------------------------------------
# Configuration
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StudyConfig:
    """Every choice of one study run; :meth:`validate` checks it and raises
    :class:`ParameterError`."""

    samples: int = 10_000
    """N, the number of random functions."""
    points: int = 100
    """n, the number of evenly spaced sample points on [0, 1]."""
    seed: int = 0
    """Seed of ``numpy.random.default_rng``; the same config gives the same result."""
    sinusoid_start: SinusoidStart = "fft"
    """Start of the sinusoid fit: ``"fft"`` (sound) or ``"ones"`` (the spec author's)."""
    generator_draw: GeneratorDraw = "random"
    """``"random"``: generator uniform per sample; ``"balanced"``: sample i uses
    generator i mod 4."""
    knot_placement: KnotPlacement = "even"
    """Piecewise-linear knots: ``"even"`` over [0, 1] or ``"random"`` sorted U(0, 1) positions."""
    sinusoid_max_evaluations: int = 200
    """Function-evaluation budget of one Levenberg–Marquardt sinusoid fit.

    With the analytic Jacobian one evaluation is about one iteration, so 200 is roughly the
    iteration budget of ``scipy.optimize.curve_fit``'s default (``maxfev = 200 (p + 1)`` calls
    with a finite-difference Jacobian).  The means hardly depend on it; the count of fits
    that did not converge does (see ``docs/function_space_study.md``).
    """

    def validate(self) -> None:
        """Raise :class:`ParameterError` naming the first field that is out of range."""
        _check_int("samples", self.samples, 1, MAX_SAMPLES)
        _check_int("points", self.points, MIN_POINTS, MAX_POINTS)
        _check_int("seed", self.seed, 0, 2**63 - 1)
        _check_choice("sinusoid_start", self.sinusoid_start, SINUSOID_STARTS)
        _check_choice("generator_draw", self.generator_draw, GENERATOR_DRAWS)
        _check_choice("knot_placement", self.knot_placement, KNOT_PLACEMENTS)
        _check_int(
            "sinusoid_max_evaluations", self.sinusoid_max_evaluations, 1, MAX_SINUSOID_EVALUATIONS
        )

    def describe(self) -> str:
        """One line per choice, for printing above the tables."""
        draw = {
            "random": "generator drawn uniformly among the four for each sample",
            "balanced": "generators in turn (sample i uses generator i mod 4)",
        }[self.generator_draw]
        knots = {
            "even": "3-8 knots evenly spaced over [0, 1] (ends included)",
            "random": "3-8 knots at sorted U(0, 1) positions, constant beyond the outer knots",
        }[self.knot_placement]
        start = {
            "fft": (
                "FFT peak frequency +/- a few trial "
                "frequencies, A/C/D solved linearly (sound start)"
            ),
            "ones": "A = B = C = D = 1 (the spec author's start)",
        }[self.sinusoid_start]
        return "\n".join(
            [
                f"samples N = {self.samples}, seed = {self.seed}",
                f"points n = {self.points}, evenly spaced on [0, 1]",
                f"generator draw: {draw}",
                f"piecewise-linear: {knots}",
                (
                    f"sinusoid fit: Levenberg-Marquardt, start = {self.sinusoid_start}: {start}; "
                    f"budget {self.sinusoid_max_evaluations} evaluations"
                ),
            ]
        )


def _check_int(field_name: str, value: object, low: int, high: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ParameterError(f"{field_name} = {value!r} must be an integer in [{low}, {high}]")
    if not low <= int(value) <= high:
        raise ParameterError(
            f"{field_name} = {value} is out of range; allowed: integer in [{low}, {high}]"
        )


def _check_choice(field_name: str, value: object, allowed: Sequence[str]) -> None:
    if value not in allowed:
        raise ParameterError(
            f"{field_name} = {value!r} is not allowed; allowed: {', '.join(allowed)}"
        )


def sample_grid(points: int) -> FloatArray:
    """The evenly spaced grid s of ``points`` values on [0, 1]; shape (n,)."""
    _check_int("points", points, 2, MAX_POINTS)
    return np.linspace(0.0, 1.0, int(points))


# --------------------------------------------------------------------------------------------
# Random function generators (spec §2.4.2)
# --------------------------------------------------------------------------------------------

GeneratorParameters = dict[str, Any]


def random_sinusoid(
    rng: np.random.Generator, s: FloatArray
) -> tuple[FloatArray, GeneratorParameters]:
    """A sin(2π F s + φ), A ~ U(0.5, 2), F ~ U(1, 3), φ ~ U(0, π); values of shape (n,)."""
    amplitude = rng.uniform(0.5, 2.0)
    frequency = rng.uniform(1.0, 3.0)
    phase = rng.uniform(0.0, math.pi)
    values = amplitude * np.sin(2.0 * math.pi * frequency * s + phase)
    return values, {"A": amplitude, "F": frequency, "phi": phase}


def random_polynomial(
    rng: np.random.Generator, s: FloatArray
) -> tuple[FloatArray, GeneratorParameters]:
    """Σ_{i=0}^{d} c_i s^i, d ~ U{1, …, 8}, c_i ~ U(−2, 2); values of shape (n,)."""
    degree = int(rng.integers(1, 9))
    coefficients = rng.uniform(-2.0, 2.0, size=degree + 1)
    values = np.polynomial.polynomial.polyval(s, coefficients)
    return values, {"degree": degree, "c": coefficients.tolist()}


def random_logistic(
    rng: np.random.Generator, s: FloatArray
) -> tuple[FloatArray, GeneratorParameters]:
    """L / (1 + exp(−k (s − s0))), L ~ U(1, 50), k ~ U(8, 100), s0 ~ U(0.1, 0.9); shape (n,)."""
    capacity = rng.uniform(1.0, 50.0)
    growth_rate = rng.uniform(8.0, 100.0)
    midpoint = rng.uniform(0.1, 0.9)
    values = capacity / (1.0 + np.exp(-growth_rate * (s - midpoint)))
    return values, {"L": capacity, "k": growth_rate, "s0": midpoint}


def random_piecewise_linear(
    rng: np.random.Generator, s: FloatArray, knot_placement: KnotPlacement = "even"
) -> tuple[FloatArray, GeneratorParameters]:
    """Linear interpolation through n' ~ U{3, …, 8} knots with values U(−1, 1); shape (n,).

    ``knot_placement="even"`` puts the knots at ``linspace(0, 1, n')``; ``"random"`` at
    sorted U(0, 1) positions, with the function held constant beyond the outer knots.
    """
    _check_choice("knot_placement", knot_placement, KNOT_PLACEMENTS)
    knot_count = int(rng.integers(3, 9))
    if knot_placement == "even":
        knot_positions = np.linspace(0.0, 1.0, knot_count)
    else:
        knot_positions = np.sort(rng.uniform(0.0, 1.0, size=knot_count))
    knot_values = rng.uniform(-1.0, 1.0, size=knot_count)
    values = np.interp(s, knot_positions, knot_values)
    return values, {
        "knots": knot_count,
        "s_i": knot_positions.tolist(),
        "y_i": knot_values.tolist(),
    }


@dataclass(frozen=True)
class RandomFunctionBatch:
    """N random functions sampled on one grid."""

    s: FloatArray
    """The grid, shape (n,)."""
    values: FloatArray
    """The sampled functions, shape (N, n)."""
    generator_index: IntArray
    """Index into :data:`GENERATOR_NAMES` of each sample's generator, shape (N,)."""
    generator_parameters: list[GeneratorParameters]
    """The drawn parameters of each sample, length N."""


def draw_random_functions(config: StudyConfig) -> RandomFunctionBatch:
    """Draw ``config.samples`` random functions on ``config.points`` points, seeded by
    ``config.seed``."""
    config.validate()
    rng = np.random.default_rng(config.seed)
    s = sample_grid(config.points)
    generators: tuple[
        Callable[[np.random.Generator, FloatArray], tuple[FloatArray, GeneratorParameters]], ...
    ] = (
        random_sinusoid,
        random_polynomial,
        random_logistic,
        lambda generator_rng, grid: random_piecewise_linear(
            generator_rng, grid, config.knot_placement
        ),
    )
    values = np.empty((config.samples, config.points))
    generator_index = np.empty(config.samples, dtype=np.int64)
    parameters: list[GeneratorParameters] = []
    for sample in range(config.samples):
        if config.generator_draw == "random":
            index = int(rng.integers(0, len(GENERATOR_NAMES)))
        else:
            index = sample % len(GENERATOR_NAMES)
        values[sample], drawn = generators[index](rng, s)
        generator_index[sample] = index
        parameters.append(drawn)
    return RandomFunctionBatch(
        s=s, values=values, generator_index=generator_index, generator_parameters=parameters
    )


# --------------------------------------------------------------------------------------------
# Candidate fits (spec §2.4.3–§2.4.4)
# --------------------------------------------------------------------------------------------


def design_matrix(candidate: str, s: FloatArray) -> FloatArray:
    """Design matrix of a linear candidate on grid s (shape (n,)); shape (n, p).

    Columns follow ``Candidate.parameter_names``: powers s^0 … s^d for the polynomials,
    1, cos(2πs), sin(2πs), cos(4πs), … for the Fourier series.
    """
    spec = candidate_by_name(candidate)
    s = np.asarray(s, dtype=np.float64)
    if candidate in ("poly4", "poly6"):
        return np.vander(s, spec.parameter_count, increasing=True)
    if candidate in ("fourier2", "fourier3"):
        order = (spec.parameter_count - 1) // 2
        columns = [np.ones_like(s)]
        for k in range(1, order + 1):
            columns += [np.cos(2.0 * math.pi * k * s), np.sin(2.0 * math.pi * k * s)]
        return np.column_stack(columns)
    raise ParameterError(
        f"candidate = {candidate!r} is not linear; allowed: poly4, poly6, fourier2, fourier3"
    )


def fit_linear_candidate(
    candidate: str, s: FloatArray, values: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Least-squares fit of a linear candidate to all samples in one batched ``lstsq`` call.

    ``s`` has shape (n,), ``values`` shape (N, n).  Returns ``(coefficients, residuals)``
    with shapes (N, p) and (N, n), residual = y − f(s).
    """
    values = np.atleast_2d(np.asarray(values, dtype=np.float64))
    design = design_matrix(candidate, s)
    coefficients, *_ = np.linalg.lstsq(design, values.T, rcond=None)
    residuals = values - (design @ coefficients).T
    return coefficients.T, residuals


def sinusoid_values(parameters: FloatArray, s: FloatArray) -> FloatArray:
    """A sin(B s + C) + D for parameters of shape (..., 4) on s of shape (n,); shape (..., n)."""
    parameters = np.asarray(parameters, dtype=np.float64)
    a, b, c, d = (parameters[..., i, None] for i in range(4))
    return a * np.sin(b * s + c) + d


def _sinusoid_linear_solve(
    s: FloatArray, values: FloatArray, angular_frequency: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """For fixed B per sample, solve A, C, D by linear least squares.

    ``values`` (N, n), ``angular_frequency`` (N, K) trial values of B.  Returns parameters
    (N, K, 4) and the sum of squared residuals (N, K).
    """
    phase = angular_frequency[..., None] * s  # (N, K, n)
    basis = np.stack([np.sin(phase), np.cos(phase), np.ones_like(phase)], axis=-1)  # (N, K, n, 3)
    coefficients = np.einsum("nkij,nj->nki", np.linalg.pinv(basis), values)  # (N, K, 3)
    residuals = values[:, None, :] - np.einsum("nkij,nkj->nki", basis, coefficients)
    sse = np.einsum("nki,nki->nk", residuals, residuals)
    sin_weight, cos_weight, offset = (
        coefficients[..., 0],
        coefficients[..., 1],
        coefficients[..., 2],
    )
    parameters = np.stack(
        [
            np.hypot(sin_weight, cos_weight),
            angular_frequency,
            np.arctan2(cos_weight, sin_weight),
            offset,
        ],
        axis=-1,
    )
    return parameters, sse


#: Trial frequencies of the FFT start: offsets (cycles) around the FFT peak, and low frequencies
#: always tried.
FFT_START_PEAK_OFFSETS: Final[tuple[float, ...]] = (-0.75, -0.5, -0.25, 0.0, 0.25, 0.5, 0.75)
FFT_START_LOW_FREQUENCIES: Final[tuple[float, ...]] = (0.25, 0.5, 0.75)
_FFT_START_CHUNK: Final[int] = 1000


def fft_start_parameters(s: FloatArray, values: FloatArray) -> FloatArray:
    """Sound starts (A, B, C, D) of the sinusoid fit, shape (N, 4), for ``values`` of shape (N, n).

    The peak of |FFT(y − mean y)| (DC excluded) gives a frequency k in cycles over the grid;
    the trial frequencies are k + :data:`FFT_START_PEAK_OFFSETS` and
    :data:`FFT_START_LOW_FREQUENCIES` (a monotone trend is best matched by less than one
    cycle).  For each trial B = 2π f, A, C and D follow from a linear least-squares solve;
    the trial with the smallest residual is the start.
    """
    values = np.atleast_2d(np.asarray(values, dtype=np.float64))
    s = np.asarray(s, dtype=np.float64)
    span = (s[-1] - s[0]) * len(s) / (len(s) - 1)  # the period the FFT assumes
    spectrum = np.abs(np.fft.rfft(values - values.mean(axis=1, keepdims=True), axis=1))
    peak_bin = 1 + np.argmax(spectrum[:, 1:], axis=1)  # (N,)
    peak_frequency = peak_bin / span
    trial = np.concatenate(
        [
            peak_frequency[:, None] + np.asarray(FFT_START_PEAK_OFFSETS)[None, :],
            np.broadcast_to(
                np.asarray(FFT_START_LOW_FREQUENCIES), (len(values), len(FFT_START_LOW_FREQUENCIES))
            ),
        ],
        axis=1,
    )
    trial = np.maximum(trial, FFT_START_LOW_FREQUENCIES[0])  # peak bin 1 minus 0.75 would be ≤ 0
    starts = np.empty((len(values), 4))
    # chunks bound the (chunk, K, n, 3) basis array
    for first in range(0, len(values), _FFT_START_CHUNK):
        chunk = slice(first, first + _FFT_START_CHUNK)
        parameters, sse = _sinusoid_linear_solve(s, values[chunk], 2.0 * math.pi * trial[chunk])
        best = np.argmin(sse, axis=1)
        starts[chunk] = parameters[np.arange(len(best)), best]
    return starts


@dataclass(frozen=True)
class SinusoidFits:
    """Result of the nonlinear fits of A sin(Bs + C) + D."""

    parameters: FloatArray
    """Fitted (A, B, C, D), shape (N, 4)."""
    start_parameters: FloatArray
    """Start of each fit, shape (N, 4)."""
    converged: BoolArray
    """True where Levenberg–Marquardt met a tolerance with a finite result, shape (N,)."""
    status: IntArray
    """``scipy.optimize.least_squares`` status of each fit (0 = budget exhausted), shape (N,)."""
    evaluations: IntArray
    """Function evaluations used per fit, shape (N,)."""


def fit_sinusoid(
    s: FloatArray,
    values: FloatArray,
    start: SinusoidStart = "fft",
    max_evaluations: int = 200,
) -> SinusoidFits:
    """Fit A sin(Bs + C) + D to every row of ``values`` (N, n) on grid ``s`` (n,).

    Levenberg–Marquardt (``least_squares(method="lm")``) with an analytic Jacobian, started
    from :func:`fft_start_parameters` (``start="fft"``) or from all ones (``start="ones"``).
    A fit that exhausts ``max_evaluations`` or ends non-finite is marked not converged; its
    last iterate is kept (or the start, if the iterate is non-finite), never dropped.
    """
    _check_choice("sinusoid_start", start, SINUSOID_STARTS)
    _check_int("sinusoid_max_evaluations", max_evaluations, 1, MAX_SINUSOID_EVALUATIONS)
    values = np.atleast_2d(np.asarray(values, dtype=np.float64))
    s = np.asarray(s, dtype=np.float64)
    starts = fft_start_parameters(s, values) if start == "fft" else np.ones((len(values), 4))
    parameters = np.empty_like(starts)
    converged = np.zeros(len(values), dtype=np.bool_)
    status = np.zeros(len(values), dtype=np.int64)
    evaluations = np.zeros(len(values), dtype=np.int64)
    jacobian = np.empty((len(s), 4))
    jacobian[:, 3] = 1.0

    for sample, y in enumerate(values):

        def residual(p: FloatArray, y: FloatArray = y) -> FloatArray:
            return p[0] * np.sin(p[1] * s + p[2]) + p[3] - y

        def residual_jacobian(p: FloatArray, y: FloatArray = y) -> FloatArray:
            phase = p[1] * s + p[2]
            cosine = np.cos(phase)
            jacobian[:, 0] = np.sin(phase)
            jacobian[:, 1] = p[0] * s * cosine
            jacobian[:, 2] = p[0] * cosine
            return jacobian.copy()

        with np.errstate(all="ignore"):
            result = least_squares(
                residual,
                starts[sample],
                jac=residual_jacobian,
                method="lm",
                max_nfev=max_evaluations,
            )
        finite = bool(np.all(np.isfinite(result.x)) and np.isfinite(result.cost))
        parameters[sample] = result.x if finite else starts[sample]
        status[sample] = result.status
        evaluations[sample] = result.nfev
        converged[sample] = finite and result.status > 0
    return SinusoidFits(
        parameters=parameters,
        start_parameters=starts,
        converged=converged,
        status=status,
        evaluations=evaluations,
    )


def mean_squared_error(residuals: FloatArray) -> FloatArray:
    """(1/n) Σ r_i², the MSE of spec §2.4.4; ``residuals`` (N, n) → shape (N,)."""
    residuals = np.atleast_2d(residuals)
    return np.mean(residuals**2, axis=1)


def range_normalised_sse(residuals: FloatArray, values: FloatArray) -> FloatArray:
    """Σ (r_i / (max y − min y))², the error the spec's Table 1 averages; shapes (N, n) → (N,).

    A constant sample (range 0) is divided by 1 instead.
    """
    residuals = np.atleast_2d(residuals)
    values = np.atleast_2d(values)
    value_range = np.ptp(values, axis=1)
    value_range = np.where(value_range > 0.0, value_range, 1.0)
    return np.sum((residuals / value_range[:, None]) ** 2, axis=1)


# --------------------------------------------------------------------------------------------
# The study
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StudyResult:
    """Everything one study run produced.  N samples, 5 candidates (order of :data:`CANDIDATES`)."""

    config: StudyConfig
    functions: RandomFunctionBatch
    mse: FloatArray
    """MSE of each fit, shape (N, 5)."""
    range_normalised_sse: FloatArray
    """Σ (r/(max y − min y))² of each fit, shape (N, 5)."""
    fitted_parameters: dict[str, FloatArray]
    """Per candidate name, the fitted parameters, shape (N, p)."""
    sinusoid: SinusoidFits
    timings: dict[str, float] = field(default_factory=dict)
    """Wall-clock seconds of the phases
    (``draw``, ``linear_fits``, ``sinusoid_fits``, ``total``)."""

    @property
    def generator_names(self) -> list[str]:
        """Generator name of each sample, length N."""
        return [GENERATOR_NAMES[i] for i in self.functions.generator_index]

    @property
    def sinusoid_not_converged(self) -> int:
        """Number of sinusoid fits that did not converge."""
        return int(np.count_nonzero(~self.sinusoid.converged))

    def metric(self, metric: str) -> FloatArray:
        """The (N, 5) error array called ``metric`` (``"mse"`` or ``"range_normalised_sse"``)."""
        if metric == "mse":
            return self.mse
        if metric == "range_normalised_sse":
            return self.range_normalised_sse
        raise ParameterError(f"metric = {metric!r} is unknown; allowed: mse, range_normalised_sse")

    def summary_rows(self, generator: str | None = None) -> list[dict[str, Any]]:
        """Per candidate: parameter count, mean and median of both errors, spec value.

        ``generator`` restricts to the samples of one generator (``None``: all samples).
        """
        mask = self.generator_mask(generator)
        rows = []
        for column, candidate in enumerate(CANDIDATES):
            mse = self.mse[mask, column]
            normalised = self.range_normalised_sse[mask, column]
            rows.append(
                {
                    "candidate": candidate.name,
                    "label": candidate.label,
                    "generator": generator or "all",
                    "samples": int(np.count_nonzero(mask)),
                    "parameters": candidate.parameter_count,
                    "mean_mse": _mean_or_nan(mse),
                    "standard_error_mse": _standard_error_or_nan(mse),
                    "median_mse": _median_or_nan(mse),
                    "mean_range_normalised_sse": _mean_or_nan(normalised),
                    "standard_error_range_normalised_sse": _standard_error_or_nan(normalised),
                    "median_range_normalised_sse": _median_or_nan(normalised),
                    "spec_table_1": candidate.spec_table_value,
                    "not_converged": (
                        int(np.count_nonzero(~self.sinusoid.converged[mask]))
                        if candidate.name == "sinusoid"
                        else 0
                    ),
                }
            )
        return rows

    def sinusoid_converged_only(self, generator: str | None = None) -> dict[str, Any]:
        """Mean and median of both errors of the sinusoid over its converged fits only.

        A faithful ``curve_fit`` port raises on the fits that do not converge and so leaves
        them out; this shows what that does to the sinusoid row.
        """
        mask = self.generator_mask(generator) & self.sinusoid.converged
        column = CANDIDATE_NAMES.index("sinusoid")
        return {
            "generator": generator or "all",
            "converged": int(np.count_nonzero(mask)),
            "mean_mse": _mean_or_nan(self.mse[mask, column]),
            "median_mse": _median_or_nan(self.mse[mask, column]),
            "mean_range_normalised_sse": _mean_or_nan(self.range_normalised_sse[mask, column]),
            "median_range_normalised_sse": _median_or_nan(self.range_normalised_sse[mask, column]),
        }

    def generator_mask(self, generator: str | None) -> BoolArray:
        """Boolean mask (N,) of the samples of ``generator`` (``None``: all samples)."""
        if generator is None:
            return np.ones(len(self.mse), dtype=np.bool_)
        _check_choice("generator", generator, GENERATOR_NAMES)
        return self.functions.generator_index == GENERATOR_NAMES.index(generator)

    def summary(self) -> dict[str, Any]:
        """JSON-serialisable summary: config, choices, timings, overall and per-generator rows."""
        return {
            "config": asdict(self.config),
            "choices": self.config.describe().splitlines(),
            "grid": f"numpy.linspace(0, 1, {self.config.points})",
            "metrics": {
                "mse": "(1/n) sum_i (y_i - f(s_i))^2  (spec 2.4.4)",
                "range_normalised_sse": (
                    "sum_i ((y_i - f(s_i)) / (max y - min y))^2  (what Table 1 averages)"
                ),
            },
            "sinusoid_start": self.config.sinusoid_start,
            "sinusoid_not_converged": self.sinusoid_not_converged,
            "sinusoid_converged_only": self.sinusoid_converged_only(),
            "generator_counts": {
                name: int(np.count_nonzero(self.functions.generator_index == index))
                for index, name in enumerate(GENERATOR_NAMES)
            },
            "timings_seconds": dict(self.timings),
            "overall": self.summary_rows(),
            "by_generator": {name: self.summary_rows(name) for name in GENERATOR_NAMES},
        }


def _mean_or_nan(values: FloatArray) -> float:
    return float(np.mean(values)) if values.size else math.nan


def _median_or_nan(values: FloatArray) -> float:
    return float(np.median(values)) if values.size else math.nan


def _standard_error_or_nan(values: FloatArray) -> float:
    """Standard error of the mean, std / sqrt(count) (NaN for fewer than two values)."""
    return float(np.std(values, ddof=1) / math.sqrt(values.size)) if values.size > 1 else math.nan


def run_study(config: StudyConfig | None = None) -> StudyResult:
    """Draw the random functions, fit the five candidates, compute both errors."""
    config = config or StudyConfig()
    config.validate()
    clock_start = time.perf_counter()
    functions = draw_random_functions(config)
    clock_drawn = time.perf_counter()

    mse = np.empty((config.samples, len(CANDIDATES)))
    normalised = np.empty_like(mse)
    fitted: dict[str, FloatArray] = {}
    for column, candidate in enumerate(CANDIDATES):
        if not candidate.is_linear:
            continue
        coefficients, residuals = fit_linear_candidate(
            candidate.name, functions.s, functions.values
        )
        fitted[candidate.name] = coefficients
        mse[:, column] = mean_squared_error(residuals)
        normalised[:, column] = range_normalised_sse(residuals, functions.values)
    clock_linear = time.perf_counter()

    sinusoid = fit_sinusoid(
        functions.s, functions.values, config.sinusoid_start, config.sinusoid_max_evaluations
    )
    residuals = functions.values - sinusoid_values(sinusoid.parameters, functions.s)
    column = CANDIDATE_NAMES.index("sinusoid")
    fitted["sinusoid"] = sinusoid.parameters
    mse[:, column] = mean_squared_error(residuals)
    normalised[:, column] = range_normalised_sse(residuals, functions.values)
    clock_end = time.perf_counter()

    timings = {
        "draw": clock_drawn - clock_start,
        "linear_fits": clock_linear - clock_drawn,
        "sinusoid_fits": clock_end - clock_linear,
        "total": clock_end - clock_start,
    }
    return StudyResult(
        config=config,
        functions=functions,
        mse=mse,
        range_normalised_sse=normalised,
        fitted_parameters=fitted,
        sinusoid=sinusoid,
        timings=timings,
    )


# --------------------------------------------------------------------------------------------
# Output: tables, CSV, figure
# --------------------------------------------------------------------------------------------


def _format_number(value: float) -> str:
    if math.isnan(value):
        return "-"
    if value != 0.0 and (abs(value) >= 1e5 or abs(value) < 1e-3):
        return f"{value:.3e}"
    return f"{value:.4f}"


def _render_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Left-align the first column, right-align the others; header, rule, one line per row."""
    widths = [max(len(headers[i]), *(len(row[i]) for row in rows)) for i in range(len(headers))]

    def render(cells: Sequence[str]) -> str:
        return "  ".join(
            cell.ljust(width) if i == 0 else cell.rjust(width)
            for i, (cell, width) in enumerate(zip(cells, widths))
        )

    return "\n".join(
        [
            render(headers),
            "  ".join("-" * width for width in widths),
            *(render(row) for row in rows),
        ]
    )


def format_overall_table(result: StudyResult) -> str:
    """Text table: per candidate, parameters, mean (± standard error) and median of both errors,
    spec value."""
    headers = [
        "candidate",
        "params",
        "mean MSE ± s.e.",
        "median MSE",
        "mean norm-SSE ± s.e.",
        "median norm-SSE",
        "spec Table 1",
    ]
    rows = [
        [
            row["label"],
            str(row["parameters"]),
            f"{_format_number(row['mean_mse'])} ± {_format_number(row['standard_error_mse'])}",
            _format_number(row["median_mse"]),
            (
                f"{_format_number(row['mean_range_normalised_sse'])} ± "
                f"{_format_number(row['standard_error_range_normalised_sse'])}"
            ),
            _format_number(row["median_range_normalised_sse"]),
            f"{row['spec_table_1']:.3f}",
        ]
        for row in result.summary_rows()
    ]
    converged = result.sinusoid_converged_only()
    footer = (
        f"Sinusoid over its {converged['converged']} converged fits only: "
        f"mean MSE {_format_number(converged['mean_mse'])}, "
        f"mean norm-SSE {_format_number(converged['mean_range_normalised_sse'])}"
    )
    title = (
        f"All samples (N = {result.config.samples}, n = "
        f"{result.config.points}, seed = {result.config.seed}, "
        f"sinusoid start = {result.config.sinusoid_start}, "
        f"sinusoid fits not converged: {result.sinusoid_not_converged})"
    )
    return title + "\n" + _render_table(headers, rows) + "\n" + footer


def format_generator_table(result: StudyResult) -> str:
    """Text table: the overall table broken down by generator."""
    headers = [
        "generator / candidate",
        "N",
        "params",
        "mean MSE",
        "median MSE",
        "mean norm-SSE",
        "median norm-SSE",
        "not conv.",
    ]
    rows = []
    for generator in GENERATOR_NAMES:
        for row in result.summary_rows(generator):
            rows.append(
                [
                    f"{generator} / {row['candidate']}",
                    str(row["samples"]),
                    str(row["parameters"]),
                    _format_number(row["mean_mse"]),
                    _format_number(row["median_mse"]),
                    _format_number(row["mean_range_normalised_sse"]),
                    _format_number(row["median_range_normalised_sse"]),
                    str(row["not_converged"]) if row["candidate"] == "sinusoid" else "",
                ]
            )
    return "By generator\n" + _render_table(headers, rows)


def format_report(result: StudyResult) -> str:
    """The choices made, both tables and the timings, as printed by the script."""
    timing = ", ".join(f"{name} {seconds:.2f} s" for name, seconds in result.timings.items())
    return "\n\n".join(
        [
            "Function-space study (spec 2.4-2.5)\n" + result.config.describe(),
            "MSE = (1/n) sum r^2 (spec 2.4.4); norm-SSE = sum "
            "(r / (max y - min y))^2 (what spec Table 1 averages)",
            format_overall_table(result),
            format_generator_table(result),
            f"Timings: {timing}",
        ]
    )


CSV_COLUMNS: Final[tuple[str, ...]] = (
    "sample",
    "generator",
    "generator_parameters",
    "candidate",
    "parameters",
    "mse",
    "range_normalised_sse",
    "converged",
    "fitted_parameters",
)


def write_fits_csv(result: StudyResult, path: str | Path) -> Path:
    """Write one row per (sample, candidate) fit, columns :data:`CSV_COLUMNS`; returns the path.

    Parameter lists are ``name=value`` pairs joined by ``;``.  Linear fits are exact and
    always ``converged``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    generator_names = result.generator_names
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(CSV_COLUMNS)
        for sample in range(result.config.samples):
            generator_text = _format_parameters(result.functions.generator_parameters[sample])
            for column, candidate in enumerate(CANDIDATES):
                fitted = result.fitted_parameters[candidate.name][sample]
                converged = (
                    bool(result.sinusoid.converged[sample])
                    if candidate.name == "sinusoid"
                    else True
                )
                writer.writerow(
                    [
                        sample,
                        generator_names[sample],
                        generator_text,
                        candidate.name,
                        candidate.parameter_count,
                        repr(float(result.mse[sample, column])),
                        repr(float(result.range_normalised_sse[sample, column])),
                        converged,
                        ";".join(
                            f"{name}={value!r}"
                            for name, value in zip(candidate.parameter_names, fitted.tolist())
                        ),
                    ]
                )
    return path


def _format_parameters(parameters: GeneratorParameters) -> str:
    parts = []
    for name, value in parameters.items():
        if isinstance(value, list):
            parts.append(f"{name}=[{' '.join(f'{v:.6g}' for v in value)}]")
        elif isinstance(value, float):
            parts.append(f"{name}={value:.6g}")
        else:
            parts.append(f"{name}={value}")
    return ";".join(parts)


def plot_errors(result: StudyResult, path: str | Path) -> Path:
    """Box plots of both errors per candidate per generator (log scale), saved as PNG; returns the
    path.

    Boxes span the quartiles, whiskers the 5th–95th percentiles, diamonds mark the means;
    values below :data:`PLOT_ERROR_FLOOR` (exact fits) are drawn at the floor.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    groups = [*GENERATOR_NAMES, "all"]
    colours = plt.get_cmap("tab10").colors
    figure, axes = plt.subplots(2, 1, figsize=(12, 9), sharex=True)
    width = 0.16
    for axis, metric, label in (
        (axes[0], "mse", "MSE (spec 2.4.4)"),
        (axes[1], "range_normalised_sse", "sum (r / (max y - min y))^2 (spec Table 1)"),
    ):
        errors = result.metric(metric)
        for column, candidate in enumerate(CANDIDATES):
            data, positions, means = [], [], []
            for group_index, group in enumerate(groups):
                mask = result.generator_mask(None if group == "all" else group)
                if not np.any(mask):
                    continue
                selected = errors[mask, column]
                data.append(np.maximum(selected, PLOT_ERROR_FLOOR))
                positions.append(group_index + (column - 2) * width)
                means.append(max(float(np.mean(selected)), PLOT_ERROR_FLOOR))
            if not data:
                continue
            boxes = axis.boxplot(
                data,
                positions=positions,
                widths=width * 0.85,
                whis=(5, 95),
                showfliers=False,
                patch_artist=True,
                manage_ticks=False,
            )
            for box in boxes["boxes"]:
                box.set_facecolor(colours[column])
                box.set_alpha(0.75)
            for median in boxes["medians"]:
                median.set_color("black")
            axis.scatter(
                positions,
                means,
                marker="D",
                s=22,
                color="white",
                edgecolors="black",
                zorder=3,
                label=None,
            )
            axis.plot(
                [],
                [],
                color=colours[column],
                linewidth=8,
                alpha=0.75,
                label=f"{candidate.label} ({candidate.parameter_count} p.)",
            )
        axis.set_yscale("log")
        axis.set_ylabel(label)
        axis.grid(True, axis="y", which="major", alpha=0.3)
        for boundary in np.arange(len(groups) - 1) + 0.5:
            axis.axvline(boundary, color="grey", linewidth=0.6)
    axes[0].scatter([], [], marker="D", s=22, color="white", edgecolors="black", label="mean")
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8, frameon=False)
    counts = [
        int(np.count_nonzero(result.functions.generator_index == i))
        for i in range(len(GENERATOR_NAMES))
    ]
    axes[1].set_xticks(range(len(groups)))
    axes[1].set_xticklabels(
        [f"{name}\n(N={count})" for name, count in zip(groups, [*counts, result.config.samples])]
    )
    figure.suptitle(
        f"Function-space study: N = {result.config.samples}, n = {result.config.points}, "
        f"seed = {result.config.seed}, sinusoid start = {result.config.sinusoid_start} "
        f"({result.sinusoid_not_converged} not converged)\n"
        f"boxes: quartiles, whiskers: 5-95 %, diamonds: means; "
        f"values < {PLOT_ERROR_FLOOR:g} drawn at {PLOT_ERROR_FLOOR:g}",
        fontsize=10,
    )
    figure.tight_layout(rect=(0.0, 0.035, 1.0, 1.0))
    figure.savefig(path, dpi=120)
    plt.close(figure)
    return path
