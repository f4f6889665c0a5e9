"""The set-up of the implicit schemes (:mod:`bladelab.runner.implicit`): the per-model
structure (kinematic tree, path and site data), the ``imp`` tuple of a simulation, and the
MuJoCo model it steps. Python, run once per model or simulation; the per-step kernels live in
:mod:`bladelab.runner.implicit`."""

from __future__ import annotations

import functools

import mujoco
import numpy as np

from bladelab.errors import SimulationError
from bladelab.runner.implicit import INTEGRATORS, site_kinematics
from bladelab.runner.kernel import mujoco_views
from bladelab.runner.layout import CP_SITE, JP_SD, JP_SDX
from bladelab.runner.mjcall import mujoco_stage_addresses
from bladelab.runner.muscle import fibre_heights


def path_dofs(mask: np.ndarray, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(seg_start, seg_dof) of :func:`bladelab.runner.implicit.path_jacobian` from the (body × dof) ``mask`` and the
    path points (site id, body id) rows."""
    start = [0]
    codes: list[int] = []
    for k in range(path.shape[0]):
        if k + 1 < path.shape[0]:
            ba, bb = int(path[k, 1]), int(path[k + 1, 1])
            for j in range(mask.shape[1]):
                if mask[ba, j] != mask[bb, j]:
                    codes.append(j + 1 if mask[bb, j] else -(j + 1))
        start.append(len(codes))
    return np.array(start, dtype=np.int64), np.array(codes, dtype=np.int64)


def muscle_dofs(seg_start: np.ndarray, seg_dof: np.ndarray, pstart: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """(mstart, mdof) of :func:`bladelab.runner.implicit.path_jacobian`: per muscle, the dofs its segments span."""
    start = [0]
    dofs: list[int] = []
    for i in range(len(pstart) - 1):
        spanned = sorted({abs(int(c)) - 1 for k in range(pstart[i], pstart[i + 1] - 1)
                          for c in seg_dof[seg_start[k]:seg_start[k + 1]]})
        dofs += spanned
        start.append(len(dofs))
    return np.array(start, dtype=np.int64), np.array(dofs, dtype=np.int64)


def body_dof_mask(m: mujoco.MjModel) -> np.ndarray:
    """(nbody, nv) uint8: 1 where dof j moves body b (its joint's body is b or an ancestor)."""
    mask = np.zeros((m.nbody, m.nv), dtype=np.uint8)
    for b in range(m.nbody):
        chain = set()
        k = b
        while k > 0:
            chain.add(k)
            k = int(m.body_parentid[k])
        for j in range(m.nv):
            if int(m.dof_bodyid[j]) in chain:
                mask[b, j] = 1
    return mask


@functools.lru_cache(maxsize=16)
def _structure(model) -> tuple:
    """The per-model constant arrays of ``imp`` (kinematic tree, path and site data), built
    once per :class:`RunnerModel` (hashed by identity): rebuilding them cost ~2 ms of Python
    per simulation. The site-free dynamics model has the same tree as ``mj_model``."""
    m = model.mj_model
    hinge_slide = all(
        int(t) in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE) for t in m.jnt_type
    )
    mask = body_dof_mask(m)
    seg_start, seg_dof = path_dofs(mask, model.path_points)
    mstart, mdof = muscle_dofs(seg_start, seg_dof, model.path_start)
    site_mat = np.zeros((m.nsite, 9))
    for k in range(m.nsite):
        mujoco.mju_quat2Mat(site_mat[k], m.site_quat[k])
    return (
        hinge_slide,
        mujoco_stage_addresses(),
        mask,
        m.M_rowadr.astype(np.int64),
        m.M_rownnz.astype(np.int64),
        m.M_colind.astype(np.int64),
        np.array(m.jnt_qposadr[m.dof_jntid], dtype=np.int64),
        seg_start,
        seg_dof,
        np.array(m.dof_parentid, dtype=np.int64),
        np.array(m.site_bodyid, dtype=np.int64),
        np.array(m.site_pos, dtype=float),
        site_mat,
        np.unique(model.contact_params[:, CP_SITE].astype(np.int64)),
        mstart,
        mdof,
    )


def simulation_model(model, integrator: str, *, compiled_loop: bool = True
                     ) -> tuple[mujoco.MjModel, bool]:
    """``(MuJoCo model to step, own_sites)`` for simulating the :class:`RunnerModel` ``model``:
    the implicit scheme in a compiled loop places the sites itself on the site-free
    ``model.mj_dynamics_model`` (``own_sites`` True, for :func:`implicit_arrays`); otherwise
    ``model.mj_model``."""
    own_sites = (integrator == "implicit" and compiled_loop
                 and model.mj_dynamics_model is not None)
    return (model.mj_dynamics_model if own_sites else model.mj_model), own_sites


def _damper_step_ratios(model, m: mujoco.MjModel, d: mujoco.MjData
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(D·(M⁻¹)ⱼⱼ [1/s], D [N·m·s/rad], (M⁻¹)ⱼⱼ)`` per joint at ``d``'s pose: an explicit
    step ``dt`` integrates joint j's damper while ``dt·D·(M⁻¹)ⱼⱼ ≤ 1``."""
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    inverse_inertia = np.diag(np.linalg.inv(full))
    damping = np.maximum(model.joint_params[:, JP_SD], model.joint_params[:, JP_SDX])
    return damping * inverse_inertia, damping, inverse_inertia


def explicit_step_limit(model) -> float:
    """The longest step [s] at which the explicit scheme integrates every joint
    spring-damper of the :class:`RunnerModel` ``model`` (at its reference pose; ``inf`` without
    dampers). See :func:`_check_explicit_dampers`."""
    m = model.mj_model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    rate = _damper_step_ratios(model, m, d)[0].max(initial=0.0)
    return float(np.inf) if rate <= 0.0 else float(1.0 / rate)


def _check_explicit_dampers(model, m: mujoco.MjModel, d: mujoco.MjData,
                            dt: float) -> None:
    """Refuse an explicit run whose joint spring-dampers it cannot integrate.

    The explicit scheme takes a damper's torque ``−D·q̇`` at the step's start; on a light
    segment it then reverses the joint's velocity within one step (and blows up at twice that)
    once ``dt·D/I`` exceeds 1, with ``I = 1/(M⁻¹)ⱼⱼ`` the joint's effective inertia [kg·m²]
    (e.g. the human body's toes: 2 N·m·s/rad on about 1.5·10⁻⁴ kg·m²)."""
    rates, damping, inverse_inertia = _damper_step_ratios(model, m, d)
    ratio = dt * rates
    j = int(np.argmax(ratio))
    if ratio[j] > 1.0:
        raise SimulationError(
            f"the explicit scheme cannot integrate the damper of {model.dof_names[j]} "
            f"({damping[j]:g} N·m·s/rad on an effective inertia of "
            f"{1.0 / inverse_inertia[j]:.3g} kg·m²) at a {dt:g} s step",
            where="integrator",
            hint=f'use integrator="newmark" or "implicit" (CLI: --integrator newmark), or a '
                 f"step of at most {dt / ratio[j]:.2g} s")


def implicit_arrays(model, m: mujoco.MjModel, d: mujoco.MjData, integrator: str = "explicit",
                    own_sites: bool = False) -> tuple:
    """The ``imp`` tuple of :func:`bladelab.runner.implicit.implicit_forces` for the :class:`RunnerModel` ``model``
    simulated as ``m``/``d`` (model data, live MuJoCo views, work arrays); its first entry,
    ``mode`` (2-array: the scheme, ``EXPLICIT``, ``IMPLICIT`` or ``NEWMARK``, which the
    compiled loops select by, and 1 until the first step is taken). ``own_sites``: ``m`` is ``model.mj_dynamics_model`` (no sites) and the
    scheme places ``model.mj_model``'s sites itself (entries 23–31; :func:`site_views`). The
    entry 34 holds the fibre heights of ``model.muscle_params`` (the muscle parameters the
    force arrays must carry, as they carry its paths), computed per simulation; entry 35 the
    Newmark scheme's fibre lengths of the previous step."""
    (hinge_slide, stages, mask, rowadr, rownnz, colind, qadr, seg_start, seg_dof, parent,
     site_body, site_pos, site_mat, oriented, mstart, mdof) = _structure(model)
    n_muscles = len(model.muscle_names)
    n_contacts = model.contact_params.shape[0]
    nsite = site_body.shape[0]
    nv = m.nv
    if integrator == "explicit":
        _check_explicit_dampers(model, m, d, m.opt.timestep)
    if integrator != "explicit" and not hinge_slide:
        raise SimulationError("the implicit scheme needs a model of hinge and slide joints only",
                              where="integrator", hint='use integrator="explicit"')
    stage = np.zeros(8, dtype=np.int64)
    stage[:6] = stages
    stage[6] = d.qfrc_bias.ctypes.data
    stage[7] = int(bool(np.any(m.dof_damping != 0) or np.any(m.jnt_stiffness != 0)))
    sites = (
        np.array([int(own_sites)], dtype=np.int64),
        d.xpos,
        d.xmat,
        site_body,
        site_pos,
        site_mat,
        oriented,
        np.zeros((nsite, 3)),
        np.zeros((nsite, 9)),
    )
    if own_sites:  # place the sites of the initial state
        site_kinematics(*sites[1:])
    return (
        np.array([INTEGRATORS[integrator], 1], dtype=np.int64),
        mask,
        rowadr,
        rownnz,
        colind,
        np.array(m.dof_damping, dtype=float),
        np.array(m.jnt_stiffness[m.dof_jntid], dtype=float),
        d.cdof,
        d.M,
        d.qfrc_passive,
        d.qfrc_bias,
        np.zeros((nv, nv)),
        np.zeros(nv),
        np.zeros((n_muscles, nv)),
        np.zeros((3, nv)),
        np.zeros((n_contacts, 2, nv)),
        np.zeros((n_contacts, 5)),
        np.zeros((nv, 2)),
        stage,
        qadr,
        seg_start,
        seg_dof,
        parent,
        *sites,
        mstart,
        mdof,
        fibre_heights(model.muscle_params),
        np.zeros(n_muscles),  # the Newmark scheme's fibre lengths of the previous step [m]
    )


def site_views(d: mujoco.MjData, imp: tuple, *, oriented: bool = True) -> tuple:
    """The ``mj`` tuple of the force kernels (:func:`bladelab.runner.kernel.mujoco_views`) with
    the sites ``imp`` places when it was built with ``own_sites``."""
    if imp[23][0] == 0:
        return mujoco_views(d, oriented=oriented)
    xmat = imp[31] if oriented else np.zeros((0, 9))
    return (d.qpos, d.qvel, imp[30], xmat, d.cvel, d.subtree_com, d.xipos, d.xfrc_applied,
            d.qfrc_applied)
