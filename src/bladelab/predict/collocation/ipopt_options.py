"""IPOPT's options of a stride solve (:meth:`~bladelab.predict.collocation.transcription.
StrideNLP.solve`).

:func:`solver_options` assembles one solve's options (CasADi ``nlpsol`` keys, IPOPT's under
``ipopt.``): the base set (MUMPS with METIS ordering, gradient-based scaling, the Hessian and its
barrier strategy), the acceptable-level stop of every L-BFGS solve
(:data:`STALL_STOP_OPTIONS`), the dual warm start's barrier (:data:`DUAL_WARM_START_OPTIONS`)
and the caller's own. :data:`PREDICTIVE_LBFGS_OPTIONS` are a predictive stage's, added by
:func:`~bladelab.predict.collocation.solve.predict_stride`. Tolerances are IPOPT's, on the
scaled NLP.
"""

from __future__ import annotations

__all__ = ["DUAL_WARM_START_OPTIONS", "PREDICTIVE_LBFGS_OPTIONS", "STALL_STOP_OPTIONS",
           "solver_options"]

#: IPOPT's stop at an acceptable level, on every L-BFGS solve: five iterations in a row
#: feasible to 1e-5 (scaled constraints), complementarity below 1e-3 and the objective
#: changing by less than 1e-5 of itself per iteration. Near a solution L-BFGS's dual
#: infeasibility wanders between 1e-2 and 1 and dips below ``tol`` only now and then, so about
#: half of a solve's iterations went on the last 0.01 % of its objective (measured on warm and
#: cold starts: 15–55 % fewer iterations, objectives within 0.033 %;
#: benchmarks/collocation_speed/README.md "Stopping a solve when the objective stalls").
STALL_STOP_OPTIONS = {
    "ipopt.acceptable_tol": 1.0,
    "ipopt.acceptable_iter": 5,
    "ipopt.acceptable_obj_change_tol": 1e-5,
    "ipopt.acceptable_constr_viol_tol": 1e-5,
    "ipopt.acceptable_compl_inf_tol": 1e-3,
}

#: IPOPT's L-BFGS Hessian of a predictive stage (:func:`~bladelab.predict.collocation.solve.
#: predict_stride` adds these options to every L-BFGS stage but the tracking stage): the
#: low-rank update held in the augmented system itself (``extended``: 2m more rows, one
#: factorisation and one back solve per step) instead of IPOPT's default Sherman-Morrison
#: route, whose 2m extra back solves per iteration were most of a solve's time; history m = 4.
#: Measured (benchmarks/collocation_speed/README.md, "The low-rank update inside the augmented
#: system"): three warm starts of the amputee Cat6 stride 58-61 against 88 ms per iteration,
#: 33 s against 57 s in all, objectives within 0.1 %; the category study with three starts
#: 932 against 1,505 s of solver time. The tracking stage keeps IPOPT's default: with these
#: options the template's tracking stage did not converge in 3,000 iterations.
PREDICTIVE_LBFGS_OPTIONS = {
    "ipopt.limited_memory_aug_solver": "extended",
    "ipopt.limited_memory_max_history": 4,
}

#: IPOPT options of a solve started from a solution's primal and dual values (its
#: multipliers): the barrier starts small and the point stays where it is, so that a solve
#: at the start's own speed ends at once and a continuation step stays on the start's branch
#: (measured, benchmarks/collocation_speed/README.md: the amputee Cat6 stride at 4 m/s again in
#: 0 iterations instead of 613; 4 -> 4.2 m/s in 197 instead of 574). mu_init 1e-3, 1e-4 and
#: 1e-5 gave the same iterates.
DUAL_WARM_START_OPTIONS = {
    "ipopt.warm_start_init_point": "yes",
    "ipopt.mu_init": 1e-4,
    "ipopt.warm_start_bound_push": 1e-9,
    "ipopt.warm_start_bound_frac": 1e-9,
    "ipopt.warm_start_slack_bound_push": 1e-9,
    "ipopt.warm_start_slack_bound_frac": 1e-9,
    "ipopt.warm_start_mult_bound_push": 1e-9,
}


def solver_options(*, max_iter: int, tol: float, hessian: str, print_level: int,
                   expand: bool, warm_duals: bool, options: dict | None = None) -> dict:
    """The ``nlpsol`` options of one solve: ``hessian`` ``"limited-memory"`` (L-BFGS, adaptive
    barrier, with :data:`STALL_STOP_OPTIONS`) or ``"exact"`` (monotone barrier); ``expand``:
    expand the graph to SX (not for a compiled node, an external that no SX graph holds);
    ``warm_duals``: a start from primal and dual values (:data:`DUAL_WARM_START_OPTIONS`);
    ``options`` last, over all of these."""
    opts = {
        "ipopt.max_iter": int(max_iter),
        "ipopt.tol": float(tol),
        "ipopt.constr_viol_tol": 1e-6,
        "ipopt.print_level": int(print_level),
        "ipopt.hessian_approximation": hessian,
        "ipopt.mu_strategy": "adaptive" if hessian == "limited-memory" else "monotone",
        "ipopt.linear_solver": "mumps",
        "ipopt.mumps_pivot_order": 5,  # METIS
        "ipopt.nlp_scaling_method": "gradient-based",
        "ipopt.sb": "yes",  # no banner
        # SX graph: about 10x faster iterations than MX (measured); a compiled node is an
        # external, which no SX graph holds
        "expand": expand,
        "print_time": False,
    }
    if hessian == "limited-memory":
        opts.update(STALL_STOP_OPTIONS)
    if warm_duals:
        opts.update(DUAL_WARM_START_OPTIONS)
    opts.update(options or {})
    return opts
