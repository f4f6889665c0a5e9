"""MuJoCo reference engine: the same blade built segment by segment with ``MjSpec``.

Every segment is its own body (rigid segments are welded children, so MuJoCo's own composite
inertia is used, independent of the kernel's merging); compliant joints are hinges about +y with
``stiffness`` K and ``damping`` D (implicit in MuJoCo's Euler integrator), the quadratic term
K2·q·|q| is added through ``qfrc_applied``. Native contact is disabled: the documented contact
law is applied as external forces (``xfrc_applied``) computed every step from MuJoCo's own
site frames (ellipse–plane geometry in 3-D) and the point velocities from ``cvel``.

The clamp is driven through slide x, slide z and hinge y joints with a large armature and a
feed-forward force ``armature × prescribed acceleration``; its position and velocity are reset to
the prescribed values before every step. So the blade sees the clamp's true velocity and
acceleration (a mocap clamp would have zero velocity in the dynamics).

The same builder makes the free "runner" of :mod:`bladelab.sim.synthetic`; the blade's bodies,
hinges and sites come from :func:`bladelab.sim.mujoco_blade.add_blade_bodies` (per-segment bodies,
K and D in MuJoCo's joints, segment capsules).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numba import njit

from bladelab.blade.model import BladeModel
from bladelab.constants import STANDARD_GRAVITY
from bladelab.contact import stick_slip_friction_coefficient
from bladelab.errors import SimulationError
from bladelab.numba_cache import refresh_stale_caches
from bladelab.sim import kernel as _k
from bladelab.sim import sole as _sole
from bladelab.sim.chain import Chain
from bladelab.sim.mujoco_blade import add_blade_bodies
from bladelab.sim.result import SimResult

CLAMP_ARMATURE = 1.0e6  # kg (slides) and kg·m² (pitch hinge)


def default_mujoco_dt(chain: Chain, *, peak_force: float = 3000.0) -> float:
    """Step [s] at which MuJoCo's explicit treatment of the contact forces is stable.

    The stiffest explicit terms are the stick-regime friction (a damper of μ_s·F/v_c, with F up
    to ``peak_force`` [N]) and the contact spring-damper, acting on the smallest effective mass
    of a sole point (from the chain's mass matrix at the undeformed posture). Returns half the
    explicit stability limit, at most 2e-5 s (about 5e-6 s for the one-joint blades with
    friction).
    """
    nj = chain.n_joints
    m, com, inertia, hinge = chain.body_mass, chain.body_com, chain.body_inertia, chain.hinge
    M = np.zeros((nj, nj))
    for j in range(nj):
        for k in range(nj):
            for b in range(max(j, k) + 1, nj + 1):
                M[j, k] += m[b] * np.dot(com[b] - hinge[j], com[b] - hinge[k]) + inertia[b]
    Minv = np.linalg.inv(M)
    law, k_c, c_c = chain.contact[0], chain.contact[1], chain.contact[2]
    mu_s, v_c = chain.contact[6], chain.contact[8]
    dt = 2e-5
    for e in range(chain.n_soles):
        b = chain.sole_body[e]
        p = chain.sole_geom[e, :2] - np.array([0.0, chain.sole_geom[e, 3]])
        jx = np.array([(p[1] - hinge[j, 1]) if j < b else 0.0 for j in range(nj)])
        jz = np.array([-(p[0] - hinge[j, 0]) if j < b else 0.0 for j in range(nj)])
        m_x = 1.0 / max(jx @ Minv @ jx, 1e-12)
        m_z = 1.0 / max(jz @ Minv @ jz, 1e-12)
        if mu_s > 0:
            dt = min(dt, m_x / (mu_s * peak_force / v_c))
        if law == 0:
            k_eff, c_eff = k_c, c_c
        else:  # Hunt-Crossley: linearise at 2 mm of penetration
            n, diss, ref = chain.contact[4], chain.contact[5], 0.002
            k_eff, c_eff = n * k_c * ref ** (n - 1.0), 1.5 * diss * k_c * ref**n
        if c_eff > 0:
            dt = min(dt, m_z / c_eff)
        dt = min(dt, 0.2 * math.sqrt(m_z / k_eff))
    return float(dt)


def build_spec(
    blade: BladeModel,
    *,
    stiffness: np.ndarray,
    damping: np.ndarray,
    dt: float,
    root: str = "prescribed",
    body_mass: float = 0.0,
    pylon_length: float = 0.0,
) -> mujoco.MjSpec:
    """The blade as an ``MjSpec``.

    ``root = "prescribed"``: world → slide x → slide z → hinge y (clamp, at the clamp origin),
    each with armature :data:`CLAMP_ARMATURE`. ``root = "runner"``: world → slide x → slide z
    (a point mass ``body_mass`` [kg] at the hip) → hinge y (pitch of the rigid pylon) → clamp
    ``pylon_length`` [m] below the hip along the pylon.
    """
    spec = mujoco.MjSpec()
    spec.modelname = "bladelab_blade"
    spec.option.timestep = dt
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.gravity = [0.0, 0.0, -STANDARD_GRAVITY]
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1],
                            contype=0, conaffinity=0)

    def _light(body, mass=1e-6):
        body.explicitinertial = True
        body.mass = mass
        body.inertia = [max(mass, 1e-6) * 1e-3] * 3

    bx = spec.worldbody.add_body(name="root_x")
    bx.add_joint(name="root_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0],
                 armature=CLAMP_ARMATURE if root == "prescribed" else 0.0)
    bz = bx.add_body(name="root_z")
    bz.add_joint(name="root_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1],
                 armature=CLAMP_ARMATURE if root == "prescribed" else 0.0)
    if root == "prescribed":
        _light(bx)
        _light(bz)
        parent = bz.add_body(name="clamp")
        parent.add_joint(name="clamp_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0],
                         armature=CLAMP_ARMATURE)
        _light(parent)
    else:
        _light(bx)
        _light(bz, body_mass)
        pylon = bz.add_body(name="pylon")
        pylon.add_joint(name="pylon_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0])
        _light(pylon)
        pylon.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0, 0, 0, 0, 0, -pylon_length],
                       size=[0.015, 0, 0], contype=0, conaffinity=0, mass=0)
        parent = pylon.add_body(name="clamp", pos=[0, 0, -pylon_length])
        _light(parent)
    parent.add_site(name="clamp", pos=[0, 0, 0])
    add_blade_bodies(parent, blade, stiffness=stiffness, damping=damping, min_inertia=1e-12,
                     capsule_radius=0.006)
    return spec


@njit(cache=True)
def _sole_point(site_pos, site_mat, a, c, cvel, subtree_com, root, body):
    """Lowest point (x, z) [m] of a sole ellipse site (semi-axes ``a`` along its x, ``c`` along
    its z) and that point's velocity (vx, vz) [m/s] from the body's ``cvel`` about the subtree
    COM of its ``root``."""
    exz = site_mat[6]  # z component of the site's x axis (row-major 3x3)
    ezz = site_mat[8]  # z component of the site's z axis
    nrm = math.sqrt(a * a * exz * exz + c * c * ezz * ezz)
    ct = -a * exz / nrm
    st = -c * ezz / nrm
    px = site_pos[0] + a * ct * site_mat[0] + c * st * site_mat[2]
    pz = site_pos[2] + a * ct * site_mat[6] + c * st * site_mat[8]
    wx = cvel[body, 0]
    wy = cvel[body, 1]
    wz = cvel[body, 2]
    rx = px - subtree_com[root, 0]
    ry = 0.0 - subtree_com[root, 1]
    rz = pz - subtree_com[root, 2]
    vpx = cvel[body, 3] + wy * rz - wz * ry
    vpz = cvel[body, 5] + wx * ry - wy * rx
    return px, pz, vpx, vpz


@njit(cache=True)
def _friction_coefficient(contact, fn, slip):
    """Signed μ: the utilised ratio −r when ``contact`` has a 12th entry r, else the stick-slip
    law (0 when friction is off or the element is unloaded)."""
    if fn <= 0.0:
        return 0.0
    if contact.shape[0] > 11:
        return -contact[11]  # utilised friction: Fx = r·Fn (drive "utilised-friction")
    if contact[6] > 0.0:
        return stick_slip_friction_coefficient(slip, contact[6], contact[7], contact[8])
    return 0.0


@njit(cache=True)
def add_point_force(xfrc, xipos, body, px, py, pz, fx, fy, fz):
    """Add the force (``fx``, ``fy``, ``fz``) [N] acting at (``px``, ``py``, ``pz``) [m] to
    ``body``'s row of MuJoCo's ``xfrc_applied``: the force and its torque about the body's COM
    (``xipos``). Used by the blade engine and the runner."""
    xfrc[body, 0] += fx
    xfrc[body, 1] += fy
    xfrc[body, 2] += fz
    dx = px - xipos[body, 0]
    dy = py - xipos[body, 1]
    dz = pz - xipos[body, 2]
    xfrc[body, 3] += dy * fz - dz * fy
    xfrc[body, 4] += dz * fx - dx * fz
    xfrc[body, 5] += dx * fy - dy * fx


@njit(cache=True)
def contact_forces_3d(contact, site_xpos, site_xmat, sites, axes, site_body, cvel, subtree_com,
                      rootid, xipos, ground_vx, xfrc, out):
    """Apply the contact law to every sole site; write xfrc_applied and per-sole outputs.

    ``out[e]`` = (fx, fz, depth, slip, elastic normal force, contact-damping power,
    friction power). A 12th entry of ``contact``, if present, is the utilised friction ratio r:
    the friction force is then r·Fn instead of the stick-slip law.
    """
    ne = sites.shape[0]
    xfrc[:, :] = 0.0
    for e in range(ne):
        b = site_body[e]
        px, pz, vpx, vpz = _sole_point(site_xpos[sites[e]], site_xmat[sites[e]], axes[e, 0],
                                       axes[e, 1], cvel, subtree_com, rootid[b], b)
        depth = -pz
        out[e, 0] = 0.0
        out[e, 1] = 0.0
        out[e, 2] = depth
        out[e, 3] = vpx - ground_vx
        out[e, 4] = 0.0
        out[e, 5] = 0.0
        out[e, 6] = 0.0
        if depth <= 0.0:
            continue
        rate = -vpz
        fn, _kn, _cn, fel = _sole.normal_force(contact, depth, rate)
        fx = -_friction_coefficient(contact, fn, vpx - ground_vx) * fn
        out[e, 0] = fx
        out[e, 1] = fn
        out[e, 4] = fel
        out[e, 5] = (fn - fel) * rate
        out[e, 6] = -fx * (vpx - ground_vx)
        add_point_force(xfrc, xipos, b, px, 0.0, pz, fx, 0.0, fn)


@njit(cache=True)
def contact_forces_track(contact, site_xpos, site_xmat, sites, axes, site_body, cvel, subtree_com,
                         rootid, xipos, ground_vx, track_u, dt, xfrc, out):
    """:func:`contact_forces_3d` through a compliant track layer (``contact[9]`` > 0).

    The track deflection ``track_u[e]`` [m] of each sole element advances by one backward-Euler
    step of ``dt`` from the penetration and its rate at the current state
    (:func:`bladelab.sim.sole.track_contact` with uh = u_n, g = dt). ``out[e]`` = (fx, fz,
    depth, slip, elastic contact force, contact-damping power, friction power, track-damping
    power, track deflection).
    """
    ne = sites.shape[0]
    xfrc[:, :] = 0.0
    ct = contact[10]
    for e in range(ne):
        b = site_body[e]
        px, pz, vpx, vpz = _sole_point(site_xpos[sites[e]], site_xmat[sites[e]], axes[e, 0],
                                       axes[e, 1], cvel, subtree_com, rootid[b], b)
        depth = -pz
        rate = -vpz
        slip = vpx - ground_vx
        fn, _kn, _cn, fel, u, w, _dud = _sole.track_contact(contact, depth, rate, track_u[e], dt)
        track_u[e] = u
        fx = -_friction_coefficient(contact, fn, slip) * fn
        out[e, 0] = fx
        out[e, 1] = fn
        out[e, 2] = depth
        out[e, 3] = slip
        out[e, 4] = fel
        out[e, 5] = (fn - fel) * (rate - w) if fn > 0.0 else 0.0
        out[e, 6] = -fx * slip
        out[e, 7] = ct * w * w
        out[e, 8] = u
        if fn == 0.0:
            continue
        add_point_force(xfrc, xipos, b, px, 0.0, pz, fx, 0.0, fn)


@njit(cache=True)
def _prescribed_forces(bs, qpos, qfrc, jq, jd, K2):
    """Clamp feed-forward and the quadratic spring term into ``qfrc_applied``."""
    qfrc[:] = 0.0
    qfrc[0] = CLAMP_ARMATURE * bs[6]
    qfrc[1] = CLAMP_ARMATURE * bs[7]
    qfrc[2] = CLAMP_ARMATURE * bs[8]
    for j in range(jd.shape[0]):
        q = qpos[jq[j]]
        qfrc[jd[j]] = -K2[j] * q * abs(q)


@njit(cache=True)
def _accumulate(acc, dt, bs, qfrc, qacc, qpos, qvel, jq, jd, D, out):
    """After a step: clamp work, dissipation; returns False when the state diverged."""
    w = 0.0
    for c in range(3):
        w += (qfrc[c] - CLAMP_ARMATURE * qacc[c]) * bs[3 + c]
    acc[0] += dt * w
    for j in range(jd.shape[0]):
        acc[1] += dt * D[j] * qvel[jd[j]] ** 2
    for e in range(out.shape[0]):
        acc[2] += dt * out[e, 5]
        acc[3] += dt * out[e, 6]
        if out.shape[1] > 7:
            acc[4] += dt * out[e, 7]
    for i in range(qpos.shape[0]):
        if not math.isfinite(qpos[i]):
            return False
    for j in range(jq.shape[0]):
        if abs(qpos[jq[j]]) > 10.0:
            return False
    return True


@njit(cache=True)
def _kinetic_potential(body_mass, body_inertia, cvel, xipos, subtree_com, rootid):
    """Kinetic and gravitational energy [J] of the bodies heavier than 1e-5 kg."""
    kin = 0.0
    pot = 0.0
    for b in range(body_mass.shape[0]):
        m = body_mass[b]
        if m <= 1e-5:
            continue
        wx, wy, wz = cvel[b, 0], cvel[b, 1], cvel[b, 2]
        r = rootid[b]
        rx = xipos[b, 0] - subtree_com[r, 0]
        ry = xipos[b, 1] - subtree_com[r, 1]
        rz = xipos[b, 2] - subtree_com[r, 2]
        vx = cvel[b, 3] + wy * rz - wz * ry
        vy = cvel[b, 4] + wz * rx - wx * rz
        vz = cvel[b, 5] + wx * ry - wy * rx
        kin += 0.5 * m * (vx * vx + vy * vy + vz * vz) + 0.5 * body_inertia[b, 1] * wy * wy
        pot += m * STANDARD_GRAVITY * xipos[b, 2]
    return kin, pot


class MujocoBlade:
    """A compiled blade model with the indices the simulation loops need."""

    def __init__(self, blade: BladeModel, spec: mujoco.MjSpec) -> None:
        self.blade = blade
        self.model = spec.compile()
        m = self.model
        self.data = mujoco.MjData(m)
        self.sole_sites = np.array([m.site(f"sole{e}").id for e in range(len(blade.soles))])
        self.sole_body = np.ascontiguousarray(m.site_bodyid[self.sole_sites])
        self.axes = np.array([[s.semi_axis_x, s.semi_axis_z] for s in blade.soles], float)
        self.joint_dofs = np.array([m.jnt_dofadr[m.joint(f"joint{i + 1}").id]
                                    for i in range(len(blade.joints))])
        self.joint_qpos = np.array([m.jnt_qposadr[m.joint(f"joint{i + 1}").id]
                                    for i in range(len(blade.joints))])
        self.tip_site = m.site("tip").id
        self.clamp_site = m.site("clamp").id
        self.rootid = np.ascontiguousarray(m.body_rootid)
        self.out = np.zeros((len(blade.soles), 7))

    def apply_contact(self, contact: np.ndarray, ground_vx: float = 0.0) -> None:
        """Compute the contact forces at the current (step1) state into ``xfrc_applied``."""
        d = self.data
        contact_forces_3d(contact, d.site_xpos, d.site_xmat, self.sole_sites, self.axes,
                          self.sole_body, d.cvel, d.subtree_com, self.rootid, d.xipos, ground_vx,
                          d.xfrc_applied, self.out)


def simulate_mujoco(problem, K: np.ndarray, D: np.ndarray, K2: np.ndarray):
    """Run one parameter set of a prescribed-clamp problem on MuJoCo; returns a SimResult."""
    blade = problem.blade
    chain = problem.chain
    mj = MujocoBlade(blade, build_spec(blade, stiffness=K, damping=D, dt=problem.dt))
    m, d = mj.model, mj.data
    base = problem.base
    nsub = problem.n_substeps
    ns = problem.n_samples
    ne = chain.n_soles
    nj = chain.n_joints
    contact = chain.contact
    vc = contact[8]
    grf = np.zeros((ns, ne, 2))
    dist = np.zeros(ns)
    qout = np.zeros((ns, nj))
    tau = np.zeros((ns, nj))
    state = np.zeros((ns, ne), np.int8)
    energy = np.zeros((ns, len(_k.ENERGY_TERMS)))
    jd = np.ascontiguousarray(mj.joint_dofs)
    jq = np.ascontiguousarray(mj.joint_qpos)
    # writable C arrays: a read-only one would make numba compile another version of the loops
    K, D, K2 = (np.require(a, np.float64, ["C", "W"]) for a in (K, D, K2))
    acc = np.zeros(5)  # clamp work, joint, contact, friction, track dissipation
    track = contact[9] > 0.0
    track_u = np.zeros(ne)
    if track:
        out = np.zeros((ne, 9))
    dt = problem.dt
    qpos, qvel, qacc, qfrc = d.qpos, d.qvel, d.qacc, d.qfrc_applied
    body_inertia = m.body_inertia
    if not track:
        out = mj.out
    n_last = base.shape[0] - 1
    utilised = base.shape[1] == _k.UTILISED_COLUMN + 1
    contact_u = np.append(contact, 0.0) if utilised else contact
    for i in range(base.shape[0]):
        bs = base[i]
        qpos[0:3] = bs[0:3]
        qvel[0:3] = bs[3:6]
        mujoco.mj_step1(m, d)
        if utilised:
            contact_u[11] = bs[_k.UTILISED_COLUMN]
        if track:
            contact_forces_track(contact_u, d.site_xpos, d.site_xmat, mj.sole_sites, mj.axes,
                                 mj.sole_body, d.cvel, d.subtree_com, mj.rootid, d.xipos, 0.0,
                                 track_u, dt, d.xfrc_applied, out)
        else:
            mj.apply_contact(contact_u)
        _prescribed_forces(bs, qpos, qfrc, jq, jd, K2)
        if i % nsub == 0:
            s = i // nsub
            q = qpos[jq]
            grf[s] = out[:, 0:2]
            depth_c = out[:, 2] - track_u if track else out[:, 2]
            state[s] = np.where(depth_c <= 0, 0, np.where(np.abs(out[:, 3]) <= vc, 1, 2))
            tip = d.site_xpos[mj.tip_site]
            dist[s] = math.hypot(tip[0] - bs[0], tip[2] - bs[1])
            qout[s] = q
            tau[s] = -(K * q + K2 * q * np.abs(q) + D * qvel[jd])
            kin, pot = _kinetic_potential(m.body_mass, body_inertia, d.cvel, d.xipos,
                                          d.subtree_com, mj.rootid)
            spring = float(np.sum(0.5 * K * q**2 + K2 * np.abs(q) ** 3 / 3.0))
            e_c = sum(_sole.contact_elastic_energy(contact, dep) for dep in depth_c)
            if track:
                e_c += float(np.sum(0.5 * contact[9] * track_u**2))
            energy[s] = (acc[0], kin, pot, spring, e_c, acc[1], acc[2], acc[3], acc[4])
        if i == n_last:
            break
        mujoco.mj_step2(m, d)
        if not _accumulate(acc, dt, bs, qfrc, qacc, qpos, qvel, jq, jd, D, out):
            raise SimulationError(
                f"MuJoCo diverged at t = {problem.time[0] + i * dt:.4g} s", where="simulate",
                hint="reduce dt",
            )
    return SimResult(
        time=problem.time.copy(), grf_x=grf[:, :, 0].sum(axis=1), grf_z=grf[:, :, 1].sum(axis=1),
        grf_elements=grf, distance=dist, deflection=qout, torque=tau, contact_state=state,
        energy={name: energy[:, i] for i, name in enumerate(_k.ENERGY_TERMS)},
        stiffness=np.asarray(K, float).copy(), damping=np.asarray(D, float).copy(),
        stiffness_quadratic=np.asarray(K2, float).copy(), engine="mujoco", dt=dt,
    )


refresh_stale_caches(globals())
