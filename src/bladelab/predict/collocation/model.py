"""The collocation model of a runner: CasADi Functions built from a :class:`RunnerModel`.

One definition feeds both sides: everything is read from the runner the forward simulation
uses (``mj_model`` for the multibody tree, ``path_points``/``path_start`` for muscle paths,
``muscle_params``, ``contact_params`` and ``joint_params`` for the force laws); nothing is
typed in twice. See ``docs/collocation.md`` for what is exact and what is smoothed.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from bladelab.predict.collocation import contact, multibody, muscles, paths
from bladelab.predict.collocation.planar import PlanarTree, planar_tree
from bladelab.predict.collocation.smooth import Smoothing
from bladelab.runner.model import RunnerModel


@dataclass(frozen=True, eq=False)
class CollocationModel:
    """CasADi (SX) Functions of one runner model (SI units; column vectors).

    Attributes
    ----------
    runner
        The forward model it was derived from.
    tree
        Its planar multibody description.
    smoothing
        The widths of the smooth approximations.
    inverse_dynamics
        ``(q, qd, qdd) -> tau`` (nv): ``M(q)·q̈ + C(q, q̇)`` with gravity [N, N·m].
    mass_matrix
        ``(q) -> M`` (nv, nv) [kg, kg·m, kg·m²].
    mtu
        ``(q, qd) -> (l_mt, v_mt)`` (n_muscles): MTU lengths [m] and lengthening velocities [m/s].
    moment_arms
        ``(q) -> r`` (n_muscles, nv): ``−∂l/∂q`` [m or m/rad].
    contacts
        ``(q, qd) -> (forces, points, tau)``: (n_contacts, 2) friction and normal force [N],
        (n_contacts, 2) lab contact points [m], (nv) their generalised force.
    passive
        ``(q, qd) -> tau`` (nv): ligament and socket (blade-joint) torques [N·m].
    fiber
        ``(l_mt, v_mt, ft, dft) -> (l_m, v_m, cos_alpha)`` (n_muscles) [m, m/s, -].
    muscle_residual
        ``(a, ft, dft, l_mt, v_mt) -> residual`` (n_muscles) [-]: fibre–tendon equilibrium.
    activation_rate
        ``(u, a) -> da/dt`` (n_muscles) [1/s].
    dynamics_residual
        ``(q, qd, qdd, ft) -> residual`` (nv) [N, N·m]: inverse dynamics minus the muscle
        (``rᵀ·Fmax·F̃_T``), passive and contact generalised forces; zero on a solution.
    """

    runner: RunnerModel
    tree: PlanarTree
    smoothing: Smoothing
    inverse_dynamics: ca.Function
    mass_matrix: ca.Function
    mtu: ca.Function
    moment_arms: ca.Function
    contacts: ca.Function
    passive: ca.Function
    fiber: ca.Function
    muscle_residual: ca.Function
    activation_rate: ca.Function
    dynamics_residual: ca.Function

    @property
    def nv(self) -> int:
        """Number of generalised coordinates."""
        return self.tree.nv

    @property
    def n_muscles(self) -> int:
        return len(self.runner.muscle_names)

    @property
    def n_contacts(self) -> int:
        return len(self.runner.contact_names)


def build_collocation_model(
    runner: RunnerModel, *, smoothing: Smoothing | None = None
) -> CollocationModel:
    """Derive the CasADi model of ``runner`` (able, amputee with a blade sphere or a
    multi-link blade).

    Parameters
    ----------
    runner
        A model from :func:`bladelab.runner.build_runner`.
    smoothing
        Widths of the smooth approximations (default :class:`Smoothing`).

    Raises
    ------
    ModelError
        If the MuJoCo model is not planar in x–z (:func:`planar_tree`).
    """
    sm = smoothing or Smoothing()
    tree = planar_tree(runner.mj_model)
    nv, nm = tree.nv, len(runner.muscle_names)
    q, qd, qdd = ca.SX.sym("q", nv), ca.SX.sym("qd", nv), ca.SX.sym("qdd", nv)
    frames = multibody.body_frames(tree, q)
    tau_id = multibody.inverse_dynamics(tree, q, qd, qdd)
    l_mt = paths.mtu_lengths(tree, frames, runner.path_points, runner.path_start)
    v_mt = paths.mtu_velocities(l_mt, q, qd)
    arms = paths.moment_arms(l_mt, q)
    f_c, p_c, tau_c = contact.contact_forces(tree, frames, q, qd, runner.contact_params, sm)
    tau_p = contact.passive_torques(q, qd, runner.joint_params, sm)

    mp = runner.muscle_params
    a, ft, dft, u = (ca.SX.sym(n, nm) for n in ("a", "ft", "dft", "u"))
    lm_s, vm_s = ca.SX.sym("l_mt", nm), ca.SX.sym("v_mt", nm)
    tau_m = arms.T @ muscles.tendon_forces(mp, ft)

    return CollocationModel(
        runner=runner,
        tree=tree,
        smoothing=sm,
        inverse_dynamics=ca.Function("inverse_dynamics", [q, qd, qdd], [tau_id],
                            ["q", "qd", "qdd"], ["tau"]),
        mass_matrix=ca.Function("mass_matrix", [q], [ca.jacobian(tau_id, qdd)], ["q"], ["M"]),
        mtu=ca.Function("mtu", [q, qd], [l_mt, v_mt], ["q", "qd"], ["l_mt", "v_mt"]),
        moment_arms=ca.Function("moment_arms", [q], [arms], ["q"], ["r"]),
        contacts=ca.Function("contacts", [q, qd], [f_c, p_c, tau_c], ["q", "qd"],
                    ["forces", "points", "tau"]),
        passive=ca.Function("passive", [q, qd], [tau_p], ["q", "qd"], ["tau"]),
        fiber=ca.Function("fiber", [lm_s, vm_s, ft, dft],
                 list(muscles.fiber_kinematics(mp, lm_s, vm_s, ft, dft, sm)),
                 ["l_mt", "v_mt", "ft", "dft"], ["l_m", "v_m", "cos_alpha"]),
        muscle_residual=ca.Function("muscle_residual", [a, ft, dft, lm_s, vm_s],
                           [muscles.equilibrium_residual(mp, a, ft, dft, lm_s, vm_s, sm)],
                           ["a", "ft", "dft", "l_mt", "v_mt"], ["residual"]),
        activation_rate=ca.Function("activation_rate", [u, a], [muscles.activation_rate(u, a, sm)],
                           ["u", "a"], ["adot"]),
        dynamics_residual=ca.Function("dynamics_residual", [q, qd, qdd, ft],
                             [tau_id - tau_m - tau_p - tau_c], ["q", "qd", "qdd", "ft"],
                             ["residual"]),
    )
