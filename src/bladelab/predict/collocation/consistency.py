"""Dynamic consistency of a collocation solution with the forward model.

At every node of a stride (coordinates q, speeds q̇, accelerations q̈ and normalised tendon
forces F̃ₜ of a collocation solution), MuJoCo's inverse dynamics of the runner's own model
(``mujoco.mj_inverse`` with ``qacc`` = q̈: ``M(q)·q̈ + C(q, q̇)`` with gravity) is set against
the generalised forces that the FORWARD model's own code applies in that state
(:func:`bladelab.runner.kernel.forces`, the function the forward simulation calls every step):

- muscles: the tendon forces F̃ₜ·Fmax [N], applied as point forces along every path segment
  (:func:`bladelab.runner.kernel.path_kinematics`); the forward muscle's fibre length is set so
  that its tendon carries exactly that force (the tendon curve inverted; the mismatch, if the
  inversion is clamped, is reported as ``tendon_force_mismatch``);
- passive: ligaments, socket and blade joints;
- contacts: the forward Hunt–Crossley (or spring–damper) normal force and the forward
  friction. The forward friction is a bristle with a state (its anchor) that a collocation
  solution does not carry, so it is taken in one of two ways (``friction``):

  - ``"coulomb"`` (default): what the forward bristle can do at this state. A contact point
    sliding at |vₓ| ≥ :data:`SLIDING_SPEED_M_PER_S` gets the bristle's sliding force
    −μ·Fn·sign(vₓ) (the kernel called with the anchor far behind); a slower one sticks, and a
    sticking bristle carries any force within ±μ·Fn, so it gets the collocation model's
    friction force clipped to the forward ±μ·Fn. The difference then measures the normal
    force, the cap and the sliding force, not the history of an anchor;
  - ``"bristle"``: the anchor reconstructed by running the forward friction along the stride
    at the forward time step (``dt``, 0.25 ms; coordinates interpolated between nodes as the
    trapezoidal transcription implies: q̇ linear, q quadratic), two periods, the second one
    kept. On a coarse mesh the interpolated foot motion between nodes is not the motion a
    forward simulation would follow, and the stretch of a sticking bristle (5·10⁴ N/m) is
    the integral of the collocation's small slip: expect large differences.

Every generalised force is ``Jᵀ·f`` of MuJoCo (``mj_applyFT``), the ligament torques as the
forward model writes them to ``qfrc_applied``.

``dynamics_residual_pct`` = the largest |inverse dynamics − (muscle + passive + contact)| over
the nodes (the last, which repeats the first, left out) and the coordinates, in % of the peak
|muscle + passive + contact|; translations [N] and rotations [N·m] are normalised separately
(each by its own peak) and the larger of the two percentages is returned. The translations'
peak is taken as at least the body weight and the rotations' as at least 1 N·m (a state set
with no ground force, e.g. an initial guess, would otherwise divide by zero; a running stride
always carries the body weight through its pelvis translations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from bladelab.errors import DataError, SpecError
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.runner.kernel import forces, mujoco_views, path_kinematics
from bladelab.runner.layout import CP_BODY, CP_MU, CP_SITE
from bladelab.runner.model import DEFAULT_DT, RunnerModel
from bladelab.runner.muscle import MP_FMAX, MP_LOPT, MP_LTS, MP_PENN, MP_TSTRAIN

__all__ = [
    "FRICTION_MODES",
    "SLIDING_SPEED_M_PER_S",
    "DynamicsResidual",
    "ForwardForces",
    "dynamics_residual",
    "dynamics_residual_pct",
    "forward_generalised_forces",
    "inverse_dynamics",
]

_TRANSLATIONS = ("pelvis_tx", "pelvis_tz")
#: Contact-point speed above which the forward bristle is taken as sliding [m/s]
#: (``docs/collocation.md``: the two friction laws agree to 0.25 % of μ·Fn from there on).
SLIDING_SPEED_M_PER_S = 0.1
FRICTION_MODES = ("coulomb", "bristle")


@dataclass(frozen=True)
class ForwardForces:
    """Generalised forces [N for pelvis translations, N·m for rotations] the forward model's
    code applies at each node, (n_nodes, n_dof) each.

    Attributes
    ----------
    muscle, passive, contact
        Tendon forces along the paths; ligaments, socket and blade joints; ground contacts.
    contact_rows
        (n_nodes, n_contacts, 7): the forward kernel's contact record (Fx, Fz [N], contact
        point x, z [m], its velocity vx, vz [m/s], compression [m]).
    tendon_force_mismatch
        Largest |applied − requested| tendon force over nodes and muscles, as a fraction of
        that muscle's Fmax [-] (0 unless the inversion of the tendon curve was clamped).
    """

    muscle: np.ndarray
    passive: np.ndarray
    contact: np.ndarray
    contact_rows: np.ndarray
    tendon_force_mismatch: float

    @property
    def total(self) -> np.ndarray:
        """Muscle + passive + contact generalised force (n_nodes, n_dof)."""
        return self.muscle + self.passive + self.contact


@dataclass(frozen=True)
class DynamicsResidual:
    """Inverse dynamics against the applied generalised forces at a solution's nodes.

    Attributes
    ----------
    pct
        The largest difference between MuJoCo's inverse dynamics and the forward model's
        muscle + passive + contact forces, in % of their peak (module docstring).
    collocation_pct
        The same against the collocation model's own (smooth) forces: how well the NLP's
        dynamics constraints hold at the nodes, with MuJoCo's inverse dynamics [%].
    component_pct
        Forward minus collocation generalised force per component (``muscle``, ``passive``,
        ``contact``), largest difference in % of the same peak as ``pct``: where a forward
        residual comes from (the contact term holds the friction's state).
    worst_dof, worst_node
        Coordinate and node of the largest (normalised) forward difference.
    worst_value
        That difference [N or N·m].
    peak_force_N, peak_moment_Nm
        The peaks used for normalisation (translations, rotations).
    per_dof
        Largest |forward difference| per coordinate [N or N·m].
    tendon_force_mismatch
        :attr:`ForwardForces.tendon_force_mismatch` [fraction of Fmax].
    friction
        How the forward friction was taken: ``"coulomb"`` or ``"bristle"``.
    contact_force_diff_N
        Largest |forward − collocation| ``friction`` and ``normal`` force of one contact over
        the nodes [N].
    """

    pct: float
    collocation_pct: float
    component_pct: dict[str, float]
    worst_dof: str
    worst_node: int
    worst_value: float
    peak_force_N: float
    peak_moment_Nm: float
    per_dof: dict[str, float] = field(default_factory=dict)
    tendon_force_mismatch: float = 0.0
    friction: str = "coulomb"
    contact_force_diff_N: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {
            "dynamics_residual_pct": self.pct,
            "collocation_residual_pct": self.collocation_pct,
            "component_pct": dict(self.component_pct),
            "worst_dof": self.worst_dof,
            "worst_node": self.worst_node,
            "worst_value": self.worst_value,
            "peak_force_N": self.peak_force_N,
            "peak_moment_Nm": self.peak_moment_Nm,
            "per_dof_max": dict(self.per_dof),
            "tendon_force_mismatch": self.tendon_force_mismatch,
            "friction": self.friction,
            "contact_force_diff_N": dict(self.contact_force_diff_N),
        }


def _nodes(solution):
    """The node arrays of a CollocationSolution (its ``nlp``) or an NLPSolution."""
    return getattr(solution, "nlp", solution)


def _check_shapes(runner: RunnerModel, q, qd, tendon_force) -> None:
    nv, nm = runner.mj_model.nv, len(runner.muscle_names)
    if q.ndim != 2 or q.shape[1] != nv or qd.shape != q.shape or q.shape[0] < 2:
        raise DataError(f"coordinates and speeds must be (n_nodes, {nv}), got {q.shape} and "
                        f"{qd.shape}", where="q, qd",
                        hint="the solution is not of this runner model")
    if tendon_force.shape != (q.shape[0], nm):
        raise DataError(f"tendon forces must be ({q.shape[0]}, {nm}), got {tendon_force.shape}",
                        where="tendon_force", hint="the solution is not of this runner model")


def inverse_dynamics(runner: RunnerModel, q: np.ndarray, qd: np.ndarray,
                     qdd: np.ndarray) -> np.ndarray:
    """MuJoCo's inverse dynamics (``mj_inverse``: ``qfrc_inverse``) of the runner's model at
    each row of q [m, rad], q̇ [m/s, rad/s], q̈ [m/s², rad/s²]: (n, n_dof) [N, N·m]."""
    m = runner.mj_model
    d = mujoco.MjData(m)
    out = np.empty((q.shape[0], m.nv))
    for k in range(q.shape[0]):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[k], qd[k], qdd[k]
        mujoco.mj_inverse(m, d)
        out[k] = d.qfrc_inverse
    return out


def forward_generalised_forces(
    runner: RunnerModel,
    q: np.ndarray,
    qd: np.ndarray,
    tendon_force: np.ndarray,
    period: float,
    *,
    friction: str = "coulomb",
    stick_friction: np.ndarray | None = None,
    dt: float = DEFAULT_DT,
) -> ForwardForces:
    """The generalised forces the forward model's code applies at the nodes of one periodic
    stride (module docstring).

    Parameters
    ----------
    runner
        The forward model.
    q, qd
        (n + 1, n_dof) coordinates [m, rad] and speeds [m/s, rad/s] at equally spaced nodes
        over one period (the last node one period after the first).
    tendon_force
        (n + 1, n_muscles) tendon forces normalised by Fmax [-].
    period
        Stride time [s].
    friction
        ``"coulomb"`` or ``"bristle"`` (module docstring).
    stick_friction
        (n + 1, n_contacts) friction force [N] of a sticking contact (``"coulomb"``; clipped
        to ±μ·Fn of the forward normal force); None: 0.
    dt
        Time step [s] of the friction state's reconstruction (the forward model's).
    """
    q, qd = np.asarray(q, float), np.asarray(qd, float)
    tendon_force = np.asarray(tendon_force, float)
    _check_shapes(runner, q, qd, tendon_force)
    if not (period > 0 and math.isfinite(period)):
        raise DataError(f"stride time must be > 0 s, got {period}", where="period")
    if friction not in FRICTION_MODES:
        raise SpecError(f"unknown friction mode {friction!r}", where="friction",
                        hint=" or ".join(FRICTION_MODES))
    m = runner.mj_model
    d = mujoco.MjData(m)
    mj = mujoco_views(d)
    nv, nm = m.nv, len(runner.muscle_names)
    mp, cp = runner.muscle_params, runner.contact_params
    nc = cp.shape[0]
    ms = np.zeros((nm, 4))
    mtu = np.zeros((nm, 2))
    seg_u = np.zeros((runner.path_points.shape[0], 3))
    u = np.zeros(nm)
    cstate = np.zeros((nc, 1))
    crec = np.zeros((nc, 7))
    lig = np.zeros(nv)
    idle = mp.copy()
    idle[:, MP_FMAX] = 0.0  # the sub-steps only carry the friction state: muscles off

    def arrays(params: np.ndarray) -> tuple:
        return (params, ms, mtu, seg_u, u, runner.path_points, runner.path_start, cp, cstate,
                runner.joint_params, crec, lig)

    root = np.zeros(3)

    def place(qk: np.ndarray, vk: np.ndarray) -> None:
        d.qpos[:], d.qvel[:] = qk, vk
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_comVel(m, d)
        root[:] = d.subtree_com[1]

    n = q.shape[0] - 1
    h = period / n
    sub = max(1, math.ceil(h / dt - 1e-9))
    step = h / sub
    # the bristle state at each node: the forward friction run along the stride, two periods
    states = np.zeros((n + 1, nc, 1))
    ms[:, 0], ms[:, 1] = 0.01, mp[:, MP_LOPT]
    for sweep in range(2 if friction == "bristle" else 0):
        for k in range(n):
            dv = qd[k + 1] - qd[k]
            for j in range(sub):
                if j == 0 and sweep == 1:
                    states[k] = cstate
                tau = j * step
                place(q[k] + qd[k] * tau + dv * tau * tau / (2 * h), qd[k] + dv * tau / h)
                forces(mj, arrays(idle), root, step)
    states[n] = cstate

    fmax, lopt, lts, penn, eref = (mp[:, c] for c in (MP_FMAX, MP_LOPT, MP_LTS, MP_PENN,
                                                       MP_TSTRAIN))
    rise = lopt * np.sin(penn)
    muscle = np.zeros((n + 1, nv))
    passive = np.zeros((n + 1, nv))
    contact = np.zeros((n + 1, nv))
    rows = np.zeros((n + 1, nc, 7))
    mismatch = 0.0
    for k in range(n + 1):
        place(q[k], qd[k])
        path_kinematics(d.site_xpos, d.cvel, root.copy(), runner.path_points, runner.path_start,
                        mtu, seg_u)
        want = np.maximum(tendon_force[k], 0.0)
        # the fibre length at which the forward tendon carries F̃ₜ·Fmax: tendon strain
        # ε_ref·√F̃ₜ, fibre along the tendon line x = l_mt − l_t, l_ce = √(x² + (l_opt sin α₀)²)
        along = np.maximum(mtu[:, 0] - lts * (1.0 + eref * np.sqrt(want)), 0.0)
        ms[:, 0], ms[:, 1], ms[:, 2] = 0.01, np.maximum(np.hypot(along, rise), 1e-6), 0.0
        muscle_state = ms.copy()
        if friction == "coulomb":  # a first call for the point velocities: anchor far behind
            cstate[:] = 0.0
            forces(mj, arrays(mp), root, step)
            cstate[:, 0] = np.sign(crec[:, 4])
            ms[:] = muscle_state
        else:
            cstate[:] = states[k]
        forces(mj, arrays(mp), root, step)
        mismatch = max(mismatch, float(np.max(np.abs(ms[:, 3] - want * fmax) / fmax)))
        passive[k] = lig
        total = np.zeros(nv)
        for b in np.flatnonzero(np.any(d.xfrc_applied != 0.0, axis=1)):
            mujoco.mj_applyFT(m, d, d.xfrc_applied[b, :3].copy(), d.xfrc_applied[b, 3:].copy(),
                              d.xipos[b].copy(), int(b), total)
        applied = _contact_generalised(m, d, cp, crec)
        muscle[k] = total - applied
        if friction == "coulomb":
            cap = cp[:, CP_MU] * crec[:, 1]
            stick = np.abs(crec[:, 4]) < SLIDING_SPEED_M_PER_S
            held = np.zeros(nc) if stick_friction is None else np.asarray(stick_friction[k])
            crec[stick, 0] = np.clip(held[stick], -cap[stick], cap[stick])
            applied = _contact_generalised(m, d, cp, crec)
        contact[k] = applied
        rows[k] = crec
    return ForwardForces(muscle, passive, contact, rows, mismatch)


def _contact_generalised(m, d, cp: np.ndarray, crec: np.ndarray) -> np.ndarray:
    """Jᵀ·f [N, N·m] of the contact rows ``crec`` (Fx, Fz at the contact points)."""
    out = np.zeros(m.nv)
    for c in range(cp.shape[0]):
        if crec[c, 0] == 0.0 and crec[c, 1] == 0.0:
            continue
        point = np.array([crec[c, 2], d.site_xpos[int(cp[c, CP_SITE]), 1], crec[c, 3]])
        mujoco.mj_applyFT(m, d, np.array([crec[c, 0], 0.0, crec[c, 1]]), np.zeros(3), point,
                          int(cp[c, CP_BODY]), out)
    return out


def _collocation_forces(cm, q, qd, tendon_force) -> tuple[list[np.ndarray], np.ndarray]:
    """([muscle, passive, contact] generalised forces (n_nodes, n_dof) [N, N·m], contact
    forces (n_nodes, n_contacts, 2): friction, normal [N]) of the collocation model at the
    nodes."""
    fmax = cm.runner.muscle_params[:, 0]
    out = [np.zeros_like(q) for _ in range(3)]
    friction = np.zeros((q.shape[0], cm.n_contacts, 2))
    for k in range(q.shape[0]):
        arms = np.asarray(cm.moment_arms(q[k]))
        out[0][k] = arms.T @ (fmax * tendon_force[k])
        out[1][k] = np.asarray(cm.passive(q[k], qd[k])).ravel()
        f, _, tau_c = cm.contacts(q[k], qd[k])
        out[2][k] = np.asarray(tau_c).ravel()
        friction[k] = np.asarray(f)
    return out, friction


#: Smallest peak rotational generalised force used for normalisation [N·m].
MIN_PEAK_MOMENT_NM = 1.0


def _peaks(runner: RunnerModel, applied: np.ndarray) -> np.ndarray:
    """(n_dof,) the normaliser of each coordinate: the peak |applied| over its group
    (translations [N], at least the body weight; rotations [N·m], at least 1 N·m)."""
    trans = np.array([n in _TRANSLATIONS for n in runner.dof_names])
    force = max(float(np.abs(applied[:, trans]).max()) if trans.any() else 0.0,
                runner.body_weight)
    moment = max(float(np.abs(applied[:, ~trans]).max()) if (~trans).any() else 0.0,
                 MIN_PEAK_MOMENT_NM)
    return np.where(trans, force, moment)


def _pct(diff: np.ndarray, peaks: np.ndarray) -> float:
    return 100.0 * float(np.max(np.abs(diff) / peaks)) if diff.size else 0.0


def dynamics_residual(solution, runner: RunnerModel, *, cm=None, friction: str = "coulomb",
                      dt: float = DEFAULT_DT) -> DynamicsResidual:
    """MuJoCo's inverse dynamics against the forward model's applied forces at the nodes of a
    solution (:class:`~bladelab.predict.collocation.solution.CollocationSolution` or
    :class:`~bladelab.predict.collocation.nlp_solution.NLPSolution`), with the breakdown of
    :class:`DynamicsResidual`. ``cm``: the collocation model of ``runner`` (built if None);
    ``friction``: how the forward friction is taken (module docstring)."""
    s = _nodes(solution)
    q, qd, qdd = (np.asarray(a, float) for a in (s.q, s.qd, s.qdd))
    ft = np.asarray(s.tendon_force, float)
    cm = cm if cm is not None else build_collocation_model(runner)
    col, col_contacts = _collocation_forces(cm, q, qd, ft)
    fwd = forward_generalised_forces(runner, q, qd, ft, float(s.period), friction=friction,
                                     stick_friction=col_contacts[:, :, 0], dt=dt)
    keep = slice(0, q.shape[0] - 1)  # the last node repeats the first
    dcon = np.abs(fwd.contact_rows[keep, :, :2] - col_contacts[keep])
    tau_id = inverse_dynamics(runner, q, qd, qdd)
    applied = fwd.total[keep]
    diff = tau_id[keep] - applied
    peaks = _peaks(runner, applied)
    trans = np.array([n in _TRANSLATIONS for n in runner.dof_names])
    k, j = np.unravel_index(int(np.argmax(np.abs(diff) / peaks)), diff.shape)
    comp = {name: _pct(f[keep] - c[keep], peaks)
            for name, f, c in zip(("muscle", "passive", "contact"),
                                  (fwd.muscle, fwd.passive, fwd.contact), col, strict=True)}
    return DynamicsResidual(
        pct=_pct(diff, peaks),
        collocation_pct=_pct(tau_id[keep] - sum(c[keep] for c in col), peaks),
        component_pct=comp,
        worst_dof=runner.dof_names[int(j)],
        worst_node=int(k),
        worst_value=float(diff[k, j]),
        peak_force_N=float(peaks[trans].max()) if trans.any() else math.nan,
        peak_moment_Nm=float(peaks[~trans].max()) if (~trans).any() else math.nan,
        per_dof={n: float(np.abs(diff[:, i]).max()) for i, n in enumerate(runner.dof_names)},
        tendon_force_mismatch=fwd.tendon_force_mismatch,
        friction=friction,
        contact_force_diff_N={"friction": float(dcon[:, :, 0].max(initial=0.0)),
                              "normal": float(dcon[:, :, 1].max(initial=0.0))},
    )


def dynamics_residual_pct(solution, runner: RunnerModel, **kwargs) -> float:
    """:attr:`DynamicsResidual.pct` of :func:`dynamics_residual`: the largest difference
    between MuJoCo's inverse dynamics and the forward model's muscle + passive + contact
    generalised forces at the solution's nodes, in % of their peak [%]."""
    return dynamics_residual(solution, runner, **kwargs).pct
