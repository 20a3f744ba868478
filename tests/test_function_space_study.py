"""Tests of the function-space study (spec §2.4–§2.5)."""

from __future__ import annotations

import csv
import importlib.util
import json
import math
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studies import function_space as study
from torus_cad.errors import ParameterError

REPO_ROOT = Path(__file__).resolve().parent.parent
POLY4, POLY6, FOURIER2, FOURIER3, SINUSOID = (
    study.CANDIDATE_NAMES.index(name)
    for name in ("poly4", "poly6", "fourier2", "fourier3", "sinusoid")
)

#: Relative slack for "never worse": exact least squares is exact up to floating rounding.
NESTING_RELATIVE_TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def small_result() -> study.StudyResult:
    """A small balanced run (every generator present), sound sinusoid start."""
    return study.run_study(study.StudyConfig(samples=200, seed=11, generator_draw="balanced"))


def _not_worse(
    larger_model: np.ndarray, smaller_model: np.ndarray, scale: np.ndarray
) -> np.ndarray:
    return larger_model <= smaller_model * (1.0 + NESTING_RELATIVE_TOLERANCE) + 1e-12 * scale


# ------------------------------------------------------------------------------------------
# Nested models
# ------------------------------------------------------------------------------------------


def test_nested_candidates_never_worse_per_sample(small_result: study.StudyResult) -> None:
    values = small_result.functions.values
    scale_mse = np.mean(values**2, axis=1)
    scale_normalised = np.ones(len(values))
    for errors, scale in (
        (small_result.mse, scale_mse),
        (small_result.range_normalised_sse, scale_normalised),
    ):
        assert np.all(_not_worse(errors[:, POLY6], errors[:, POLY4], scale)), (
            "degree 6 worse than quartic"
        )
        assert np.all(_not_worse(errors[:, FOURIER3], errors[:, FOURIER2], scale)), (
            "Fourier 3 worse than Fourier 2"
        )


@settings(max_examples=60, deadline=None)
@given(
    points=st.integers(min_value=study.MIN_POINTS, max_value=60),
    seed=st.integers(min_value=0, max_value=2**32 - 1),
    scale=st.floats(min_value=1e-3, max_value=1e3),
)
def test_nesting_holds_for_any_data(points: int, seed: int, scale: float) -> None:
    s = study.sample_grid(points)
    values = scale * np.random.default_rng(seed).standard_normal((3, points))
    sse = {
        name: np.sum(study.fit_linear_candidate(name, s, values)[1] ** 2, axis=1)
        for name in ("poly4", "poly6", "fourier2", "fourier3")
    }
    total = np.sum(values**2, axis=1)
    assert np.all(_not_worse(sse["poly6"], sse["poly4"], total))
    assert np.all(_not_worse(sse["fourier3"], sse["fourier2"], total))


# ------------------------------------------------------------------------------------------
# Exact fits
# ------------------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    coefficients=st.lists(st.floats(min_value=-10.0, max_value=10.0), min_size=5, max_size=5),
    points=st.integers(min_value=study.MIN_POINTS, max_value=200),
)
def test_any_quartic_is_fitted_by_the_quartic_to_zero(
    coefficients: list[float], points: int
) -> None:
    s = study.sample_grid(points)
    values = np.polynomial.polynomial.polyval(s, coefficients)[None, :]
    fitted, residuals = study.fit_linear_candidate("poly4", s, values)
    assert study.mean_squared_error(residuals)[0] <= 1e-22 * (1.0 + np.max(np.abs(values)) ** 2)
    np.testing.assert_allclose(
        fitted[0], coefficients, atol=1e-8 * (1.0 + max(map(abs, coefficients)))
    )


def test_polynomials_up_to_degree_four_are_exact_for_the_quartic(
    small_result: study.StudyResult,
) -> None:
    low_degree = [
        sample
        for sample, parameters in enumerate(small_result.functions.generator_parameters)
        if small_result.generator_names[sample] == "polynomial" and parameters["degree"] <= 4
    ]
    assert low_degree
    assert np.max(small_result.mse[low_degree, POLY4]) < 1e-20
    assert np.max(small_result.range_normalised_sse[low_degree, POLY4]) < 1e-18


def test_fft_start_fits_generated_sinusoids_exactly(small_result: study.StudyResult) -> None:
    mask = small_result.functions.generator_index == study.GENERATOR_NAMES.index("sinusoid")
    assert np.count_nonzero(mask) == 50
    assert np.all(small_result.sinusoid.converged[mask])
    assert np.max(small_result.mse[mask, SINUSOID]) < 1e-20


