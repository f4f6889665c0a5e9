"""The collocation model's quantities at the nodes of a stride: muscle–tendon and fibre
kinematics, contact forces, points and point velocities, passive torques (for a solution's
file, its forward re-play and seed 002's responses)."""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.predict.collocation.contact import contact_kinematics
from bladelab.predict.collocation.multibody import body_frames

__all__ = ["evaluate_nodes", "force_zigzag_steps", "on_fine_grid", "periodic_runs"]


def on_fine_grid(values: np.ndarray, per_interval: int) -> np.ndarray:
    """Node values (n + 1, ...) of a periodic stride, interpolated linearly onto
    ``n·per_interval`` equally spaced samples (the last node, one period on, left out)."""
    values = np.asarray(values, float)
    n = values.shape[0] - 1
    x = np.linspace(0.0, n, n * per_interval, endpoint=False)
    flat = values.reshape(n + 1, -1)
    fine = np.stack([np.interp(x, np.arange(n + 1), flat[:, j]) for j in range(flat.shape[1])],
                    axis=1)
    return fine.reshape((n * per_interval,) + values.shape[1:])


def periodic_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start index, length) [samples] of the True stretches of a periodic boolean sequence (a
    stretch across the end continues at the start), in order from the first False sample."""
    mask = np.asarray(mask, bool)
    if mask.all():
        return [(0, mask.size)]
    if not mask.any():
        return []
    start = int(np.argmin(mask))  # rotate so that the sequence starts unloaded
    m = np.roll(mask, -start).astype(np.int8)
    edges = np.diff(np.concatenate([[0], m, [0]]))
    ons, offs = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(int((on + start) % mask.size), int(off - on)) for on, off in zip(ons, offs, strict=True)]


def force_zigzag_steps(force: np.ndarray, step: float, loaded: float) -> int:
    """The longest run of node-to-node steps of a periodic force ``force`` (n nodes of one
    period, without the repeated last node) that each reach ``step`` and alternate in sign
    (up, down, up, …) while the force stays above ``loaded`` (same unit as ``force``).

    A force a stance's landing and push-off shape rises and falls once, with a turn or two at
    an impact (runs of 1–3 on the human body's strides at 2.5–8 m/s on 100–200 intervals); a
    force that zigzags from node to node over many nodes is the mesh's, not the runner's (a
    stance the mesh does not resolve)."""
    x = np.asarray(force, float)
    x = np.roll(x, -int(np.argmin(x)))  # start unloaded: no run crosses the period's end
    best = run = prev = 0
    for a, b in zip(x[:-1], x[1:], strict=True):
        d = b - a
        sign = int(np.sign(d)) if abs(d) >= step and min(a, b) > loaded else 0
        run = run + 1 if sign and sign == -prev else (1 if sign else 0)
        prev = sign
        best = max(best, run)
    return best


def _node_samples(cm):
    """A CasADi Function of one sample (q, q̇, F̃ₜ, dF̃ₜ/dt) -> (l_mt, v_mt, l_m, v_m, vec(forces),
    vec(points), vec(point velocities), passive torques) of the collocation model. A point's
    velocity is that of the body's material point there (as the contact law and the forward
    kernel take it), not the rate of the lowest point, which rolls over a turning sphere."""
    nv, nm = cm.nv, cm.n_muscles
    q, qd = ca.SX.sym("q", nv), ca.SX.sym("qd", nv)
    ft, dft = ca.SX.sym("ft", nm), ca.SX.sym("dft", nm)
    l_mt, v_mt = cm.mtu(q, qd)
    l_m, v_m, _ = cm.fiber(l_mt, v_mt, ft, dft)
    f, p, _ = cm.contacts(q, qd)
    frames = body_frames(cm.tree, q)
    vel = [v for *_, v in contact_kinematics(cm.tree, frames, q, qd, cm.runner.contact_params)]
    pv = ca.vertcat(*[v[0] for v in vel], *[v[1] for v in vel])  # as ca.vec of (nc, 2)
    tau_p = cm.passive(q, qd)
    return ca.Function("node_samples", [q, qd, ft, dft],
                       [l_mt, v_mt, l_m, v_m, ca.vec(f), ca.vec(p), pv, tau_p])


def evaluate_nodes(cm, q, qd, ft, dft) -> dict[str, np.ndarray]:
    """The collocation model's quantities at samples (rows of q, q̇, F̃ₜ, dF̃ₜ/dt): MTU and
    fibre lengths and velocities [m, m/s], contact ``forces`` (N, n_contacts, 2: Fx, Fz on
    the body [N]), lowest ``points`` and their ``point_velocities`` [m, m/s], ``passive``
    torques [N·m]."""
    fn = _node_samples(cm).map(q.shape[0])
    out = [np.asarray(v, dtype=float).T for v in fn(q.T, qd.T, ft.T, dft.T)]
    nc = cm.n_contacts

    def per_contact(a):  # (N, 2·nc) column-major vec of (nc, 2) -> (N, nc, 2)
        return a.reshape(a.shape[0], 2, nc).swapaxes(1, 2)

    return {"l_mt": out[0], "v_mt": out[1], "l_m": out[2], "v_m": out[3],
            "forces": per_contact(out[4]), "points": per_contact(out[5]),
            "point_velocities": per_contact(out[6]), "passive": out[7]}
