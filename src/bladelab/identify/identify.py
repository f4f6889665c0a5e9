"""Identify K* and D* of one stance with the blade simulation (seed 000 §2.3), and compare models.

:func:`identify_stance` prepares the simulation once (``bladelab.sim.prepare``), then lets the chosen
optimiser propose (K, D[, K2]) candidates; every iteration's candidates are simulated in one
``simulate_batch`` call and scored by :class:`~bladelab.identify.cost.StanceCost`. After the search
:func:`~bladelab.identify.identifiability.assess_identifiability` gives the K–D correlation and
profile-likelihood confidence intervals. :func:`compare_spring_locations` repeats this for
candidate hinge positions over a set of stances; :func:`compare_spring_models` compares the linear
and the nonlinear (K + K2·|q|) spring by AIC/BIC.
"""

from __future__ import annotations

import dataclasses
import math
import re
import time
from collections.abc import Sequence

import numpy as np
import pandas as pd

from bladelab import sim
from bladelab.blade import load_blade
from bladelab.blade.model import BladeModel
from bladelab.errors import DataError, ModelError, OptimizationError
from bladelab.identify.bounds import (
    FALLBACK_STIFFNESS_BOUNDS_NM_PER_DEG,
    ParameterBounds,
    make_bounds,
    parameter_bounds,
)
from bladelab.identify.cost import StanceCost
from bladelab.identify.formulations import DEFAULT_FORMULATION, DISTANCE_ONLY, formulation_drive
from bladelab.identify.identifiability import (
    assess_identifiability,
    cost_landscape,
    effective_sample_size,
)
from bladelab.identify.optimizers import minimize
from bladelab.identify.quality import TrialQuality, assess_quality
from bladelab.parameters import JOINT_PARAMETERS
from bladelab.sim.api import DEFAULT_DT


