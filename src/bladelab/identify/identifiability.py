"""How well are the identified parameters determined? Landscape, correlation, confidence intervals.

Works on a *residual batch* function ``(m, d) -> (m, n_res)`` (for a stance:
:meth:`bladelab.identify.cost.StanceCost.residuals` of simulated signals), whose residual sum of
squares RSS(θ) = ‖r(θ)‖² is the least-squares analogue of the identification cost.

- **Correlation** (and an approximate covariance) from the Gauss–Newton Hessian at the optimum:
  cov = s²·(JᵀJ)⁻¹, s² = RSS/(n_eff − d), J by central differences (one batch).
- **Confidence intervals** by **profile likelihood** on the RSS: for each parameter θ_i on a grid,
  the other parameters are re-optimised (batched Levenberg–Marquardt) and the interval is the set
  where (RSS_i(θ_i) − RSS_min)/s² ≤ F₁,ₙ₋d(level). For a linear model this is exactly the classical
  t interval; for the simulation it follows the true, curved valley (compensation shows up as a
  flat profile). Profiles are chosen over a residual bootstrap because they need no re-identification
  (a few hundred batched simulations instead of hundreds of optimisations).
- **Autocorrelated residuals**: by default (``variance="hac"``) each parameter's profile is read
  against s²·c_i, s² = RSS/(n − d) and c_i ≥ 1 its Newey–West variance inflation computed per
  measured channel (:func:`hac_inflation`), with n_eff,i = n/c_i; ``variance="ar1"`` uses one
  n_eff = n·(1 − ρ₁)/(1 + ρ₁) for all (the earlier default, which under-covered D:
  benchmarks/bench_coverage.py).
- **Re-centring**: the search minimises J (a sum of nRMSEs), the profiles the RSS (a sum of their
  squares); when a profile finds an RSS lower than at ``x_opt`` by more than a tenth of the interval
  threshold (ΔRSS/s² > 0.1·F), that point becomes the estimate and the analysis starts again there
  (at most ``max_recentre`` times). The estimate always lies inside its own interval (an interval
  that would miss it, e.g. a multimodal profile, is widened, with a note); limits below a
  parameter's physical minimum (``physical_lower``, e.g. D < 0) are clipped, with a note.
- **Flags**: a parameter is poorly determined when its interval reaches a search bound (open), its
  half-width exceeds ``max_rel_halfwidth`` of the estimate, it correlates with another parameter
  with |ρ| > ``max_abs_corr`` (K–D compensation), or the optimiser did not converge (still a
  clearly lower RSS after the re-centrings).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats

from bladelab.errors import OptimizationError
from bladelab.identify.optimizers import as_bounds

ResidualBatch = Callable[[np.ndarray], np.ndarray]
"""``(m, d)`` parameter sets -> ``(m, n_res)`` residuals."""


def _eval_residuals(residual_batch: ResidualBatch, X: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(X)):  # never simulate a NaN candidate
        raise OptimizationError("a non-finite parameter set reached the residual function",
                                where="identifiability")
    R = np.atleast_2d(np.asarray(residual_batch(np.atleast_2d(X)), dtype=float))
    if R.shape[0] != len(np.atleast_2d(X)):
        raise OptimizationError(f"residual function returned {R.shape[0]} rows for {len(X)} sets",
                                where="residual_batch")
    return R


def _steps(x: np.ndarray, b: np.ndarray, rel_step: float) -> np.ndarray:
    return rel_step * (b[:, 1] - b[:, 0]) * np.ones_like(x)


def jacobian(
    residual_batch: ResidualBatch, x, *, bounds, rel_step: float = 1e-3
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals r(x) (n_res,) and Jacobian J (n_res, d) by central differences in one batch.

    Steps are ``rel_step`` × box width, shifted inside the box at a wall (one-sided there).
    """
    b = as_bounds(bounds)
    x = np.asarray(x, dtype=float)
    d = len(x)
    h = _steps(x, b, rel_step)
    plus = np.minimum(x + h, b[:, 1])
    minus = np.maximum(x - h, b[:, 0])
    X = np.vstack([x, x + np.diag(plus - x), x + np.diag(minus - x)])
    R = _eval_residuals(residual_batch, X)
    J = (R[1 : d + 1] - R[d + 1 :]).T / (plus - minus)
    return R[0], J


