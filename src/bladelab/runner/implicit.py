"""Linearly implicit steps of the runner's stiff forces (``integrator="implicit"`` and
``"newmark"``, numba).

The explicit scheme (:func:`bladelab.runner.kernel.forces` + MuJoCo's semi-implicit Euler)
evaluates every bladelab force at the start of the step. Under running loads the foot's
Hunt–Crossley contacts are the stiff term: at 2 kN a foot sphere's damping
``∂F/∂δ̇ = 1.5·c·k·δⁿ`` is ~3000 N·s/m on a foot whose heel–toe rotation has an effective mass
of a few hundred grams, so an explicit 0.5 ms step already oscillates (measured: 2 ms
sawtooth in the intact foot's contact forces and ankle velocity, 7 % power-balance residual on
seed 001's amputee reflex gait).

Here the forces of the stiff terms are taken at the *end* of the step, linearised (one
Newton step of backward Euler in the velocities, the position taken as ``q + dt·v_new`` as
MuJoCo's Euler does):

    (M + dt·D + dt²·K)·a = F_mujoco + f − dt·K·v

``f``: bladelab's forces at the step's start (muscles, ligaments, socket, contacts), as
generalized forces [N or N·m]; ``K = −∂f/∂q`` and ``D = −∂f/∂v`` of the contacts (normal
Hunt–Crossley stiffness and damping, the bristle friction's spring and damper, or the
friction cap's dependence on the normal force), of the ligaments and the socket spring, and of
MuJoCo's own joint springs and dampers (``hold_pose``); muscles stay explicit (their fibre is
already implicit, :func:`bladelab.runner.muscle.muscle_step`). ``M`` is MuJoCo's mass matrix
(dense from its CSR ``M``), ``F_mujoco = qfrc_passive − qfrc_bias`` (gravity, Coriolis, joint
springs). The solution ``a`` is handed to MuJoCo's Euler through ``qfrc_applied``
(``(M + dt·D_mj)·a − F_mujoco``, everything in generalized coordinates: ``xfrc_applied`` stays
zero), so MuJoCo's ``mj_step2`` produces exactly ``a``. The recorded contact forces and ligament
torques are the end-of-step (effective) ones, so the power balance checks the forces that
acted.

``"newmark"`` is the second-order version: Newmark's average-acceleration rule
(β = 1/4, γ = 1/2, the trapezoidal rule), linearised the same way. The forces are evaluated
once per step, at the predicted state ``q* = q + dt·v + dt²/4·a``, ``v* = v + dt/2·a``
(:func:`implicit_advance`); then

    (M + dt/2·D + dt²/4·K)·a' = F_mujoco + f        at (q*, v*)

and the corrector ``v' = v* + dt/2·a'``, ``q' = q* + dt²/4·a'`` (:func:`newmark_correct`).
Position and velocity are at the same instant (in the Euler schemes the recorded velocity is
the one that led to the position, half a step behind it), the first step takes the initial
state's own acceleration, and the muscle fibres take BDF2 steps against the MTU length at the
step's end (:func:`bladelab.runner.muscle.muscle_step`). Measured on the shipped amputee
solution's first 0.8 s (2026-11-27): power-balance residual 0.22 % at 1 ms, 0.11 % at 0.5 ms
(explicit 0.25 ms: 0.39 %; ``"implicit"`` 1 ms: 1.32 %); largest joint-angle error in the
first 0.5 s of the sinking test against a 0.025 ms reference 0.31° (explicit 0.25 ms: 1.67°).
It has no numerical damping: the stiff contact modes keep their physical damping only.

All Jacobians come from MuJoCo's ``cdof`` (motion axes of the dofs about the root subtree's
centre of mass, the origin of ``cvel``) and a (body × dof) mask of which dofs move which body.
"""

from __future__ import annotations

import math

from numba import njit

