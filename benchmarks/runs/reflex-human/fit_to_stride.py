"""Reflex parameters fitted to a collocation stride's excitations: a measuring probe.

The stride (repeated three times, sampled at about 1 ms) gives every sensor the reflex
controller reads: fibre lengths and tendon forces, coordinates and speeds, contact forces and
points. The controller's own compiled steps (``push_sensors``, ``update_gait_states``,
``compute_excitations``) replay it with a parameter vector, and least squares fits the gains
and offsets so that the controller's excitations over the third stride match the stride's,
with a prior pulling every parameter towards SCONE's value (weight ``PRIOR``, in units of the
layout's search step). The gait-state thresholds and the initial offsets stay at SCONE's.
Prints R² per muscle before and after, writes the fitted parameter file, and simulates both
from the stride's own state (``--start-stride``, with ``--run-up``: the mean-speed
reflexes act from the start, as in the fit) for 4 s.

    .venv/bin/python benchmarks/runs/reflex-human/fit_to_stride.py STRIDE.json OUT.json [PRIOR]
"""

from __future__ import annotations

import sys

import numpy as np
from numba import njit
from scipy.optimize import least_squares

from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.reflex import controller as ctl
from bladelab.predict.reflex.objective import ObjectiveSettings, simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout


@njit(cache=False)
def replay(table, p, nh, muscles, mp, qpos, qvel, contacts, cp, ix, bw, thr, leg_length,
           run_up):
    """The controller's excitations and gait states at every sample of a recorded run."""
    ns, nm, nq = qpos.shape[0], muscles.shape[1], qpos.shape[1]
    hist = np.zeros((nh, 3 * nm + 2 * nq))
    cs = np.zeros(ctl.CONTROLLER_STATE_SIZE)
    cs[0] = cs[1] = 3.0  # swing, as a simulation starts
    cs[4] = run_up  # 1: the mean-velocity reflexes act from the start
    out = np.zeros((ns, nm))
    states = np.zeros((ns, 2))
    u = np.zeros(nm)
    for k in range(ns):
        ctl.push_sensors(hist, cs, muscles[k], mp, qpos[k], qvel[k])
        ctl.update_gait_states(cs, contacts[k], cp, qpos[k], ix, bw, thr, leg_length)
        ctl.compute_excitations(u, table, p, hist, cs, nm, nq)
        out[k] = u
        states[k] = cs[:2]
    return out, states


def replay_inputs(model, layout, x, dt, muscles, qpos, qvel, contacts, run_up):
    """The arguments of :func:`replay` after its table and parameters: the recorded muscle
    states, coordinates, speeds and contacts (one row per step of ``dt`` [s]) with the
    gait-state thresholds of the parameter vector ``x``, as the simulation passes them."""
    thr = np.array([x[layout.index(f"{name}{side}")] for name in
                    ("stance_load_threshold_", "liftoff_load_margin_") for side in "lr"])
    return (ctl.history_length(layout, dt), np.ascontiguousarray(muscles),
            model.muscle_params, np.ascontiguousarray(qpos), np.ascontiguousarray(qvel),
            np.ascontiguousarray(contacts), model.contact_params, model.dof("pelvis_tx"),
            model.body_weight, thr, float(model.stand_qpos[model.dof("pelvis_tz")]),
            float(run_up))


def main(stride: str, out: str, prior: float = 0.1) -> None:
    model, layout = runner_and_layout("able", None, "human")
    sol = CollocationSolution.read(stride)
    n = np.asarray(sol.nlp.q).shape[0] - 1
    rec = sol.to_runner_result(3, refine=int(np.ceil(sol.period_s / n / 1e-3)), runner=model)
    x0 = layout.x0.copy()
    args = replay_inputs(model, layout, x0, rec.dt, rec.muscles, rec.qpos, rec.qvel,
                         rec.contacts, run_up=True)
    table = layout.table_for(rec.dt)
    last = rec.time >= 2 * sol.period_s - 1e-9
    target = rec.excitation[last]
    free = np.array([not (name.startswith(("stance_load", "liftoff")) or name.endswith(".offset"))
                     for name in layout.names])

    def full(theta):
        x = x0.copy()
        x[free] = theta
        return x

    def residuals(theta):
        u, _ = replay(table, full(theta), *args)
        pull = prior * (theta - x0[free]) / layout.std[free] / np.sqrt(free.sum())
        return np.concatenate([(u[last] - target).ravel(), pull])

    def r2(x, label):
        u, states = replay(table, x, *args)
        err = u[last] - target
        ss = ((target - target.mean(0)) ** 2).sum(0)
        leg = [m for m, s in zip(model.muscle_names, ss, strict=True) if s > 1e-6]
        val = 1 - (err ** 2).sum(0) / np.maximum(ss, 1e-12)
        print(f"{label}: RMS {np.sqrt((err ** 2).mean()):.3f}; R² "
              + ", ".join(f"{m} {v:.2f}" for m, v, s in zip(model.muscle_names, val, ss,
                                                                    strict=True)
                          if s > 1e-6))
        print(f"  (muscles the stride does not vary, left out: "
              f"{sorted(set(model.muscle_names) - set(leg))})")
        return states

    states = r2(x0, "SCONE's parameters")
    names = ctl.STATE_NAMES
    print("  gait states over the stride (left leg, samples):",
          {names[int(s)]: int(c) for s, c in zip(*np.unique(states[last, 0], return_counts=True),
                                                       strict=True)})
    lo, hi = layout.lower[free], layout.upper[free]
    fit = least_squares(residuals, np.clip(x0[free], lo, hi), bounds=(lo, hi),
                        x_scale=layout.std[free], max_nfev=200)
    x = full(fit.x)
    r2(x, f"fitted ({fit.nfev} evaluations, {fit.message})")
    ctl.write_parameters(out, layout, x, body="human", source=f"fitted to {stride}")
    for label, xx in (("SCONE's parameters", x0), ("fitted", x)):
        s = ObjectiveSettings(speed=sol.mean_speed_mps, duration=4.0, integrator="newmark",
                              dt=1e-3, start_stride=stride, run_up=True)
        ev, _ = simulate_controlled(model, xx, layout=layout, settings=s)
        print(f"{label} from the stride's state: falls {ev.fell} at {ev.duration:.3f} s, "
              f"cost {ev.cost:.2f}, {ev.n_steps} steps")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], *(float(a) for a in sys.argv[3:4]))