@dataclasses.dataclass(frozen=True)
class Identification:
    """Identified parameters of one stance (edge units: N·m/deg, N·m·s/deg; errors in %).

    Attributes
    ----------
    K_Nm_per_deg, D_Nms_per_deg
        K* and D*.
    K2_Nm_per_deg2
        Quadratic stiffness of the nonlinear spring (τ = −(K·q + K2·q·|q|)), None for linear.
    nrmse_grf_pct, nrmse_distance_pct
        nRMSE of GRF and distance at the optimum [%].
    cost
        J at the optimum (fraction).
    evaluations
        Simulations used (search + polish; identifiability excluded, see ``ci_evaluations``).
    wall_s
        Wall-clock time of the whole identification [s] (set-up included).
    seed, optimizer
        As given.
    joint_point
        Hinge position (index into the blade's points).
    ci
        Parameter name -> (low, high) confidence interval in edge units (empty if not computed).
    ci_level
        Confidence level.
    KD_correlation
        Correlation of the K and D estimates (Gauss–Newton), NaN if not computed.
    poorly_determined
        Names of the parameters flagged as poorly determined, with reasons.
    aic, bic
        Information criteria from the residual sum of squares with the effective sample size.
    bounds
        The search bounds (edge units, with their source).
    ci_evaluations
        Simulations used by the identifiability analysis.
    formulation
        How the stance drove the model (:mod:`bladelab.identify.formulations`).
    quality
        Quality indicators and flags (:mod:`bladelab.identify.quality`).
    notes
        What the identifiability step changed (estimate moved to the profiles' lowest point,
        interval widened or clipped), in words.
    """

    K_Nm_per_deg: float
    D_Nms_per_deg: float
    K2_Nm_per_deg2: float | None
    nrmse_grf_pct: float
    nrmse_distance_pct: float
    cost: float
    evaluations: int
    wall_s: float
    seed: int
    optimizer: str
    joint_point: int
    ci: dict[str, tuple[float, float]]
    ci_level: float
    KD_correlation: float
    poorly_determined: dict[str, str]
    aic: float
    bic: float
    bounds: dict
    ci_evaluations: int
    formulation: str = "seed"
    quality: TrialQuality | None = None
    notes: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """JSON-ready dictionary with the keys of the CLI's ``--json`` output."""
        out = {
            "K_Nm_per_deg": self.K_Nm_per_deg,
            "D_Nms_per_deg": self.D_Nms_per_deg,
            "nrmse_grf_pct": self.nrmse_grf_pct,
            "nrmse_distance_pct": self.nrmse_distance_pct,
            "cost": self.cost,
            "evaluations": self.evaluations,
            "wall_s": self.wall_s,
            "seed": self.seed,
        }
        if self.K2_Nm_per_deg2 is not None:
            out["K2_Nm_per_deg2"] = self.K2_Nm_per_deg2
        for name, key in ((n, p.ci_key) for n, p in JOINT_PARAMETERS.items()):
            if name in self.ci:
                out[key] = list(self.ci[name])
        out.update({
            "ci_level": self.ci_level,
            "ci_method": "profile likelihood",
            "KD_correlation": None if math.isnan(self.KD_correlation) else self.KD_correlation,
            "poorly_determined": dict(self.poorly_determined),
            "optimizer": self.optimizer,
            "formulation": self.formulation,
            "joint_point": self.joint_point,
            "aic": self.aic,
            "bic": self.bic,
            "bounds": self.bounds,
            "ci_evaluations": self.ci_evaluations,
            "notes": list(self.notes),
        })
        if self.quality is not None:
            out["quality"] = self.quality.to_dict()
        return out

    def to_row(self) -> dict:
        """Columns of the ``results.sqlite`` table."""
        row = {
            "K_Nm_per_deg": self.K_Nm_per_deg, "D_Nms_per_deg": self.D_Nms_per_deg,
            "K2_Nm_per_deg2": self.K2_Nm_per_deg2, "nrmse_grf_pct": self.nrmse_grf_pct,
            "nrmse_distance_pct": self.nrmse_distance_pct, "cost": self.cost,
            "evaluations": self.evaluations, "wall_s": self.wall_s, "aic": self.aic, "bic": self.bic,
            "KD_correlation": None if math.isnan(self.KD_correlation) else self.KD_correlation,
            "poorly_determined": "; ".join(f"{k}: {v}" for k, v in self.poorly_determined.items()),
        }
        if "K" in self.ci:
            row["K_ci_low_Nm_per_deg"], row["K_ci_high_Nm_per_deg"] = self.ci["K"]
        if "D" in self.ci:
            row["D_ci_low_Nms_per_deg"], row["D_ci_high_Nms_per_deg"] = self.ci["D"]
        if self.quality is not None:
            row.update(self.quality.to_row())
        return row


def _as_model(blade: BladeModel | str) -> BladeModel:
    if isinstance(blade, BladeModel):
        return blade
    return load_blade(blade).build()


def _with_joint(blade: BladeModel, joint: int | None) -> BladeModel:
    if len(blade.joints) != 1:
        raise ModelError(f"identification needs a blade with one compliant joint, this one has "
                         f"{len(blade.joints)}", where="blade.joints")
    if joint is None:
        return blade
    if not 1 <= joint <= blade.n_segments - 1:
        raise ModelError(f"joint point {joint} outside 1..{blade.n_segments - 1}", where="joint")
    return dataclasses.replace(blade, joints=(dataclasses.replace(blade.joints[0], point=int(joint)),))


def _to_edge(name: str, value: float) -> float:
    return JOINT_PARAMETERS[name].to_edge(value)


PHYSICAL_LOWER: dict[str, float] = {"K": 0.0, "D": 0.0}
"""Lowest physical value of each parameter (SI): a confidence limit below it is clipped."""

SYSTEMATIC_REL_SD: dict[str, float] = {"K": 0.002, "D": 0.030}
"""Relative SD of the systematic error of the measurement pipeline per parameter (fraction of the
estimate), added in quadrature (±1.96·σ·estimate) to the statistical interval of the formulations
in :data:`SYSTEMATIC_FORMULATIONS`. Calibrated by ``benchmarks/bench_coverage.py`` on degraded
synthetic stances (markers 100 Hz with 1 mm noise, 20 Hz low-pass, forces 1 kHz 1 %) so that
the 95 % intervals cover the truth 95 % of the time; checked on held-out stances
(benchmarks/RESULTS.md, "Coverage")."""

