"""The node functions of the stride NLP, assembled from a :class:`CollocationModel`.

:func:`stride_dynamics` turns the model layer into the :class:`StrideDynamics` that the
transcription needs: the multibody residual ``M·q̈ + C − τ_muscle − τ_passive − τ_contact``,
the fibre–tendon equilibrium of every muscle, the normalised fibre velocities kept within
[−1, 1] (the force–velocity curve's domain), the activation rate, the smooth metabolic rate
and the bounds of coordinates and speeds (the model's ligament ranges widened, so that the
ligaments, not the bounds, limit the joints).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.contact import contact_kinematics, passive_torques
from bladelab.predict.collocation.metabolics import (
    MetabolicSmoothing,
    muscle_metabolic_rates,
    whole_body_rate,
)
from bladelab.predict.collocation.model import CollocationModel
from bladelab.predict.collocation.multibody import body_frames, point_position
from bladelab.predict.collocation.smooth import sigmoid
from bladelab.predict.collocation.stride_problem import StrideDynamics
from bladelab.runner.layout import CP_LEG
from bladelab.runner.muscle import MP_ACTIVE, MP_LOPT, MP_VMAX

__all__ = ["COORDINATE_BOUNDS_DEG", "stride_dynamics"]

#: Bounds of the rotational coordinates [deg] (pelvis translations: :data:`PELVIS_BOUNDS_M`).
COORDINATE_BOUNDS_DEG: dict[str, tuple[float, float]] = {
    "pelvis_tilt": (-60.0, 30.0),
    "hip_flexion": (-60.0, 130.0),
    "knee_angle": (-150.0, 5.0),
    "ankle_angle": (-70.0, 70.0),
    "socket_angle": (-30.0, 30.0),
    "lumbar_extension": (-30.0, 30.0),
    "mtp_angle": (-45.0, 80.0),
    "midtarsal_angle": (-30.0, 45.0),
}
PELVIS_BOUNDS_M = {"pelvis_tx": (-math.inf, math.inf), "pelvis_tz": (0.4, 1.4)}
SPEED_BOUNDS = {"pelvis_tx": (0.0, 12.0), "pelvis_tz": (-4.0, 4.0)}  # m/s
MAX_ANGULAR_SPEED = 40.0  # rad/s
# Fibre length along the tendon line [optimal lengths]: positive (cos α > 0) and within the
# forward model's clamp at 0.2 (bladelab.runner.muscle) and a generous stretch.
MIN_FIBER_ALONG, MAX_FIBER_ALONG = 0.2, 2.0


def _bounds(dof_names) -> tuple[np.ndarray, np.ndarray]:
    q, qd = [], []
    for name in dof_names:
        if name in PELVIS_BOUNDS_M:
            q.append(PELVIS_BOUNDS_M[name])
            qd.append(SPEED_BOUNDS[name])
            continue
        base = name[:-2] if name.endswith(("_l", "_r")) else name
        lo, hi = COORDINATE_BOUNDS_DEG.get(base, (-90.0, 90.0))
        q.append((math.radians(lo), math.radians(hi)))
        qd.append((-MAX_ANGULAR_SPEED, MAX_ANGULAR_SPEED))
    return np.array(q), np.array(qd)


#: Width [m/s] of the switch of the swing clearance (:func:`swing_clearance`).
SWING_SPEED_WIDTH_MPS = 0.25
#: Penetration [m] the swing clearance allows a contact that is not swinging (far more than a
#: stance's few millimetres: the inequality is then inactive).
SWING_ALLOWANCE_M = 0.1


def swing_clearance(cm: CollocationModel, q: ca.SX, qd: ca.SX, height_m: float) -> ca.SX:
    """Per contact, ``height − s·height_m + (1 − s)·SWING_ALLOWANCE_M`` [m], with ``height`` its
    lowest point's height above the ground and ``s`` a smooth switch that is on (1) while the
    contact's material point moves forward faster than the pelvis by more than
    2·:data:`SWING_SPEED_WIDTH_MPS`: ≥ 0 keeps a swinging foot or blade ``height_m`` clear of
    the ground, and leaves a stance contact (at rest, slower than the pelvis: s ≈ 0) free."""
    frames = body_frames(cm.tree, q)
    v_pelvis = qd[cm.runner.dof("pelvis_tx")]
    out = []
    for _, depth, _, v in contact_kinematics(cm.tree, frames, q, qd, cm.runner.contact_params):
        # ½(1 + tanh((Δv − 2w)/w)): the smooth step of width w/2 centred at Δv = 2w
        on = sigmoid(v[0] - v_pelvis - 2.0 * SWING_SPEED_WIDTH_MPS, 0.5 * SWING_SPEED_WIDTH_MPS)
        out.append(-depth - height_m * on + (1.0 - on) * SWING_ALLOWANCE_M)
    return ca.vertcat(*out)


def _prosthetic_contacts(runner, setting: str) -> np.ndarray:
    """Indices of the prosthetic leg's contact rows of a transfemoral runner; SpecError naming
    ``setting`` for a runner without a prosthetic knee."""
    if runner.kind != "transfemoral":
        raise SpecError(f"the {runner.kind} model has no prosthetic knee", where=setting,
                        hint="a transfemoral runner's setting")
    return np.flatnonzero(runner.contact_params[:, CP_LEG] == 1)


def knee_extension_moment(cm: CollocationModel, q: ca.SX, qd: ca.SX) -> ca.SX:
    """External extension moment [N·m] of the prosthetic contacts' ground forces about the
    prosthetic knee's axis, ``Σ (x_c − x_k)·F_z − (z_c − z_k)·F_x`` over the contacts c (seed
    002's knee-buckling moment, as :func:`bladelab.design.constraints.knee_extension_moment`
    with the centre of pressure): negative flexes the knee; 0 while the prosthesis is off the
    ground."""
    runner = cm.runner
    prosthetic = _prosthetic_contacts(runner, "knee_moment_min_nm")
    body = runner.mj_model.joint("knee_angle_r").bodyid[0]
    joint = next(j for j in cm.tree.joints[body] if j.dof == runner.dof("knee_angle_r"))
    knee = point_position(body_frames(cm.tree, q), body, joint.anchor)
    forces, points, _ = cm.contacts(q, qd)
    moment = 0.0
    for c in prosthetic:
        moment += ((points[c, 0] - knee[0]) * forces[c, 1]
                   - (points[c, 1] - knee[1]) * forces[c, 0])
    return moment


def prosthetic_load_margin(cm: CollocationModel, q: ca.SX, qd: ca.SX, max_bw: float) -> ca.SX:
    """``max_bw − F_z/(m·g)`` [body weights], ``F_z`` the prosthetic (right) leg's vertical
    ground force: ≥ 0 keeps the load the residual limb takes through its socket at or below
    ``max_bw`` body weights. The tolerated load a person's residual limb sets and the body's
    rigid socket does not (docs/runner-model.md, "The transfemoral runner")."""
    runner = cm.runner
    if runner.kind == "able":
        raise SpecError("the able model has no prosthetic leg", where="prosthetic_load_max_bw",
                        hint="an amputee or transfemoral runner's setting")
    prosthetic = np.flatnonzero(runner.contact_params[:, CP_LEG] == 1)
    return float(max_bw) - _vertical_force_bw(cm, q, qd, prosthetic)


def _vertical_force_bw(cm: CollocationModel, q: ca.SX, qd: ca.SX, contacts) -> ca.SX:
    """The vertical ground force of ``contacts`` (contact rows) [body weights]."""
    forces, _, _ = cm.contacts(q, qd)
    f_z = 0.0
    for c in contacts:
        f_z += forces[c, 1]
    return f_z / (cm.runner.total_mass * cm.runner.gravity)


def knee_straight_while_loaded(cm: CollocationModel, q: ca.SX, qd: ca.SX,
                               max_flexion_rad: float) -> ca.SX:
    """``(F_z / (m·g))·(q_knee + max_flexion_rad)`` [rad·body weights]: ≥ 0 keeps the
    prosthetic knee (``knee_angle_r``, negative flexes) within ``max_flexion_rad`` of straight
    whenever its contacts carry a vertical force F_z, and leaves it free in swing (F_z = 0).
    The straight, loaded stance a transfemoral sprinter holds with the hip extensors, and the
    stance in which seed 002's knee-buckling moment can stay extending."""
    runner = cm.runner
    prosthetic = _prosthetic_contacts(runner, "knee_flexion_max_loaded_deg")
    return (_vertical_force_bw(cm, q, qd, prosthetic)
            * (q[runner.dof("knee_angle_r")] + float(max_flexion_rad)))


