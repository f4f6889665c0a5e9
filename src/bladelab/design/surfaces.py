"""Second-order response surfaces fitted by least squares, with their statistics.

:func:`fit_surface` fits ``y = Σ b_j f_j(c)`` over coded design points ``c`` for a full quadratic
model or any term subset (always with the intercept) and returns a :class:`ResponseSurface`:

- R², adjusted R², predicted R² = 1 − PRESS/SS_total with PRESS = Σ (e_i / (1 − h_ii))² from the
  hat-matrix diagonal h (no refits), and the leave-one-out RMSE = sqrt(PRESS / n);
- ANOVA: model (regression), each term (partial, "type III" sum of squares b_j²/(XᵀX)⁻¹_jj with
  1 df, F = t²), residual, lack of fit and pure error where replicated points exist, total;
- coefficients with standard errors, t and p values, confidence intervals;
- predictions with confidence intervals (of the mean surface) and prediction intervals (of a new
  observation).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from bladelab.design.doe import require_estimable
from bladelab.design.terms import Term, model_matrix, parse_terms, term_name
from bladelab.errors import DataError, SpecError

__all__ = ["EXACT_FIT_LEVERAGE", "ResponseSurface", "SurfacePrediction", "fit_surface"]

#: A run with leverage h_ii at least this is fitted exactly whatever its value (h_ii = 1 to
#: round-off): it has no leave-one-out prediction, so PRESS and R²pred are undefined.
EXACT_FIT_LEVERAGE = 1.0 - 1e-10


@dataclass(frozen=True, eq=False)
class SurfacePrediction:
    """Predictions at m points with two-sided intervals at ``level``.

    ``mean``, ``se_mean`` (standard error of the fitted mean), ``ci_lower``/``ci_upper``
    (confidence interval of the mean surface), ``pi_lower``/``pi_upper`` (prediction interval of a
    new observation), all arrays of length m in the response's unit.
    """

    mean: np.ndarray
    se_mean: np.ndarray
    ci_lower: np.ndarray
    ci_upper: np.ndarray
    pi_lower: np.ndarray
    pi_upper: np.ndarray
    level: float

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame(
            {
                "mean": self.mean,
                "se_mean": self.se_mean,
                "ci_lower": self.ci_lower,
                "ci_upper": self.ci_upper,
                "pi_lower": self.pi_lower,
                "pi_upper": self.pi_upper,
            }
        )

    def to_dict(self) -> dict:
        d = {k: v.tolist() for k, v in self.to_frame().items()}
        d["level"] = self.level
        return d


@dataclass(frozen=True, eq=False)
class ResponseSurface:
    """A fitted response surface over coded factors.

    Attributes
    ----------
    response, unit
        Name and unit of the response.
    factor_names
        Factor names, in column order of the coded points.
    terms
        Model terms (see :mod:`bladelab.design.terms`).
    coef, se
        Coefficients (coded units) and their standard errors.
    n, df_resid
        Number of runs and residual degrees of freedom.
    sigma
        Residual standard deviation sqrt(SSE / df_resid).
    r2, r2_adj, r2_pred
        R², adjusted R², predicted R² (from PRESS); ``r2_pred`` is NaN if a run has leverage 1.
    press, loo_rmse
        PRESS and the leave-one-out RMSE sqrt(PRESS / n) [response unit].
    coded, y, fitted, leverage
        The data, fitted values and hat-matrix diagonal.
    r2_pred_selected, selection
        For a surface whose terms were chosen from the data
        (:func:`~bladelab.design.reduction.fit_reduced`): the predicted R² with the choice
        repeated without each run, and how the terms were chosen; NaN and "" otherwise.
    """

    response: str
    unit: str
    factor_names: tuple[str, ...]
    terms: tuple[Term, ...]
    coef: np.ndarray
    se: np.ndarray
    xtx_inv: np.ndarray = field(repr=False)
    n: int
    df_resid: int
    sigma: float
    sse: float
    sst: float
    r2: float
    r2_adj: float
    r2_pred: float
    press: float
    loo_rmse: float
    coded: np.ndarray = field(repr=False)
    y: np.ndarray = field(repr=False)
    fitted: np.ndarray = field(repr=False)
    leverage: np.ndarray = field(repr=False)
    anova: pd.DataFrame = field(repr=False)
    r2_pred_selected: float = float("nan")
    selection: str = ""

    @property
    def term_names(self) -> tuple[str, ...]:
        return tuple(term_name(t, self.factor_names) for t in self.terms)

    @property
    def label(self) -> str:
        """``"response [unit]"`` for plot axes."""
        return f"{self.response} [{self.unit}]" if self.unit else self.response

    def _t_crit(self, level: float) -> float:
        if not 0.0 < level < 1.0:
            raise SpecError(f"level must lie in (0, 1), got {level}", where="level")
        return float(stats.t.ppf(0.5 + 0.5 * level, self.df_resid))

    def predict_mean(self, coded: np.ndarray | Sequence) -> np.ndarray | float:
        """Fitted surface at coded points (shape (m, k) -> (m,), or one point -> float)."""
        arr = np.asarray(coded, dtype=float)
        single = arr.ndim == 1
        X = model_matrix(np.atleast_2d(arr), self.terms)
        out = X @ self.coef
        return float(out[0]) if single else out

    def predict(self, coded: np.ndarray | Sequence, *, level: float = 0.95) -> SurfacePrediction:
        """Predictions with confidence and prediction intervals at coded points.

        Parameters
        ----------
        coded
            Coded points, shape (m, k) or (k,).
        level
            Two-sided confidence level of the intervals.
        """
        X = model_matrix(np.atleast_2d(np.asarray(coded, dtype=float)), self.terms)
        if X.shape[0] and np.atleast_2d(np.asarray(coded)).shape[1] != len(self.factor_names):
            raise SpecError(
                f"points must have {len(self.factor_names)} coded columns", where="predict"
            )
        mean = X @ self.coef
        h0 = np.einsum("ij,jk,ik->i", X, self.xtx_inv, X)
        se_mean = self.sigma * np.sqrt(np.maximum(h0, 0.0))
        se_obs = self.sigma * np.sqrt(1.0 + np.maximum(h0, 0.0))
        t = self._t_crit(level)
        return SurfacePrediction(
            mean, se_mean, mean - t * se_mean, mean + t * se_mean,
            mean - t * se_obs, mean + t * se_obs, level,
        )

    def gradient(self, coded: np.ndarray | Sequence) -> np.ndarray:
        """Gradient of the fitted surface with respect to the coded factors at one point."""
        c = np.asarray(coded, dtype=float).reshape(-1)
        g = np.zeros(len(self.factor_names))
        for b, term in zip(self.coef, self.terms, strict=True):
            if len(term) == 1:
                g[term[0]] += b
            elif len(term) == 2:
                i, j = term
                if i == j:
                    g[i] += 2.0 * b * c[i]
                else:
                    g[i] += b * c[j]
                    g[j] += b * c[i]
        return g

    def coefficients(self, *, level: float = 0.95) -> pd.DataFrame:
        """Tidy coefficient table: term, estimate, std_error, t, p_value, ci_lower, ci_upper."""
        with np.errstate(divide="ignore", invalid="ignore"):
            tval = np.where(self.se > 0, self.coef / np.where(self.se > 0, self.se, 1.0), np.inf)
        tval = np.where((self.se == 0) & (self.coef == 0), 0.0, tval)
        p = 2.0 * stats.t.sf(np.abs(tval), self.df_resid)
        tc = self._t_crit(level)
        return pd.DataFrame(
            {
                "response": self.response,
                "term": list(self.term_names),
                "estimate": self.coef,
                "std_error": self.se,
                "t": tval,
                "p_value": p,
                "ci_lower": self.coef - tc * self.se,
                "ci_upper": self.coef + tc * self.se,
            }
        )

    def loo_residuals(self) -> np.ndarray:
        """Leave-one-out (deleted) residuals e_i / (1 − h_ii); NaN where h_ii = 1."""
        e = self.y - self.fitted
        ok = self.leverage < EXACT_FIT_LEVERAGE
        out = np.full_like(e, np.nan)
        out[ok] = e[ok] / (1.0 - self.leverage[ok])
        return out

    def to_dict(self) -> dict:
        return {
            "response": self.response,
            "unit": self.unit,
            "factors": list(self.factor_names),
            "terms": list(self.term_names),
            "coefficients": {n: float(b) for n, b in zip(self.term_names, self.coef, strict=True)},
            "std_errors": {n: float(s) for n, s in zip(self.term_names, self.se, strict=True)},
            "n_runs": self.n,
            "df_resid": self.df_resid,
            "sigma": self.sigma,
            "r2": _json_float(self.r2),
            "r2_adj": _json_float(self.r2_adj),
            "r2_pred": _json_float(self.r2_pred),
            "press": _json_float(self.press),
            "loo_rmse": _json_float(self.loo_rmse),
            **({"r2_pred_selected": _json_float(self.r2_pred_selected),
                "selection": self.selection} if self.selection else {}),
            "anova": [
                {k: _json_float(v) if isinstance(v, float) else v for k, v in row.items()}
                for row in self.anova.to_dict(orient="records")
            ],
        }


def _json_float(v: float) -> float | None:
    v = float(v)
    return v if np.isfinite(v) else None


def _noise_floor(y: np.ndarray) -> float:
    """Sums of squares below this are round-off of a response of this size."""
    return 1e-20 * max(float(y @ y), 1e-300)


def _anova(
    X: np.ndarray,
    y: np.ndarray,
    coded: np.ndarray,
    coef: np.ndarray,
    xtx_inv: np.ndarray,
    names: Sequence[str],
    terms: Sequence[Term],
    sse: float,
    sst: float,
    df_resid: int,
    response: str,
) -> pd.DataFrame:
    n, p = X.shape
    mse = sse / df_resid
    rows = []
    floor = _noise_floor(y)  # sums of squares below this are round-off

    def f_p(ss: float, df1: int, ss_err: float, df2: int) -> tuple[float, float]:
        if ss_err > floor:
            f = (ss / df1) / (ss_err / df2)
            return f, float(stats.f.sf(f, df1, df2))
        return (float("inf"), 0.0) if ss > floor else (float("nan"), float("nan"))

    ssr = max(sst - sse, 0.0)
    f, pv = f_p(ssr, p - 1, sse, df_resid) if p > 1 else (np.nan, np.nan)
    rows.append(("model", ssr, p - 1, ssr / (p - 1) if p > 1 else np.nan, f, pv))
    for j, term in enumerate(terms):
        if not term:
            continue
        ss = coef[j] ** 2 / xtx_inv[j, j]
        f, pv = f_p(ss, 1, sse, df_resid)
        rows.append((term_name(term, names), ss, 1, ss, f, pv))
    rows.append(("residual", sse, df_resid, mse, np.nan, np.nan))
    # replicates: pure error and lack of fit
    keys = np.round(coded, 9)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    group = np.asarray(group).reshape(-1)
    n_groups = int(group.max()) + 1
    df_pe = n - n_groups
    df_lof = df_resid - df_pe
    if df_pe > 0 and df_lof > 0:
        means = np.bincount(group, weights=y, minlength=n_groups) / np.bincount(group)
        sspe = float(np.sum((y - means[group]) ** 2))
        sslof = max(sse - sspe, 0.0)
        f, pv = f_p(sslof, df_lof, sspe, df_pe)
        rows.append(("lack_of_fit", sslof, df_lof, sslof / df_lof, f, pv))
        rows.append(("pure_error", sspe, df_pe, sspe / df_pe, np.nan, np.nan))
    rows.append(("total", sst, n - 1, np.nan, np.nan, np.nan))
    df = pd.DataFrame(rows, columns=["source", "sum_sq", "df", "mean_sq", "F", "p_value"])
    df.insert(0, "response", response)
    return df


def fit_surface(
    coded: np.ndarray,
    y: np.ndarray | Sequence[float],
    *,
    factor_names: Sequence[str],
    model: str | Sequence = "quadratic",
    response: str = "y",
    unit: str = "",
) -> ResponseSurface:
    """Fit a response surface by least squares.

    Parameters
    ----------
    coded
        Coded design points, shape (n_runs, n_factors), values in [-1, 1].
    y
        The response at each run [response unit].
    factor_names
        Names of the factors (columns of ``coded``).
    model
        ``"quadratic"`` (default), ``"linear"``, ``"interaction"``, ``"pure_quadratic"``, or a
        list / comma-separated string of terms such as ``"A,B,A*B,A^2"`` (intercept implied).
    response, unit
        Name and unit of the response, for tables and plots.

    Raises
    ------
    SpecError
        If the design cannot estimate the model or leaves no residual degree of freedom (the
        message suggests a reduced model).
    DataError
        If ``y`` has the wrong length or non-finite values.
    """
    coded = np.atleast_2d(np.asarray(coded, dtype=float))
    y = np.asarray(y, dtype=float).reshape(-1)
    names = tuple(str(n) for n in factor_names)
    if coded.shape[1] != len(names):
        raise SpecError(
            f"coded points have {coded.shape[1]} columns but {len(names)} factor names",
            where="fit_surface",
        )
    if y.shape[0] != coded.shape[0]:
        raise DataError(
            f"{y.shape[0]} responses for {coded.shape[0]} runs", where=f"response {response}"
        )
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise DataError(
            f"run {int(bad[0]) + 1} has a non-finite value ({y[bad[0]]})",
            where=f"response {response}",
            hint="check the evaluator output for that run, or leave the run out",
        )
    terms = parse_terms(model, names)
    if terms[0] != ():
        terms = ((),) + tuple(t for t in terms if t != ())
    require_estimable(coded, terms, names)
    X = model_matrix(coded, terms)
    n, p = X.shape
    Q, R = np.linalg.qr(X)
    coef = np.linalg.solve(R, Q.T @ y)
    r_inv = np.linalg.solve(R, np.eye(p))
    xtx_inv = r_inv @ r_inv.T
    fitted = X @ coef
    resid = y - fitted
    lev = np.sum(Q**2, axis=1)
    df_resid = n - p
    sse = float(resid @ resid)
    sst = float(np.sum((y - y.mean()) ** 2))
    sigma2 = sse / df_resid
    se = np.sqrt(np.maximum(np.diag(xtx_inv), 0.0) * sigma2)
    if sst > _noise_floor(y):
        r2 = 1.0 - sse / sst
        r2_adj = 1.0 - (sse / df_resid) / (sst / (n - 1))
    else:
        r2 = r2_adj = float("nan")
    if np.all(lev < EXACT_FIT_LEVERAGE):
        press = float(np.sum((resid / (1.0 - lev)) ** 2))
        r2_pred = 1.0 - press / sst if sst > _noise_floor(y) else float("nan")
        loo_rmse = float(np.sqrt(press / n))
    else:  # a run with leverage 1 is fitted exactly whatever its value: no LOO prediction
        press = r2_pred = loo_rmse = float("nan")
    anova = _anova(X, y, coded, coef, xtx_inv, names, terms, sse, sst, df_resid, response)
    return ResponseSurface(
        response=response,
        unit=unit,
        factor_names=names,
        terms=tuple(terms),
        coef=coef,
        se=se,
        xtx_inv=xtx_inv,
        n=n,
        df_resid=df_resid,
        sigma=float(np.sqrt(sigma2)),
        sse=sse,
        sst=sst,
        r2=float(r2),
        r2_adj=float(r2_adj),
        r2_pred=float(r2_pred),
        press=press,
        loo_rmse=loo_rmse,
        coded=coded.copy(),
        y=y.copy(),
        fitted=fitted,
        leverage=lev,
        anova=anova,
    )
