"""Group statistics against hand-computed and published values (docs/statistics.md)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats as sps

from bladelab.errors import DataError
from bladelab.stats import RESULT_COLUMNS, compare_groups, kruskal_dunn, mann_whitney, summarize

# Three groups with ties (2, 5, 8 and 9 appear twice). Pooled and sorted (N = 14):
#   value 1  2   2   3 4 5   5   6 7 8    8    9    9    10
#   rank  1  2.5 2.5 4 5 6.5 6.5 8 9 10.5 10.5 12.5 12.5 14
A = [1, 2, 2, 4]  # ranks 1 + 2.5 + 2.5 + 5          = 11
B = [3, 5, 5, 7, 8]  # ranks 4 + 6.5 + 6.5 + 9 + 10.5  = 36.5
C = [6, 8, 9, 9, 10]  # ranks 8 + 10.5 + 12.5 + 12.5 + 14 = 57.5
RANK_SUMS = {"A": 11.0, "B": 36.5, "C": 57.5}
SIZES = {"A": 4, "B": 5, "C": 5}
N = 14
TIES = 4 * (2**3 - 2)  # four tie groups of two: Σ(t³ − t) = 24


def _table(**groups) -> pd.DataFrame:
    return pd.DataFrame([{"group": g, "value": v} for g, values in groups.items() for v in values])


def test_kruskal_wallis_and_dunn_with_ties_match_the_hand_computation():
    out = kruskal_dunn(_table(A=A, B=B, C=C), value="value", by="group")
    assert list(out.columns) == list(RESULT_COLUMNS)
    # H = [12/(N(N+1)) Σ R²/n − 3(N+1)] / [1 − Σ(t³−t)/(N³−N)]
    h_raw = 12 / (N * (N + 1)) * sum(RANK_SUMS[g] ** 2 / SIZES[g] for g in "ABC") - 3 * (N + 1)
    h = h_raw / (1 - TIES / (N**3 - N))
    assert h == pytest.approx(9.8264, abs=5e-5)  # (54.74 − 45)/0.991209, by hand
    kw = out.iloc[0]
    assert kw["test"] == "Kruskal-Wallis H" and kw["groups"] == "A | B | C"
    assert kw["statistic"] == pytest.approx(h, rel=1e-12)
    assert kw["p"] == pytest.approx(math.exp(-h / 2), rel=1e-12)  # χ² with 2 df: e^{−H/2}
    assert kw["n"] == "4 | 5 | 5"
    # Dunn: z = (R̄i − R̄j) / sqrt([N(N+1)/12 − Σ(t³−t)/(12(N−1))] (1/ni + 1/nj))
    unit = N * (N + 1) / 12 - TIES / (12 * (N - 1))
    dunn = out.iloc[1:].set_index("groups")
    assert list(dunn.index) == ["A | B", "A | C", "B | C"]
    for gi, gj in (("A", "B"), ("A", "C"), ("B", "C")):
        z = (RANK_SUMS[gi] / SIZES[gi] - RANK_SUMS[gj] / SIZES[gj]) / math.sqrt(
            unit * (1 / SIZES[gi] + 1 / SIZES[gj])
        )
        p = math.erfc(abs(z) / math.sqrt(2))  # two-sided normal
        row = dunn.loc[f"{gi} | {gj}"]
        assert row["z"] == pytest.approx(z, rel=1e-12)
        assert row["p"] == pytest.approx(p, rel=1e-10)
        assert row["p_adjusted"] == pytest.approx(min(1.0, 3 * p), rel=1e-10)
        assert row["effect_size_r"] == pytest.approx(z / math.sqrt(N))  # N of the H test
    assert dunn.loc["A | B", "z"] == pytest.approx(-1.62855, abs=1e-5)  # −4.55 / 2.79388
    # A vs C: z = −8.75/2.79388 = −3.1318, p = 0.00174, Bonferroni 0.0052 -> significant.
    assert bool(dunn.loc["A | C", "significant"])
    assert not bool(dunn.loc["B | C", "significant"])


def test_kruskal_wallis_matches_hollander_wolfe_example_and_scipy():
    # Hollander & Wolfe (1973, p. 116), the example of R's kruskal.test:
    # "Kruskal-Wallis chi-squared = 0.77143, df = 2, p-value = 0.68".
    x = [2.9, 3.0, 2.5, 2.6, 3.2]
    y = [3.8, 2.7, 4.0, 2.4]
    z = [2.8, 3.4, 3.7, 2.2, 2.0]
    kw = kruskal_dunn(_table(x=x, y=y, z=z), value="value", by="group").iloc[0]
    assert kw["statistic"] == pytest.approx(0.77143, abs=1e-5)
    assert kw["p"] == pytest.approx(0.68, abs=0.005)
    # With ties, scipy is an independent reference for H and p.
    ref = sps.kruskal(A, B, C)
    got = kruskal_dunn(_table(A=A, B=B, C=C), value="value", by="group").iloc[0]
    assert got["statistic"] == pytest.approx(ref.statistic, rel=1e-12)
    assert got["p"] == pytest.approx(ref.pvalue, rel=1e-12)


def test_mann_whitney_u_z_and_r_by_hand_and_against_scipy():
    # A vs B pooled (N = 9): 1 2 2 3 4 5 5 7 8 -> ranks 1 2.5 2.5 4 5 6.5 6.5 8 9.
    # R_A = 11, U_A = 11 − 4·5/2 = 1; σ² = 4·5/12 · (10 − 12/(9·8)) = 16.3889; Z = (1 − 10)/σ.
    out = mann_whitney(_table(A=A, B=B), value="value", by="group")
    row = out.iloc[0]
    sigma = math.sqrt(4 * 5 / 12 * (10 - 12 / 72))
    assert row["statistic"] == 1.0
    assert row["z"] == pytest.approx(-9 / sigma, rel=1e-12)
    assert row["z"] == pytest.approx(-2.22314, abs=1e-5)
    assert row["effect_size_r"] == pytest.approx(-9 / sigma / 3, rel=1e-12)  # Z/√9
    ref = sps.mannwhitneyu(A, B, alternative="two-sided")
    assert row["statistic"] == ref.statistic and row["p"] == pytest.approx(ref.pvalue)
    assert row["n"] == "4 | 5" and row["groups"] == "A | B"


def test_mann_whitney_published_example_hollander_wolfe():
    # R's wilcox.test example (Hollander & Wolfe 1973, p. 69), alternative "greater":
    # W = 35, p-value = 0.1272 (exact, no ties) -> two-sided p = 0.2544.
    x = [0.80, 0.83, 1.89, 1.04, 1.45, 1.38, 1.91, 1.64, 0.73, 1.46]
    y = [1.15, 0.88, 0.90, 0.74, 1.21]
    row = mann_whitney(_table(x=x, y=y), value="value", by="group").iloc[0]
    assert row["statistic"] == 35.0
    assert row["p"] == pytest.approx(2 * 0.1272, abs=2e-4)


def _cohort(rng: np.random.Generator) -> pd.DataFrame:
    rows = []
    for group, amp, k_mean, n in (
        ("TF", "TF", 14.0, 20),
        ("TT-A", "TT", 19.0, 10),
        ("TT-B", "TT", 21.0, 10),
        ("TT-C", "TT", 18.0, 10),
    ):
        for i in range(n):
            fast = i % 2 == 0
            rows.append(
                {
                    "group": group,
                    "amputation": amp,
                    "speed_pct_pb": 100.0 if fast else 60.0,
                    "K_Nm_per_deg": k_mean - (1.5 if fast else 0.0) + rng.normal(0, 0.6),
                    "D_Nms_per_deg": (0.2 if amp == "TF" else 0.4) + rng.normal(0, 0.03),
                }
            )
    return pd.DataFrame(rows)


def test_compare_groups_builds_the_seed_analysis_as_one_tidy_table():
    table = compare_groups(_cohort(np.random.default_rng(5)))
    assert list(table.columns) == list(RESULT_COLUMNS)
    k = table[table["parameter"] == "K_Nm_per_deg"]
    tests = k["test"].tolist()
    assert tests.count("Mann-Whitney U") == 1
    assert tests.count("Kruskal-Wallis H") == 1 and tests.count("Dunn (Bonferroni)") == 6
    band = k[k["test"] == "Mann-Whitney U (speed band)"]
    assert band["subset"].tolist() == [
        "all",
        "amputation=TF",
        "amputation=TT",
        "group=TF",
        "group=TT-A",
        "group=TT-B",
        "group=TT-C",
    ]
    assert (band["groups"] == "≥90% PB | <90% PB").all()
    # TF vs TT: all 20 TF values below all 30 TT values -> U = 0, |r| large.
    amp = k[k["test"] == "Mann-Whitney U"].iloc[0]
    assert amp["statistic"] == 0 and amp["effect_size_r"] < -0.5 and amp["significant"]
    assert amp["n"] == "20 | 30"


def test_summarize_gives_t_confidence_intervals():
    data = pd.DataFrame({"group": ["a", "a", "a", "b"], "K_Nm_per_deg": [1.0, 2.0, 3.0, 5.0]})
    out = summarize(data, values=["K_Nm_per_deg"], by=["group"]).set_index("group")
    half = 4.302653 / math.sqrt(3)  # t(0.975, 2) · s/√n with s = 1
    assert out.loc["a", "K_Nm_per_deg"] == 2.0 and out.loc["a", "n"] == 3
    assert out.loc["a", "K_Nm_per_deg_ci_low"] == pytest.approx(2 - half, abs=1e-6)
    assert out.loc["a", "K_Nm_per_deg_ci_high"] == pytest.approx(2 + half, abs=1e-6)
    assert np.isnan(out.loc["b", "K_Nm_per_deg_ci_low"])
    # a lower limit below the physical minimum is clipped and marked (as D* (−0.003, 0.458) was)
    clipped = summarize(data, values=["K_Nm_per_deg"], by=["group"],
                        lower_limits={"K_Nm_per_deg": 0.0}).set_index("group")
    assert 2 - half < 0 and clipped.loc["a", "K_Nm_per_deg_ci_low"] == 0.0
    assert clipped.loc["a", "K_Nm_per_deg_ci_clipped"] and not out.loc["a", "K_Nm_per_deg_ci_clipped"]
    assert clipped.loc["a", "K_Nm_per_deg_ci_high"] == pytest.approx(2 + half, abs=1e-6)
    from bladelab.report.tables import parameter_summary_display

    shown = parameter_summary_display(
        clipped.reset_index().assign(speed_band="all", D_Nms_per_deg=0.3, D_Nms_per_deg_ci_low=0.2,
                                     D_Nms_per_deg_ci_high=0.4))
    assert "(0.00‡–" in shown.iloc[0, 3]


def test_bad_tables_are_clear_errors():
    with pytest.raises(DataError, match="exactly two groups"):
        mann_whitney(_table(A=A, B=B, C=C), value="value", by="group")
    with pytest.raises(DataError, match="'K'"):
        kruskal_dunn(_table(A=A), value="K", by="group")
    with pytest.raises(DataError, match="missing columns"):
        compare_groups(_table(A=A, B=B))


def test_trials_are_nested_in_athletes():
    from bladelab.stats import athlete_means, speed_band, unit_of_analysis

    rng = np.random.default_rng(7)
    rows = []
    for amp, group, athletes in (("TF", "TF cat 2", ("TF1", "TF2", "TF3")),
                                 ("TT", "TT cat 5", ("TT1", "TT2", "TT3"))):
        for a in athletes:
            for i in range(6):
                rows.append({"athlete": a, "amputation": amp, "group": group,
                             "speed_pct_pb": 100.0 if i % 2 else 60.0,
                             "K_Nm_per_deg": (16 if amp == "TF" else 20) + rng.normal(0, 1),
                             "D_Nms_per_deg": 0.3 + rng.normal(0, 0.02)})
    trials = pd.DataFrame(rows)
    trials["speed_band"] = speed_band(trials["speed_pct_pb"])
    unit = unit_of_analysis(trials)
    assert unit.unit == "athlete" and unit.athletes_per_group["TF"] == ("TF1", "TF2", "TF3")
    assert "athlete means" in unit.statement
    means = athlete_means(trials, values=["K_Nm_per_deg", "D_Nms_per_deg"])
    assert len(means) == 12 and (means["n_trials"] == 3).all()  # 6 athletes × 2 speed bands
    tf1 = trials[(trials["athlete"] == "TF1") & (trials["speed_band"] == "≥90% PB")]
    row = means[(means["athlete"] == "TF1") & (means["speed_band"] == "≥90% PB")].iloc[0]
    assert row["K_Nm_per_deg"] == pytest.approx(tf1["K_Nm_per_deg"].mean())
    res = compare_groups(means)
    amp = res[(res["test"] == "Mann-Whitney U") & (res["parameter"] == "K_Nm_per_deg")].iloc[0]
    assert amp["n"] == "6 | 6"  # athlete × band means, not the 18 | 18 trials
    # one athlete per group: the tests describe that athlete's trials
    one = trials[trials["athlete"].isin(["TF1", "TT1"])]
    u1 = unit_of_analysis(one)
    assert u1.unit == "trial" and "ONE athlete" in u1.statement
    assert "TF: TF1" in u1.statement and "not a population" in u1.statement
    mixed = trials[~trials["athlete"].isin(["TT2", "TT3"])]
    assert unit_of_analysis(mixed).unit == "trial"
    assert "Some groups hold a single athlete" in unit_of_analysis(mixed).statement