@settings(max_examples=30, deadline=None)
@given(
    amplitude=st.floats(min_value=0.5, max_value=2.0),
    frequency=st.floats(min_value=1.0, max_value=3.0),
    phase=st.floats(min_value=0.0, max_value=math.pi),
    offset=st.floats(min_value=-5.0, max_value=5.0),
)
def test_fft_start_is_near_the_true_frequency(
    amplitude: float, frequency: float, phase: float, offset: float
) -> None:
    s = study.sample_grid(100)
    values = (amplitude * np.sin(2 * math.pi * frequency * s + phase) + offset)[None, :]
    start = study.fft_start_parameters(s, values)[0]
    assert abs(start[1] - 2 * math.pi * frequency) <= 2 * math.pi * 0.25
    fits = study.fit_sinusoid(s, values, "fft")
    assert fits.converged[0]
    assert study.mean_squared_error(values - study.sinusoid_values(fits.parameters, s))[0] < 1e-18


# ------------------------------------------------------------------------------------------
# Generators (spec §2.4.2)
# ------------------------------------------------------------------------------------------


def test_generators_follow_the_spec_ranges(small_result: study.StudyResult) -> None:
    s = small_result.functions.s
    for values, name, parameters in zip(
        small_result.functions.values,
        small_result.generator_names,
        small_result.functions.generator_parameters,
    ):
        if name == "sinusoid":
            assert (
                0.5 <= parameters["A"] <= 2
                and 1 <= parameters["F"] <= 3
                and 0 <= parameters["phi"] <= math.pi
            )
            expected = parameters["A"] * np.sin(
                2 * math.pi * parameters["F"] * s + parameters["phi"]
            )
        elif name == "polynomial":
            assert (
                1 <= parameters["degree"] <= 8 and len(parameters["c"]) == parameters["degree"] + 1
            )
            assert all(-2 <= c <= 2 for c in parameters["c"])
            expected = np.polynomial.polynomial.polyval(s, parameters["c"])
        elif name == "logistic":
            assert (
                1 <= parameters["L"] <= 50
                and 8 <= parameters["k"] <= 100
                and 0.1 <= parameters["s0"] <= 0.9
            )
            expected = parameters["L"] / (1 + np.exp(-parameters["k"] * (s - parameters["s0"])))
        else:
            assert 3 <= parameters["knots"] <= 8
            assert all(-1 <= y <= 1 for y in parameters["y_i"])
            np.testing.assert_allclose(parameters["s_i"], np.linspace(0, 1, parameters["knots"]))
            expected = np.interp(s, parameters["s_i"], parameters["y_i"])
        np.testing.assert_allclose(values, expected, rtol=1e-12, atol=1e-12)


def test_generator_draw_and_knot_placement_options() -> None:
    balanced = study.draw_random_functions(study.StudyConfig(samples=40, generator_draw="balanced"))
    assert np.array_equal(np.bincount(balanced.generator_index, minlength=4), [10, 10, 10, 10])
    drawn = study.draw_random_functions(study.StudyConfig(samples=400, seed=1))
    assert np.all(np.bincount(drawn.generator_index, minlength=4) > 50)
    random_knots = study.draw_random_functions(
        study.StudyConfig(samples=80, generator_draw="balanced", knot_placement="random")
    )
    for index, parameters in zip(random_knots.generator_index, random_knots.generator_parameters):
        if study.GENERATOR_NAMES[index] == "piecewise_linear":
            positions = np.asarray(parameters["s_i"])
            assert np.all(np.diff(positions) >= 0) and np.all((positions >= 0) & (positions <= 1))


# ------------------------------------------------------------------------------------------
# Metrics, sinusoid start, reproducibility
# ------------------------------------------------------------------------------------------


def test_error_metrics_by_hand() -> None:
    values = np.array([[0.0, 2.0, 4.0, 1.0]])
    residuals = np.array([[1.0, -1.0, 2.0, 0.0]])
    assert study.mean_squared_error(residuals)[0] == pytest.approx(6.0 / 4.0)
    assert study.range_normalised_sse(residuals, values)[0] == pytest.approx(6.0 / 16.0)
    assert study.range_normalised_sse(np.zeros((1, 4)), np.ones((1, 4)))[0] == 0.0


def test_sinusoid_start_is_reported_and_non_convergence_counted() -> None:
    config = study.StudyConfig(
        samples=80, seed=2, sinusoid_start="ones", sinusoid_max_evaluations=20
    )
    result = study.run_study(config)
    assert result.sinusoid_not_converged == int(np.count_nonzero(result.sinusoid.status == 0))
    assert result.sinusoid_not_converged > 0, (
        "a budget of 20 evaluations from all-ones must leave fits unfinished"
    )
    assert np.all(result.sinusoid.start_parameters == 1.0)
    assert np.all(np.isfinite(result.mse[:, SINUSOID]))
    summary = result.summary()
    assert summary["sinusoid_start"] == "ones"
    assert summary["sinusoid_not_converged"] == result.sinusoid_not_converged
    assert "start = ones" in study.format_overall_table(result)
    assert f"not converged: {result.sinusoid_not_converged}" in study.format_overall_table(result)


