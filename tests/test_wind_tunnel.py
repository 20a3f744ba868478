"""The wind-tunnel data reader and the comparison that validation runs are judged by
(studies/wind_tunnel.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studies.wind_tunnel import (
    APC_10X7SF,
    Comparison,
    Measured,
    WindTunnelFormatError,
    markdown_table,
    read_table,
    read_wind_tunnel,
)


def test_the_shipped_apc_data_reads_with_every_sweep_merged_by_rpm() -> None:
    data = read_wind_tunnel(APC_10X7SF)
    assert sorted(data.sweeps) == [3000, 4000, 5000, 6000]
    assert len(data.static.rows) == 16
    # 5003 and 5006 rpm are one sweep over J from 0.114 to 0.953, in order of J.
    j = data.sweeps[5000].column("J")
    assert (
        j[0] == pytest.approx(0.114) and j[-1] == pytest.approx(0.953) and np.all(np.diff(j) >= 0.0)
    )


def test_each_sweep_row_s_efficiency_is_j_ct_over_cp_to_the_file_s_rounding() -> None:
    for table in read_wind_tunnel(APC_10X7SF).sweeps.values():
        # past zero thrust, CP's 4 decimals dominate eta
        thrusting = table.rows[table.column("CT") > 0.0]
        j, ct, cp, eta = thrusting.T
        assert len(thrusting) >= 10 and np.max(np.abs(j * ct / cp - eta)) < 0.004


def test_a_measured_row_is_returned_as_it_is_and_between_rows_linearly() -> None:
    data = read_wind_tunnel(APC_10X7SF)
    row = data.static_point(5015.0)
    assert (row.ct, row.cp, row.efficiency) == (pytest.approx(0.1564), pytest.approx(0.0763), None)
    middle = data.static_point((4782.0 + 5015.0) / 2.0)
    assert middle.ct == pytest.approx((0.1545 + 0.1564) / 2.0)
    assert data.sweep_point(4990.0, 0.2).rpm == 5000.0


def test_nothing_is_extrapolated_beyond_the_measured_range() -> None:
    data = read_wind_tunnel(APC_10X7SF)
    with pytest.raises(ValueError, match="outside the measured range"):
        data.static_point(7000.0)
    with pytest.raises(ValueError, match=r"J = 1\.2 is outside"):
        data.sweep_point(5000.0, 1.2)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("RPM CP CT\n1 2 3\n4 5 6\n", "line 1: expected the header RPM CT CP"),
        ("RPM CT CP\n1 2 3\n4 5\n", "line 3: 2 values, expected 3"),
        ("RPM CT CP\n1 2 3\n4 x 6\n", "line 3: not a number"),
        ("RPM CT CP\n1 2 nan\n4 5 6\n", "line 2: not a finite number"),
        ("RPM CT CP\n1 2 3\n", "fewer than two rows"),
    ],
)
def test_a_malformed_file_is_refused_naming_its_line(
    tmp_path: Path, text: str, message: str
) -> None:
    path = tmp_path / "data.txt"
    path.write_text(text, encoding="ascii")
    with pytest.raises(WindTunnelFormatError, match=message):
        read_table(path, ("RPM", "CT", "CP"))


def test_errors_and_targets_of_a_comparison() -> None:
    measured = Measured(5000.0, 0.4, 0.10, 0.05)
    close = Comparison(measured, ct=0.109, cp=0.046)
    assert close.ct_error == pytest.approx(0.09) and close.cp_error == pytest.approx(-0.08)
    assert close.efficiency == pytest.approx(0.4 * 0.109 / 0.046)
    assert close.efficiency_error == pytest.approx(0.4 * 0.109 / 0.046 - 0.8)
    assert not close.within_targets  # eta 0.948 against 0.8: 0.148 off, over 0.05
    assert Comparison(measured, ct=0.104, cp=0.052).within_targets
    # CT +13 %
    assert not Comparison(Measured(5000.0, 0.0, 0.15, 0.07), ct=0.17, cp=0.07).within_targets
    table = markdown_table([close])
    assert "| 5000 | 0.40 | 0.1000 | 0.1090 | +9.0 % |" in table and table.endswith("| no |")
