"""Group comparisons of identified blade parameters as tidy tables (seed 000 §3.6).

Non-parametric tests on a per-trial table (one row per trial, e.g. ``K_Nm_per_deg``,
``D_Nms_per_deg``, ``amputation``, ``group``, ``speed_pct_pb``):

- Mann–Whitney U between two groups (amputation levels; speed bands),
- Kruskal–Wallis H across k groups (categories) with Dunn's post-hoc z tests, Bonferroni-adjusted,
- the effect of the speed band (≥ 90 % vs < 90 % of personal best) overall, per amputation level
  and per category.

Every result row holds: ``test``, ``parameter``, ``subset`` (the rows tested), ``groups`` (group
names in order, ``" | "``-separated), ``group_1``/``group_2`` (pairwise rows), ``statistic_name``,
``statistic``, ``z``, ``p``, ``p_adjusted``, ``effect_size_r``, ``n`` (per group, in the order of
``groups``), ``significant`` (``p_adjusted < alpha``).

Formulas (ranks are mid-ranks over the pooled sample, N values, tie groups of size t):

- U = R₁ − n₁(n₁+1)/2 (R₁ the rank sum of the first group); Z = (U − n₁n₂/2)/σ_U with
  σ_U² = n₁n₂/12 · [(N+1) − Σ(t³−t)/(N(N−1))]; p two-sided from :func:`scipy.stats.mannwhitneyu`
  (``method="auto"``: exact without ties for small samples, else normal with continuity
  correction).
- H = [12/(N(N+1)) Σ Rᵢ²/nᵢ − 3(N+1)] / [1 − Σ(t³−t)/(N³−N)], p = χ²_{k−1} survival.
- Dunn: zᵢⱼ = (R̄ᵢ − R̄ⱼ)/√{[N(N+1)/12 − Σ(t³−t)/(12(N−1))]·(1/nᵢ + 1/nⱼ)}, p two-sided normal,
  Bonferroni p_adj = min(1, m·p) with m = k(k−1)/2 comparisons.
- Effect size r = Z/√N: for Mann–Whitney N = n₁ + n₂; for a Dunn pair N is the total of the
  Kruskal–Wallis test (Dunn's z uses the variance of the pooled ranking, so dividing by the pair
  size alone can give |r| > 1). |r| ≈ 0.1 small, 0.3 medium, ≥ 0.5 large (Cohen). Positive r:
  the first group ranks higher. No r for the omnibus H test (NaN).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from scipy import stats as _sps

from bladelab.errors import DataError

__all__ = [
    "ALPHA",
    "RESULT_COLUMNS",
    "UnitOfAnalysis",
    "athlete_means",
    "unit_of_analysis",
    "mann_whitney",
    "kruskal_dunn",
    "speed_band",
    "compare_groups",
    "summarize",
]

ALPHA = 0.05
FAST_BAND = "≥90% PB"
SLOW_BAND = "<90% PB"
RESULT_COLUMNS: tuple[str, ...] = (
    "test",
    "parameter",
    "subset",
    "groups",
    "group_1",
    "group_2",
    "statistic_name",
    "statistic",
    "z",
    "p",
    "p_adjusted",
    "effect_size_r",
    "n",
    "significant",
)


def _tie_sum(values: np.ndarray) -> float:
    """Σ (t³ − t) over tie groups."""
    _, counts = np.unique(values, return_counts=True)
    counts = counts.astype(float)
    return float(np.sum(counts**3 - counts))


def _samples(
    data: pd.DataFrame, value: str, by: str, groups: Sequence[str] | None
) -> tuple[list[str], list[np.ndarray]]:
    for col in (value, by):
        if col not in data.columns:
            raise DataError(
                f"column {col!r} not in the table (columns: {', '.join(map(str, data.columns))})",
                where=col,
                hint="name the parameter and grouping columns of the per-trial table",
            )
    clean = data[[value, by]].dropna()
    names = list(groups) if groups is not None else sorted(clean[by].astype(str).unique())
    samples = [clean.loc[clean[by].astype(str) == g, value].to_numpy(float) for g in names]
    return names, samples


def _row(**kw) -> dict:
    row = dict.fromkeys(RESULT_COLUMNS, np.nan)
    row.update(kw)
    return row


def _finish(rows: list[dict], alpha: float) -> pd.DataFrame:
    out = pd.DataFrame(rows, columns=list(RESULT_COLUMNS))
    out["significant"] = out["p_adjusted"] < alpha
    return out


def mann_whitney(
    data: pd.DataFrame,
    *,
    value: str,
    by: str,
    groups: Sequence[str] | None = None,
    subset: str = "all",
    test: str = "Mann-Whitney U",
    alpha: float = ALPHA,
) -> pd.DataFrame:
    """Two-sided Mann–Whitney U test of ``value`` between two groups of column ``by``.

    Parameters
    ----------
    data
        Per-trial table.
    value
        Column tested (e.g. ``K_Nm_per_deg``).
    by
        Grouping column (e.g. ``amputation``).
    groups
        The two group names, in order (default: the two sorted names present).
    subset, test
        Labels written into the ``subset`` and ``test`` columns.
    alpha
        Significance level.

    Returns
    -------
    pandas.DataFrame
        One row (:data:`RESULT_COLUMNS`); ``statistic`` is U of the first group.
    """
    names, (x, y) = _two(data, value, by, groups)
    n1, n2 = len(x), len(y)
    pooled = np.concatenate([x, y])
    n = n1 + n2
    ranks = _sps.rankdata(pooled)
    u1 = float(ranks[:n1].sum() - n1 * (n1 + 1) / 2)
    var = n1 * n2 / 12.0 * ((n + 1) - _tie_sum(pooled) / (n * (n - 1)))
    z = (u1 - n1 * n2 / 2.0) / np.sqrt(var) if var > 0 else 0.0
    p = float(_sps.mannwhitneyu(x, y, alternative="two-sided", method="auto").pvalue)
    row = _row(
        test=test,
        parameter=value,
        subset=subset,
        groups=" | ".join(names),
        group_1=names[0],
        group_2=names[1],
        statistic_name="U",
        statistic=u1,
        z=float(z),
        p=p,
        p_adjusted=p,
        effect_size_r=float(z / np.sqrt(n)),
        n=f"{n1} | {n2}",
    )
    return _finish([row], alpha)


def _two(data, value, by, groups):
    names, samples = _samples(data, value, by, groups)
    if len(names) != 2:
        raise DataError(
            f"Mann–Whitney U needs exactly two groups, found {len(names)}: {names}",
            where=by,
            hint="pass groups=[first, second]",
        )
    for name, s in zip(names, samples, strict=True):
        if len(s) < 1:
            raise DataError(f"group {name!r} has no values", where=f"{by}={name}")
    return names, samples


def kruskal_dunn(
    data: pd.DataFrame,
    *,
    value: str,
    by: str,
    groups: Sequence[str] | None = None,
    subset: str = "all",
    alpha: float = ALPHA,
) -> pd.DataFrame:
    """Kruskal–Wallis H test across the groups of ``by``, then Dunn–Bonferroni pairwise tests.

    Parameters
    ----------
    data
        Per-trial table.
    value
        Column tested.
    by
        Grouping column (e.g. ``group`` = category).
    groups
        Group names in order (default sorted); pairs follow this order.
    subset
        Label written into the ``subset`` column.
    alpha
        Significance level.

    Returns
    -------
    pandas.DataFrame
        The omnibus row (``test="Kruskal-Wallis H"``) then one ``"Dunn (Bonferroni)"`` row per
        pair; ``statistic`` of a Dunn row is its z (R̄₁ − R̄₂ sign).
    """
    names, samples = _samples(data, value, by, groups)
    if len(names) < 2 or any(len(s) == 0 for s in samples):
        raise DataError(
            f"Kruskal–Wallis needs at least two non-empty groups, found {names} with "
            f"sizes {[len(s) for s in samples]}",
            where=by,
        )
    sizes = np.array([len(s) for s in samples], float)
    pooled = np.concatenate(samples)
    n = len(pooled)
    ranks = _sps.rankdata(pooled)
    bounds = np.concatenate([[0], np.cumsum(sizes).astype(int)])
    rank_sums = np.array([ranks[a:b].sum() for a, b in itertools.pairwise(bounds)])
    ties = _tie_sum(pooled)
    correction = 1.0 - ties / (n**3 - n) if n > 1 else 1.0
    h_raw = 12.0 / (n * (n + 1)) * np.sum(rank_sums**2 / sizes) - 3.0 * (n + 1)
    h = float(h_raw / correction) if correction > 0 else 0.0
    k = len(names)
    p_h = float(_sps.chi2.sf(h, k - 1))
    rows = [
        _row(
            test="Kruskal-Wallis H",
            parameter=value,
            subset=subset,
            groups=" | ".join(names),
            statistic_name="H",
            statistic=h,
            p=p_h,
            p_adjusted=p_h,
            n=" | ".join(str(int(s)) for s in sizes),
        )
    ]
    mean_ranks = rank_sums / sizes
    var_unit = n * (n + 1) / 12.0 - ties / (12.0 * (n - 1))
    pairs = list(itertools.combinations(range(k), 2))
    for i, j in pairs:
        se = np.sqrt(var_unit * (1.0 / sizes[i] + 1.0 / sizes[j]))
        z = float((mean_ranks[i] - mean_ranks[j]) / se) if se > 0 else 0.0
        p = float(2.0 * _sps.norm.sf(abs(z)))
        rows.append(
            _row(
                test="Dunn (Bonferroni)",
                parameter=value,
                subset=subset,
                groups=f"{names[i]} | {names[j]}",
                group_1=names[i],
                group_2=names[j],
                statistic_name="z",
                statistic=z,
                z=z,
                p=p,
                p_adjusted=min(1.0, p * len(pairs)),
                effect_size_r=z / np.sqrt(n),
                n=f"{int(sizes[i])} | {int(sizes[j])}",
            )
        )
    return _finish(rows, alpha)


def speed_band(speed_pct_pb: pd.Series | np.ndarray, *, threshold: float = 90.0) -> np.ndarray:
    """Speed band label per trial: ``"≥90% PB"`` or ``"<90% PB"``.

    Parameters
    ----------
    speed_pct_pb
        Running speed as a percentage of the athlete's personal best [%].
    threshold
        Band limit [%] (seed 000: 90).
    """
    s = np.asarray(speed_pct_pb, float)
    if np.any(~np.isfinite(s)):
        raise DataError("speed has missing values", where="speed_pct_pb", hint="fill it per trial")
    return np.where(s >= threshold, FAST_BAND, SLOW_BAND).astype(object)


def compare_groups(
    data: pd.DataFrame,
    *,
    parameters: Sequence[str] = ("K_Nm_per_deg", "D_Nms_per_deg"),
    amputation: str = "amputation",
    category: str = "group",
    speed: str = "speed_pct_pb",
    amputation_order: Sequence[str] | None = None,
    category_order: Sequence[str] | None = None,
    band_threshold: float = 90.0,
    alpha: float = ALPHA,
) -> pd.DataFrame:
    """The statistics of seed 000 §3.6 for each parameter, as one tidy table.

    For each parameter: Mann–Whitney U between amputation levels (if there are two);
    Kruskal–Wallis + Dunn–Bonferroni across categories; Mann–Whitney U between speed bands
    (≥ ``band_threshold`` % vs below) over all trials, per amputation level and per category
    (where both bands have at least one trial).

    Parameters
    ----------
    data
        Per-trial table with the parameter columns, ``amputation``, ``category`` and ``speed``
        [% of personal best] columns.
    parameters
        Columns to test.
    amputation, category, speed
        Column names.
    amputation_order, category_order
        Group orders (default sorted).
    band_threshold
        Speed band limit [% PB].
    alpha
        Significance level.

    Returns
    -------
    pandas.DataFrame
        Rows as described in the module docstring (:data:`RESULT_COLUMNS`).
    """
    missing = [c for c in (*parameters, amputation, category, speed) if c not in data.columns]
    if missing:
        raise DataError(
            f"missing columns {missing}",
            where="per-trial table",
            hint=f"the table needs {[*parameters, amputation, category, speed]}",
        )
    table = data.copy()
    table["speed_band"] = speed_band(table[speed], threshold=band_threshold)
    bands = [FAST_BAND, SLOW_BAND]
    frames: list[pd.DataFrame] = []
    for par in parameters:
        if table[amputation].nunique() == 2:
            frames.append(
                mann_whitney(table, value=par, by=amputation, groups=amputation_order, alpha=alpha)
            )
        if table[category].nunique() >= 2:
            frames.append(
                kruskal_dunn(table, value=par, by=category, groups=category_order, alpha=alpha)
            )
        subsets = [("all", table)]
        for col, order in ((amputation, amputation_order), (category, category_order)):
            names = order if order is not None else sorted(table[col].astype(str).unique())
            subsets += [(f"{col}={g}", table[table[col].astype(str) == g]) for g in names]
        for label, sub in subsets:
            if all((sub["speed_band"] == b).any() for b in bands):
                frames.append(
                    mann_whitney(
                        sub,
                        value=par,
                        by="speed_band",
                        groups=bands,
                        subset=label,
                        test="Mann-Whitney U (speed band)",
                        alpha=alpha,
                    )
                )
    if not frames:
        return pd.DataFrame(columns=list(RESULT_COLUMNS))
    return pd.concat(frames, ignore_index=True)


def summarize(
    data: pd.DataFrame,
    *,
    values: Sequence[str],
    by: Sequence[str],
    confidence: float = 0.95,
    lower_limits: Mapping[str, float] | None = None,
) -> pd.DataFrame:
    """Mean, SD, n and the t-based confidence interval of the mean per group.

    Parameters
    ----------
    data
        Per-trial table.
    values
        Columns to summarise (e.g. ``["K_Nm_per_deg", "D_Nms_per_deg"]``).
    by
        Grouping columns (e.g. ``["group", "speed_band"]``).
    confidence
        Confidence level of the interval.
    lower_limits
        Value column -> its lowest physical value (e.g. 0 for a stiffness or a damping): a lower
        confidence limit below it is clipped to it and ``<value>_ci_clipped`` is True.

    Returns
    -------
    pandas.DataFrame
        One row per group: the ``by`` columns, ``n``, and per value ``<value>`` (mean),
        ``<value>_sd``, ``<value>_ci_low``, ``<value>_ci_high`` (NaN interval for n < 2),
        ``<value>_ci_clipped`` — the input of :func:`bladelab.report.figures.parameter_bars`.
    """
    rows = []
    for key, sub in data.groupby(list(by), sort=True):
        key = key if isinstance(key, tuple) else (key,)
        row = dict(zip(by, key, strict=True))
        row["n"] = len(sub)
        for v in values:
            x = sub[v].dropna().to_numpy(float)
            mean = float(np.mean(x)) if len(x) else np.nan
            sd = float(np.std(x, ddof=1)) if len(x) > 1 else np.nan
            half = (
                float(_sps.t.ppf(0.5 + confidence / 2, len(x) - 1) * sd / np.sqrt(len(x)))
                if len(x) > 1
                else np.nan
            )
            low = mean - half
            floor = (lower_limits or {}).get(v)
            clipped = bool(floor is not None and np.isfinite(low) and low < floor)
            row.update(
                {v: mean, f"{v}_sd": sd, f"{v}_ci_low": max(low, floor) if clipped else low,
                 f"{v}_ci_high": mean + half, f"{v}_ci_clipped": clipped}
            )
        rows.append(row)
    return pd.DataFrame(rows)


@dataclasses.dataclass(frozen=True)
class UnitOfAnalysis:
    """What a group comparison's observations are (trials are nested in athletes).

    Attributes
    ----------
    unit
        ``"trial"`` (each trial one observation) or ``"athlete"`` (each athlete's mean).
    athletes_per_group
        Group -> the athletes in it (sorted).
    statement
        One paragraph for a report saying what the tests compare and what they do not.
    """

    unit: str
    athletes_per_group: dict[str, tuple[str, ...]]
    statement: str


def unit_of_analysis(data: pd.DataFrame, *, athlete: str = "athlete",
                     groups: Sequence[str] = ("amputation", "group")) -> UnitOfAnalysis:
    """Choose the unit of analysis of group comparisons from how athletes fill the groups.

    Trials of one athlete are not independent samples of a population. With at least two
    athletes in every group of every grouping column in ``groups``, the athletes' means are
    compared (``unit="athlete"``, see :func:`athlete_means`); otherwise the trials are, and the
    statement says what that means: with one athlete per group the tests describe that athlete's
    trials (their variation between trials), not a population, and a group difference cannot be
    told apart from a difference between the athletes.
    """
    for col in (athlete, *groups):
        if col not in data.columns:
            raise DataError(f"column {col!r} not in the table", where=col,
                            hint="the per-trial table needs the athlete of each trial")
    per: dict[str, tuple[str, ...]] = {}
    for col in groups:
        for g, sub in data.groupby(col, sort=True):
            per.setdefault(str(g), tuple(sorted(sub[athlete].astype(str).unique())))
    counts = [len(v) for v in per.values()]
    if counts and min(counts) >= 2:
        n_ath = data[athlete].nunique()
        return UnitOfAnalysis("athlete", per, (
            f"Unit of analysis: the athlete. Every group holds at least two athletes "
            f"({n_ath} in all), so each athlete's trials are averaged first (per group and "
            "speed band) and the tests compare athlete means: n counts athletes, not trials. "
            "Trials of one athlete are not independent observations."))
    single = {g: a for g, a in per.items() if len(a) == 1}
    listed = "; ".join(f"{g}: {a[0]}" for g, a in single.items())
    if len(single) == len(per):
        text = ("Unit of analysis: the trial. Each group holds ONE athlete (" + listed + "), so "
                "these tests compare the trials of these athletes: they describe the variation "
                "between that athlete's trials, not a population of athletes with that "
                "amputation or blade, and a difference between groups cannot be told apart from "
                "a difference between the athletes. p-values treat trials as independent, which "
                "repeated trials of one person are not; read them as descriptive.")
    else:
        text = ("Unit of analysis: the trial. Some groups hold a single athlete (" + listed + "), "
                "so athlete means cannot be compared in every group; trials of one athlete are "
                "not independent, so the p-values are optimistic and describe these athletes' "
                "trials rather than a population.")
    return UnitOfAnalysis("trial", per, text)


def athlete_means(data: pd.DataFrame, *, values: Sequence[str], athlete: str = "athlete",
                  by: Sequence[str] = ("amputation", "group", "speed_band"),
                  speed: str | None = "speed_pct_pb") -> pd.DataFrame:
    """One row per athlete and cell of ``by``: the mean of each value over the athlete's trials.

    Columns: ``athlete``, the ``by`` columns, the means of ``values`` (and of ``speed``, kept
    for :func:`compare_groups`), ``n_trials``.
    """
    keys = [athlete, *[b for b in by if b in data.columns]]
    cols = [*values, *([speed] if speed and speed in data.columns else [])]
    out = data.groupby(keys, sort=True)[cols].mean().reset_index()
    out["n_trials"] = data.groupby(keys, sort=True).size().to_numpy()
    return out
