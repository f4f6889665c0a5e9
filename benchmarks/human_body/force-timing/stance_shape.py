"""The shape of a stance: vertical force, which contact carries it, and the leg's angles, model
against the measured runner (a measuring probe; solves nothing, changes nothing in src).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/force-timing/stance_shape.py [STRIDE.json]

STRIDE.json: a collocation stride of the able runner (default: the shipped 3.5 m/s stride).
Prints, per leg of the stride and per stance of the Fukuchi trial's mean stride (100 nodes),
the vertical force [BW] at 0, 10, …, 100 % of the stance, where it peaks and where half the
stance's impulse is reached [% of the stance]; the stride's left stance node by node with the
force of each contact [BW]; and the left leg's knee, hip and ankle angles [deg] over the stance
with where the knee flexes most; and per stance of both, the centre of mass's drop from
touch-down to its lowest point [mm] (the total vertical force integrated twice over the periodic
stride, zero mean vertical speed), where in the stance it is lowest and the vertical stiffness
k_vert = peak force / drop [BW/m] (McMahon & Cheng 1990). A stance: the nodes where the leg's
vertical force exceeds 0.03 BW.
"""

from __future__ import annotations

import sys

import numpy as np

from bladelab.predict.collocation import stored
from bladelab.predict.collocation.guess import measured_trial_guess
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.runner.params import RUNNER_DATA_DIR

SHIPPED = RUNNER_DATA_DIR / "collocation" / "able-3.5-human.json"
DECILES = np.arange(0, 101, 10)
GRAVITY = 9.81  # [m/s²], the runner's


def stances(force_bw: np.ndarray, threshold: float = 0.03) -> list[list[int]]:
    """The node indices of each stance of a periodic force (n + 1 nodes, the last = the first)."""
    n = len(force_bw) - 1
    on = force_bw[:-1] > threshold
    out = []
    for k0 in range(n):
        if on[k0] and not on[k0 - 1]:
            length = next(k for k in range(1, n + 1) if not on[(k0 + k) % n])
            out.append([(k0 + k) % n for k in range(length)])
    return out


def on_deciles(values: np.ndarray) -> np.ndarray:
    """``values`` over a stance, resampled to 0, 10, …, 100 % of it."""
    return np.interp(DECILES, np.linspace(0.0, 100.0, len(values)), values)


def force_line(name: str, force: np.ndarray) -> str:
    fine = np.interp(np.linspace(0, 100, 101), np.linspace(0, 100, len(force)), force)
    impulse = np.cumsum(fine) / fine.sum()
    return (f"{name}: {len(force)} nodes; peak at {np.argmax(fine):.0f} %, half the impulse by "
            f"{np.searchsorted(impulse, 0.5):.0f} %; force [BW]: "
            + " ".join(f"{v:.2f}" for v in on_deciles(force)))


def com_height(force_bw: np.ndarray, period_s: float) -> np.ndarray:
    """The centre of mass's vertical displacement [m] at the nodes of a periodic stride from
    its total vertical ground force [BW] (n + 1 nodes), up to a constant."""
    t = np.linspace(0.0, period_s, len(force_bw))
    accel = GRAVITY * (force_bw - 1.0)
    speed = np.concatenate([[0.0], np.cumsum(0.5 * (accel[1:] + accel[:-1]) * np.diff(t))])
    speed -= np.trapezoid(speed, t) / period_s  # a periodic stride neither rises nor sinks
    return np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])


def com_lines(name: str, force_bw: np.ndarray, period_s: float) -> list[str]:
    """Per stance of the total force: the centre of mass's drop, where it is lowest, k_vert."""
    height = com_height(force_bw, period_s)
    out = []
    for idx in stances(force_bw):
        drop = height[idx[0]] - height[idx].min()
        out.append(f"{name}: peak {force_bw[idx].max():.2f} BW, centre of mass drops "
                   f"{1000 * drop:.0f} mm, lowest at {100 * np.argmin(height[idx]) / len(idx):.0f} "
                   f"% of the stance, k_vert {force_bw[idx].max() / drop:.0f} BW/m")
    return out


def main() -> None:
    sol = CollocationSolution.read(sys.argv[1] if len(sys.argv) > 1 else SHIPPED)
    runner = stored.runner_from_spec(sol.model_spec)
    fz = sol.leg_vertical_force() / sol.body_weight_N
    for j, leg in enumerate(sol.leg_names):
        for idx in stances(fz[:, j]):
            print(force_line(f"model, {leg}", fz[idx, j]))
    people = measured_trial_guess(runner, n=100)
    total = np.asarray(people.vertical_grf_bw)
    for idx in stances(total):
        print(force_line(f"people, stance from node {idx[0]}", total[idx]))

    left = np.flatnonzero(sol.contact_legs == 0)
    per_contact = sol.contact_forces[:, left, 1] / sol.body_weight_N
    idx = stances(fz[:, 0])[0]
    print("model, left stance: node, total, per contact "
          + ", ".join(runner.contact_names[c] for c in left) + " [BW]")
    for k in idx:
        print(f"  {k:3d} {fz[k, 0]:.2f}  " + " ".join(f"{v:.2f}" for v in per_contact[k]))

    for line in (com_lines("model", fz.sum(axis=1), sol.period_s)
                 + com_lines("people", total, people.period)):
        print(line)

    names, people_names = list(sol.dof_names), list(people.dof_names or runner.dof_names)
    # the trial's left stance: the one of its two (total force) where the left knee is the
    # straighter (the other is the left leg's swing)
    knee = people_names.index("knee_angle_l")
    p_idx = max(stances(total), key=lambda s: people.q[s, knee].mean())
    for dof in ("knee_angle_l", "hip_flexion_l", "ankle_angle_l"):
        for who, q, i in (("model", sol.nlp.q[idx, names.index(dof)], idx),
                          ("people", people.q[p_idx, people_names.index(dof)], p_idx)):
            angle = np.degrees(q)
            where = (f" (most flexed at {np.linspace(0, 100, len(i))[np.argmin(angle)]:.0f} %)"
                     if dof.startswith("knee") else "")
            print(f"{who} {dof} [deg]: " + " ".join(f"{v:.0f}" for v in on_deciles(angle))
                  + where)


if __name__ == "__main__":
    main()