#: The body's own joints whose limit torques :attr:`StrideWeights.passive` counts.
BODY_JOINTS = ("hip_flexion_l", "hip_flexion_r", "knee_angle_l", "knee_angle_r",
               "ankle_angle_l", "ankle_angle_r", "mtp_angle_l", "mtp_angle_r",
               "lumbar_extension")


def body_joints(runner) -> list[str]:
    """The coordinates of :data:`BODY_JOINTS` that ``runner`` has as its own joints: an
    amputee's prosthetic ankle (its blade) and a transfemoral runner's prosthetic knee are
    devices, not counted."""
    names = [n for n in BODY_JOINTS if n in runner.dof_names]
    if runner.kind == "transfemoral":
        names.remove("knee_angle_r")
    return names


def stride_dynamics(cm: CollocationModel, *, metabolic: MetabolicSmoothing | None = None,
                    swing_clearance_m: float = 0.0,
                    knee_moment_min_nm: float | None = None,
                    knee_flexion_max_loaded_deg: float | None = None,
                    prosthetic_load_max_bw: float | None = None,
                    blade_backward_euler: bool = False) -> StrideDynamics:
    """The :class:`StrideDynamics` of a collocation model (see the module docstring); with
    ``swing_clearance_m`` > 0 [m], the path inequalities also keep every swinging contact that
    high above the ground (:func:`swing_clearance`); with ``knee_moment_min_nm`` [N·m], the
    prosthetic knee's :func:`knee_extension_moment` at or above it (on each mesh interval's
    mean: ``StrideDynamics.interval_mean_inequalities``); with
    ``knee_flexion_max_loaded_deg`` [deg], the prosthetic knee within that flexion while its
    contacts carry load (:func:`knee_straight_while_loaded`); with ``prosthetic_load_max_bw``
    [body weights], the prosthetic leg's vertical ground force at or below it
    (:func:`prosthetic_load_margin`); with ``blade_backward_euler``, a multi-link blade's
    joints are transcribed by backward Euler (``StrideDynamics.backward_euler_dofs``)."""
    runner = cm.runner
    nv, nm = cm.nv, cm.n_muscles
    q, qd, qdd = ca.SX.sym("q", nv), ca.SX.sym("qd", nv), ca.SX.sym("qdd", nv)
    a, ft, dft, u = (ca.SX.sym(n, nm) for n in ("a", "ft", "dft", "u"))
    l_mt, v_mt = cm.mtu(q, qd)
    r_mb = cm.dynamics_residual(q, qd, qdd, ft)
    r_hill = cm.muscle_residual(a, ft, dft, l_mt, v_mt)
    rates = muscle_metabolic_rates(runner, u, a, ft, dft, l_mt, v_mt, cm.smoothing, metabolic)
    met = whole_body_rate(runner, rates)
    l_m, v_m, cos_a = cm.fiber(l_mt, v_mt, ft, dft)
    l_opt = ca.DM(runner.muscle_params[:, MP_LOPT])
    v_norm = v_m / (ca.DM(runner.muscle_params[:, MP_VMAX]) * l_opt)
    along = l_m * cos_a / l_opt  # fibre length along the tendon line [optimal lengths]
    q_b, qd_b = _bounds(runner.dof_names)
    clearance = (swing_clearance(cm, q, qd, float(swing_clearance_m))
                 if swing_clearance_m > 0 else ca.SX.zeros(0, 1))
    interval_mean = ()
    if knee_moment_min_nm is not None:  # ≥ 0 like the clearances, on each interval's mean
        interval_mean = (2 * nm + int(clearance.numel()),)
        clearance = ca.vertcat(clearance, knee_extension_moment(cm, q, qd)
                               - float(knee_moment_min_nm))
    if knee_flexion_max_loaded_deg is not None:
        clearance = ca.vertcat(clearance, knee_straight_while_loaded(
            cm, q, qd, math.radians(knee_flexion_max_loaded_deg)))
    if prosthetic_load_max_bw is not None:
        clearance = ca.vertcat(clearance, prosthetic_load_margin(cm, q, qd,
                                                                 prosthetic_load_max_bw))
    weight = runner.total_mass * runner.gravity
    fz = cm.contacts(q, qd)[0][:, 1]  # vertical force of every contact [N]
    scale = np.array([weight if n.startswith("pelvis_t") and n != "pelvis_tilt" else 100.0
                      for n in runner.dof_names])
    return StrideDynamics(
        dof_names=tuple(runner.dof_names),
        muscle_names=tuple(runner.muscle_names),
        mass=float(runner.total_mass),
        gravity=float(runner.gravity),
        residuals=ca.Function("residuals", [q, qd, qdd, a, ft, dft], [r_mb, r_hill]),
        activation_rate=cm.activation_rate,
        metabolic_rate=ca.Function("metabolic_rate", [q, qd, a, ft, dft, u], [met]),
        muscle_metabolic_rates=ca.Function("muscle_metabolic_rates", [q, qd, a, ft, dft, u],
                                           [rates]),
        passive_joint_torques=ca.Function(
            "passive_joint_torques", [q, qd],
            [passive_torques(q, qd, runner.joint_params, cm.smoothing, limits_only=True)[
                [runner.dof(n) for n in body_joints(runner)]]]),
        q_bounds=q_b,
        qd_bounds=qd_b,
        residual_scale=scale,
        inequalities=ca.Function("path_inequalities", [q, qd, a, ft, dft],
                                 [ca.vertcat(v_norm, along, clearance)]),
        inequality_bounds=np.vstack([np.tile([-1.0, 1.0], (nm, 1)),
                                     np.tile([MIN_FIBER_ALONG, MAX_FIBER_ALONG], (nm, 1)),
                                     np.tile([0.0, np.inf], (int(clearance.numel()), 1))]),
        static_tendon_force=lambda q_nodes, a_nodes: static_tendon_forces(cm, q_nodes, a_nodes),
        active_strength=np.array(runner.muscle_params[:, MP_ACTIVE]),
        vertical_grf=ca.Function("vertical_grf", [q, qd], [ca.sum1(fz)]),
        leg_vertical_grf=ca.Function("leg_vertical_grf", [q, qd],
                                     [_leg_sums(fz, runner.contact_params[:, CP_LEG])]),
        backward_euler_dofs=tuple(n for n in runner.dof_names if n.startswith("blade_joint"))
        if blade_backward_euler else (),
        interval_mean_inequalities=interval_mean,
    )


