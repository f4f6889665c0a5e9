"""Numba kernels of the runner: muscle path kinematics, muscle/ligament/contact forces, and the
whole time loop calling MuJoCo's C ``mj_step1``/``mj_step2`` directly.

Muscle paths are straight lines between via points (H0918 has no wrapping surfaces); length and
lengthening velocity are summed over the segments, and the tendon force is applied as a pair of
point forces along every segment (so the generalized force is exactly ``−F·∂l/∂q``, the same as
a MuJoCo spatial tendon; ``tests/test_runner_simulate.py`` checks both against MuJoCo's tendon).
Contacts: Hunt–Crossley normal force (:func:`bladelab.contact.hunt_crossley_force`) and an
elastic–plastic (bristle) friction force capped at ``μ·Fn``, applied at the lowest point of the
sphere. Ligaments: joint-limit springs–dampers; the socket: ``−(K·q + K2·q·|q|) − D·q̇``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numba import njit

from bladelab.contact import hunt_crossley_force, smooth_spring_damper_force
from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.contact_point import lowest_point
from bladelab.runner.implicit import EXPLICIT, implicit_advance, implicit_begin, implicit_forces
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
from bladelab.runner.mjcall import call_mujoco, mujoco_step_addresses  # noqa: F401 (re-exported)
from bladelab.runner.model import FRICTION_DAMPING, FRICTION_STIFFNESS
from bladelab.runner.muscle import muscle_step
from bladelab.sim.mujoco_engine import add_point_force

# numba's cache is keyed on the file that defines a function, not on the files of the functions
# it calls; bladelab.numba_cache (called at the end of this module) flushes it whenever a
# compiled source of bladelab changes (this file used to carry a number to bump by hand).

# The per-step kernels here and in implicit.py, muscle.py and contact_point.py allocate nothing
# and are compiled without numba's reference counting (``_nrt=False``, numba's option for it):
# with it, every call to them incremented and decremented the count of each array in its tuple
# arguments (``mj``, ``arrays``, ``imp``: ~60 arrays) with an atomic instruction, 15-20 % of the
# implicit 1 ms step (measured with perf). The functions they call inherit the setting; an
# allocation in any of them fails to compile ("NRT required but not enabled"), and none may
# return an array (its caller would get a reference it does not own). ``run_loop`` allocates
# and keeps the counting. ``inline="always"`` (numba inlines the function's code into its
# compiled callers, which must then also be compiled without counting): step_forces and
# record_sample into step_end, which saves a copy of the argument tuples per step.


@njit(cache=True, _nrt=False)
def path_kinematics(site_xpos, cvel, root_com, path, pstart, mtu, seg_u):
    """MTU lengths [m] and lengthening velocities [m/s] into ``mtu`` (n, 2); unit vectors of the
    path segments into ``seg_u`` (one row per path point, the last of each muscle unused)."""
    for i in range(pstart.shape[0] - 1):
        length = 0.0
        vel = 0.0
        for k in range(pstart[i], pstart[i + 1] - 1):
            a = path[k, 0]
            b = path[k + 1, 0]
            ba = path[k, 1]
            bb = path[k + 1, 1]
            dx = site_xpos[b, 0] - site_xpos[a, 0]
            dy = site_xpos[b, 1] - site_xpos[a, 1]
            dz = site_xpos[b, 2] - site_xpos[a, 2]
            seg = math.sqrt(dx * dx + dy * dy + dz * dz)
            ux, uy, uz = dx / seg, dy / seg, dz / seg
            seg_u[k, 0], seg_u[k, 1], seg_u[k, 2] = ux, uy, uz
            # point velocities v + w x (p - root_com)
            rx = site_xpos[a, 0] - root_com[0]
            ry = site_xpos[a, 1] - root_com[1]
            rz = site_xpos[a, 2] - root_com[2]
            vax = cvel[ba, 3] + cvel[ba, 1] * rz - cvel[ba, 2] * ry
            vay = cvel[ba, 4] + cvel[ba, 2] * rx - cvel[ba, 0] * rz
            vaz = cvel[ba, 5] + cvel[ba, 0] * ry - cvel[ba, 1] * rx
            rx = site_xpos[b, 0] - root_com[0]
            ry = site_xpos[b, 1] - root_com[1]
            rz = site_xpos[b, 2] - root_com[2]
            vbx = cvel[bb, 3] + cvel[bb, 1] * rz - cvel[bb, 2] * ry
            vby = cvel[bb, 4] + cvel[bb, 2] * rx - cvel[bb, 0] * rz
            vbz = cvel[bb, 5] + cvel[bb, 0] * ry - cvel[bb, 1] * rx
            length += seg
            vel += ux * (vbx - vax) + uy * (vby - vay) + uz * (vbz - vaz)
        mtu[i, 0] = length
        mtu[i, 1] = vel


@njit(cache=True, _nrt=False)
def forces(mj, arrays, root_com, dt):
    """Muscles, ligaments and contacts for one step; writes ``xfrc`` and ``qfrc``.

    ``mj`` = (qpos, qvel, site_xpos, site_xmat, cvel, subtree_com, xipos, xfrc, qfrc): live
    views of MuJoCo's buffers (:func:`mujoco_views`); ``arrays`` = (mp, ms, mtu, seg_u, u, path,
    pstart, cp, cstate, jp, crec, lig): the model's parameters and the force state
    (:func:`force_arrays`); ``root_com`` the root subtree's COM [m] (MuJoCo's ``cvel`` origin).
    ``site_xmat`` (n_site, 9) orients ellipse contacts; an empty (0, 9) array treats every
    contact as a sphere (lowest point straight below the site).
    """
    qpos, qvel, site_xpos, site_xmat, cvel, _, xipos, xfrc, qfrc = mj
    mp, ms, mtu, seg_u, u, path, pstart, cp, cstate, jp, crec, lig = arrays
    xfrc[:, :] = 0.0
    path_kinematics(site_xpos, cvel, root_com, path, pstart, mtu, seg_u)
    muscle_step(mp, ms, mtu[:, 0], u, dt)
    for i in range(pstart.shape[0] - 1):
        f = ms[i, 3]
        if f == 0.0:
            continue
        for k in range(pstart[i], pstart[i + 1] - 1):
            a = path[k, 0]
            b = path[k + 1, 0]
            fx, fy, fz = f * seg_u[k, 0], f * seg_u[k, 1], f * seg_u[k, 2]
            add_point_force(
                xfrc,
                xipos,
                path[k, 1],
                site_xpos[a, 0],
                site_xpos[a, 1],
                site_xpos[a, 2],
                fx,
                fy,
                fz,
            )
            add_point_force(
                xfrc,
                xipos,
                path[k + 1, 1],
                site_xpos[b, 0],
                site_xpos[b, 1],
                site_xpos[b, 2],
                -fx,
                -fy,
                -fz,
            )
    # ligaments (joint-limit springs-dampers) and the socket's nonlinear spring
    for j in range(jp.shape[0]):
        q = qpos[j]
        qd = qvel[j]
        tau = 0.0
        if q > jp[j, JP_HI]:
            tau = min(-jp[j, JP_K] * (q - jp[j, JP_HI]) - jp[j, JP_D] * qd, 0.0)
        elif q < jp[j, JP_LO]:
            tau = max(-jp[j, JP_K] * (q - jp[j, JP_LO]) - jp[j, JP_D] * qd, 0.0)
        if jp[j, JP_SK] != 0.0 or jp[j, JP_SD] != 0.0 or jp[j, JP_SDX] != 0.0:
            damping = jp[j, JP_SD] if qd < 0.0 else jp[j, JP_SDX]
            tau -= jp[j, JP_SK] * q + jp[j, JP_SK2] * q * abs(q) + damping * qd
        if jp[j, JP_EA] != 0.0:  # the capsule's passive moment within the range
            tau += jp[j, JP_EA] * math.exp(jp[j, JP_EB] * q)
        qfrc[j] = tau
        lig[j] = tau
    # ground contacts: sphere or ellipse (semi-axes ax, az in the site's x-z plane)
    for c in range(cp.shape[0]):
        body = int(cp[c, CP_BODY])
        px, py, pz, depth = lowest_point(cp, c, site_xpos, site_xmat)
        rx, ry, rz = px - root_com[0], py - root_com[1], pz - root_com[2]
        vx = cvel[body, 3] + cvel[body, 1] * rz - cvel[body, 2] * ry
        vz = cvel[body, 5] + cvel[body, 0] * ry - cvel[body, 1] * rx
        fn = 0.0
        ft = 0.0
        if depth > 0.0:
            if cp[c, CP_LAW] == 0.0:
                fn = hunt_crossley_force(depth, -vz, cp[c, CP_K], cp[c, CP_EXP], cp[c, CP_C])
            else:
                fn = smooth_spring_damper_force(
                    depth, -vz, cp[c, CP_K], cp[c, CP_DAMP], cp[c, CP_WIDTH]
                )
            s = cstate[c, 0] + vx * dt
            ft = -FRICTION_STIFFNESS * s - FRICTION_DAMPING * vx
            lim = cp[c, CP_MU] * fn
            if ft > lim:
                ft = lim
                s = -lim / FRICTION_STIFFNESS
            elif ft < -lim:
                ft = -lim
                s = lim / FRICTION_STIFFNESS
            cstate[c, 0] = s
        else:
            cstate[c, 0] = 0.0
        add_point_force(xfrc, xipos, body, px, py, pz, ft, 0.0, fn)
        crec[c, 0] = ft
        crec[c, 1] = fn
        crec[c, 2] = px
        crec[c, 3] = pz
        crec[c, 4] = vx
        crec[c, 5] = vz
        crec[c, 6] = depth if depth > 0.0 else 0.0


@njit(cache=True, _nrt=False, inline="always")
def _copy_row(dst, i, src):
    """``dst[i] = src`` for a 1-D ``src``: a loop, as numba's slice assignment may allocate a
    temporary copy (which needs the reference counting these kernels go without)."""
    for j in range(src.shape[0]):
        dst[i, j] = src[j]


@njit(cache=True, _nrt=False, inline="always")
def _copy_block(dst, i, src):
    """``dst[i] = src`` for a 2-D ``src`` (a loop, as :func:`_copy_row`)."""
    for j in range(src.shape[0]):
        for k in range(src.shape[1]):
            dst[i, j, k] = src[j, k]


@njit(cache=True, _nrt=False, inline="always")
def record_sample(rec, i, t, mj, arrays):
    """Store sample ``i`` at time ``t`` [s] in ``rec`` = (t, qpos, qvel, muscles, mtu,
    excitation, contacts, ligament) arrays (:class:`bladelab.runner.simulate.Recording`)."""
    rec_t, rec_q, rec_v, rec_ms, rec_mtu, rec_u, rec_c, rec_l = rec
    _, ms, mtu, _, u, _, _, _, _, _, crec, lig = arrays
    rec_t[i] = t
    _copy_row(rec_q, i, mj[0])
    _copy_row(rec_v, i, mj[1])
    _copy_block(rec_ms, i, ms)
    _copy_block(rec_mtu, i, mtu)
    _copy_row(rec_u, i, u)
    _copy_block(rec_c, i, crec)
    _copy_row(rec_l, i, lig)


@njit(cache=True, _nrt=False)
def step_begin(f1, mptr, dptr, mj, root_com, imp):
    """First half of a step: MuJoCo's ``mj_step1`` (positions, velocities, forces of the
    current state; with the implicit scheme only the stages it needs,
    :func:`bladelab.runner.implicit.implicit_begin`), then ``root_com`` [m] = the root
    subtree's COM (MuJoCo's ``cvel`` origin)."""
    if imp[0][0] != EXPLICIT:
        implicit_begin(mptr, dptr, imp)
    else:
        call_mujoco(f1, mptr, dptr)
    subtree_com = mj[5]
    root_com[0] = subtree_com[1, 0]
    root_com[1] = subtree_com[1, 1]
    root_com[2] = subtree_com[1, 2]


@njit(cache=True, _nrt=False, inline="always")
def step_forces(mj, arrays, imp, root_com, dt):
    """The forces of one step by the scheme ``imp[0][0]`` selects: :func:`forces` (explicit)
    or :func:`bladelab.runner.implicit.implicit_forces`."""
    if imp[0][0] != EXPLICIT:
        implicit_forces(mj, arrays, imp, root_com, dt)
    else:
        forces(mj, arrays, root_com, dt)


@njit(cache=True, _nrt=False)
def step_advance(f2, mptr, dptr, mj, imp, dt):
    """Advance the state by the step: MuJoCo's ``mj_step2`` (explicit scheme) or the implicit
    scheme's Euler update (:func:`bladelab.runner.implicit.implicit_advance`)."""
    if imp[0][0] != EXPLICIT:
        implicit_advance(mj, imp, dt)
    else:
        call_mujoco(f2, mptr, dptr)


