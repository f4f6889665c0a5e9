"""Where a stride's metabolic energy goes: per muscle, in its leg's stance and swing (a
measuring probe; changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/cadence_budget.py STRIDE.json [STRIDE.json ...]

For each stride file prints its stride time, the objective's terms it stores, and every
muscle's metabolic energy per body mass and distance [J/(kg·m)], split into the time its leg is
on the ground (vertical force above the contact threshold) and in the air (the basal rate is
the rest of the gross cost of transport), and the positive work of the first leg's hip, knee
and ankle [J/kg per stride] in its stance and swing (the forward model's joint powers on the
stride sampled 16 times per mesh interval). Two strides of the same body at different stride
times (e.g. the shipped one and `stride_time.py`'s) show which muscles make the longer stride
dearer.
"""

from __future__ import annotations

import sys

import casadi as ca
import numpy as np

from bladelab.predict.collocation.metabolics import muscle_metabolic_rates
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.solution import CONTACT_THRESHOLD_N, CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner import analyses as an
from bladelab.runner.metabolics import BASAL_RATE_W_PER_KG

JOINTS = ("hip_flexion", "knee_angle", "ankle_angle")


def budget(path: str) -> dict:
    """Per-muscle stance and swing energy [J/(kg·m)] of the stride in ``path``."""
    sol = CollocationSolution.read(path)
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    nv, nm = cm.nv, cm.n_muscles
    q, qd = ca.SX.sym("q", nv), ca.SX.sym("qd", nv)
    a, ft, dft, u = (ca.SX.sym(n, nm) for n in ("a", "ft", "dft", "u"))
    l_mt, v_mt = cm.mtu(q, qd)
    rates = muscle_metabolic_rates(runner, u, a, ft, dft, l_mt, v_mt, cm.smoothing)
    s = sol.nlp
    n_nodes = s.q.shape[0]
    f = ca.Function("rates", [q, qd, a, ft, dft, u], [rates]).map(n_nodes)
    r = np.asarray(f(s.q.T, s.qd.T, s.activation.T, s.tendon_force.T,
                     s.tendon_force_rate.T, s.excitation.T), float)  # (nm, nodes) [W]
    mass = float(runner.total_mass)
    j = list(sol.dof_names).index("pelvis_tx")
    distance = float(s.q[-1, j] - s.q[0, j])
    h = sol.period_s / (n_nodes - 1)
    w = np.full(n_nodes, h)
    w[0] = w[-1] = h / 2  # trapezoidal weights
    fz = sol.leg_vertical_force()  # (nodes, 2) [N]
    names = list(runner.muscle_names)
    out = {"file": path, "stride_s": sol.period_s, "distance_m": distance,
           "objective": sol.objective if hasattr(sol, "objective") else None,
           "basal": BASAL_RATE_W_PER_KG * sol.period_s / distance, "muscles": {}}
    for i, name in enumerate(names):
        leg = 0 if name.endswith("_l") else 1  # unsided (trunk) muscles: the right leg's phases
        ground = fz[:, leg] > CONTACT_THRESHOLD_N
        e = r[i] * w / (mass * distance)
        out["muscles"][name] = (float(e[ground].sum()), float(e[~ground].sum()))
    out["joints"] = joint_work(sol, mass)
    return out


def joint_work(sol, mass: float) -> dict:
    """{joint: (stance, swing)} positive work [J/kg] of the first leg's joints per stride."""
    res = sol.to_runner_result(1, refine=16)
    grf = res.leg_grf()
    fz = grf[grf.leg == sol.leg_names[0]]["Fz"].to_numpy(float)
    ground = fz > CONTACT_THRESHOLD_N
    pw = an.joint_powers(res)
    out = {}
    for joint in JOINTS:
        df = pw[pw.joint == f"{joint}_l"]
        t, p = df["time"].to_numpy(float), np.maximum(df["power"].to_numpy(float), 0.0)
        out[joint] = tuple(float(np.trapezoid(np.where(m, p, 0.0), t)) / mass
                           for m in (ground, ~ground))
    return out


def main() -> None:
    results = [budget(p) for p in sys.argv[1:]]
    for res in results:
        tot = sum(a + b for a, b in res["muscles"].values())
        print(f"{res['file']}: stride {res['stride_s']:.3f} s, {res['distance_m']:.3f} m; "
              f"muscles {tot:.3f} + basal {res['basal']:.3f} J/(kg·m)")
    names = list(results[0]["muscles"])
    head = " | ".join(f"stance / swing ({k + 1})" for k in range(len(results)))
    print(f"| muscle | {head} |")
    for name in names:
        cells = " | ".join("{:.3f} / {:.3f}".format(*res["muscles"][name]) for res in results)
        print(f"| {name} | {cells} |")
    for k, lab in ((0, "stance"), (1, "swing")):
        cells = " | ".join(f"{sum(v[k] for v in res['muscles'].values()):.3f}" for res in results)
        print(f"| all, {lab} | {cells} |")
    print(f"| joint, first leg [J/kg] | {head} |")
    for joint in JOINTS:
        cells = " | ".join("{:.3f} / {:.3f}".format(*res["joints"][joint]) for res in results)
        print(f"| {joint} | {cells} |")


if __name__ == "__main__":
    main()