SYSTEMATIC_FORMULATIONS: tuple[str, ...] = ("utilised-friction",)
"""Formulations :data:`SYSTEMATIC_REL_SD` was calibrated for."""


def _with_systematic(ci: dict, estimate: dict) -> dict:
    """Intervals widened in quadrature by ±1.96·σ_sys·estimate, clipped at the physical minimum."""
    out = dict(ci)
    for name, (lo, hi) in ci.items():
        s = SYSTEMATIC_REL_SD.get(name, 0.0)
        if s <= 0:
            continue
        x = estimate[name]
        add = 1.959964 * s * abs(x)
        lo2, hi2 = x - math.hypot(x - lo, add), x + math.hypot(hi - x, add)
        floor = PHYSICAL_LOWER.get(name)
        out[name] = (max(lo2, floor) if floor is not None else lo2, hi2)
    return out


def _edge_note(note: str) -> str:
    """An identifiability note with the SI values of K and D in edge units (N·m/deg ...)."""
    def conv(m):
        name, a, b = m.group(1), float(m.group(2)), float(m.group(3))
        p = JOINT_PARAMETERS[name]
        return f"{name} {p.to_edge(a):.4g} -> {p.to_edge(b):.4g} {p.edge_unit}"

    return re.sub(r"\b(K2|K|D) ([-+0-9.eE]+) -> ([-+0-9.eE]+)", conv, note)