def _leg_sums(values: ca.SX, legs: np.ndarray) -> ca.SX:
    """(2,) sums of the per-contact ``values`` over the left (intact) leg's contacts, then the
    right (prosthetic) leg's (``legs``: each contact's leg, 0 or 1)."""
    return ca.vertcat(*[ca.sum1(values[np.flatnonzero(legs == leg).tolist()])
                        for leg in (0, 1)])


def static_tendon_forces(cm: CollocationModel, q_nodes: np.ndarray, a_nodes: np.ndarray,
                         *, grid: int = 400) -> np.ndarray:
    """Normalised tendon forces (n_nodes, n_muscles) in static equilibrium (ṽ = 0, the
    fibre–tendon residual's root in F̃ₜ, found on a log grid from 1e-3 to 3) at poses
    ``q_nodes`` and activations ``a_nodes``: a consistent initial guess of the muscle states."""
    nm = cm.n_muscles
    levels = np.logspace(-3, math.log10(3.0), grid)
    out = np.empty((q_nodes.shape[0], nm))
    zeros_v = np.zeros(cm.nv)
    for k, (qk, ak) in enumerate(zip(q_nodes, a_nodes, strict=True)):
        l_mt, _ = cm.mtu(qk, zeros_v)
        l_mt = np.tile(np.asarray(l_mt).ravel()[:, None], (1, grid))
        r = np.asarray(cm.muscle_residual(np.tile(ak[:, None], (1, grid)),
                                          np.tile(levels, (nm, 1)), np.zeros((nm, grid)),
                                          l_mt, np.zeros((nm, grid))))
        for i in range(nm):
            change = np.flatnonzero(np.sign(r[i, :-1]) != np.sign(r[i, 1:]))
            out[k, i] = levels[change[0]] if change.size else levels[np.argmin(np.abs(r[i]))]
    return out