from bladelab.contact import hunt_crossley_force, smooth_spring_damper_force
from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.contact_point import lowest_point
from bladelab.runner.layout import (
    CP_BODY,
    CP_C,
    CP_DAMP,
    CP_EXP,
    CP_K,
    CP_LAW,
    CP_MU,
    CP_WIDTH,
    JP_D,
    JP_EA,
    JP_EB,
    JP_HI,
    JP_K,
    JP_LO,
    JP_SD,
    JP_SDX,
    JP_SK,
    JP_SK2,
)
from bladelab.runner.mjcall import (
    call_mujoco,
    call_mujoco_rne,
)
from bladelab.runner.model import FRICTION_DAMPING, FRICTION_STIFFNESS
from bladelab.runner.muscle import muscle_step

EXPLICIT, IMPLICIT, NEWMARK = 0, 1, 2
# The muscles' Newton tolerance on the normalised fibre velocity in this scheme (the explicit
# scheme's: 1e-8; a step below 1e-6·v_max leaves an error of order 1e-12·v_max).
NEWTON_TOL = 1e-6
INTEGRATORS = {"explicit": EXPLICIT, "implicit": IMPLICIT, "newmark": NEWMARK}
# ``_nrt=False``: no reference counting in the per-step kernels (bladelab.runner.kernel).


@njit(cache=True, error_model="numpy", _nrt=False)
def point_jacobian(cdof, mask, body, px, py, pz, root_com, jac):
    """``jac`` (3, nv) = ∂v/∂q̇ of the point (px, py, pz) [m] fixed to ``body``."""
    rx, ry, rz = px - root_com[0], py - root_com[1], pz - root_com[2]
    for j in range(cdof.shape[0]):
        if mask[body, j]:
            jac[0, j] = cdof[j, 3] + cdof[j, 1] * rz - cdof[j, 2] * ry
            jac[1, j] = cdof[j, 4] + cdof[j, 2] * rx - cdof[j, 0] * rz
            jac[2, j] = cdof[j, 5] + cdof[j, 0] * ry - cdof[j, 1] * rx
        else:
            jac[0, j] = 0.0
            jac[1, j] = 0.0
            jac[2, j] = 0.0


@njit(cache=True, error_model="numpy", _nrt=False)
def path_jacobian(site_xpos, cdof, root_com, path, pstart, seg_start, seg_dof, mstart, mdof, qvel,
                  mtu, moment):
    """MTU lengths [m] and lengthening velocities [m/s] into ``mtu`` (n, 2) and the path
    Jacobians ``moment`` (n, nv) = ∂l/∂q [m or m/rad] (minus the moment arms): straight
    segments between via points, as :func:`bladelab.runner.kernel.path_kinematics`.

    The segment from path point k to k + 1 changes length only with the dofs between its two
    bodies (a dof that moves both ends moves them rigidly): ``seg_dof[seg_start[k]:seg_start[k
    + 1]]`` lists them, +(j + 1) where dof j moves the end k + 1, −(j + 1) where it moves the
    end k (:func:`bladelab.runner.implicit_setup.path_dofs`). ``mdof[mstart[i]:mstart[i +
    1]]``: the dofs muscle i spans (the other entries of its row stay 0)."""
    for i in range(pstart.shape[0] - 1):
        length = 0.0
        for e in range(mstart[i], mstart[i + 1]):
            moment[i, mdof[e]] = 0.0
        for k in range(pstart[i], pstart[i + 1] - 1):
            a = path[k, 0]
            b = path[k + 1, 0]
            dx = site_xpos[b, 0] - site_xpos[a, 0]
            dy = site_xpos[b, 1] - site_xpos[a, 1]
            dz = site_xpos[b, 2] - site_xpos[a, 2]
            seg = math.sqrt(dx * dx + dy * dy + dz * dz)
            length += seg
            ux, uy, uz = dx / seg, dy / seg, dz / seg
            for e in range(seg_start[k], seg_start[k + 1]):
                code = seg_dof[e]
                if code > 0:
                    j = code - 1
                    sign = 1.0
                    p = b
                else:
                    j = -code - 1
                    sign = -1.0
                    p = a
                rx = site_xpos[p, 0] - root_com[0]
                ry = site_xpos[p, 1] - root_com[1]
                rz = site_xpos[p, 2] - root_com[2]
                jx = cdof[j, 3] + cdof[j, 1] * rz - cdof[j, 2] * ry
                jy = cdof[j, 4] + cdof[j, 2] * rx - cdof[j, 0] * rz
                jz = cdof[j, 5] + cdof[j, 0] * ry - cdof[j, 1] * rx
                moment[i, j] += sign * (ux * jx + uy * jy + uz * jz)
        vel = 0.0
        for e in range(mstart[i], mstart[i + 1]):
            vel += moment[i, mdof[e]] * qvel[mdof[e]]
        mtu[i, 0] = length
        mtu[i, 1] = vel