def identify_stance(
    stance,
    blade: BladeModel | str,
    *,
    optimizer: str = "pso",
    seed: int = 0,
    weights: tuple[float, float] = (0.5, 0.5),
    grf_components: Sequence[str] = ("z",),
    joint: int | None = None,
    nonlinear: bool = False,
    polish: bool | None = None,
    bounds: ParameterBounds | None = None,
    max_evals: int = 600,
    identifiability: bool = True,
    dt: float = DEFAULT_DT,
    engine: str = "kernel",
    belt_speed: float = 0.0,
    contact_threshold: float = 20.0,
    formulation: str = DEFAULT_FORMULATION,
    ci_variance: str = "hac",
    ci_systematic: bool = True,
) -> Identification:
    """Identify K* [N·m/deg] and D* [N·m·s/deg] (and K2 if ``nonlinear``) of one stance.

    Parameters
    ----------
    stance
        A :class:`bladelab.trial.Stance` (clamp pose, GRF, distance).
    blade
        A built :class:`BladeModel` or a blade name / spec file for ``bladelab.blade.load_blade``.
    optimizer
        ``"pso"`` (seed 000, 20 × 30) or ``"cmaes"``.
    seed
        Seed of the optimiser (same seed, same result).
    weights
        (w_grf, w_dst) of the cost.
    grf_components
        ``("z",)`` or ``("z", "x")``.
    joint
        Hinge position (index into ``blade.points``); None = the blade's own.
    nonlinear
        Identify K2 of τ = −(K·q + K2·q·|q|) − D·q̇ as well.
    polish
        Refine the optimum with bounded L-BFGS-B. None (default): on for the nonlinear model, off
        for the linear one. (In the 3-D nonlinear problem K and K2 lie in a long, narrow valley
        that PSO 20 × 30 alone leaves 4–34 % off on MuJoCo stances; with the polish, or with
        CMA-ES, K came within 1.3 %.)
    bounds
        Search bounds (SI); default from the stance's instantaneous stiffness
        (:func:`~bladelab.identify.bounds.parameter_bounds`).
    max_evals
        Evaluation budget of the global search.
    identifiability
        Compute the K–D correlation and confidence intervals.
    dt, engine, belt_speed
        Passed to ``bladelab.sim.prepare`` (``dt`` [s], default the kernel's default accuracy).
    contact_threshold
        Vertical GRF [N] defining the contact window of the cost.
    formulation
        How the stance drives the model (:mod:`bladelab.identify.formulations`):
        ``"utilised-friction"`` (default: friction of each sole element = measured Fx/Fz × its
        normal force; robust to motion-capture noise and 100 Hz kinematics) or ``"seed"`` (seed
        000 exactly: prescribed clamp, stick-slip friction) or ``"grf-driven"`` (the measured GRF
        drives the model, distance-only cost: ``weights`` is then (0, 1)). See
        docs/robust-identification.md.

    ci_variance
        Scale of the confidence intervals: ``"hac"`` (default; Newey–West inflation for
        autocorrelated residuals, per channel) or ``"ar1"`` (one AR(1) effective sample size):
        :func:`~bladelab.identify.identifiability.assess_identifiability`.
    ci_systematic
        Widen the intervals by the calibrated systematic error of the measurement pipeline
        (:data:`SYSTEMATIC_REL_SD`; only for :data:`SYSTEMATIC_FORMULATIONS`).

    Raises
    ------
    DataError
        No contact, a constant or missing channel.
    OptimizationError
        Bad bounds or options.
    """
    t0 = time.perf_counter()
    drive = formulation_drive(formulation)
    if formulation in DISTANCE_ONLY:
        weights = (0.0, 1.0)  # its simulated GRF is the measured one
    model = _with_joint(_as_model(blade), joint)
    point = model.joints[0].point
    cost = StanceCost.from_stance(stance, weights=weights, grf_components=grf_components,
                                  contact_threshold=contact_threshold)
    if bounds is None:
        try:
            soles = np.array([e.center for e in model.soles]) if model.soles else None
            bounds = parameter_bounds(
                stance, hinge=model.points[point], tip=model.tip,
                contact_point=None if soles is None else soles.mean(axis=0),
                nonlinear=nonlinear, contact_threshold=contact_threshold)
        except DataError as err:
            if "no contact" in err.message:
                raise
            fb = make_bounds(k_nm_per_deg=FALLBACK_STIFFNESS_BOUNDS_NM_PER_DEG, source="fallback")
            bounds = fb
            if nonlinear:
                hi = fb.upper[0]
                bounds = ParameterBounds(("K", "D", "K2"), (*fb.lower, -hi / 0.5),
                                         (*fb.upper, hi / 0.5), source="fallback")
    expected = ("K", "D", "K2") if nonlinear else ("K", "D")
    if tuple(bounds.names) != expected:
        raise ModelError(f"bounds are for {bounds.names}, the model needs {expected}", where="bounds")
    problem = sim.prepare(model, stance, dt=dt, engine=engine, belt_speed=belt_speed,
                          drive=drive)

    def run(X: np.ndarray):
        X = np.atleast_2d(X)
        if not np.all(np.isfinite(X)):
            raise OptimizationError("a non-finite candidate reached the simulation",
                                    where="identify", hint="report this as a bug")
        k2 = X[:, 2:3] if nonlinear else np.zeros((len(X), 1))
        return sim.simulate_batch(problem, X[:, 0:1], X[:, 1:2], k2)

    def fun_batch(X: np.ndarray) -> np.ndarray:
        res = run(X)
        return cost.evaluate(grf_z=res.grf_z, grf_x=res.grf_x, distance=res.distance).cost

    def residual_batch(X: np.ndarray) -> np.ndarray:
        res = run(X)
        return cost.residuals(grf_z=res.grf_z, grf_x=res.grf_x, distance=res.distance)

    box = bounds.as_array()
    if nonlinear:
        box[2, 0] = max(box[2, 0], 0.0)  # stiffening spring only: the engines take K2 >= 0
    if polish is None:
        polish = nonlinear
    opt = minimize(fun_batch, box, optimizer=optimizer, seed=seed, max_evals=max_evals,
                   polish=polish)
    x = np.asarray(opt.x, dtype=float)
    ci: dict[str, tuple[float, float]] = {}
    ci_open: dict[str, bool] = {}
    corr = float("nan")
    flagged: dict[str, str] = {}
    notes: tuple[str, ...] = ()
    converged: bool | None = None
    ci_evals = 0
    names = bounds.names
    n_eff = None
    if identifiability:
        ident = assess_identifiability(residual_batch, x, box, names=names,
                                       physical_lower=PHYSICAL_LOWER, variance=ci_variance,
                                       blocks=cost.residual_blocks())
        x = ident.x  # the lowest point the profiles found, if clearly below the search's optimum
        ci = {n: (_to_edge(n, lo), _to_edge(n, hi))
              for n, lo, hi in zip(names, ident.ci_lower, ident.ci_upper, strict=True)}
        ci_open = dict(zip(names, ident.ci_open, strict=True))
        corr = float(ident.correlation[0, 1])
        flagged = {n: why for n, flag, why in zip(names, ident.poorly_determined, ident.reasons,
                                                   strict=True) if flag}
        ci_evals = ident.evaluations
        n_eff = ident.n_effective
        converged = ident.converged
        notes = tuple(_edge_note(n) for n in ident.notes)
        if ci_systematic and formulation in SYSTEMATIC_FORMULATIONS:
            ci = _with_systematic(ci, {n: _to_edge(n, v) for n, v in zip(names, x, strict=True)})
    res = run(x[None, :])
    terms = cost.evaluate(grf_z=res.grf_z, grf_x=res.grf_x, distance=res.distance)
    r = cost.residuals(grf_z=res.grf_z, grf_x=res.grf_x, distance=res.distance)[0]
    if n_eff is None:
        n_eff = effective_sample_size(r, len(names))
    rss = max(float(r @ r), 1e-300)
    k = len(names)
    aic = n_eff * math.log(rss / n_eff) + 2 * k
    bic = n_eff * math.log(rss / n_eff) + k * math.log(n_eff)
    estimate = {n: _to_edge(n, v) for n, v in zip(names, x, strict=True)}
    edge_bounds = {n: (_to_edge(n, lo), _to_edge(n, hi)) for n, (lo, hi) in zip(names, box, strict=True)}
    quality = assess_quality(
        estimate=estimate, bounds=edge_bounds, ci=ci, ci_open=ci_open, correlation=corr,
        converged=converged, nrmse_grf_pct=100 * float(terms.nrmse_grf[0]),
        nrmse_distance_pct=100 * float(terms.nrmse_distance[0]),
        peak_force_measured_N=float(np.max(cost.references.get("grf_z", stance.grf_z[cost.mask]))),
        peak_force_simulated_N=float(np.max(np.asarray(res.grf_z)[0][cost.mask])),
    )
    return Identification(
        K_Nm_per_deg=estimate["K"], D_Nms_per_deg=estimate["D"],
        K2_Nm_per_deg2=estimate["K2"] if nonlinear else None,
        nrmse_grf_pct=100 * float(terms.nrmse_grf[0]),
        nrmse_distance_pct=100 * float(terms.nrmse_distance[0]), cost=float(terms.cost[0]),
        evaluations=opt.evaluations, wall_s=time.perf_counter() - t0, seed=int(seed),
        optimizer=opt.optimizer, joint_point=point, ci=ci, ci_level=0.95, KD_correlation=corr,
        poorly_determined=flagged, aic=float(aic), bic=float(bic), bounds=bounds.to_dict(),
        ci_evaluations=ci_evals, formulation=str(formulation), quality=quality, notes=notes,
    )


