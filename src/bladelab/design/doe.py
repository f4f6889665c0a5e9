"""Designs of experiments in coded units, and what a design can estimate.

- :func:`central_composite`: face-centred central composite design (the default): the 2^k
  factorial corners, 2k axial points on the faces (±1) and centre points; three levels per factor.
- :func:`box_behnken`: the ±1 2² factorial of every pair of factors with the others at 0, plus
  centre points (4 factors: 24 + centre points). For k >= 6 this all-pairs construction has more
  runs than the tabulated Box–Behnken designs built on incomplete blocks.
- :func:`d_optimal`: n runs chosen from a candidate set (default: the 3^k grid) by Fedorov's
  exchange algorithm to maximise det(XᵀX) of the model; seeded, several random starts.
- :func:`read_runs_csv`: any user list of runs (seed 002 built 9 blades).
- :func:`estimability` / :func:`require_estimable`: rank, conditioning and which terms a design
  can estimate; refuses a model the design cannot estimate and suggests a reduced one.

Computer experiments are deterministic, so the default is one centre point (replicates add no
information about a simulation); pass ``n_center`` for physical tests with replicates, which
also give the ANOVA's pure-error and lack-of-fit rows.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.design.space import DesignSpace
from bladelab.design.terms import MODELS, Term, model_matrix, parse_terms, term_name
from bladelab.errors import DataError, InputFileError, SpecError

__all__ = [
    "Design",
    "EstimabilityReport",
    "central_composite",
    "box_behnken",
    "d_optimal",
    "read_runs_csv",
    "make_design",
    "estimability",
    "require_estimable",
    "log_det_information",
]

_RANK_RTOL = 1e-9


@dataclass(frozen=True, eq=False)
class Design:
    """A design of experiments: ``coded`` points (n_runs × n_factors) in [-1, 1].

    Attributes
    ----------
    coded
        Coded design points, one row per run.
    kind
        ``"ccd"``, ``"bbd"``, ``"dopt"`` or ``"user"``.
    """

    coded: np.ndarray
    kind: str

    def __post_init__(self) -> None:
        arr = np.atleast_2d(np.asarray(self.coded, dtype=float)).copy()
        arr.setflags(write=False)
        object.__setattr__(self, "coded", arr)

    @property
    def n_runs(self) -> int:
        return int(self.coded.shape[0])

    @property
    def n_factors(self) -> int:
        return int(self.coded.shape[1])

    def to_frame(self, space: DesignSpace) -> pd.DataFrame:
        """One row per run: ``run``, each factor in its unit and ``<name>_coded``."""
        if space.n_factors != self.n_factors:
            raise SpecError(
                f"the design has {self.n_factors} factors, the space {space.n_factors}",
                where="design",
            )
        values = space.decode(self.coded)
        data: dict[str, np.ndarray] = {"run": np.arange(1, self.n_runs + 1)}
        for j, f in enumerate(space.factors):
            data[f.name] = values[:, j]
        for j, f in enumerate(space.factors):
            data[f"{f.name}_coded"] = self.coded[:, j]
        return pd.DataFrame(data)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "coded": self.coded.tolist()}


def _k(factors: DesignSpace | int) -> int:
    k = factors.n_factors if isinstance(factors, DesignSpace) else int(factors)
    if k < 1:
        raise SpecError("a design needs at least one factor", where="factors")
    return k


def _names(factors: DesignSpace | int) -> list[str]:
    if isinstance(factors, DesignSpace):
        return list(factors.names)
    return [f"x{i + 1}" for i in range(int(factors))]


def _center(k: int, n_center: int) -> np.ndarray:
    if n_center < 0:
        raise SpecError("n_center must be >= 0", where="n_center")
    return np.zeros((int(n_center), k))


def central_composite(factors: DesignSpace | int, *, n_center: int = 1) -> Design:
    """Face-centred central composite design.

    Parameters
    ----------
    factors
        The design space, or the number of factors k.
    n_center
        Number of centre points (default 1).

    Returns
    -------
    Design
        2^k corners, 2k face points (one factor at ±1, others 0), ``n_center`` centre points:
        for k = 4, 16 + 8 + n_center runs.
    """
    k = _k(factors)
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=k)))
    axial = np.zeros((2 * k, k))
    for i in range(k):
        axial[2 * i, i] = -1.0
        axial[2 * i + 1, i] = 1.0
    return Design(np.vstack([corners, axial, _center(k, n_center)]), "ccd")


def box_behnken(factors: DesignSpace | int, *, n_center: int = 1) -> Design:
    """Box–Behnken design: ±1 2² factorial on every pair of factors, others at 0, plus centres.

    For k = 4: 6 pairs × 4 = 24 runs + ``n_center``. Needs k >= 3.
    """
    k = _k(factors)
    if k < 3:
        raise SpecError(
            f"a Box–Behnken design needs at least 3 factors, got {k}",
            where="runs",
            hint="use the central composite design (ccd) for 1 or 2 factors",
        )
    rows = []
    for i, j in itertools.combinations(range(k), 2):
        for a, b in itertools.product((-1.0, 1.0), repeat=2):
            row = np.zeros(k)
            row[i], row[j] = a, b
            rows.append(row)
    return Design(np.vstack([np.array(rows), _center(k, n_center)]), "bbd")


def log_det_information(coded: np.ndarray, terms: Sequence[Term]) -> float:
    """log det(XᵀX) of the model matrix; ``-inf`` if singular."""
    X = model_matrix(coded, terms)
    sign, logdet = np.linalg.slogdet(X.T @ X)
    if sign <= 0:
        return float("-inf")
    # slogdet of a numerically singular matrix returns a huge negative number: call it singular
    s = np.linalg.svd(X, compute_uv=False)
    if s[-1] <= _RANK_RTOL * s[0] * max(X.shape):
        return float("-inf")
    return float(logdet)


def d_optimal(
    factors: DesignSpace | int,
    n_runs: int,
    *,
    model: str | Sequence = "quadratic",
    seed: int | np.random.Generator = 0,
    candidates: np.ndarray | None = None,
    n_starts: int = 5,
    max_iter: int = 200,
) -> Design:
    """D-optimal design by Fedorov's exchange algorithm.

    Parameters
    ----------
    factors
        The design space, or the number of factors k.
    n_runs
        Number of runs; at least the number of model terms.
    model
        A named model (``"quadratic"`` ...) or a list of term names.
    seed
        Seed or Generator for the random starting designs.
    candidates
        Candidate points (coded, n_cand × k); default the 3^k grid of levels -1, 0, 1.
    n_starts
        Random starts; the design with the largest det(XᵀX) is returned.
    max_iter
        Maximum exchanges per start.

    Returns
    -------
    Design
        ``kind="dopt"``. Points may repeat (replicates) when that maximises det(XᵀX).
    """
    k = _k(factors)
    terms = parse_terms(model, _names(factors))
    p = len(terms)
    n = int(n_runs)
    if n < p:
        raise SpecError(
            f"a D-optimal design for {p} model terms needs at least {p} runs, got {n}",
            where="n_runs",
            hint=f"ask for >= {p} runs or a smaller model ({', '.join(MODELS)})",
        )
    if candidates is None:
        cand = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=k)))
    else:
        cand = np.atleast_2d(np.asarray(candidates, dtype=float))
        if cand.shape[1] != k or not np.all(np.isfinite(cand)) or np.any(np.abs(cand) > 1 + 1e-9):
            raise SpecError(
                f"candidates must be finite coded points in [-1, 1] with {k} columns",
                where="candidates",
            )
    F = model_matrix(cand, terms)
    if np.linalg.matrix_rank(F) < p:
        raise SpecError(
            "the candidate set cannot estimate the model", where="candidates",
            hint="add candidate points (three levels per factor for a quadratic model)",
        )
    rng = np.random.default_rng(seed)
    ridge = 1e-8 * n
    best_idx, best_val = None, -np.inf
    for _ in range(max(1, int(n_starts))):
        idx = rng.choice(len(cand), size=n, replace=n > len(cand))
        for _it in range(int(max_iter)):
            X = F[idx]
            Minv = np.linalg.inv(X.T @ X + ridge * np.eye(p))
            d_all = np.einsum("ij,jk,ik->i", F, Minv, F)
            d_cur = d_all[idx]
            d_cross = F[idx] @ Minv @ F.T  # (n, n_cand)
            # Fedorov: det(M') / det(M) = 1 + d_j - d_i - (d_i d_j - d_ij^2)
            delta = d_all[None, :] - d_cur[:, None] * (1.0 + d_all[None, :]) + d_cross**2
            i, j = np.unravel_index(int(np.argmax(delta)), delta.shape)
            if delta[i, j] <= 1e-10:
                break
            idx[i] = j
        val = log_det_information(cand[idx], terms)
        if val > best_val:
            best_val, best_idx = val, idx.copy()
    if best_idx is None or not np.isfinite(best_val):
        raise SpecError("no non-singular D-optimal design was found", where="runs")
    order = np.lexsort(cand[best_idx].T[::-1])
    return Design(cand[best_idx][order], "dopt")


def read_runs_csv(path: str | Path, space: DesignSpace) -> Design:
    """Read a user list of runs.

    The CSV has one row per run and one column per factor, named as the factor, in the factor's
    unit (e.g. ``stiffness_kN_per_m,width_m,height_m,toe_length_m``); or, instead, columns
    ``<name>_coded`` in coded units. Other columns (``run``, ``blade`` ...) are ignored.
    """
    path = Path(path)
    if not path.is_file():
        raise InputFileError("run list not found", file=path, hint="give a CSV of design points")
    try:
        df = pd.read_csv(path, comment="#")
    except Exception as exc:  # pandas raises several types
        raise InputFileError(f"cannot read the run list as CSV ({exc})", file=path) from None
    df.columns = [str(c).strip() for c in df.columns]
    if df.empty:
        raise DataError("the run list has no runs", file=path)
    names = list(space.names)
    coded_cols = [f"{n}_coded" for n in names]
    if all(n in df.columns for n in names):
        cols, coded = names, False
    elif all(c in df.columns for c in coded_cols):
        cols, coded = coded_cols, True
    else:
        missing = [n for n in names if n not in df.columns]
        raise DataError(
            f"missing factor column(s) {missing}",
            file=path,
            hint=f"the header must name every factor: {','.join(names)} (values in the factors' "
            "units), or <name>_coded columns",
        )
    values = df[cols].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        r, c = (int(v) for v in bad[0])
        raise DataError(
            f"row {r + 1}: {cols[c]} = {df[cols[c]].iloc[r]!r} is not a number",
            file=path,
            where=cols[c],
        )
    try:
        arr = values if coded else space.code(values)
        space.check_coded(arr, what="run list")
    except SpecError as err:
        raise SpecError(err.message, file=path, where=err.where, hint=err.hint) from None
    return Design(arr, "user")


def make_design(
    runs: str | Path | Design | np.ndarray,
    space: DesignSpace,
    *,
    n_runs: int | None = None,
    n_center: int = 1,
    model: str | Sequence = "quadratic",
    seed: int | np.random.Generator = 0,
) -> Design:
    """A design from ``"ccd"``, ``"bbd"``, ``"dopt"``, a CSV path, a Design or coded points."""
    if isinstance(runs, Design):
        if runs.n_factors != space.n_factors:
            raise SpecError(
                f"the design has {runs.n_factors} factors, the space {space.n_factors}",
                where="runs",
            )
        space.check_coded(runs.coded)
        return runs
    if isinstance(runs, np.ndarray):
        d = Design(runs, "user")
        return make_design(d, space)
    key = str(runs).lower()
    if key == "ccd":
        return central_composite(space, n_center=n_center)
    if key == "bbd":
        return box_behnken(space, n_center=n_center)
    if key == "dopt":
        p = len(parse_terms(model, space.names))
        n = p + max(3, space.n_factors) if n_runs is None else n_runs
        return d_optimal(space, n, model=model, seed=seed)
    path = Path(runs)
    if path.suffix.lower() == ".csv" or path.exists():
        return read_runs_csv(path, space)
    raise SpecError(
        f"unknown design {runs!r}", where="runs", hint="use ccd, bbd, dopt or a CSV file of runs"
    )


@dataclass(frozen=True)
class EstimabilityReport:
    """What a design can estimate for a model.

    Attributes
    ----------
    n_runs, n_terms, rank
        Runs, model terms, rank of the model matrix.
    df_resid
        Residual degrees of freedom n_runs - n_terms.
    condition_number
        Of the model matrix (2-norm); ``inf`` if singular.
    d_efficiency
        100·det(XᵀX)^(1/p)/n [%]; 0 if singular.
    max_vif
        Largest variance inflation factor of a non-intercept term; ``inf`` if singular.
    terms, estimable_terms, aliased_terms
        Term names: all; those estimable in hierarchical order; those aliased with earlier ones.
    estimable
        True if every term can be estimated (rank == n_terms).
    """

    n_runs: int
    n_terms: int
    rank: int
    df_resid: int
    condition_number: float
    d_efficiency: float
    max_vif: float
    terms: tuple[str, ...]
    estimable_terms: tuple[str, ...]
    aliased_terms: tuple[str, ...]
    estimable: bool

    def to_dict(self) -> dict:
        return {
            "n_runs": self.n_runs,
            "n_terms": self.n_terms,
            "rank": self.rank,
            "df_resid": self.df_resid,
            "condition_number": self.condition_number,
            "d_efficiency_percent": self.d_efficiency,
            "max_vif": self.max_vif,
            "terms": list(self.terms),
            "estimable_terms": list(self.estimable_terms),
            "aliased_terms": list(self.aliased_terms),
            "estimable": self.estimable,
        }


def _rank(X: np.ndarray) -> int:
    if X.size == 0:
        return 0
    s = np.linalg.svd(X, compute_uv=False)
    return int(np.sum(s > _RANK_RTOL * s[0] * max(X.shape))) if s[0] > 0 else 0


def estimability(
    coded: np.ndarray | Design, terms: Sequence[Term], names: Sequence[str]
) -> EstimabilityReport:
    """Rank and conditioning report of a design for a model.

    Terms are taken in the given (hierarchical) order; a term that does not raise the rank of
    the model matrix is aliased with the terms before it.
    """
    pts = coded.coded if isinstance(coded, Design) else np.atleast_2d(np.asarray(coded, float))
    X = model_matrix(pts, terms)
    n, p = X.shape
    rank = _rank(X)
    keep: list[int] = []
    aliased: list[int] = []
    for j in range(p):
        if _rank(X[:, keep + [j]]) > len(keep):
            keep.append(j)
        else:
            aliased.append(j)
    if rank == p:
        s = np.linalg.svd(X, compute_uv=False)
        cond = float(s[0] / s[-1])
        sign, logdet = np.linalg.slogdet(X.T @ X)
        d_eff = float(100.0 * np.exp(logdet / p) / n)
        xtx_inv = np.linalg.inv(X.T @ X)
        centred = X - X.mean(axis=0)
        ss = np.sum(centred**2, axis=0)
        vifs = [xtx_inv[j, j] * ss[j] for j in range(p) if terms[j] != ()]
        max_vif = float(max(vifs)) if vifs else 1.0
    else:
        cond, d_eff, max_vif = float("inf"), 0.0, float("inf")
    term_names = tuple(term_name(t, names) for t in terms)
    return EstimabilityReport(
        n_runs=n,
        n_terms=p,
        rank=rank,
        df_resid=n - p,
        condition_number=cond,
        d_efficiency=d_eff,
        max_vif=max_vif,
        terms=term_names,
        estimable_terms=tuple(term_names[j] for j in keep),
        aliased_terms=tuple(term_names[j] for j in aliased),
        estimable=rank == p,
    )


def require_estimable(
    coded: np.ndarray | Design,
    terms: Sequence[Term],
    names: Sequence[str],
    *,
    min_df_resid: int = 1,
) -> EstimabilityReport:
    """The :func:`estimability` report, or a :class:`SpecError` suggesting a reduced model.

    A model is refused if the design cannot estimate all its terms, or leaves fewer than
    ``min_df_resid`` residual degrees of freedom (no error estimate, no PRESS).
    """
    rep = estimability(coded, terms, names)
    if rep.estimable and rep.df_resid >= min_df_resid:
        return rep
    pts = coded.coded if isinstance(coded, Design) else np.atleast_2d(np.asarray(coded, float))
    fitting = []
    for m in ("quadratic", "interaction", "pure_quadratic", "linear"):
        r = estimability(pts, parse_terms(m, names), names)
        if r.estimable and r.df_resid >= min_df_resid:
            fitting.append(f"{m} ({r.n_terms} terms)")
    max_terms = min(rep.rank, rep.n_runs - min_df_resid)
    subset = ",".join(rep.estimable_terms[: max(max_terms, 1)])
    why = (
        f"{rep.n_runs} runs cannot estimate the {rep.n_terms}-term model (rank {rep.rank}"
        + (f"; aliased: {', '.join(rep.aliased_terms)}" if rep.aliased_terms else "")
        + ")"
        if not rep.estimable
        else f"{rep.n_runs} runs leave {rep.df_resid} residual degrees of freedom for the "
        f"{rep.n_terms}-term model (need >= {min_df_resid})"
    )
    hint = f"fit a reduced model of at most {max_terms} terms"
    if fitting:
        hint += f", e.g. model={fitting[0].split(' ')[0]!r}; estimable named models: " + "; ".join(
            fitting
        )
    if max_terms >= 1:
        hint += f"; or terms={subset!r}"
    hint += "; or add runs"
    raise SpecError(why, where="model", hint=hint)