@njit(cache=True, error_model="numpy", _nrt=False)
def dense_mass(m_csr, rowadr, rownnz, colind, out):
    """MuJoCo's mass matrix (lower-triangular CSR ``M``) into the dense symmetric ``out``."""
    for i in range(rowadr.shape[0]):
        for k in range(rowadr[i], rowadr[i] + rownnz[i]):
            c = colind[k]
            out[i, c] = m_csr[k]
            out[c, i] = m_csr[k]


@njit(cache=True, error_model="numpy", _nrt=False)
def solve_tree(a, b, parent):
    """Solve ``a·x = b`` for a matrix with the sparsity of a kinematic tree's mass matrix
    (``a[i, j]`` ≠ 0 only if dof i is dof j, its ancestor or its descendant; ``parent[j]`` <
    j, −1 at a root); ``x`` into ``b``, ``a`` overwritten. Elimination from the leaves without
    pivoting, as MuJoCo factorises M (no fill-in); ``a`` need not be symmetric but must not
    need pivoting (M plus positive stiffness and damping terms)."""
    n = b.shape[0]
    for k in range(n - 1, -1, -1):
        inv = 1.0 / a[k, k]
        i = parent[k]
        while i >= 0:
            fac = a[i, k] * inv
            if fac != 0.0:
                j = parent[k]
                while j >= 0:
                    a[i, j] -= fac * a[k, j]
                    j = parent[j]
                b[i] -= fac * b[k]
            i = parent[i]
    for k in range(n):
        s = b[k]
        j = parent[k]
        while j >= 0:
            s -= a[k, j] * b[j]
            j = parent[j]
        b[k] = s / a[k, k]


@njit(cache=True, error_model="numpy", _nrt=False)
def _normal_force(cp, c, depth, rate):
    """Normal force [N] and its derivatives by depth [N/m] and depth rate [N·s/m]."""
    if cp[c, CP_LAW] == 0.0:
        k, n, diss = cp[c, CP_K], cp[c, CP_EXP], cp[c, CP_C]
        fn = hunt_crossley_force(depth, rate, k, n, diss)
        if fn <= 0.0:
            return 0.0, 0.0, 0.0
        dn = depth ** (n - 1.0)
        return fn, n * k * dn * (1.0 + 1.5 * diss * rate), 1.5 * diss * k * dn * depth
    k, d, w = cp[c, CP_K], cp[c, CP_DAMP], cp[c, CP_WIDTH]
    fn = smooth_spring_damper_force(depth, rate, k, d, w)
    if fn <= 0.0:
        return 0.0, 0.0, 0.0
    h = 1e-7 * max(depth, 1e-4)
    kn = (smooth_spring_damper_force(depth + h, rate, k, d, w)
          - smooth_spring_damper_force(depth - h, rate, k, d, w)) / (2.0 * h)
    hv = 1e-6
    dv = (smooth_spring_damper_force(depth, rate + hv, k, d, w)
          - smooth_spring_damper_force(depth, rate - hv, k, d, w)) / (2.0 * hv)
    return fn, kn, dv