def identification_landscape(
    stance,
    blade: BladeModel | str,
    ident: Identification,
    *,
    n: int = 21,
    rel_span: float = 0.3,
    weights: tuple[float, float] = (0.5, 0.5),
    grf_components: Sequence[str] = ("z",),
    dt: float = DEFAULT_DT,
    belt_speed: float = 0.0,
    contact_threshold: float = 20.0,
    formulation: str | None = None,
) -> pd.DataFrame:
    """The cost on an n × n K × D grid (± ``rel_span``) around an identification, one batch.

    Use the same cost options as the identification (``formulation`` None: the
    identification's own). Returns a tidy DataFrame with columns
    ``K_Nm_per_deg``, ``D_Nms_per_deg``, ``cost`` (K2, if any, held at its identified value).
    """
    model = _with_joint(_as_model(blade), ident.joint_point)
    if (ident.formulation if formulation is None else formulation) in DISTANCE_ONLY:
        weights = (0.0, 1.0)
    cost = StanceCost.from_stance(stance, weights=weights, grf_components=grf_components,
                                  contact_threshold=contact_threshold)
    problem = sim.prepare(model, stance, dt=dt, belt_speed=belt_speed, drive=formulation_drive(
        ident.formulation if formulation is None else formulation))
    k2 = 0.0 if ident.K2_Nm_per_deg2 is None else JOINT_PARAMETERS["K2"].from_edge(ident.K2_Nm_per_deg2)

    def fun_batch(X: np.ndarray) -> np.ndarray:
        res = sim.simulate_batch(problem, X[:, 0:1], X[:, 1:2], np.full((len(X), 1), k2))
        return cost.evaluate(grf_z=res.grf_z, grf_x=res.grf_x, distance=res.distance).cost

    K, D = JOINT_PARAMETERS["K"], JOINT_PARAMETERS["D"]
    centre = [K.from_edge(ident.K_Nm_per_deg), D.from_edge(ident.D_Nms_per_deg)]
    box = [[c * (1 - rel_span), c * (1 + rel_span)] for c in centre]
    df = cost_landscape(fun_batch, centre, box, names=("K", "D"), n=n, rel_span=rel_span)
    return pd.DataFrame({K.edge_key: K.to_edge(df["K"].to_numpy()),
                         D.edge_key: D.to_edge(df["D"].to_numpy()),
                         "cost": df["cost"].to_numpy()})


