"""Design-study mathematics: DOE, surface fits, optimum, blade generator, compression test."""

from __future__ import annotations

import tempfile
import time

import numpy as np


def _t(fn, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def run() -> str:
    from bladelab.design import (
        central_composite,
        compression_test,
        constrained_optimum,
        d_optimal,
        default_design_space,
        fit_surface,
        generate_blade,
        run_design,
    )
    from bladelab.design.optimum import SurfaceConstraint

    space = default_design_space()
    d = central_composite(space)
    rng = np.random.default_rng(0)
    y = 1 + d.coded @ rng.normal(size=4) - 0.3 * d.coded[:, 0] ** 2 + rng.normal(0, 0.01, 25)
    g = 0.5 - d.coded[:, 3] + 0.1 * d.coded[:, 0]
    s = fit_surface(d.coded, y, factor_names=space.names)
    c = fit_surface(d.coded, g, factor_names=space.names, response="g")
    rows = [
        ("D-optimal design, 4 factors, 25 runs, quadratic (5 starts)",
         _t(lambda: d_optimal(space, 25, seed=1))),
        ("fit a 15-term quadratic surface (25 runs) with ANOVA and PRESS",
         _t(lambda: fit_surface(d.coded, y, factor_names=space.names))),
        ("constrained optimum (22 SLSQP starts, 1 constraint)",
         _t(lambda: constrained_optimum(s, constraints=[SurfaceConstraint(c, 0.0)], seed=0))),
        ("generate one 6-link blade (target stiffness)",
         _t(lambda: generate_blade(space.point(d.coded[0])))),
    ]
    blade = generate_blade(space.point(d.coded[0]))
    rows.append(("large-deflection compression test, 30 steps",
                 _t(lambda: compression_test(blade.model, load=500.0), repeat=1)))

    def evaluator(point):
        b = generate_blade(point)
        r = compression_test(b.model, max_displacement=0.06, n_steps=10, load=500.0)
        return {"stiffness_at_bw_N_per_m": r.stiffness_at_load, "mass_kg": b.model.mass}

    with tempfile.TemporaryDirectory() as tmp:
        t_study = _t(lambda: run_design(space, evaluator=evaluator, out_dir=tmp, progress=False,
                                        objective="stiffness_at_bw_N_per_m"), repeat=1)
    rows.append(("25-run study, generator + compression-test evaluator (no simulation)", t_study))

    # the simulation evaluators
    from bladelab.design.evaluators import BladeEvaluator
    from bladelab.design.transfemoral import RunnerEvaluator

    blade_ev = BladeEvaluator()
    blade_ev(space.point(d.coded[-1]))  # compile the numba helpers once
    with tempfile.TemporaryDirectory() as tmp:
        t_blade = _t(lambda: run_design(space, evaluator=blade_ev, out_dir=tmp, progress=False,
                                        objective="delta_vx_m_per_s"), repeat=1)
    rows.append(("25-run CCD study, blade evaluator (generated blade + simulated stance, "
                 "dt 1e-5 s)", t_blade))
    runner_ev = RunnerEvaluator()
    runner_ev(space.point(d.coded[-1]))
    t_runner = _t(lambda: runner_ev(space.point(d.coded[0])), repeat=2)
    rows.append(("runner evaluator, one run (blade + one 0.52 s transfemoral gait cycle, "
                 "dt 2e-5 s)", t_runner))
    lines = ["## Design studies (`bladelab.design`)", "",
             "| operation | time |", "|---|---|"]
    lines += [f"| {name} | {t * 1e3:.1f} ms |" if t < 1 else f"| {name} | {t:.2f} s |"
              for name, t in rows]
    return "\n".join(lines)


if __name__ == "__main__":
    print(run())