@njit(cache=True, error_model="numpy", _nrt=False)
def _add_outer(a, rhs, jx, jz, kxx, kxz, kzx, kzz, dxx, dxz, dzx, dzz, qvel, c_d, c_k, c_v):
    """``a += Jᵀ·(c_d·D + c_k·K)·J`` and ``rhs −= c_v·Jᵀ·K·J·v`` for the (x, z) rows ``jx``,
    ``jz`` of a point's Jacobian and its 2×2 stiffness ``K`` and damping ``D`` (the scheme's
    coefficients, :func:`scheme_coefficients`)."""
    nv = qvel.shape[0]
    vx = 0.0
    vz = 0.0
    for j in range(nv):
        vx += jx[j] * qvel[j]
        vz += jz[j] * qvel[j]
    hxx = c_d * dxx + c_k * kxx
    hxz = c_d * dxz + c_k * kxz
    hzx = c_d * dzx + c_k * kzx
    hzz = c_d * dzz + c_k * kzz
    gx = c_v * (kxx * vx + kxz * vz)
    gz = c_v * (kzx * vx + kzz * vz)
    for r in range(nv):
        if jx[r] == 0.0 and jz[r] == 0.0:
            continue
        rhs[r] -= jx[r] * gx + jz[r] * gz
        ax = jx[r] * hxx + jz[r] * hzx
        az = jx[r] * hxz + jz[r] * hzz
        for c in range(nv):
            a[r, c] += ax * jx[c] + az * jz[c]


@njit(cache=True, error_model="numpy", _nrt=False)
def scheme_coefficients(mode, dt):
    """``(c_d, c_k, c_v)``: the state change over which the stiff forces are linearised,
    ``Δv = c_d·a`` and ``Δq = c_v·v + c_k·a`` [s, s², s] (module docstring). Semi-implicit
    Euler: (dt, dt², dt). Newmark: (dt/2, dt²/4, 0) about the predicted state, and (0, 0, 0)
    on its first step (the exact acceleration of the initial state: ``mode[1]`` is 1)."""
    if mode[0] == NEWMARK:
        if mode[1] != 0:
            return 0.0, 0.0, 0.0
        return 0.5 * dt, 0.25 * dt * dt, 0.0
    return dt, dt * dt, dt


