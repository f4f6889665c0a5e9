"""Response surfaces: exact recovery, and statistics against statsmodels' OLS."""

from __future__ import annotations

import numpy as np
import pytest
import statsmodels.api as sm
from statsmodels.stats.outliers_influence import OLSInfluence

from bladelab.design.doe import box_behnken, central_composite
from bladelab.design.surfaces import fit_surface
from bladelab.design.terms import model_matrix, model_terms
from bladelab.errors import DataError, SpecError

NAMES = ("k", "w", "h", "t")


def _quadratic(c: np.ndarray) -> np.ndarray:
    k, w, h, t = c.T
    return (3.0 + 1.5 * k - 0.7 * w + 0.2 * h + 0.05 * t + 0.4 * k * w - 0.3 * h * t
            - 0.8 * k**2 + 0.25 * t**2)


def test_recovers_noise_free_quadratic_exactly():
    d = central_composite(4)
    y = _quadratic(d.coded)
    s = fit_surface(d.coded, y, factor_names=NAMES, model="quadratic")
    truth = dict(zip(s.term_names, np.zeros(15), strict=True))
    truth.update({"1": 3.0, "k": 1.5, "w": -0.7, "h": 0.2, "t": 0.05, "k*w": 0.4, "h*t": -0.3,
                  "k^2": -0.8, "t^2": 0.25})
    np.testing.assert_allclose(s.coef, [truth[n] for n in s.term_names], atol=1e-12)
    assert s.r2 == pytest.approx(1.0, abs=1e-12)
    assert s.loo_rmse < 1e-10
    # off-design prediction is exact too
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1, 1, size=(20, 4))
    np.testing.assert_allclose(s.predict_mean(pts), _quadratic(pts), atol=1e-11)
    # the gradient matches finite differences
    p0 = pts[0]
    num = [(_quadratic((p0 + e)[None]) - _quadratic((p0 - e)[None]))[0] / 2e-6
           for e in np.eye(4) * 1e-6]
    np.testing.assert_allclose(s.gradient(p0), num, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("design", ["ccd3", "bbd"])
def test_statistics_equal_statsmodels(design):
    d = central_composite(4, n_center=3) if design == "ccd3" else box_behnken(4, n_center=3)
    rng = np.random.default_rng(7)
    y = _quadratic(d.coded) + rng.normal(0.0, 0.1, d.n_runs)
    s = fit_surface(d.coded, y, factor_names=NAMES, response="v", unit="m/s")
    X = model_matrix(d.coded, model_terms(4))
    res = sm.OLS(y, X).fit()
    infl = OLSInfluence(res)
    assert s.press == pytest.approx(infl.ess_press, rel=1e-10)
    assert s.r2 == pytest.approx(res.rsquared, rel=1e-10)
    assert s.r2_adj == pytest.approx(res.rsquared_adj, rel=1e-10)
    assert s.r2_pred == pytest.approx(1.0 - infl.ess_press / res.centered_tss, rel=1e-10)
    np.testing.assert_allclose(s.leverage, infl.hat_matrix_diag, rtol=1e-10)
    np.testing.assert_allclose(s.coef, res.params, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(s.se, res.bse, rtol=1e-10)
    tab = s.coefficients()
    np.testing.assert_allclose(tab["p_value"], res.pvalues, rtol=1e-8, atol=1e-14)
    # overall F of the model row
    model_row = s.anova.set_index("source").loc["model"]
    assert model_row["F"] == pytest.approx(res.fvalue, rel=1e-10)
    assert model_row["p_value"] == pytest.approx(res.f_pvalue, rel=1e-6, abs=1e-300)
    # per-term partial F = t^2 (drop-one test)
    term_rows = s.anova.set_index("source").loc[list(s.term_names[1:])]
    np.testing.assert_allclose(term_rows["F"], res.tvalues[1:] ** 2, rtol=1e-10)
    # intervals
    rng2 = np.random.default_rng(1)
    pts = rng2.uniform(-1, 1, size=(6, 4))
    pred = s.predict(pts, level=0.9)
    frame = res.get_prediction(model_matrix(pts, model_terms(4))).summary_frame(alpha=0.1)
    np.testing.assert_allclose(pred.mean, frame["mean"], rtol=1e-10)
    np.testing.assert_allclose(pred.ci_lower, frame["mean_ci_lower"], rtol=1e-9)
    np.testing.assert_allclose(pred.pi_upper, frame["obs_ci_upper"], rtol=1e-9)
    # lack of fit + pure error from the 3 replicated centre points add up to the residual
    a = s.anova.set_index("source")
    assert a.loc["pure_error", "df"] == 2
    assert a.loc["lack_of_fit", "sum_sq"] + a.loc["pure_error", "sum_sq"] == pytest.approx(
        a.loc["residual", "sum_sq"])
    assert a.loc["lack_of_fit", "df"] + 2 == a.loc["residual", "df"]
    # the leave-one-out residual is the real refit residual (one check by brute force)
    i = 4
    keep = np.arange(d.n_runs) != i
    refit = sm.OLS(y[keep], X[keep]).fit()
    assert s.loo_residuals()[i] == pytest.approx(y[i] - X[i] @ refit.params, rel=1e-9)


def test_term_subset_and_tables():
    d = central_composite(4)
    y = 1.0 + 2.0 * d.coded[:, 0] - d.coded[:, 1] ** 2
    s = fit_surface(d.coded, y, factor_names=NAMES, model="k,w^2", response="r", unit="N")
    assert s.term_names == ("1", "k", "w^2")
    np.testing.assert_allclose(s.coef, [1.0, 2.0, -1.0], atol=1e-12)
    tab = s.coefficients()
    assert list(tab.columns[:3]) == ["response", "term", "estimate"]
    d_ = s.to_dict()
    assert d_["coefficients"]["k"] == pytest.approx(2.0)
    assert s.label == "r [N]"


def test_refuses_model_the_design_cannot_estimate():
    rng = np.random.default_rng(0)
    coded = rng.choice([-1.0, 0.0, 1.0], size=(9, 4))
    with pytest.raises(SpecError, match="9 runs cannot estimate the 15-term model") as err:
        fit_surface(coded, rng.normal(size=9), factor_names=NAMES)
    assert "reduced model" in err.value.hint


def test_bad_response_values():
    d = central_composite(4)
    y = _quadratic(d.coded)
    y[3] = np.nan
    with pytest.raises(DataError, match="run 4"):
        fit_surface(d.coded, y, factor_names=NAMES)
    with pytest.raises(DataError):
        fit_surface(d.coded, y[:5], factor_names=NAMES)


def test_degenerate_responses_give_no_spurious_statistics():
    d = central_composite(4)
    const = fit_surface(d.coded, np.full(d.n_runs, 2.5), factor_names=NAMES)
    assert np.isnan(const.r2) and np.isnan(const.r2_pred)
    assert const.anova["F"].isna().all()
    assert const.to_dict()["r2"] is None
    exact = fit_surface(d.coded, 0.1 * d.coded[:, 1], factor_names=NAMES)
    a = exact.anova.set_index("source")
    assert a.loc["w", "F"] == np.inf and a.loc["w", "p_value"] == 0.0
    assert np.isnan(a.loc["k", "F"])  # a zero effect fitted exactly: no test possible
