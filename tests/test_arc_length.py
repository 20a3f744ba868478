"""Equal arc-length resampling (spec §5)."""

from itertools import pairwise

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from torus_cad.geometry.section.airfoil import NacaAirfoil, airfoil_points
from torus_cad.geometry.section.arc_length import (
    ARC_LENGTH_QUAD_ABS,
    equal_arc_length_section,
    spacing_deviation,
)
from torus_cad.tolerances import FOLD_RATIO_LIMIT


def dense_perimeter(airfoil: NacaAirfoil, samples: int = 400001) -> float:
    u = np.linspace(0.0, 1.0, samples)  # t = u^2 resolves the leading edge
    upper, lower = airfoil.surfaces(u * u)
    return sum(
        float(np.linalg.norm(np.diff(side, axis=0), axis=1).sum()) for side in (upper, lower)
    )


def test_perimeter_matches_a_dense_polyline():
    airfoil = NacaAirfoil()
    assert equal_arc_length_section(airfoil, 200).perimeter == pytest.approx(
        dense_perimeter(airfoil), rel=1e-8
    )


def arc_gaps(airfoil: NacaAirfoil, t: np.ndarray) -> np.ndarray:
    """Arc length between consecutive parameters (closed), measured on a fine polyline."""
    closed = np.append(t, 2.0)
    gaps = []
    for start, stop in pairwise(closed):
        fine = airfoil_points(airfoil, np.linspace(start, stop, 400))
        gaps.append(np.linalg.norm(np.diff(fine, axis=0), axis=1).sum())
    return np.array(gaps)


def test_spec_procedure_spaces_points_equally_in_arc_length():
    airfoil = NacaAirfoil()
    sampling = equal_arc_length_section(airfoil, 200, anchor_trailing_edge=False)
    gaps = arc_gaps(airfoil, sampling.t)
    assert np.abs(gaps / gaps.mean() - 1).max() < 2e-3


def test_anchored_sampling_keeps_the_trailing_edge_and_near_equal_spacing():
    sampling = equal_arc_length_section(NacaAirfoil(), 200)
    assert sampling.t[sampling.trailing_edge_index] == pytest.approx(1.0)
    np.testing.assert_allclose(
        sampling.points[sampling.trailing_edge_index], [1.0, 0.0], atol=1e-12
    )
    assert spacing_deviation(sampling.points) < 1.0 / 200


@settings(max_examples=25, deadline=None)
@given(
    m=st.floats(0.0, 0.09),
    p=st.floats(0.1, 0.9),
    thickness=st.floats(0.02, 0.6),
    camber_normal=st.booleans(),
    count=st.integers(40, 400),
)
def test_spacing_is_equal_on_each_surface_for_any_section(m, p, thickness, camber_normal, count):
    airfoil = NacaAirfoil(m, p, thickness, camber_normal)
    # folded sections are refused by the parameters
    assume(airfoil.fold_ratio()[0] < FOLD_RATIO_LIMIT)
    sampling = equal_arc_length_section(airfoil, count)
    te = sampling.trailing_edge_index
    gaps = arc_gaps(airfoil, sampling.t)
    for side in (gaps[:te], gaps[te:]):
        assert np.abs(side / side.mean() - 1).max() < 2e-3
    assert sampling.points.shape == (count, 2)


def _adaptive_table(airfoil, upper: bool, edges: np.ndarray) -> np.ndarray:
    """The arc-length table of the same grid by QUADPACK's adaptive Gauss-Kronrod quadrature
    (scipy's ``quad_vec``, run to ARC_LENGTH_QUAD_ABS): the method the table used before
    Gauss-Legendre."""
    from scipy.integrate import quad_vec

    starts, widths = edges[:-1], np.diff(edges)
    pieces, _ = quad_vec(
        lambda f: airfoil.speed_on_half(starts + f * widths, upper) * widths,
        0.0,
        1.0,
        epsabs=ARC_LENGTH_QUAD_ABS,
        epsrel=1e-10,
        norm="max",
    )
    return np.concatenate([[0.0], np.cumsum(pieces)])


def test_gauss_legendre_table_agrees_with_adaptive_quadrature_within_its_tolerance():
    """The arc-length table (ARC_LENGTH_GAUSS_POINTS per interval) within ARC_LENGTH_QUAD_ABS of
    adaptive Gauss-Kronrod at every grid point: NACA 4-digit sections from thin to thick and
    strongly cambered, blunt trailing edges, and the coordinate files of examples/airfoils (whose
    speed is only piecewise
    smooth)."""
    from pathlib import Path

    from torus_cad.geometry.section.airfoil_file import load_airfoil_file
    from torus_cad.geometry.section.arc_length import surface_arc_length_table

    nacas = [
        NacaAirfoil(),
        NacaAirfoil(0.04, 0.4, 0.15, True),
        NacaAirfoil(0.09, 0.9, 0.6, False),
        NacaAirfoil(0.0, 0.5, 0.02, True),
        NacaAirfoil(0.06, 0.2, 0.3, False),
    ]
    files = [
        load_airfoil_file(path)
        for path in sorted((Path(__file__).parents[1] / "examples" / "airfoils").iterdir())
    ]
    sections = (
        nacas + files + [section.with_trailing_edge_gap(0.01) for section in (nacas[1], files[0])]
    )
    assert len(files) >= 3
    for section in sections:
        for upper in (True, False):
            table = surface_arc_length_table(section, upper)
            difference = np.abs(
                table.arc_length - _adaptive_table(section, upper, table.root_chord)
            ).max()
            assert difference <= ARC_LENGTH_QUAD_ABS, (section, upper, difference)