@njit(cache=True, error_model="numpy", _nrt=False)
def implicit_forces(mj, arrays, imp, root_com, dt):
    """Forces of one step with the stiff terms linearly implicit (module docstring): writes
    ``qfrc_applied`` (and zeroes ``xfrc_applied``), the muscle states, ``mtu``, and the
    effective contact forces and ligament torques into ``crec`` and ``lig``.

    ``mj``, ``arrays`` as :func:`bladelab.runner.kernel.forces`; ``imp`` from
    :func:`bladelab.runner.implicit_setup.implicit_arrays`.
    """
    qpos, qvel, site_xpos, site_xmat, _, _, _, xfrc, qfrc = mj
    mp, ms, mtu, _, u, path, pstart, cp, cstate, jp, crec, lig = arrays
    (_, mask, rowadr, rownnz, colind, mj_damp, mj_stiff, cdof, m_csr, passive, bias,
     a, rhs, moment, jac, cjac, ckd, lkd, _, _, seg_start, seg_dof, parent) = imp[:23]
    nv = qvel.shape[0]
    c_d, c_k, c_v = scheme_coefficients(imp[0], dt)
    newmark = imp[0][0] == NEWMARK
    # the friction bristle's anchor integrates the contact point's velocity over the step:
    # backward Euler (dt·v'), or the trapezoidal rule with Newmark (dt/2·(v + v'))
    h_b = 0.5 * dt if newmark else dt
    xfrc[:, :] = 0.0
    mstart, mdof = imp[32], imp[33]
    path_jacobian(site_xpos, cdof, root_com, path, pstart, seg_start, seg_dof, mstart, mdof, qvel,
                  mtu, moment)
    if newmark:
        muscle_step(mp, ms, mtu[:, 0], u, dt, NEWTON_TOL, imp[34], imp[35], mtu[:, 1])
    else:
        muscle_step(mp, ms, mtu[:, 0], u, dt, NEWTON_TOL, imp[34])
    a[:, :] = 0.0
    dense_mass(m_csr, rowadr, rownnz, colind, a)
    for j in range(nv):
        rhs[j] = passive[j] - bias[j]
        a[j, j] += c_d * mj_damp[j] + c_k * mj_stiff[j]
        rhs[j] -= c_v * mj_stiff[j] * qvel[j]
    for i in range(pstart.shape[0] - 1):
        f = ms[i, 3]
        if f != 0.0:
            for e in range(mstart[i], mstart[i + 1]):
                rhs[mdof[e]] -= f * moment[i, mdof[e]]
    # ligaments and socket: diagonal stiffness and damping
    for j in range(jp.shape[0]):
        q = qpos[j]
        qd = qvel[j]
        tau = 0.0
        kj = 0.0
        dj = 0.0
        if q > jp[j, JP_HI]:
            tau = -jp[j, JP_K] * (q - jp[j, JP_HI]) - jp[j, JP_D] * qd
            if tau < 0.0:
                kj, dj = jp[j, JP_K], jp[j, JP_D]
            else:
                tau = 0.0
        elif q < jp[j, JP_LO]:
            tau = -jp[j, JP_K] * (q - jp[j, JP_LO]) - jp[j, JP_D] * qd
            if tau > 0.0:
                kj, dj = jp[j, JP_K], jp[j, JP_D]
            else:
                tau = 0.0
        if jp[j, JP_SK] != 0.0 or jp[j, JP_SD] != 0.0 or jp[j, JP_SDX] != 0.0:
            damping = jp[j, JP_SD] if qd < 0.0 else jp[j, JP_SDX]
            tau -= jp[j, JP_SK] * q + jp[j, JP_SK2] * q * abs(q) + damping * qd
            kj += jp[j, JP_SK] + 2.0 * jp[j, JP_SK2] * abs(q)
            dj += damping
        if jp[j, JP_EA] != 0.0:  # the capsule's passive moment within the range
            capsule = jp[j, JP_EA] * math.exp(jp[j, JP_EB] * q)
            tau += capsule
            kj -= jp[j, JP_EB] * capsule
        lig[j] = tau
        lkd[j, 0] = kj
        lkd[j, 1] = dj
        rhs[j] += tau - c_v * kj * qd
        a[j, j] += c_d * dj + c_k * kj
    # contacts: (x, z) Jacobian rows at the contact point, 2x2 stiffness and damping
    for c in range(cp.shape[0]):
        body = int(cp[c, CP_BODY])
        px, py, pz, depth = lowest_point(cp, c, site_xpos, site_xmat)
        point_jacobian(cdof, mask, body, px, py, pz, root_com, jac)
        vx = 0.0
        vz = 0.0
        for j in range(nv):
            cjac[c, 0, j] = jac[0, j]
            cjac[c, 1, j] = jac[2, j]
            vx += jac[0, j] * qvel[j]
            vz += jac[2, j] * qvel[j]
        fn = 0.0
        ft = 0.0
        kn = 0.0
        dn = 0.0
        dxx = 0.0
        kxz = 0.0
        dxz = 0.0
        if depth > 0.0:
            fn, kn, dn = _normal_force(cp, c, depth, -vz)
            if newmark:
                s = cstate[c, 0] + h_b * (crec[c, 4] + vx)  # crec: the last step's end
            else:
                s = cstate[c, 0] + vx * dt
            ft = -FRICTION_STIFFNESS * s - FRICTION_DAMPING * vx
            lim = cp[c, CP_MU] * fn
            if ft > lim:
                ft = lim
                s = -lim / FRICTION_STIFFNESS
                kxz, dxz = cp[c, CP_MU] * kn, cp[c, CP_MU] * dn
            elif ft < -lim:
                ft = -lim
                s = lim / FRICTION_STIFFNESS
                kxz, dxz = -cp[c, CP_MU] * kn, -cp[c, CP_MU] * dn
            else:
                # the anchor already moves with dt·v: the spring acts as a damper dt·k_f
                dxx = FRICTION_STIFFNESS * h_b + FRICTION_DAMPING
            cstate[c, 0] = s
        else:
            cstate[c, 0] = 0.0
        # restoring 2x2 matrices in (x, z): Fx depends on z through the cap (kxz, dxz)
        ckd[c, 0] = dxx
        ckd[c, 1] = kxz
        ckd[c, 2] = dxz
        ckd[c, 3] = kn
        ckd[c, 4] = dn
        for j in range(nv):
            rhs[j] += jac[0, j] * ft + jac[2, j] * fn
        if fn > 0.0:
            _add_outer(a, rhs, cjac[c, 0], cjac[c, 1], 0.0, kxz, 0.0, kn, dxx, dxz, 0.0, dn,
                       qvel, c_d, c_k, c_v)
        crec[c, 0] = ft
        crec[c, 1] = fn
        crec[c, 2] = px
        crec[c, 3] = pz
        crec[c, 4] = vx
        crec[c, 5] = vz
        crec[c, 6] = depth if depth > 0.0 else 0.0
    solve_tree(a, rhs, parent)  # rhs := the acceleration a
    # qfrc_applied so that MuJoCo's Euler, (M + dt·D_mj)·a = F_mj + qfrc_applied, gives a
    for r in range(nv):
        qfrc[r] = dt * mj_damp[r] * rhs[r] - passive[r] + bias[r]
    for r in range(nv):  # + M·a from the lower-triangular CSR
        for k in range(rowadr[r], rowadr[r] + rownnz[r]):
            c = colind[k]
            qfrc[r] += m_csr[k] * rhs[c]
            if c != r:
                qfrc[c] += m_csr[k] * rhs[r]
    # the effective (end-of-step) ligament torques and contact forces, for the record
    for j in range(nv):
        lig[j] -= lkd[j, 0] * (c_v * qvel[j] + c_k * rhs[j]) + lkd[j, 1] * c_d * rhs[j]
    for c in range(cp.shape[0]):
        if crec[c, 1] <= 0.0 and not newmark:
            continue
        vx0 = crec[c, 4]
        vz0 = crec[c, 5]
        dax = 0.0
        daz = 0.0
        for j in range(nv):
            dax += cjac[c, 0, j] * rhs[j]
            daz += cjac[c, 1, j] * rhs[j]
        vx1 = vx0 + c_d * dax
        vz1 = vz0 + c_d * daz
        dz = c_v * vz0 + c_k * daz  # the contact point's vertical displacement [m]
        if crec[c, 1] > 0.0:
            dxx, kxz, dxz, kn, dn = ckd[c, 0], ckd[c, 1], ckd[c, 2], ckd[c, 3], ckd[c, 4]
            crec[c, 0] -= kxz * dz + dxx * (vx1 - vx0) + dxz * (vz1 - vz0)
            crec[c, 1] -= kn * dz + dn * (vz1 - vz0)
            if dxx != 0.0:
                cstate[c, 0] += h_b * (vx1 - vx0)  # the anchor follows the end-of-step velocity
        if newmark:  # the record's contact point at the corrected state
            crec[c, 2] += c_k * dax
            crec[c, 3] += dz
            crec[c, 4] = vx1
            crec[c, 5] = vz1
            if crec[c, 6] > 0.0:
                crec[c, 6] = max(crec[c, 6] - dz, 0.0)
    if newmark:
        newmark_correct(qpos, qvel, mtu, moment, mstart, mdof, imp[19], rhs, c_d, c_k)


