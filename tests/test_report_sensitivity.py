"""The sensitivity table behind the report's "How far to trust K* and D*" section."""

import pandas as pd
import pytest

from bladelab.errors import InputFileError
from bladelab.report.sensitivity import (
    SENSITIVITY_COLUMNS,
    read_sensitivity,
    sensitivity_figure,
    sensitivity_summary,
)


def _table() -> pd.DataFrame:
    rows = []
    # Ten stances at one condition with |K error| 1..10 % and D errors alternating in sign.
    for i in range(10):
        rows.append({"case": f"s{i}", "blade": "xtreme-cat5", "marker_rate_Hz": 100.0,
                     "marker_noise_mm": 1.0, "formulation": "utilised-friction",
                     "K_err_pct": float(i + 1) * (-1) ** i, "D_err_pct": 2.0 * (i + 1),
                     "K_ci_halfwidth_pct": 3.0, "D_ci_halfwidth_pct": 6.0})
    return pd.DataFrame(rows)


def test_summary_statistics_by_hand():
    row = sensitivity_summary(_table()).iloc[0]
    assert row["n_stances"] == 10
    assert row["K_abs_error_median_pct"] == pytest.approx(5.5)  # median of 1..10
    # numpy's linear 90th percentile of 1..10: 1 + 0.9 * 9 = 9.1
    assert row["K_abs_error_p90_pct"] == pytest.approx(9.1)
    assert row["D_abs_error_median_pct"] == pytest.approx(11.0)
    assert row["K_ci_halfwidth_median_pct"] == pytest.approx(3.0)


def test_missing_columns_name_the_file(tmp_path):
    bad = tmp_path / "s.csv"
    _table().drop(columns=["D_err_pct"]).to_csv(bad, index=False)
    with pytest.raises(InputFileError, match="D_err_pct") as err:
        read_sensitivity(bad)
    assert str(bad) in str(err.value)
    with pytest.raises(InputFileError, match="not found"):
        read_sensitivity(tmp_path / "none.csv")


def test_packaged_table_covers_both_formulations_and_rates():
    table = read_sensitivity()
    assert set(SENSITIVITY_COLUMNS) <= set(table.columns)
    assert {"seed", "utilised-friction"} <= set(table["formulation"])
    assert len(set(table["marker_rate_Hz"])) >= 2 and table["marker_noise_mm"].nunique() >= 3
    fig = sensitivity_figure(table)
    assert len(fig.axes) == 2 and all(ax.lines for ax in fig.axes)
