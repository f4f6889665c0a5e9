"""Probe: the reserve homotopy of the transfemoral runner (2026-12-01, README.md here).

Usage (repository root, with ``reserve-homotopy.patch`` applied to ``src``)::

    BL_RESERVE_W=W [BL_RESERVE_BOUND=B] .venv/bin/python \\
        benchmarks/design/transfemoral-gait-2026-12-01/homotopy.py solve OUT.json TOL [from=PREV.json] [raw=1] [grounded=1] [set:SETTING=VALUE ...]
    .venv/bin/python benchmarks/design/transfemoral-gait-2026-12-01/homotopy.py measure A.json B.json ...
    .venv/bin/python benchmarks/design/transfemoral-gait-2026-12-01/homotopy.py profile A.json

``solve``: without ``from=``, the predictive stage started directly (no tracking stage) from
the transtibial stride mapped onto the transfemoral runner as
``../transfemoral-gait-2026-11-29/from_transtibial.py`` maps it (the prosthetic knee shifted
to straight in stance unless ``raw=1``; speeds by periodic differences), keeping its muscle
activations by name and its flights (the pelvis height shifted per node so that the stance
leg's lowest contact is as deep as the transtibial runner's, the shift interpolated through the
flights; ``grounded=1``: as ``make_guess`` maps it, the lowest contact 1 cm deep at every node,
no flight) (muscles it lacks at 0.05, tendon forces from static equilibrium); with
``from=``, from that solution and its multipliers (a warm start). TOL: the alternating-steps
tolerance, or ``none``. ``set:SETTING=VALUE``: a ``CollocationSettings`` field, as in
from_transtibial.py (e.g. ``set:knee_flexion_max_loaded_deg=10``). The problem is that probe's: 4 m/s, mesh 50, the design box's centre
blade by backward Euler, people's angles at weight 10, swing clearance 2 cm, the myodesis.
The reserve (ideal torque at the prosthetic knee, the knee's dynamics row freed) is set by
the environment: ``BL_RESERVE_W`` (weight of its mean square per 100 N·m in the objective),
``BL_RESERVE_BOUND`` (|reserve| ≤ B N·m; 0: no reserve, the passive knee as it is),
``BL_RESERVE_ZERO_NODES`` (comma-separated mesh nodes where the bound is 0).

Added on 2026-12-06 (``../transfemoral-gait-2026-12-06/``, with that folder's
``probe.patch`` applied instead of ``reserve-homotopy.patch``): ``body:FIELD=JSON``, a field of
the transfemoral parameter set as in from_transtibial.py; ``BL_SM_UPDATE=1`` in the
environment solves with IPOPT's default L-BFGS update (the library's until that day) instead of
the library's ``PREDICTIVE_LBFGS_OPTIONS``.

``measure``: one line of JSON per solution: converged, step phase, peaks, contacts, stride,
objective and its terms, the reserve (the knee's dynamics residual of the collocation model:
inverse dynamics − muscle − passive − contact; positive = extension, knee_angle_r being
negative in flexion) RMS and peak, split into stance (prosthetic vertical force > 50 N) and
swing, and the largest forward-model residual of the other coordinates [%].
"""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location(
    "from_transtibial", HERE.parent / "transfemoral-gait-2026-11-29" / "from_transtibial.py")
ft = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ft)