@njit(cache=True, error_model="numpy", _nrt=False)
def newmark_correct(qpos, qvel, mtu, moment, mstart, mdof, qadr, acc, c_d, c_k):
    """Newmark's corrector: the state of the step's end from the predicted one, ``v += c_d·a``,
    ``q += c_k·a``, and the MTU lengths [m] and velocities [m/s] with it (to first order in
    the correction, through the path Jacobians ``moment``)."""
    for i in range(mstart.shape[0] - 1):
        for e in range(mstart[i], mstart[i + 1]):
            j = mdof[e]
            mtu[i, 0] += moment[i, j] * c_k * acc[j]
            mtu[i, 1] += moment[i, j] * c_d * acc[j]
    for j in range(qvel.shape[0]):
        qvel[j] += c_d * acc[j]
        qpos[qadr[j]] += c_k * acc[j]


@njit(cache=True, error_model="numpy", _nrt=False)
def site_kinematics(xpos, xmat, site_body, site_pos, site_mat, oriented, site_xpos, site_xmat):
    """Site positions [m] ``xpos[b] + xmat[b]·pos`` into ``site_xpos``, and the frames
    ``xmat[b]·mat`` of the ``oriented`` sites into ``site_xmat`` (row-major 3×3, as MuJoCo)."""
    for s in range(site_body.shape[0]):
        b = site_body[s]
        for r in range(3):
            site_xpos[s, r] = (xpos[b, r] + xmat[b, 3 * r] * site_pos[s, 0]
                               + xmat[b, 3 * r + 1] * site_pos[s, 1]
                               + xmat[b, 3 * r + 2] * site_pos[s, 2])
    for k in range(oriented.shape[0]):
        s = oriented[k]
        b = site_body[s]
        for r in range(3):
            for c in range(3):
                site_xmat[s, 3 * r + c] = (xmat[b, 3 * r] * site_mat[s, c]
                                           + xmat[b, 3 * r + 1] * site_mat[s, 3 + c]
                                           + xmat[b, 3 * r + 2] * site_mat[s, 6 + c])


