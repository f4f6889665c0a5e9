"""Probe: the tracking stage with the objective's own Hessian (measuring only).

The template's cold start spends most of its time in the tracking stage (a least-squares fit
of the template's joint angles and vertical force under the stride's dynamics): about 1,450
L-BFGS iterations. A tracking problem's curvature is mostly its objective's (squares of the
angles' deviations, of the force's, of the effort terms), so IPOPT is given the exact Hessian
of the objective alone, the constraints' curvature left out (a Gauss-Newton-like step; no
constraint Hessian is built, and the matrix is nearly positive semi-definite). Variants:

- ``lbfgs``: the library's tracking stage (L-BFGS, IPOPT's default update);
- ``objective``: ``hess_lag`` = σ·∇²f, the adaptive barrier;
- ``objective-monotone``: the same with the monotone barrier.

The able runner at 3.5 m/s from the template (mesh 50, people's angles, as ``make bench``'s
template row), the predictive stage after it with the library's options. One JSON line per
run is printed and appended to ``objective_hessian_records.jsonl`` (``lowrank_update.record``).

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/collocation_speed/objective_hessian.py objective
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import casadi as ca
from lowrank_update import record

from bladelab.predict.collocation import solve as solve_module
from bladelab.predict.collocation.guess import template_guess
from bladelab.predict.collocation.settings import CollocationSettings, people_settings
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner

RECORDS = Path(__file__).with_name("objective_hessian_records.jsonl")


def objective_hessian(nlp: StrideNLP) -> ca.Function:
    """``hess_lag`` for IPOPT: σ·∇²f of ``nlp``'s objective (upper triangle), SX."""
    x, p, f = nlp.nlp["x"], nlp.nlp["p"], nlp.nlp["f"]
    sigma = ca.MX.sym("lam_f")
    lam_g = ca.MX.sym("lam_g", nlp.nlp["g"].sparsity())
    hess = ca.triu(sigma * ca.hessian(f, x)[0])
    fn = ca.Function("nlp_hess_l", [x, p, sigma, lam_g], [hess],
                     ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    return fn.expand()


def use_objective_hessian(mu_strategy: str) -> dict:
    """Make every tracking NLP solve with σ·∇²f as its Hessian; returns a record of the build."""
    solve = StrideNLP.solve
    info: dict = {}

    def staged(self, x0, *args, options=None, hessian="limited-memory", **kw):
        if self.tracking is None:
            return solve(self, x0, *args, options=options, hessian=hessian, **kw)
        nlp = self.interpreted()
        t0 = time.perf_counter()
        hess = objective_hessian(nlp)
        info["hessian_build_s"] = round(time.perf_counter() - t0, 1)
        info["hessian_nnz"] = int(hess.sparsity_out(0).nnz())
        opts = {**(options or {}), "hess_lag": hess, "ipopt.mu_strategy": mu_strategy}
        return solve(nlp, x0, *args, options=opts, hessian="exact", **kw)

    StrideNLP.solve = staged
    return info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("variant", choices=["lbfgs", "objective", "objective-monotone"])
    ap.add_argument("--max-iter", type=int, default=3000)
    args = ap.parse_args()
    info = {}
    if args.variant != "lbfgs":
        info = use_objective_hessian("adaptive" if args.variant == "objective" else "monotone")
    runner = build_runner("able", body="human")
    settings = CollocationSettings(mesh_intervals=50, speed_m_per_s=3.5,
                                   max_iter=args.max_iter, **people_settings("human"))
    guess = template_guess(runner, speed=3.5, n=50)
    t0 = time.perf_counter()

    def progress(p) -> None:
        if p.event != "iteration" or p.iteration % 100 == 0:
            print(f"{p.stage} {p.event} {p.iteration} objective {p.objective:.4g} "
                  f"violation {p.violation:.2g} {p.elapsed_s:.0f} s", flush=True)

    sol = solve_module.predict_stride(runner, settings, guess, progress=progress,
                                      model_spec={"model": "able", "body": "human"})
    trk = sol.tracking or {}
    row = {"tracking_iterations": trk.get("iterations"), "tracking_s": trk.get("wall_s"),
           "tracking_status": trk.get("status"), "tracking_objective": trk.get("objective"),
           "stage": sol.stage,
           "iterations": sol.nlp.iterations, "predictive_s": round(sol.nlp.wall_s, 1),
           "converged": sol.converged, "objective": sol.nlp.objective,
           "warnings": sol.gait_warnings() if sol.converged else None}
    row = {"case": "template able 3.5", "variant": args.variant, **info, **row,
           "wall_s": round(time.perf_counter() - t0, 1)}
    record(row, RECORDS)


if __name__ == "__main__":
    main()