@njit(cache=True, _nrt=False)
def step_end(k, k_rec, record_every, dt, iz, fall_height, mj, arrays, rec, root_com, imp):
    """Second half of step ``k`` (after any controller): muscle, ligament and contact forces
    (:func:`step_forces`; ``imp`` from :func:`bladelab.runner.implicit_setup.implicit_arrays`),
    a sample every ``record_every`` steps. Returns (samples recorded, fell): the pelvis height
    ``qpos[iz]`` below ``fall_height`` [m] or NaN is a fall."""
    step_forces(mj, arrays, imp, root_com, dt)
    if k % record_every == 0:
        record_sample(rec, k_rec, k * dt, mj, arrays)
        k_rec += 1
    return k_rec, not mj[0][iz] >= fall_height  # also catches NaN


@njit(cache=True)
def run_loop(f1, f2, mptr, dptr, n_steps, record_every, dt, iz, fall_height, mj, arrays, rec,
             imp):
    """The whole open-loop time loop (constant excitations ``u`` in ``arrays``) in compiled
    code, MuJoCo's C ``mj_step1``/``mj_step2`` called directly (:func:`step_begin`,
    :func:`step_end`; a controller runs between the two, as in
    :func:`bladelab.predict.reflex.closed_loop.run_closed_loop`). Stops after ``n_steps`` or at
    a fall. Returns (last step, samples recorded, fell).
    """
    root_com = np.zeros(3)
    k_rec = 0
    k = 0
    for k in range(n_steps + 1):
        step_begin(f1, mptr, dptr, mj, root_com, imp)
        k_rec, fell = step_end(k, k_rec, record_every, dt, iz, fall_height, mj, arrays, rec,
                               root_com, imp)
        if fell:
            return k, k_rec, True
        if k == n_steps:
            break
        step_advance(f2, mptr, dptr, mj, imp, dt)
    return k, k_rec, False


def mujoco_views(d: mujoco.MjData, *, oriented: bool = True) -> tuple:
    """The live MuJoCo buffers :func:`forces` reads and writes, as its ``mj`` tuple
    (``oriented=False``: every contact a sphere)."""
    xmat = d.site_xmat if oriented else np.zeros((0, 9))
    return (
        d.qpos,
        d.qvel,
        d.site_xpos,
        xmat,
        d.cvel,
        d.subtree_com,
        d.xipos,
        d.xfrc_applied,
        d.qfrc_applied,
    )


refresh_stale_caches(globals())
