"""Re-run the function-space study of spec §2.4–§2.5 and write its tables, CSV, figure and JSON.

Usage::

    python scripts/function_space_study.py [--samples 10000] [--points 100] [--seed 0]
        [--sinusoid-start fft|ones] [--generator-draw random|balanced]
        [--knot-placement even|random] [--sinusoid-max-evaluations 200] [--out study_out/]

Writes ``<out>/fits.csv`` (one row per fit), ``<out>/errors.png`` (both errors per candidate
per generator, log scale), ``<out>/summary.json`` and ``<out>/tables.txt`` (what is printed).
Exit codes: 0 done, 2 bad option, 1 the output could not be written.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any, NoReturn

# studies/ sits beside torus_cad, outside it
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from studies import function_space as study
from torus_cad.errors import ParameterError


class _OneLineErrorParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr and exit code 2."""

    def error(self, message: str) -> NoReturn:
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    """The command-line options; defaults are those of
    :class:`studies.function_space.StudyConfig`."""
    defaults = study.StudyConfig()
    parser = _OneLineErrorParser(
        prog="function_space_study.py",
        description=(
            "Monte Carlo function-space study of spec 2.4-2.5 (which transform family fits best)."
        ),
    )
    parser.add_argument(
        "--samples", type=int, default=defaults.samples, help="N, number of random functions"
    )
    parser.add_argument(
        "--points", type=int, default=defaults.points, help="n, evenly spaced points on [0, 1]"
    )
    parser.add_argument(
        "--seed", type=int, default=defaults.seed, help="seed of numpy.random.default_rng"
    )
    parser.add_argument(
        "--sinusoid-start",
        choices=study.SINUSOID_STARTS,
        default=defaults.sinusoid_start,
        help="start of the A sin(Bs+C)+D fit: fft (sound) or ones (the spec author's)",
    )
    parser.add_argument(
        "--generator-draw",
        choices=study.GENERATOR_DRAWS,
        default=defaults.generator_draw,
        help="random: generator uniform per sample (as the original); balanced: generators in turn",
    )
    parser.add_argument(
        "--knot-placement",
        choices=study.KNOT_PLACEMENTS,
        default=defaults.knot_placement,
        help="piecewise-linear knots: even over [0, 1] or random sorted U(0, 1) positions",
    )
    parser.add_argument(
        "--sinusoid-max-evaluations",
        type=int,
        default=defaults.sinusoid_max_evaluations,
        help="Levenberg-Marquardt evaluation budget per sinusoid fit",
    )
    parser.add_argument("--out", type=Path, default=Path("study_out"), help="output directory")
    return parser


def _json_ready(value: Any) -> Any:
    """Replace NaN/inf (not valid JSON) by None, recursively."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {key: _json_ready(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(item) for item in value]
    return value


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv``, run the study, print the tables and write the outputs; return the exit
    code."""
    parser = build_parser()
    try:
        arguments = parser.parse_args(argv)
    except SystemExit as exit_request:  # bad option (2) or --help (0)
        return int(exit_request.code or 0)
    config = study.StudyConfig(
        samples=arguments.samples,
        points=arguments.points,
        seed=arguments.seed,
        sinusoid_start=arguments.sinusoid_start,
        generator_draw=arguments.generator_draw,
        knot_placement=arguments.knot_placement,
        sinusoid_max_evaluations=arguments.sinusoid_max_evaluations,
    )
    try:
        config.validate()
    except ParameterError as error:
        sys.stderr.write(f"{parser.prog}: error: {error}\n")
        return 2

    result = study.run_study(config)
    report = study.format_report(result)
    print(report)

    out: Path = arguments.out
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / "tables.txt").write_text(report + "\n", encoding="utf-8")
        csv_path = study.write_fits_csv(result, out / "fits.csv")
        png_path = study.plot_errors(result, out / "errors.png")
        json_path = out / "summary.json"
        json_path.write_text(
            json.dumps(_json_ready(result.summary()), indent=2) + "\n", encoding="utf-8"
        )
    except OSError as error:
        sys.stderr.write(f"{parser.prog}: error: cannot write to {out}: {error}\n")
        return 1
    print(f"\nWrote {csv_path}, {png_path}, {json_path}, {out / 'tables.txt'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