@njit(cache=True, error_model="numpy", _nrt=False)
def implicit_begin(mptr, dptr, imp):
    """The MuJoCo stages the implicit step needs, instead of ``mj_step1``: kinematics (site
    positions and frames), centre-of-mass frames and ``cdof``, the mass matrix, ``cvel``, the
    bias forces (``mj_rne``) and, where the model has joint springs or dampers, the passive
    forces. (``mj_step1`` also checks the state, computes tendons, actuators, collisions and
    factorises M, none of which this scheme uses.) With a site-free model
    (``RunnerModel.mj_dynamics_model``) the sites are placed by :func:`site_kinematics`."""
    stage = imp[18]
    call_mujoco(stage[0], mptr, dptr)
    call_mujoco(stage[1], mptr, dptr)
    call_mujoco(stage[2], mptr, dptr)
    call_mujoco(stage[3], mptr, dptr)
    call_mujoco_rne(stage[4], mptr, dptr, stage[6])
    if stage[7] != 0:
        call_mujoco(stage[5], mptr, dptr)
    if imp[23][0] != 0:
        site_kinematics(imp[24], imp[25], imp[26], imp[27], imp[28], imp[29], imp[30], imp[31])


@njit(cache=True, error_model="numpy", _nrt=False)
def implicit_advance(mj, imp, dt):
    """Advance the state by the step with the acceleration :func:`implicit_forces` solved
    (``imp[12]``; hinge and slide joints: ``imp[19]`` maps dofs to ``qpos``). Semi-implicit
    Euler, as MuJoCo's ``mj_step2`` would do it with that ``qfrc_applied``: ``v += dt·a``, then
    ``q += dt·v``. Newmark (β = 1/4, γ = 1/2): the predicted state of the next step,
    ``q += dt·v + dt²/4·a``, ``v += dt/2·a`` (its corrector runs in :func:`implicit_forces`).
    MuJoCo's ``time`` is not advanced (the loops keep the time)."""
    qpos, qvel = mj[0], mj[1]
    acc = imp[12]
    qadr = imp[19]
    mode = imp[0]
    if mode[0] == NEWMARK:
        mode[1] = 0
        for j in range(qvel.shape[0]):
            qpos[qadr[j]] += dt * qvel[j] + 0.25 * dt * dt * acc[j]
            qvel[j] += 0.5 * dt * acc[j]
        return
    for j in range(qvel.shape[0]):
        qvel[j] += dt * acc[j]
        qpos[qadr[j]] += dt * qvel[j]


refresh_stale_caches(globals())