def solve(out: str, step_tol: str, *extra: str) -> None:
    fields = dict(kv.split("=", 1) for kv in extra)
    start, raw = fields.pop("from", None), fields.pop("raw", None)
    grounded = fields.pop("grounded", None)
    sets = {k[4:]: (None if v == "none" else float(v))
            for k, v in list(fields.items()) if k.startswith("set:")}
    for k in sets:
        fields.pop("set:" + k)
    body = {k[5:]: json.loads(v) for k, v in list(fields.items()) if k.startswith("body:")}
    for k in body:
        fields.pop("body:" + k)
    if body:
        ft.stored.default_runner_params = ft._with_knee({}, body)
    import os
    if os.environ.get("BL_SM_UPDATE"):  # IPOPT's default L-BFGS update
        from bladelab.predict.collocation import solve as _solve
        _solve.PREDICTIVE_LBFGS_OPTIONS = {}
    assert not fields, fields
    space = ft.default_design_space()
    blade = ft.CollocationEvaluator().blade_spec(space.point([0.0] * len(space.names)))
    spec = {"model": "transfemoral", "blade": blade["name"], "blade_spec": blade,
            "body": "human"}
    runner = ft.stored.runner_from_spec(spec)
    settings = ft.CollocationSettings(
        mesh_intervals=50, speed_m_per_s=4.0, blade_backward_euler=True,
        step_phase_tolerance=None if step_tol == "none" else float(step_tol),
        **{"swing_clearance_m": 0.02, **ft.people_term(10.0), **sets})
    if start is not None:
        guess = ft.make_guess(runner, start, n=50, speed=4.0)
    else:
        transtibial = ft.CollocationSolution.read(ft.START)
        if grounded:  # as from_transtibial.py: the pelvis lowered at EVERY node (no flight)
            guess = ft.make_guess(runner, str(ft.START), n=50, speed=4.0)
        else:
            guess = transtibial.to_guess("transtibial stride "
                                         f"{ft.START.name}").on_model(runner)
        j = list(guess.dof_names or runner.dof_names).index("knee_angle_r")
        force = transtibial.leg_vertical_force()
        q = guess.q.copy()
        if not raw:
            q[:, j] = np.minimum(q[:, j] - q[force[:, 1] > 50.0, j].max(), 0.0)
        if not grounded:
            q[:, runner.dof("pelvis_tz")] += _pelvis_offset(runner, transtibial, q, force)
        guess = dataclasses.replace(
            guess, q=q, qd=ft.periodic_derivative(q, guess.period), qdd=None, excitation=None,
            tendon_force_rate=None, multipliers=None, tendon_force=None,
            source=f"{guess.source}, {'grounded' if grounded else 'flight kept'}, prosthetic knee "
                   f"{'as it is' if raw else 'straight in stance'}, no tracking stage")
    t0 = time.perf_counter()

    def progress(p) -> None:
        if p.event != "iteration" or p.iteration % 250 == 0:
            print(f"{p.stage} {p.event} it {p.iteration} obj {p.objective:.4g} "
                  f"viol {p.violation:.3g} {p.elapsed_s:.0f} s {p.message}", flush=True)

    sol = ft.predict_stride(runner, settings, guess, model_spec=spec, track=False,
                            progress=progress)
    print(f"wall {time.perf_counter() - t0:.0f} s")
    sol.write(out)
    print(json.dumps(measure_one(out)), flush=True)