def effective_sample_size(residuals: np.ndarray, n_parameters: int) -> float:
    """n·(1 − ρ₁)/(1 + ρ₁) (AR(1) approximation), kept within [n_parameters + 2, n]."""
    r = np.asarray(residuals, dtype=float).ravel()
    n = r.size
    rc = r - r.mean()
    denom = float(rc @ rc)
    rho = float(rc[1:] @ rc[:-1]) / denom if denom > 0 else 0.0
    rho = min(max(rho, 0.0), 0.999)
    return float(min(max(n * (1 - rho) / (1 + rho), n_parameters + 2), n))


def _bandwidth(r: np.ndarray) -> int:
    """Bartlett bandwidth of a residual block: twice the first lag at which its autocorrelation
    is no longer positive (its correlation length), at most half the block."""
    n = r.size
    rc = r - r.mean()
    denom = float(rc @ rc)
    if n < 4 or denom <= 0:
        return 0
    half = n // 2
    for k in range(1, half + 1):
        if float(rc[k:] @ rc[:-k]) / denom <= 0.0:
            return min(2 * k, half)
    return half


def hac_inflation(residuals: np.ndarray, J: np.ndarray, *,
                  blocks: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Variance inflation of least-squares estimates by autocorrelated residuals (Newey–West).

    The sandwich covariance V = H⁻¹ S H⁻¹ (H = JᵀJ) with S = Σ_b Σ_|l|≤L_b w_l Σ_t g_t g_{t+l}ᵀ
    (g_t = J_t r_t, Bartlett weights w_l = 1 − |l|/(L_b + 1)) summed within each residual block b
    (a measured channel; channels come from different instruments and are taken as independent),
    each with its own bandwidth L_b (:func:`_bandwidth`). Compared with the independent-residual
    covariance s²H⁻¹ (s² = RSS/(n − d)), the inflation per parameter is c_i = V_ii/(s²H⁻¹)_ii,
    floored at 1 (never narrower than the independent-residual interval).

    Returns
    -------
    inflation, covariance, bandwidths
        c (d,), V (d, d) and the L_b of each block.
    """
    r = np.asarray(residuals, dtype=float).ravel()
    n, d = J.shape
    sizes = [n] if not blocks else [int(b) for b in blocks]
    if sum(sizes) != n:
        raise OptimizationError(f"residual blocks sum to {sum(sizes)}, not {n}", where="blocks")
    H = J.T @ J
    w, Q = np.linalg.eigh(H)
    floor = max(float(np.max(w)), 1e-300) * 1e-12
    Hinv = (Q / np.maximum(w, floor)) @ Q.T
    S = np.zeros((d, d))
    lags = []
    start = 0
    for size in sizes:
        rb, Jb = r[start:start + size], J[start:start + size]
        start += size
        g = Jb * rb[:, None]
        L = _bandwidth(rb)
        lags.append(L)
        S += g.T @ g
        for lag in range(1, L + 1):
            G = g[lag:].T @ g[:-lag]
            S += (1.0 - lag / (L + 1.0)) * (G + G.T)
    V = Hinv @ S @ Hinv
    s2 = float(r @ r) / max(n - d, 1)
    iid = s2 * np.diag(Hinv)
    c = np.where(iid > 0, np.diag(V) / np.where(iid > 0, iid, 1.0), 1.0)
    return np.maximum(c, 1.0), V, lags


def _covariance(J: np.ndarray, s2: float) -> tuple[np.ndarray, np.ndarray]:
    H = J.T @ J
    w, V = np.linalg.eigh(H)
    floor = max(float(np.max(w)), 1e-300) * 1e-12
    cov = s2 * (V / np.maximum(w, floor)) @ V.T
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sd, sd)
    np.fill_diagonal(corr, 1.0)
    return cov, np.clip(corr, -1.0, 1.0)


def _profile(
    residual_batch: ResidualBatch,
    x_opt: np.ndarray,
    b: np.ndarray,
    index: int,
    grid: np.ndarray,
    *,
    iterations: int,
    rel_step: float,
) -> tuple[np.ndarray, int, np.ndarray]:
    """Minimum RSS over the other parameters at each grid value of parameter ``index``, the
    evaluations used and the (m, d) parameter sets where each minimum was found."""
    d = len(x_opt)
    free = [j for j in range(d) if j != index]
    m = len(grid)
    X = np.repeat(x_opt[None, :], m, axis=0)
    X[:, index] = grid
    if not free:
        R = _eval_residuals(residual_batch, X)
        rss = np.sum(R**2, axis=1)
        return np.where(np.isfinite(rss), rss, np.inf), m, X
    bf = b[free]
    h = rel_step * (bf[:, 1] - bf[:, 0])
    k = len(free)
    cur = X.copy()
    cur_rss = np.full(m, np.inf)
    cur_r: list[np.ndarray | None] = [None] * m
    cur_J: list[np.ndarray | None] = [None] * m
    lam = np.full(m, 1e-3)
    trial = X.copy()
    evals = 0
    for _ in range(iterations):
        rows = []
        for i in range(m):
            xt = trial[i]
            plus = np.minimum(xt[free] + h, bf[:, 1])
            minus = np.maximum(xt[free] - h, bf[:, 0])
            block = np.repeat(xt[None, :], 1 + 2 * k, axis=0)
            for a in range(k):
                block[1 + a, free[a]] = plus[a]
                block[1 + k + a, free[a]] = minus[a]
            rows.append((block, plus - minus))
        R = _eval_residuals(residual_batch, np.vstack([r[0] for r in rows]))
        evals += len(R)
        R = R.reshape(m, 1 + 2 * k, -1)
        for i in range(m):
            r0 = R[i, 0]
            rss = float(r0 @ r0)
            Ji = (R[i, 1 : 1 + k] - R[i, 1 + k :]).T / rows[i][1]
            # a failed simulation (non-finite residuals) is never accepted nor stepped from
            if np.isfinite(rss) and rss < cur_rss[i]:
                cur[i], cur_rss[i] = trial[i], rss
                ok = np.all(np.isfinite(Ji))
                cur_r[i] = r0 if ok else None
                cur_J[i] = Ji if ok else None
                lam[i] = max(lam[i] / 3.0, 1e-9)
            else:
                lam[i] *= 4.0
            J, r = cur_J[i], cur_r[i]
            if J is None:
                trial[i] = cur[i]
                continue
            H = J.T @ J
            g = J.T @ r
            try:
                step = -np.linalg.solve(H + lam[i] * np.diag(np.diag(H) + 1e-300), g)
            except np.linalg.LinAlgError:
                step = np.full(k, np.nan)
            nxt = cur[i].copy()
            if np.all(np.isfinite(step)):
                nxt[free] = np.clip(cur[i][free] + step, bf[:, 0], bf[:, 1])
            trial[i] = nxt
    return cur_rss, evals, cur


def _crossing(grid: np.ndarray, z: np.ndarray, center: int, threshold: float, side: int):
    """First grid crossing of z(θ) = sqrt(ΔRSS/s²) over ``threshold`` walking from ``center``
    (the profile's minimum)."""
    idx = range(center, len(grid)) if side > 0 else range(center, -1, -1)
    prev = None
    for i in idx:
        if prev is not None and z[i] >= threshold:
            z0, z1 = z[prev], z[i]
            t = min(max((threshold - z0) / (z1 - z0), 0.0), 1.0) if z1 > z0 else 1.0
            return float(grid[prev] + t * (grid[i] - grid[prev])), False
        prev = i
    return float(grid[prev]), True


@dataclasses.dataclass(frozen=True)
class Identifiability:
    """Identifiability of parameters at an optimum (units as the parameters given).

    Attributes
    ----------
    names, x
        Parameter names and optimum.
    covariance, correlation
        Gauss–Newton covariance (d, d) and correlation matrix.
    ci_lower, ci_upper
        Profile-likelihood confidence interval per parameter.
    ci_open
        True where the interval reached a search bound without the profile crossing the threshold.
    level
        Confidence level (e.g. 0.95).
    n_effective
        Effective number of independent residuals.
    rss
        Residual sum of squares at the optimum.
    poorly_determined
        Flag per parameter.
    reasons
        Why each flagged parameter is flagged ('' if not).
    profiles
        Tidy DataFrame: parameter, value, rss (the profiles).
    evaluations
        Residual evaluations used.
    converged
        False when the profiles still found a clearly lower RSS after ``recentred`` re-centrings.
    recentred
        How many times the estimate moved to a lower point found by the profiles.
    x_start
        The ``x_opt`` given (``x`` is the estimate after re-centring).
    ci_clipped
        Per parameter: the lower limit was clipped to its physical minimum.
    notes
        What was changed (re-centring, widened or clipped intervals), for the messages.
    inflation
        Per parameter: the variance inflation c_i for autocorrelated residuals (1 without HAC).
    bandwidths
        Bartlett bandwidth [samples] of each residual block (HAC only).
    """

    names: tuple[str, ...]
    x: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    ci_lower: np.ndarray
    ci_upper: np.ndarray
    ci_open: tuple[bool, ...]
    level: float
    n_effective: float
    rss: float
    poorly_determined: tuple[bool, ...]
    reasons: tuple[str, ...]
    profiles: pd.DataFrame
    evaluations: int
    converged: bool = True
    recentred: int = 0
    x_start: np.ndarray | None = None
    ci_clipped: tuple[bool, ...] = ()
    notes: tuple[str, ...] = ()
    inflation: tuple[float, ...] = ()
    bandwidths: tuple[int, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready dictionary (no profiles)."""
        return {
            "names": list(self.names),
            "x": self.x.tolist(),
            "correlation": self.correlation.tolist(),
            "ci_lower": self.ci_lower.tolist(),
            "ci_upper": self.ci_upper.tolist(),
            "ci_open": list(self.ci_open),
            "ci_method": "profile likelihood",
            "level": self.level,
            "n_effective": self.n_effective,
            "rss": self.rss,
            "poorly_determined": list(self.poorly_determined),
            "reasons": list(self.reasons),
            "evaluations": self.evaluations,
            "converged": self.converged,
            "recentred": self.recentred,
            "notes": list(self.notes),
        }


def assess_identifiability(
    residual_batch: ResidualBatch,
    x_opt,
    bounds,
    *,
    names: Sequence[str] | None = None,
    level: float = 0.95,
    n_effective: float | None = None,
    n_profile: int = 21,
    profile_iterations: int = 6,
    rel_step: float = 1e-3,
    max_rel_halfwidth: float = 0.25,
    max_abs_corr: float = 0.95,
    max_recentre: int = 3,
    physical_lower: Mapping[str, float] | None = None,
    variance: str = "hac",
    blocks: Sequence[int] | None = None,
) -> Identifiability:
    """Correlation, profile-likelihood confidence intervals and flags at ``x_opt``.

    Parameters
    ----------
    residual_batch
        ``(m, d) -> (m, n_res)`` residuals.
    x_opt
        The optimum (d,).
    bounds
        (d, 2) search bounds; intervals never extend beyond them.
    names
        Parameter names (default p0, p1, ...).
    level
        Confidence level.
    n_effective
        Number of independent residuals; default: AR(1) estimate from the residuals at x_opt.
    n_profile
        Grid points per profile (odd; the optimum is the centre point).
    profile_iterations
        Levenberg–Marquardt iterations re-optimising the other parameters at each grid point.
    rel_step
        Finite-difference step as a fraction of the box width.
    max_rel_halfwidth, max_abs_corr
        Flag thresholds.
    max_recentre
        How often the analysis may move to a clearly lower point found by the profiles and start
        again there; still lower after that: flagged as not converged.
    variance
        ``"hac"`` (default): each parameter's interval scale is s² of independent residuals times
        its Newey–West inflation for autocorrelated residuals (:func:`hac_inflation`), with
        n_eff,i = n/c_i; ``"ar1"``: one n_eff = n(1 − ρ₁)/(1 + ρ₁) for all (the earlier
        default, which under-covered). Ignored when ``n_effective`` is given.
    blocks
        Lengths of the residual blocks (one per measured channel, in order), for ``"hac"``.
    physical_lower
        Parameter name -> lowest physical value (e.g. 0 for a damping); interval limits below it
        are clipped to it (``ci_clipped``, with a note).

    The returned ``x`` is the estimate: ``x_opt`` itself, or the lowest point the profiles found
    when that is clearly lower (``recentred`` > 0). The interval of every parameter contains it.
    """
    b = as_bounds(bounds)
    x = np.clip(np.asarray(x_opt, dtype=float), b[:, 0], b[:, 1])
    x_start = x.copy()
    d = len(x)
    names = tuple(names) if names is not None else tuple(f"p{i}" for i in range(d))
    if len(names) != d:
        raise OptimizationError(f"{len(names)} names for {d} parameters", where="names")
    if not np.all(np.isfinite(x)):
        raise OptimizationError("the optimum has non-finite parameters", where="x_opt")
    evals = 0
    recentred = 0
    notes: list[str] = []
    while True:
        r0, J = jacobian(residual_batch, x, bounds=b, rel_step=rel_step)
        evals += 2 * d + 1
        if not (np.all(np.isfinite(r0)) and np.all(np.isfinite(J))):
            raise OptimizationError("the residuals at (or next to) the optimum are not finite",
                                    where="residual_batch",
                                    hint="the simulation failed there; see the solver's messages")
        rss0 = float(r0 @ r0)
        n_res = r0.size
        if n_effective is None and variance == "hac" and n_res > d + 2:
            # every parameter gets its own scale: s² of independent residuals × its inflation
            c, _, bandwidths = hac_inflation(r0, J, blocks=blocks)
            n_par = np.maximum(n_res / c, d + 2.0)
            s2 = max(rss0, 1e-300) / (n_res - d)
            scale = s2 * c
            thresholds = np.sqrt(stats.f.ppf(level, 1, n_par - d))
            n_eff = float(np.min(n_par))
            inflation = tuple(float(v) for v in c)
        else:
            n_eff = effective_sample_size(r0, d) if n_effective is None else float(n_effective)
            if n_eff <= d:
                raise OptimizationError(f"n_effective={n_eff:g} must exceed the {d} parameters",
                                        where="n_effective")
            s2 = max(rss0, 1e-300) / (n_eff - d)
            scale = np.full(d, s2)
            thresholds = np.full(d, float(np.sqrt(stats.f.ppf(level, 1, n_eff - d))))
            bandwidths, inflation = [], (1.0,) * d
        cov, corr = _covariance(J, 1.0)
        cov = cov * np.sqrt(np.outer(scale, scale))  # per-parameter scales, the GN correlation
        sd = np.sqrt(np.diag(cov))
        half = max(1, n_profile // 2)
        lo_ci, hi_ci, opened, frames = [], [], [], []
        best_rss, best_x = rss0, x.copy()
        for i in range(d):
            width = b[i, 1] - b[i, 0]
            threshold = float(thresholds[i])
            span = min(max(3.0 * threshold * sd[i], 1e-3 * width), width)
            left = np.linspace(max(x[i] - span, b[i, 0]), x[i], half + 1)
            right = np.linspace(x[i], min(x[i] + span, b[i, 1]), half + 1)
            grid = np.concatenate([left[:-1], right])
            rss, n, where = _profile(residual_batch, x, b, i, grid,
                                     iterations=profile_iterations, rel_step=rel_step)
            evals += n
            rss = np.where(np.isfinite(rss), rss, np.inf)
            j = int(np.argmin(rss))
            if rss[j] < best_rss:
                best_rss, best_x = float(rss[j]), where[j].copy()
            rss_min = min(rss0, float(rss[j]))
            z = np.sqrt(np.maximum(rss - rss_min, 0.0) / scale[i])
            lo_v, lo_open = _crossing(grid, z, j, threshold, -1)
            hi_v, hi_open = _crossing(grid, z, j, threshold, +1)
            lo_open = lo_open and np.isclose(lo_v, b[i, 0])
            hi_open = hi_open and np.isclose(hi_v, b[i, 1])
            lo_ci.append(lo_v)
            hi_ci.append(hi_v)
            opened.append(bool(lo_open or hi_open))
            frames.append(pd.DataFrame({"parameter": names[i], "value": grid, "rss": rss}))
        # the estimate should be the lowest point the profiles saw; a clearly lower RSS elsewhere
        # means the search stopped short of the least-squares optimum (or optimised another
        # cost: J sums nRMSEs, the RSS their squares): that point becomes the estimate and the
        # analysis is repeated there
        i_min = int(np.argmin(scale))  # the most sensitive scale
        gap = (rss0 - best_rss) / scale[i_min]
        not_converged = gap > 0.1 * float(thresholds[i_min]) ** 2
        if not not_converged or recentred >= max_recentre:
            break
        recentred += 1
        x = np.clip(best_x, b[:, 0], b[:, 1])
    lo_ci, hi_ci = np.asarray(lo_ci, dtype=float), np.asarray(hi_ci, dtype=float)
    if recentred:
        moved = ", ".join(f"{n} {a:.4g} -> {c:.4g}" for n, a, c in zip(names, x_start, x, strict=True))
        notes.append(f"estimate moved from the search's optimum to the lowest cost the profiles "
                     f"found ({moved}; {recentred} re-centring(s))")
    # an estimate always lies inside its own interval: a profile whose minimum is not at the
    # estimate (multimodal or not converged) could leave it outside; the interval is widened
    extended = [i for i in range(d) if not lo_ci[i] <= x[i] <= hi_ci[i]]
    for i in extended:
        lo_ci[i], hi_ci[i] = min(lo_ci[i], x[i]), max(hi_ci[i], x[i])
        notes.append(f"interval of {names[i]} widened to contain the estimate")
    clipped = [False] * d
    for i, name in enumerate(names):
        floor = (physical_lower or {}).get(name)
        if floor is not None and lo_ci[i] < floor:
            lo_ci[i] = min(floor, x[i])  # never above the estimate
            clipped[i] = True
            notes.append(f"lower limit of {name} clipped at {floor:g} (non-physical below)")
            if x[i] < floor:
                notes.append(f"the estimate of {name} is below its physical minimum {floor:g}")
    flags, reasons = [], []
    for i in range(d):
        why = []
        if not_converged:
            why.append(f"the optimiser did not converge: after {recentred} re-centring(s) the "
                       f"profiles still found a lower cost (ΔRSS/s² = {gap:.3g}); raise max_evals "
                       "or use --polish / CMA-ES")
        if opened[i]:
            why.append("confidence interval reaches a search bound")
        rel = 0.5 * (hi_ci[i] - lo_ci[i]) / max(abs(x[i]), 1e-300)
        if rel > max_rel_halfwidth:
            why.append(f"CI half-width {100 * rel:.0f} % of the estimate > {100 * max_rel_halfwidth:.0f} %")
        partners = [names[j] for j in range(d) if j != i and abs(corr[i, j]) > max_abs_corr]
        if partners:
            why.append(f"|correlation| > {max_abs_corr} with {', '.join(partners)} (compensation)")
        flags.append(bool(why))
        reasons.append("; ".join(why))
    return Identifiability(
        names=names, x=x, covariance=cov, correlation=corr, ci_lower=lo_ci, ci_upper=hi_ci,
        ci_open=tuple(opened), level=float(level), n_effective=n_eff, rss=rss0,
        poorly_determined=tuple(flags), reasons=tuple(reasons),
        profiles=pd.concat(frames, ignore_index=True), evaluations=evals,
        converged=not not_converged, recentred=recentred, x_start=x_start,
        ci_clipped=tuple(clipped), notes=tuple(notes), inflation=inflation,
        bandwidths=tuple(int(v) for v in bandwidths),
    )


def cost_landscape(
    fun_batch: Callable[[np.ndarray], np.ndarray],
    center,
    bounds,
    *,
    names: Sequence[str] = ("K", "D"),
    n: int = 21,
    rel_span: float = 0.3,
) -> pd.DataFrame:
    """Cost on an n × n grid of the first two parameters around ``center`` (one batch call).

    The grid spans ``center ± rel_span·|center|`` per parameter, clipped to the bounds; further
    parameters are held at ``center``. Returns a tidy DataFrame with columns ``names[0]``,
    ``names[1]`` and ``cost``.
    """
    b = as_bounds(bounds)
    c = np.asarray(center, dtype=float)
    if len(c) < 2:
        raise OptimizationError("a landscape needs at least two parameters", where="center")
    axes = []
    for i in range(2):
        half = rel_span * abs(c[i]) if c[i] != 0 else rel_span * (b[i, 1] - b[i, 0])
        axes.append(np.linspace(max(c[i] - half, b[i, 0]), min(c[i] + half, b[i, 1]), n))
    g0, g1 = np.meshgrid(axes[0], axes[1], indexing="ij")
    X = np.repeat(c[None, :], g0.size, axis=0)
    X[:, 0], X[:, 1] = g0.ravel(), g1.ravel()
    f = np.asarray(fun_batch(X), dtype=float).reshape(-1)
    return pd.DataFrame({names[0]: X[:, 0], names[1]: X[:, 1], "cost": f})