def test_same_seed_gives_the_same_table() -> None:
    config = study.StudyConfig(samples=60, seed=5)
    first, second = study.run_study(config), study.run_study(config)
    assert study.format_overall_table(first) == study.format_overall_table(second)
    assert study.format_generator_table(first) == study.format_generator_table(second)
    np.testing.assert_array_equal(first.mse, second.mse)
    np.testing.assert_array_equal(first.range_normalised_sse, second.range_normalised_sse)
    other = study.run_study(study.StudyConfig(samples=60, seed=6))
    assert not np.array_equal(first.mse, other.mse)


@settings(max_examples=15, deadline=None)
@given(
    seed=st.integers(min_value=0, max_value=2**63 - 1),
    samples=st.integers(min_value=1, max_value=12),
)
def test_any_seed_reproduces(seed: int, samples: int) -> None:
    config = study.StudyConfig(samples=samples, points=30, seed=seed)
    first, second = study.run_study(config), study.run_study(config)
    np.testing.assert_array_equal(first.functions.values, second.functions.values)
    np.testing.assert_array_equal(first.mse, second.mse)
    assert (
        study.format_report(first).split("Timings")[0]
        == study.format_report(second).split("Timings")[0]
    )


def test_table_lists_every_candidate_with_parameters_and_spec_value(
    small_result: study.StudyResult,
) -> None:
    rows = small_result.summary_rows()
    assert [row["candidate"] for row in rows] == list(study.CANDIDATE_NAMES)
    assert [row["parameters"] for row in rows] == [5, 7, 5, 7, 4]
    assert [row["spec_table_1"] for row in rows] == [2.064, 0.845, 2.441, 1.193, 5.748]
    table = study.format_overall_table(small_result)
    for value in ("2.064", "0.845", "2.441", "1.193", "5.748"):
        assert value in table
    per_generator_counts = [
        small_result.summary_rows(name)[0]["samples"] for name in study.GENERATOR_NAMES
    ]
    assert per_generator_counts == [50, 50, 50, 50]


# ------------------------------------------------------------------------------------------
# Validation
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "field_name"),
    [
        ({"samples": 0}, "samples"),
        ({"points": 3}, "points"),
        ({"seed": -1}, "seed"),
        ({"sinusoid_start": "zeros"}, "sinusoid_start"),
        ({"generator_draw": "sometimes"}, "generator_draw"),
        ({"knot_placement": "odd"}, "knot_placement"),
        ({"sinusoid_max_evaluations": 0}, "sinusoid_max_evaluations"),
        ({"samples": 2.5}, "samples"),
    ],
)
def test_invalid_options_raise_parameter_error_naming_the_field(
    changes: dict, field_name: str
) -> None:
    config = study.StudyConfig(**changes)
    with pytest.raises(ParameterError, match=field_name) as raised:
        study.run_study(config)
    value = next(iter(changes.values()))
    assert repr(value) in str(raised.value) or str(value) in str(raised.value)
    assert "allowed" in str(raised.value) or "[" in str(raised.value)


# ------------------------------------------------------------------------------------------
# Script
# ------------------------------------------------------------------------------------------


def _load_script() -> ModuleType:
    path = REPO_ROOT / "scripts" / "function_space_study.py"
    spec = importlib.util.spec_from_file_location("function_space_study_script", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_script_writes_csv_png_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    script = _load_script()
    out = tmp_path / "study"
    argv = [
        "--samples",
        "24",
        "--points",
        "40",
        "--seed",
        "3",
        "--sinusoid-start",
        "ones",
        "--out",
        str(out),
    ]
    assert script.main(argv) == 0
    printed = capsys.readouterr().out
    assert "spec Table 1" in printed and "start = ones" in printed
    with (out / "fits.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 24 * 5
    assert set(rows[0]) == set(study.CSV_COLUMNS)
    assert {row["candidate"] for row in rows} == set(study.CANDIDATE_NAMES)
    assert (out / "errors.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["config"]["samples"] == 24 and summary["sinusoid_start"] == "ones"
    assert len(summary["overall"]) == 5 and set(summary["by_generator"]) == set(
        study.GENERATOR_NAMES
    )


@pytest.mark.parametrize(
    "argv",
    [
        ["--samples", "0"],
        ["--samples", "many"],
        ["--sinusoid-start", "zeros"],
        ["--points", "2"],
        ["--unknown"],
    ],
)
def test_script_bad_options_exit_2_with_one_line(
    argv: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    script = _load_script()
    assert script.main([*argv, "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "error" in error