def _pelvis_offset(runner, transtibial, q: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Per node, the pelvis height change [m] that puts the stance leg's lowest contact of
    the transfemoral runner at the pose ``q`` where the transtibial runner's was (its
    smaller body), interpolated (periodically, linearly) through the flights, so that the
    flights stay flights (``make_guess`` grounds the lowest contact at every node)."""
    from bladelab.runner.layout import CP_LEG
    from bladelab.runner.model import contact_heights
    rtt = ft.stored.runner_from_spec(transtibial.model_spec)
    lt, lf = rtt.contact_params[:, CP_LEG], runner.contact_params[:, CP_LEG]
    n = len(q) - 1
    d = np.full(n, np.nan)
    for k in range(n):
        leg = 0 if force[k, 0] > 50.0 else 1 if force[k, 1] > 50.0 else None
        if leg is not None:
            d[k] = (contact_heights(rtt, transtibial.nlp.q[k])[lt == leg].min()
                    - contact_heights(runner, q[k])[lf == leg].min())
    have = np.flatnonzero(np.isfinite(d))
    d = np.interp(np.arange(n), have, d[have], period=n)
    return np.append(d, d[0])


def measure_one(path: str) -> dict:
    sol = ft.CollocationSolution.read(path)
    runner = ft.stored.runner_from_spec(sol.model_spec)
    from bladelab.predict.collocation.model import build_collocation_model
    cm = build_collocation_model(runner)
    s = sol.nlp
    k = list(sol.dof_names).index("knee_angle_r")
    res = np.array([np.asarray(cm.dynamics_residual(s.q[i], s.qd[i], s.qdd[i],
                                                    s.tendon_force[i])).ravel()[k]
                    for i in range(len(s.q) - 1)])
    fz = sol.leg_vertical_force()[:-1]
    stance = fz[:, 1] > 50.0
    summ = sol.summary()
    cons = sol.residual
    per = cons.get("per_dof_max", {})
    peak_m = cons.get("peak_moment_Nm") or np.nan
    peak_f = cons.get("peak_force_N") or np.nan
    other = max((v / (peak_f if n in ("pelvis_tx", "pelvis_tz") else peak_m)
                 for n, v in per.items() if n != "knee_angle_r"), default=np.nan) * 100

    def rms(x):
        return float(np.sqrt(np.mean(x ** 2))) if x.size else 0.0

    q_knee = np.degrees(s.q[:-1, k])
    return {
        "file": Path(path).name, "converged": sol.converged, "status": str(s.status),
        "iterations": summ["iterations"], "wall_s": round(summ["wall_s"]),
        "step_phase": summ["step_phase"],
        "peak_intact_bw": summ.get("peak_vertical_grf_intact_bw"),
        "peak_prosthetic_bw": summ.get("peak_vertical_grf_prosthetic_bw"),
        "contact_intact_s": summ.get("contact_time_intact_s"),
        "contact_prosthetic_s": summ.get("contact_time_prosthetic_s"),
        "stride_s": summ["stride_time_s"], "cot": summ["cost_of_transport_J_per_kg_m"],
        "objective": s.objective, "terms": s.objective_terms,
        "max_violation": s.max_violation,
        "reserve_rms_Nm": rms(res), "reserve_peak_Nm": float(np.abs(res).max()),
        "reserve_max_ext_Nm": float(res.max()), "reserve_max_flex_Nm": float(res.min()),
        "reserve_rms_stance_Nm": rms(res[stance]), "reserve_rms_swing_Nm": rms(res[~stance]),
        "reserve_mean_stance_Nm": float(res[stance].mean()) if stance.any() else 0.0,
        "reserve_mean_swing_Nm": float(res[~stance].mean()) if (~stance).any() else 0.0,
        "knee_deg_stance_min_max": [float(q_knee[stance].min()), float(q_knee[stance].max())]
        if stance.any() else None,
        "knee_deg_swing_min": float(q_knee[~stance].min()) if (~stance).any() else None,
        "residual_forward_pct": summ["dynamics_residual_pct"],
        "residual_other_dofs_pct": other,
        "warnings": summ["warnings"],
    }


def profile(path: str) -> None:
    """Per node: time [s], each leg's vertical force [BW], the prosthetic knee's angle [deg,
    flexion negative] and speed [deg/s], the reserve [N·m, extension positive]."""
    sol = ft.CollocationSolution.read(path)
    runner = ft.stored.runner_from_spec(sol.model_spec)
    from bladelab.predict.collocation.model import build_collocation_model
    cm = build_collocation_model(runner)
    s = sol.nlp
    k = list(sol.dof_names).index("knee_angle_r")
    fz = sol.leg_vertical_force() / sol.body_weight_N
    print("node t Fi Fp knee dknee reserve")
    for i in range(len(s.q) - 1):
        r = float(np.asarray(cm.dynamics_residual(s.q[i], s.qd[i], s.qdd[i],
                                                  s.tendon_force[i])).ravel()[k])
        print(f"{i:3d} {s.time[i]:.3f} {fz[i, 0]:5.2f} {fz[i, 1]:5.2f} "
              f"{np.degrees(s.q[i, k]):7.1f} {np.degrees(s.qd[i, k]):7.0f} {r:8.1f}")


def measure(*paths: str) -> None:
    for p in paths:
        print(json.dumps(measure_one(p)))


if __name__ == "__main__":
    {"solve": solve, "measure": measure, "profile": profile}[sys.argv[1]](*sys.argv[2:])