def compare_spring_locations(
    stances: Sequence,
    blade: BladeModel | str,
    *,
    points: Sequence[int] = (5, 6, 7),
    seed: int = 0,
    **options,
) -> pd.DataFrame:
    """Mean identification cost per candidate hinge position over a set of stances (seed 000).

    ``points`` index the blade's segment end points: the hinge between segments i and i+1 (1-based,
    as in seed 000's "7–8") is point i. Returns a tidy DataFrame with columns ``joint_point``,
    ``mean_cost``, ``sd_cost``, ``mean_K_Nm_per_deg``, ``mean_D_Nms_per_deg``, ``best`` (True on
    the row with the lowest mean cost).
    """
    model = _as_model(blade)
    rows = []
    for p in points:
        ids = [identify_stance(s, model, joint=p, seed=seed, identifiability=False, **options)
               for s in stances]
        costs = np.array([i.cost for i in ids])
        rows.append({
            "joint_point": int(p), "mean_cost": float(costs.mean()),
            "sd_cost": float(costs.std(ddof=1)) if len(costs) > 1 else 0.0,
            "mean_K_Nm_per_deg": float(np.mean([i.K_Nm_per_deg for i in ids])),
            "mean_D_Nms_per_deg": float(np.mean([i.D_Nms_per_deg for i in ids])),
        })
    df = pd.DataFrame(rows)
    df["best"] = df["mean_cost"] == df["mean_cost"].min()
    return df


def compare_spring_models(stance, blade: BladeModel | str, *, seed: int = 0, **options) -> pd.DataFrame:
    """Linear vs nonlinear spring on one stance: cost, AIC, BIC; ``preferred`` marks the lower BIC."""
    rows = []
    for nonlinear in (False, True):
        ident = identify_stance(stance, blade, nonlinear=nonlinear, seed=seed, **options)
        rows.append({"model": "nonlinear" if nonlinear else "linear", "cost": ident.cost,
                     "aic": ident.aic, "bic": ident.bic, "K_Nm_per_deg": ident.K_Nm_per_deg,
                     "D_Nms_per_deg": ident.D_Nms_per_deg, "K2_Nm_per_deg2": ident.K2_Nm_per_deg2})
    df = pd.DataFrame(rows)
    df["preferred"] = df["bic"] == df["bic"].min()
    return df
