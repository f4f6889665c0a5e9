"""Reduced second-order surfaces: backward elimination of the full quadratic, per response.

The model ``"reduced"`` of a study (:data:`bladelab.design.terms.MODELS`) starts every
response from the full quadratic and removes, one at a time, the term with the largest p-value
above :data:`REDUCTION_ALPHA` among the terms no remaining term contains (a linear term stays
while its factor's interaction or square does: the model stays hierarchical), refitting each
time (Montgomery, *Design and Analysis of Experiments*, and Myers, Montgomery & Anderson-Cook,
*Response Surface Methodology*: the textbook reduction of a fitted second-order model). Each
response gets its own terms; the intercept and the linear terms of every factor are kept when
they are significant or hold a higher term.

A reduced surface's PRESS R² is computed on the terms chosen from all runs, so it flatters: the
left-out run took part in the choice. :func:`fit_reduced` therefore also reports
``r2_pred_selected``, the predicted R² with the whole selection repeated without each run
(nested leave-one-out): that is the number to compare with the full quadratic's R²pred.
:func:`fit_response` fits either kind of model by name.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from scipy import stats

from bladelab.design.surfaces import ResponseSurface, fit_surface
from bladelab.design.terms import Term, model_matrix, model_terms

__all__ = ["REDUCED_MODEL", "REDUCTION_ALPHA", "backward_terms", "fit_reduced",
           "fit_response"]

#: The study model whose surfaces are reduced from the full quadratic, response by response.
REDUCED_MODEL = "reduced"
#: Largest p-value of a term kept by the reduction (Montgomery's customary 0.10).
REDUCTION_ALPHA = 0.10


def _holds(term: Term, other: Term) -> bool:
    """True if ``other`` is a higher term containing ``term`` (A in A*B or A^2)."""
    return len(other) > len(term) and all(other.count(f) >= term.count(f) for f in set(term))


def backward_terms(coded: np.ndarray, y: np.ndarray, n_factors: int, *,
                   alpha: float = REDUCTION_ALPHA) -> tuple[Term, ...]:
    """The hierarchical backward elimination of the full quadratic (module docstring): the
    terms kept, intercept first. ``coded``: (n_runs, n_factors) in [-1, 1]; ``y``: responses."""
    terms = list(model_terms(n_factors, "quadratic"))
    y = np.asarray(y, float)
    while True:
        # by hand, not with fit_surface: a subset of the runs (a fold of the PRESS, the clean
        # runs of a study) can alias terms, where fit_surface refuses and the pseudo-inverse
        # gives the aliased terms no weight
        x = model_matrix(coded, terms)
        n, p = x.shape
        if n <= p:
            return tuple(terms)
        coef, *_ = np.linalg.lstsq(x, y, rcond=None)
        resid = y - x @ coef
        sigma2 = float(resid @ resid) / (n - p)
        se = np.sqrt(np.maximum(np.diag(np.linalg.pinv(x.T @ x)), 0.0) * sigma2)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(se > 0, np.abs(coef) / np.where(se > 0, se, 1.0), np.inf)
        p_value = 2.0 * stats.t.sf(t, n - p)
        free = [k for k, term in enumerate(terms)
                if term and not any(_holds(term, other) for other in terms)]
        if not free:
            return tuple(terms)
        worst = max(free, key=lambda k: p_value[k])
        if p_value[worst] <= alpha:
            return tuple(terms)
        terms.pop(worst)


def fit_reduced(coded: np.ndarray, y: np.ndarray | Sequence[float], *,
                factor_names: Sequence[str], response: str = "y", unit: str = "",
                alpha: float = REDUCTION_ALPHA) -> ResponseSurface:
    """The reduced surface of one response (:func:`backward_terms`, then
    :func:`~bladelab.design.surfaces.fit_surface` on its terms), with ``r2_pred_selected``:
    1 − PRESS/SS_total where each run is predicted by a surface whose terms were chosen and
    fitted without it [-]."""
    coded = np.atleast_2d(np.asarray(coded, float))
    y = np.asarray(y, float).reshape(-1)
    k = coded.shape[1]
    surface = fit_surface(coded, y, factor_names=factor_names, response=response, unit=unit,
                          model=backward_terms(coded, y, k, alpha=alpha))
    press = 0.0
    for i in range(y.size):
        keep = np.arange(y.size) != i
        terms = backward_terms(coded[keep], y[keep], k, alpha=alpha)
        x = model_matrix(coded, terms)
        coef, *_ = np.linalg.lstsq(x[keep], y[keep], rcond=None)
        press += float((y[i] - x[i] @ coef) ** 2)
    sst = float(np.sum((y - y.mean()) ** 2))
    nested = 1.0 - press / sst if sst > 0 else float("nan")
    return dataclasses.replace(surface, r2_pred_selected=nested, selection=(
        f"reduced from the full quadratic (backward elimination, hierarchical, terms kept at "
        f"p <= {alpha:g})"))


def fit_response(coded: np.ndarray, y: np.ndarray | Sequence[float], *, model,
                 factor_names: Sequence[str], response: str = "y",
                 unit: str = "") -> ResponseSurface:
    """One response's surface of a study's ``model``: :data:`REDUCED_MODEL` reduces the full
    quadratic (:func:`fit_reduced`); any other model or term list is fitted as it is
    (:func:`~bladelab.design.surfaces.fit_surface`)."""
    if isinstance(model, str) and model == REDUCED_MODEL:
        return fit_reduced(coded, y, factor_names=factor_names, response=response, unit=unit)
    return fit_surface(coded, y, factor_names=factor_names, model=model, response=response,
                       unit=unit)
