"""Coverage of the 95 % confidence intervals of K* and D*.

How often does the interval contain the true value? Stances come from the MuJoCo runner generator
(``bladelab.sim.synthetic.generate_stance``, not the identification model; the cases of
``bench_robust.make_cases``: both blade families, K 13–22 N·m/deg, D 0.15–0.5 N·m·s/deg, 4–9 m/s),
clean and degraded as a lab records them (``bladelab.example.degrade_stance``: cluster and tip
markers at 100 Hz with 1 mm noise, 20 Hz low-pass, forces 1 kHz with 1 % noise). Each is
identified with the default formulation (utilised friction), PSO 20 × 30, and its interval
computed three ways:

- ``ar1``: the profile likelihood with one AR(1) effective sample size (the method before ``hac+sys``);
- ``hac``: the profile likelihood with a per-parameter Newey–West scale, per measured channel
  (``bladelab.identify.identifiability.hac_inflation``);
- ``hac+sys`` (the default): ``hac`` widened in quadrature by the systematic error
  of the measurement pipeline, ±1.96·σ_sys·estimate (``SYSTEMATIC_REL_SD`` in
  ``bladelab.identify.identify``), σ_sys the smallest σ (step 0.1 %) for which the degraded
  stances reach 95 % coverage. Two sets of stances are drawn with different seeds; σ_sys is
  calibrated on each and tested on the other (2-fold cross-validation: the out-of-sample
  coverage), and the package's value is calibrated on both.

Run alone: ``python benchmarks/run.py coverage`` (about 10 minutes on 2 cores).
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from bench_robust import _markdown, clean_stance, make_cases  # noqa: E402
from tqdm import tqdm  # noqa: E402

from bladelab.example.measurement import degrade_stance  # noqa: E402
from bladelab.identify.identify import identify_stance  # noqa: E402

HERE = Path(__file__).resolve().parent
RAW = HERE / "results" / "coverage-raw.csv"
N_STANCES = 60
CALIBRATION_SEED, HELD_OUT_SEED = 7, 11
PARAMS = {"K": "K_Nm_per_deg", "D": "D_Nms_per_deg"}


def identify_all(n: int, seed: int, split: str) -> pd.DataFrame:
    """Identify every case clean and degraded with the ar1 and the hac interval (no systematic
    term: it is applied afterwards, from the hac interval)."""
    rows = []
    for case in tqdm(make_cases(n, seed=seed), desc=f"coverage: {split}"):
        blade, stance, tip, _ = clean_stance(case)
        deg = degrade_stance(stance, tip=tip, marker_rate_hz=100.0, marker_noise_m=1e-3,
                             force_noise_frac=0.01, seed=seed * 1000 + int(case["id"][1:]))
        for condition, st in (("clean", stance), ("degraded 100 Hz, 1 mm", deg)):
            for variance in ("ar1", "hac"):
                ident = identify_stance(st, blade, seed=0, ci_variance=variance,
                                        ci_systematic=False)
                row = {**case, "split": split, "condition": condition, "variance": variance,
                       "flagged": ident.quality.flagged}
                for p, col in PARAMS.items():
                    row[f"{p}_hat"] = getattr(ident, col)
                    row[f"{p}_lo"], row[f"{p}_hi"] = ident.ci[p]
                rows.append(row)
    return pd.DataFrame(rows)


def widen(df: pd.DataFrame, sigma: dict[str, float]) -> pd.DataFrame:
    """The intervals widened in quadrature by ±1.96·σ·estimate (per parameter)."""
    out = df.copy()
    for p, s in sigma.items():
        add = 1.959964 * s * out[f"{p}_hat"].abs()
        out[f"{p}_lo"] = out[f"{p}_hat"] - np.hypot(out[f"{p}_hat"] - out[f"{p}_lo"], add)
        out[f"{p}_hi"] = out[f"{p}_hat"] + np.hypot(out[f"{p}_hi"] - out[f"{p}_hat"], add)
    return out


def covered(df: pd.DataFrame, p: str) -> pd.Series:
    return (df[f"{p}_lo"] <= df[p]) & (df[p] <= df[f"{p}_hi"])


def calibrate(df: pd.DataFrame, p: str, target: float = 0.95) -> float:
    """Smallest σ_sys (relative SD, step 0.1 %) giving ``target`` coverage of ``p`` on ``df``."""
    for s in np.arange(0.0, 0.30001, 0.001):
        if covered(widen(df, {p: float(s)}), p).mean() >= target:
            return round(float(s), 4)
    return 0.30


def table(frames: dict[str, pd.DataFrame]) -> pd.DataFrame:
    rows = []
    for method, df in frames.items():
        for (split, cond), g in df.groupby(["split", "condition"], sort=False):
            row = {"interval": method, "stances": f"{split} ({len(g)})", "condition": cond}
            for p in PARAMS:
                hw = 50 * (g[f"{p}_hi"] - g[f"{p}_lo"]) / g[f"{p}_hat"].abs()
                row[f"{p} coverage"] = f"{100 * covered(g, p).mean():.0f} %"
                row[f"{p} CI ± median [%]"] = f"{hw.median():.2f}"
            rows.append(row)
    return pd.DataFrame(rows)


def run() -> str:
    t0 = time.perf_counter()
    timing = RAW.with_suffix(".json")
    if RAW.is_file() and timing.is_file() and os.environ.get("BLADELAB_COVERAGE_REUSE"):
        raw = pd.read_csv(RAW)  # the last run's identifications (set while editing the text)
        wall = float(json.loads(timing.read_text())["wall_s"])
    else:
        raw = pd.concat([identify_all(N_STANCES, CALIBRATION_SEED, "calibration"),
                         identify_all(N_STANCES, HELD_OUT_SEED, "held-out")], ignore_index=True)
        RAW.parent.mkdir(exist_ok=True)
        raw.to_csv(RAW, index=False)
        wall = time.perf_counter() - t0
        timing.write_text(json.dumps({"wall_s": wall}) + "\n")
    hac = raw[raw["variance"] == "hac"]
    degraded = hac[hac["condition"] != "clean"]
    sigma = {p: calibrate(degraded, p) for p in PARAMS}  # both sets: the package's value
    frames = {"ar1 (before)": raw[raw["variance"] == "ar1"], "hac": hac,
              "hac+sys (package σ)": widen(hac, sigma)}
    tab = table(frames)
    folds = []
    for train, test in (("calibration", "held-out"), ("held-out", "calibration")):
        s_fold = {p: calibrate(degraded[degraded["split"] == train], p) for p in PARAMS}
        for cond, g in hac[hac["split"] == test].groupby("condition", sort=False):
            w = widen(g, s_fold)
            folds.append({"σ calibrated on": train, "tested on": f"{test} ({len(g)})",
                          "condition": cond,
                          "σ_sys K / D [%]": f"{100 * s_fold['K']:.1f} / {100 * s_fold['D']:.1f}",
                          **{f"{p} coverage": f"{100 * covered(w, p).mean():.0f} %"
                             for p in PARAMS}})
    cv = pd.DataFrame(folds)
    deg_cv = cv[cv["condition"] != "clean"]
    cv_mean = {p: np.mean([float(v.rstrip(" %")) for v in deg_cv[f"{p} coverage"]])
               for p in PARAMS}
    from bladelab.identify.identify import SYSTEMATIC_REL_SD

    lines = [
        "## Coverage of the 95 % intervals of K* and D*",
        "",
        f"{N_STANCES} + {N_STANCES} stances from the MuJoCo runner generator (calibration seed "
        f"{CALIBRATION_SEED}, held-out seed {HELD_OUT_SEED}; blades xtreme-cat5 and xceed-cat2, "
        "K 13–22 N·m/deg, D 0.15–0.5 N·m·s/deg, 4–9 m/s), each clean and degraded "
        "(`degrade_stance`: markers 100 Hz with 1 mm noise, 20 Hz low-pass, forces 1 kHz 1 %), "
        "identified with the default formulation (utilised friction), PSO 20 × 30; coverage = "
        f"fraction of stances whose true value lies in the 95 % interval ({wall:.0f} s).",
        "",
        "- **ar1**: profile likelihood, one AR(1) effective sample size for all parameters (the "
        "method before hac+sys).",
        "- **hac**: profile likelihood whose scale per parameter is s² of independent residuals × "
        "its Newey–West inflation for autocorrelated residuals, per measured channel (Bartlett "
        "bandwidth = twice the residual's correlation length).",
        "- **hac+sys** (default): hac widened in quadrature by ±1.96·σ_sys·estimate, σ_sys the "
        "systematic error of the measurement pipeline (filter lag, resampling of 100 Hz "
        "kinematics, the utilised-friction approximation), calibrated on the degraded stances of "
        f"both sets: σ_sys = {100 * sigma['K']:.1f} % for K and {100 * sigma['D']:.1f} % for D "
        f"(in the package: K {100 * SYSTEMATIC_REL_SD['K']:.1f} %, D "
        f"{100 * SYSTEMATIC_REL_SD['D']:.1f} %); its rows are in-sample.",
        "",
        _markdown(tab),
        "",
        "**Out of sample** (2-fold cross-validation: σ_sys calibrated on one set, coverage on the "
        "other):",
        "",
        _markdown(cv),
        "",
        f"Cross-validated coverage of the degraded stances (mean of the two folds): K "
        f"{cv_mean['K']:.0f} %, D {cv_mean['D']:.1f} % (target 90–98 %).",
        "",
        "Residuals of a stance are autocorrelated (the distance channel comes from 100 Hz markers "
        "low-passed at 20 Hz and resampled to 1 kHz), but most misses of D are a bias of the "
        "measurement pipeline, the same sign on most stances, which no residual-based scale "
        "sees: hence the calibrated systematic term. It holds for this generator and these "
        "measurement conditions; on clean stances it over-covers. The seed's formulation is "
        "biased by 15–17 % in K on degraded stances (robust section) and is not calibrated.",
        "",
        f"Raw results: `benchmarks/results/{RAW.name}`.",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run())
