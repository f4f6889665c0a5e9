"""Fits of a predicted-gait design study, side by side: quadratic and first-order R²pred, the
start spread's R² ceiling (all of a design's clean strides; those within 5 % of its best; for
the stride objective also from the last complete settling pass's drops, the error of a kept
optimum rather than the spread of every optimum found), and the first-order effects per coded
unit with their p-values.

Reads a study folder as committed (``results.csv``, ``settling.json``); solves nothing. The
report gives the quadratic fits and the start spread; this adds the first-order fits that
25 runs estimate better, for the study READMEs and docs/design.md.

Usage (repository root)::

    .venv/bin/python benchmarks/design/fits.py benchmarks/design/transtibial-collocation-4mps \
        [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

from bladelab.design.responses import MAX_SPEED_RESPONSE_UNITS, PREDICTED_RESPONSE_UNITS
from bladelab.design.start_spread import start_spread
from bladelab.design.surfaces import fit_surface

FACTORS = ("stiffness_kN_per_m", "width_m", "height_m", "toe_length_m")
RESPONSES = ("stride_objective", "max_speed_m_per_s", "cost_of_transport_J_per_kg_m",
             "delta_vx_m_per_s", "evaluation_E_m", "impulse_z_Ns", "knee_moment_min_Nm",
             "swing_clearance_m", "contact_time_prosthetic_s", "socket_force_max_N",
             "socket_moment_max_Nm", "blade_moment_max_Nm")


def last_pass_ceiling(study: Path, y: np.ndarray) -> float | None:
    """R² ceiling of the stride objective from the last complete settling pass: each design's
    kept objective is off its best by what a further pass would still lower it, estimated as
    the RMS of that pass's drops (relative, times the mean objective) against the spread
    across the box. None without a complete pass."""
    record = json.loads((study / "settling.json").read_text(encoding="utf-8"))
    done = [p for p in record.get("passes", []) if p.get("complete")]
    if not done:
        return None
    drops = np.array([1.0 - r["after"] / r["before"] for r in done[-1]["designs"]])
    sd = float(np.sqrt(np.mean(drops ** 2))) * float(np.mean(y))
    return max(0.0, 1.0 - sd ** 2 / float(np.var(y, ddof=1)))


def study_fits(study: Path) -> dict:
    """Per response: R², R²pred of the quadratic and first-order fits, the start ceiling, and
    the first-order effects with p-values."""
    table = pd.read_csv(study / "results.csv")
    coded = table[[f"{f}_coded" for f in FACTORS]].to_numpy(float)
    units = {**PREDICTED_RESPONSE_UNITS, **MAX_SPEED_RESPONSE_UNITS}
    spread = start_spread(study, units=units)
    ceiling = dict(zip(spread["response"], spread["r2_ceiling"], strict=True))
    near = dict(zip(spread["response"], spread["r2_ceiling_near"], strict=True))
    out = {}
    for name in RESPONSES:
        if name not in table:
            continue
        y = table[name].to_numpy(float)
        quad = fit_surface(coded, y, factor_names=FACTORS, model="quadratic", response=name)
        lin = fit_surface(coded, y, factor_names=FACTORS, model="linear", response=name)
        coef = lin.coefficients().set_index("term")
        out[name] = {"unit": units.get(name, ""),
                     "quadratic_r2": quad.r2, "quadratic_r2_pred": quad.r2_pred,
                     "linear_r2": lin.r2, "linear_r2_pred": lin.r2_pred,
                     "start_ceiling": ceiling.get(name),
                     "start_ceiling_near": near.get(name),
                     "last_pass_ceiling": (last_pass_ceiling(study, y)
                                           if name == "stride_objective" else None),
                     "range": [float(y.min()), float(y.max())],
                     "effects": {f: {"per_coded_unit": float(coef.loc[f, "estimate"]),
                                     "p": float(coef.loc[f, "p_value"])} for f in FACTORS}}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("study", type=Path)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    fits = study_fits(args.study)
    print("| response | range | R² / R²pred quadratic | R² / R²pred first-order "
          "| start ceiling (within 5 %; last pass) "
          "| stiffness | width | height | toe |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, f in fits.items():
        eff = " | ".join(f"{e['per_coded_unit']:+.3g} (p {e['p']:.2g})"
                         for e in f["effects"].values())
        ceil = "–" if f["start_ceiling"] is None else (
            f"{f['start_ceiling']:.2f} ({f['start_ceiling_near']:.2f}"
            + ("" if f["last_pass_ceiling"] is None else f"; {f['last_pass_ceiling']:.2f}")
            + ")")
        print(f"| {name} [{f['unit']}] | {f['range'][0]:.4g} … {f['range'][1]:.4g} | "
              f"{f['quadratic_r2']:.2f} / {f['quadratic_r2_pred']:.2f} | "
              f"{f['linear_r2']:.2f} / {f['linear_r2_pred']:.2f} | {ceil} | {eff} |")
    if args.json is not None:
        args.json.write_text(json.dumps(fits, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
