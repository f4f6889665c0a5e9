"""The numba planar-chain kernel: a blade chain driven by a prescribed clamp.

Equations (see ``docs/blade-model.md``): generalised coordinates are the compliant-joint angles
q (rad, rotation of the distal body relative to the proximal one about +y). With the clamp pose
(x, z, θ) prescribed,

    M(q) q̈ = τ_spring(q, q̇) + Q_gravity(q) + Q_contact(q, q̇, t) − b(q, q̇, t)

where M_jk = Σ_{b > max(j,k)} m_b (r_b − H_j)·(r_b − H_k) + I_b, b is the bias from the clamp's
acceleration and the centripetal terms (the generalised inertia force at q̈ = 0), and a force F at a
point P of body b contributes F·perp(P − H_j) to every joint j proximal to b
(perp(x, z) = (z, −x), the derivative of a point with respect to a rotation about +y).

Integrator: linearly-implicit BDF2 (backward Euler on the first step and after a restart). Each
step linearises the generalised force around the predictor with analytic contact and spring
Jacobians and solves (M − γ·∂Q/∂q̇ − γ²·∂Q/∂q) Δq̇ = γ·(Q − b) − M(q̇* − q̇̂), γ = 2h/3; steps
where a loaded sole element lands or slides are redone as sub-steps. It is stable with the stiff
stick-slip friction (≈ 4e4 N·s/m in stick) at h = 2e-4 s, where explicit schemes need ≈ 1e-5 s.
The sole contact (geometry, laws, friction, compliant track) is in :mod:`bladelab.sim.sole`; its
functions and the helpers here are inlined at numba-IR level (``inline="always"``). Caveat of
numba's cache: editing :mod:`bladelab.sim.sole` or :mod:`bladelab.contact` does not invalidate
the cached kernel; touch this file (or clear ``__pycache__``) after such an edit.

This module is longer than the project's other modules by design: :func:`simulate_prescribed`
is one compiled step loop (predictor, Newton refinement, regime-change sub-steps, restarts and
energy bookkeeping share its work arrays), kept in one numba function so that no array is
allocated per step; its parts are marked by comments.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from bladelab.constants import STANDARD_GRAVITY
from bladelab.numba_cache import refresh_stale_caches
from bladelab.sim.chain import Chain
from bladelab.sim.sole import (
    contact_elastic_energy,
    friction,
    sole_contact,
    track_contact,
    track_state_force,
)

# Columns of the energy output.
ENERGY_TERMS: tuple[str, ...] = (
    "clamp_work",
    "kinetic",
    "potential_gravity",
    "spring",
    "contact_elastic",
    "dissipated_joint",
    "dissipated_contact",
    "dissipated_friction",
    "dissipated_track",
)

# Normal force [N] below which a touching sole element does not count as loaded when the kernel
# decides to sub-step (an element hovering at the surface must not trigger sub-steps every step).
REGIME_MIN_FORCE = 50.0
# Time [s] after an element becomes loaded during which its sliding is sub-stepped (the landing
# slide decides where the sole sticks; later steady sliding is smooth and needs no sub-steps).
SLIDE_WINDOW = 0.005

# Column of ``base`` that holds the utilised friction ratio r(t) = measured Fx/Fz when the clamp
# drive is "utilised-friction" (``base`` then has 12 columns): the friction of every loaded sole
# element is r(t)·Fn instead of the stick-slip law (see docs/identification.md).
UTILISED_COLUMN = 11
# Columns of ``base`` that hold the measured GRF x, z [N] when the drive is "grf-driven" (``base``
# then has 13 columns): the measured force is applied to the sole, split over the elements in
# proportion to the model's normal forces of the previous step; the contact law only sets the split.
GRF_X_COLUMN = 11
GRF_Z_COLUMN = 12

STATUS_OK = 0
STATUS_DIVERGED = 1


class ChainModel(NamedTuple):
    """The fixed blade description the kernel simulates (SI, clamp frame, undeformed posture).

    Fields: ``body_mass`` (nb,) [kg]; ``body_com`` (nb, 2) centre of mass x, z [m];
    ``body_inertia`` (nb,) about the centre of mass and +y [kg·m²]; ``hinge`` (nj, 2) hinge
    points x, z [m] (hinge j joins body j and body j + 1); ``sole_body`` (ne,) int64 body of each
    sole ellipse; ``sole_geom`` (ne, 5) ellipse centre x, z [m], semi-axes x, z [m], angle [rad];
    ``tip_body`` (int) body of the tip marker; ``tip`` (2,) its position x, z [m]; ``contact``
    (11,) the contact vector of :class:`~bladelab.sim.chain.Chain` (law code, k, c, transition
    width [m], exponent, dissipation [s/m], μ_s, μ_k, v_c [m/s], k_t [N/m], c_t [N·s/m]).
    """

    body_mass: np.ndarray
    body_com: np.ndarray
    body_inertia: np.ndarray
    hinge: np.ndarray
    sole_body: np.ndarray
    sole_geom: np.ndarray
    tip_body: int
    tip: np.ndarray
    contact: np.ndarray

    @classmethod
    def from_chain(cls, chain: Chain) -> ChainModel:
        """The kernel's view of ``chain`` (the arrays themselves, not copies)."""
        return cls(chain.body_mass, chain.body_com, chain.body_inertia, chain.hinge,
                   chain.sole_body, chain.sole_geom, int(chain.tip_body), chain.tip, chain.contact)


class StanceDrive(NamedTuple):
    """The prescribed clamp motion, its time base and the joints' initial state.

    Fields: ``base`` (n_steps + 1, 11–13) clamp row at every step time (columns in
    :func:`simulate_prescribed`); ``dt`` integration step [s]; ``nsub`` (int) steps per output
    sample; ``ground_vx`` ground (belt) velocity along x [m/s]; ``q0``, ``v0`` (nj,) initial
    joint angles [rad] and rates [rad/s].
    """

    base: np.ndarray
    dt: float
    nsub: int
    ground_vx: float
    q0: np.ndarray
    v0: np.ndarray


class JointParams(NamedTuple):
    """The joint parameters being identified: (nj,) for one set, (n_sets, nj) for a batch.

    Fields: ``stiffness`` K [N·m/rad]; ``damping`` D [N·m·s/rad]; ``stiffness_quadratic``
    K2 [N·m/rad²] (spring torque −K·q − K2·q·|q| − D·q̇).
    """

    stiffness: np.ndarray
    damping: np.ndarray
    stiffness_quadratic: np.ndarray


class SolverSettings(NamedTuple):
    """Integrator settings.

    Fields: ``order`` (int) 2 = BDF2, 1 = backward Euler; ``n_iter`` (int) Newton iterations per
    step (1 = linearly implicit); ``refine`` (int) sub-steps of a step in which a sole element
    changes regime (1 = never); ``with_energy`` (bool) keep the energy bookkeeping.
    """

    order: int
    n_iter: int
    refine: int
    with_energy: bool


class KernelOutputs(NamedTuple):
    """Buffers the kernel writes into, one row per output sample (a leading set axis in a batch).

    Fields: ``grf`` (ns, ne, 2) force x, z on each sole element [N]; ``dist`` (ns,) tip–clamp
    distance [m]; ``qout`` (ns, nj) joint angles [rad]; ``tau`` (ns, nj) spring-damper torques
    [N·m]; ``state`` (ns, ne) int8 contact state (0 free, 1 stick, 2 slip); ``energy`` (ns, 9)
    [J], columns :data:`ENERGY_TERMS`.
    """

    grf: np.ndarray
    dist: np.ndarray
    qout: np.ndarray
    tau: np.ndarray
    state: np.ndarray
    energy: np.ndarray

    @classmethod
    def zeros(cls, n_sets: int, n_samples: int, n_soles: int, n_joints: int) -> KernelOutputs:
        """Zeroed buffers for a batch of ``n_sets`` parameter sets."""
        return cls(
            grf=np.zeros((n_sets, n_samples, n_soles, 2)),
            dist=np.zeros((n_sets, n_samples)),
            qout=np.zeros((n_sets, n_samples, n_joints)),
            tau=np.zeros((n_sets, n_samples, n_joints)),
            state=np.zeros((n_sets, n_samples, n_soles), np.int8),
            energy=np.zeros((n_sets, n_samples, len(ENERGY_TERMS))),
        )


@njit(cache=True, inline="always", error_model="numpy")
def _rot(c: float, s: float, x: float, z: float) -> tuple[float, float]:
    """Rotate (x, z) by the pitch whose cosine and sine are ``c``, ``s`` (about +y)."""
    return c * x + s * z, -s * x + c * z


@njit(cache=True, inline="always", error_model="numpy")
def _kinematics(bs, q, v, hinge, com0, Ob, vO, aO, phi, cph, sph, om, al, R, VR, AR):
    """Body origins (Ob), angles, COMs (R) with velocities and bias accelerations (q̈ = 0)."""
    nb = com0.shape[0]
    Ob[0, 0] = bs[0]
    Ob[0, 1] = bs[1]
    phi[0] = bs[2]
    cph[0] = bs[9]
    sph[0] = bs[10]
    vO[0, 0] = bs[3]
    vO[0, 1] = bs[4]
    om[0] = bs[5]
    aO[0, 0] = bs[6]
    aO[0, 1] = bs[7]
    al[0] = bs[8]
    for b in range(nb):
        if b > 0:
            o0x = hinge[b - 2, 0] if b > 1 else 0.0
            o0z = hinge[b - 2, 1] if b > 1 else 0.0
            dx, dz = _rot(cph[b - 1], sph[b - 1], hinge[b - 1, 0] - o0x, hinge[b - 1, 1] - o0z)
            w = om[b - 1]
            Ob[b, 0] = Ob[b - 1, 0] + dx
            Ob[b, 1] = Ob[b - 1, 1] + dz
            vO[b, 0] = vO[b - 1, 0] + w * dz
            vO[b, 1] = vO[b - 1, 1] - w * dx
            aO[b, 0] = aO[b - 1, 0] + al[b - 1] * dz - w * w * dx
            aO[b, 1] = aO[b - 1, 1] - al[b - 1] * dx - w * w * dz
            phi[b] = phi[b - 1] + q[b - 1]
            cph[b] = math.cos(phi[b])
            sph[b] = math.sin(phi[b])
            om[b] = om[b - 1] + v[b - 1]
            al[b] = al[b - 1]
        o0x = hinge[b - 1, 0] if b > 0 else 0.0
        o0z = hinge[b - 1, 1] if b > 0 else 0.0
        ex, ez = _rot(cph[b], sph[b], com0[b, 0] - o0x, com0[b, 1] - o0z)
        w = om[b]
        R[b, 0] = Ob[b, 0] + ex
        R[b, 1] = Ob[b, 1] + ez
        VR[b, 0] = vO[b, 0] + w * ez
        VR[b, 1] = vO[b, 1] - w * ex
        AR[b, 0] = aO[b, 0] + al[b] * ez - w * w * ex
        AR[b, 1] = aO[b, 1] - al[b] * ex - w * w * ez


@njit(cache=True, inline="always", error_model="numpy")
def _body_point(b, x0, z0, hinge, Ob, cph, sph):
    o0x = hinge[b - 1, 0] if b > 0 else 0.0
    o0z = hinge[b - 1, 1] if b > 0 else 0.0
    ex, ez = _rot(cph[b], sph[b], x0 - o0x, z0 - o0z)
    return Ob[b, 0] + ex, Ob[b, 1] + ez


@njit(cache=True, inline="always", error_model="numpy")
def _solve(A, rhs, x):
    """Solve A x = rhs in place (Gaussian elimination, partial pivoting; A, rhs destroyed)."""
    n = rhs.shape[0]
    if n == 1:
        x[0] = rhs[0] / A[0, 0]
        return
    for k in range(n):
        p = k
        big = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > big:
                big = abs(A[i, k])
                p = i
        if p != k:
            for j in range(n):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
            tmp = rhs[k]
            rhs[k] = rhs[p]
            rhs[p] = tmp
        for i in range(k + 1, n):
            f = A[i, k] / A[k, k]
            if f != 0.0:
                for j in range(k, n):
                    A[i, j] -= f * A[k, j]
                rhs[i] -= f * rhs[k]
    for i in range(n - 1, -1, -1):
        acc = rhs[i]
        for j in range(i + 1, n):
            acc -= A[i, j] * x[j]
        x[i] = acc / A[i, i]


@njit(cache=True, error_model="numpy")
def simulate_prescribed(model, drive, params, solver, out):
    """Simulate one parameter set with the clamp prescribed.

    ``model`` :class:`ChainModel`; ``drive`` :class:`StanceDrive`; ``params`` :class:`JointParams`
    of one set, (nj,) each; ``solver`` :class:`SolverSettings`; ``out`` :class:`KernelOutputs` of
    one set, written in place. Returns (status, step index where it diverged or −1).

    ``drive.base`` (n_steps + 1, 11): clamp x, z [m], θ [rad], ẋ, ż, θ̇, ẍ, z̈, θ̈, cos θ, sin θ at
    every step time; with a 12th column r(t) (drive "utilised-friction") the friction of each
    sole element is r·Fn (no stick-slip law); with 13 columns (measured GRF x, z [N]: drive
    "grf-driven") the measured GRF is applied to the sole elements (split by the model's normal
    forces of the previous step) and the contact law only decides the split (energy terms are
    then not balanced). ``solver.refine``: a step in which any sole element changes regime
    (touch-down, stick ↔ slip, lift-off) is redone as ``refine`` sub-steps with the clamp row
    interpolated linearly. Samples are recorded every ``drive.nsub`` steps. ``model.contact[9]``
    > 0 adds a compliant track layer in series with every sole element (:func:`track_contact`;
    its deflection is a state integrated with the same BDF2/Euler formula).
    """
    body_mass, com0, body_inertia, hinge, sole_body, sole_geom, tip_body, tip, contact = model
    base, dt, nsub, ground_vx, q0, v0 = drive
    stiffness, damping, stiffness_quadratic = params
    order, n_iter, refine, with_energy = solver
    grf, dist, qout, tau, state, energy = out
    nb = com0.shape[0]
    nj = nb - 1
    ne = sole_body.shape[0]
    n_steps = base.shape[0] - 1
    Ob = np.zeros((nb, 2))
    vO = np.zeros((nb, 2))
    aO = np.zeros((nb, 2))
    phi = np.zeros(nb)
    cph = np.zeros(nb)
    sph = np.zeros(nb)
    ce = np.cos(sole_geom[:, 4])
    se = np.sin(sole_geom[:, 4])
    # an ellipse whose centre is higher than its larger semi-axis cannot touch z = 0
    reach = np.maximum(sole_geom[:, 2], sole_geom[:, 3]) * 1.000001
    om = np.zeros(nb)
    al = np.zeros(nb)
    R = np.zeros((nb, 2))
    VR = np.zeros((nb, 2))
    AR = np.zeros((nb, 2))
    M = np.zeros((nj, nj))
    Jq = np.zeros((nj, nj))
    Jv = np.zeros((nj, nj))
    rhs = np.zeros(nj)
    dv = np.zeros(nj)
    vi = np.zeros(nj)
    res = np.zeros(nj)
    qh = np.zeros(nj)
    vh = np.zeros(nj)
    qp = np.zeros(nj)
    vp = np.zeros(nj)
    q = q0.copy()
    v = v0.copy()
    qs = np.zeros(nj)
    q_save = np.zeros(nj)
    v_save = np.zeros(nj)
    qp_save = np.zeros(nj)
    vp_save = np.zeros(nj)
    fe = np.zeros((ne, 2))
    pe = np.zeros((ne, 2))
    regime = np.zeros(ne, np.int64)
    regime_old = np.zeros(ne, np.int64)
    onset = np.full(ne, -(10**9), np.int64)  # step at which each element became loaded
    window = int(SLIDE_WINDOW / dt + 0.5)
    # the clamp row of the current (sub-)step, copied so that no array view is made per step
    ncol = base.shape[1]
    bs = np.zeros(ncol)
    vc = contact[8]
    # a 12th column of ``base`` holds the utilised friction ratio r(t) (drive "utilised-friction")
    utilised = base.shape[1] == UTILISED_COLUMN + 1
    grf_driven = base.shape[1] == GRF_Z_COLUMN + 1
    wgt = np.zeros(ne)  # grf-driven: share of the measured GRF carried by each sole element
    fn_model = np.zeros(ne)
    dep_model = np.full(ne, -1e300)
    w_clamp = 0.0
    d_joint = 0.0
    d_contact = 0.0
    d_friction = 0.0
    have_history = False
    # compliant track layer in series with the contact: its deflection per element is a state
    kt = contact[9]
    ct = contact[10]
    track = kt > 0.0
    ut = np.zeros(ne)
    utp = np.zeros(ne)
    ut_new = np.zeros(ne)
    wt = np.zeros(ne)
    dud = np.zeros(ne)
    ut_save = np.zeros(ne)
    utp_save = np.zeros(ne)
    d_track = 0.0

    for i in range(n_steps + 1):
        if i > 0:
            for j in range(nj):
                q_save[j] = q[j]
                v_save[j] = v[j]
                qp_save[j] = qp[j]
                vp_save[j] = vp[j]
            for e in range(ne):
                ut_save[e] = ut[e]
                utp_save[e] = utp[e]
            n_here = 1
            for attempt in range(2):
                wc = 0.0
                dj = 0.0
                dc = 0.0
                df = 0.0
                dtk = 0.0
                h = dt / n_here
                changed = False
                for k in range(1, n_here + 1):
                    if n_here == 1:
                        for c in range(ncol):
                            bs[c] = base[i, c]
                        use_bdf2 = (order == 2) & have_history
                    else:
                        f = k / n_here
                        for c in range(ncol):
                            bs[c] = base[i - 1, c] + f * (base[i, c] - base[i - 1, c])
                        use_bdf2 = (order == 2) & (k > 1)
                    if use_bdf2:
                        # BDF2: x_{n+1} = 4/3 x_n - 1/3 x_{n-1} + 2/3 h f(x_{n+1})
                        g = 2.0 * h / 3.0
                        for j in range(nj):
                            qh[j] = (4.0 * q[j] - qp[j]) / 3.0
                            vh[j] = (4.0 * v[j] - vp[j]) / 3.0
                            vi[j] = 2.0 * v[j] - vp[j]
                    else:
                        g = h
                        for j in range(nj):
                            qh[j] = q[j]
                            vh[j] = v[j]
                            vi[j] = v[j]
                    p_fric = 0.0
                    p_cdamp = 0.0
                    p_track = 0.0
                    for _it in range(n_iter):
                        for j in range(nj):
                            qs[j] = qh[j] + g * vi[j]
                        _kinematics(bs, qs, vi, hinge, com0, Ob, vO, aO, phi, cph, sph, om, al, R, VR, AR)
                        for j in range(nj):
                            hx = Ob[j + 1, 0]
                            hz = Ob[j + 1, 1]
                            acc = 0.0
                            for k in range(j, nj):
                                kx = Ob[k + 1, 0]
                                kz = Ob[k + 1, 1]
                                mjk = 0.0
                                for b in range(k + 1, nb):
                                    mjk += (body_mass[b] * ((R[b, 0] - hx) * (R[b, 0] - kx)
                                                            + (R[b, 1] - hz) * (R[b, 1] - kz))
                                            + body_inertia[b])
                                M[j, k] = mjk
                                M[k, j] = mjk
                                Jq[j, k] = 0.0
                                Jq[k, j] = 0.0
                                Jv[j, k] = 0.0
                                Jv[k, j] = 0.0
                            for b in range(j + 1, nb):
                                rx = R[b, 0] - hx
                                rz = R[b, 1] - hz
                                # gravity minus inertia (bias) generalised force
                                acc += body_mass[b] * (STANDARD_GRAVITY * rx - (AR[b, 0] * rz - AR[b, 1] * rx))
                                acc -= body_inertia[b] * al[b]
                            qa = qs[j]
                            acc -= stiffness[j] * qa + stiffness_quadratic[j] * qa * abs(qa) + damping[j] * vi[j]
                            Jq[j, j] -= stiffness[j] + 2.0 * stiffness_quadratic[j] * abs(qa)
                            Jv[j, j] -= damping[j]
                            rhs[j] = acc
                        p_fric = 0.0
                        p_cdamp = 0.0
                        p_track = 0.0
                        for e in range(ne):
                            b = sole_body[e]
                            cx, cz = _body_point(b, sole_geom[e, 0], sole_geom[e, 1], hinge, Ob, cph, sph)
                            if cz > reach[e] and not grf_driven:  # far above the ground: no force
                                fe[e, 0] = 0.0
                                fe[e, 1] = 0.0
                                regime[e] = 0
                                if track:  # the track relaxes on its own
                                    uhe = (4.0 * ut[e] - utp[e]) / 3.0 if use_bdf2 else ut[e]
                                    ut_new[e] = ct * uhe / g / (kt + ct / g)
                                    wt[e] = (ut_new[e] - uhe) / g
                                    dud[e] = 0.0
                                    p_track += ct * wt[e] * wt[e]
                                continue
                            (px, pz, fx, fz, depth, rate, slip, kn, cn, mu, dmu, fel) = sole_contact(
                                contact, cx, cz, sph[b] * ce[e] + cph[b] * se[e], cph[b] * ce[e] - sph[b] * se[e],
                                sole_geom[e, 2], sole_geom[e, 3],
                                Ob[b, 0], Ob[b, 1], vO[b, 0], vO[b, 1], om[b], ground_vx)
                            rc = rate
                            if track:
                                uhe = (4.0 * ut[e] - utp[e]) / 3.0 if use_bdf2 else ut[e]
                                (fz, kn, cn, fel, u_e, w_e, dud_e) = track_contact(
                                    contact, depth, rate, uhe, g)
                                ut_new[e] = u_e
                                wt[e] = w_e
                                dud[e] = dud_e
                                rc = rate - w_e
                                p_track += ct * w_e * w_e
                                mu = 0.0
                                dmu = 0.0
                                if fz > 0.0:
                                    mu, dmu = friction(contact, slip)
                                fx = -mu * fz
                            if grf_driven:
                                # measured GRF applied at the element's lowest point, share wgt[e]
                                fn_model[e] = fz
                                dep_model[e] = depth
                                fx = bs[GRF_X_COLUMN] * wgt[e]
                                fz = bs[GRF_Z_COLUMN] * wgt[e]
                                kn = 0.0
                                cn = 0.0
                                mu = 0.0
                                dmu = 0.0
                            elif utilised:
                                # utilised friction: Fx = r(t)·Fn with the measured r = Fx/Fz
                                mu = -bs[UTILISED_COLUMN]
                                dmu = 0.0
                                fx = -mu * fz
                            fe[e, 0] = fx
                            fe[e, 1] = fz
                            pe[e, 0] = px
                            pe[e, 1] = pz
                            if fz == 0.0:
                                regime[e] = 0
                                continue
                            speed = abs(slip)
                            if fz < REGIME_MIN_FORCE or grf_driven:
                                regime[e] = 0  # a barely touching element: no refinement
                            elif utilised:
                                regime[e] = 1  # no stick/slip regimes: refine only at touch-down
                            elif speed <= vc:
                                regime[e] = 1
                            else:
                                regime[e] = 2 if speed < 1.5 * vc else 3
                            p_fric += -fx * slip
                            p_cdamp += (fz - fel) * rc
                            # gradients of (fx, fz) with respect to the point's position and velocity
                            gv00 = -dmu * fz
                            gv01 = mu * cn
                            gv11 = -cn
                            gp01 = mu * kn
                            gp11 = -kn
                            for j in range(b):
                                jx = pz - Ob[j + 1, 1]
                                jz = -(px - Ob[j + 1, 0])
                                rhs[j] += fx * jx + fz * jz
                                for k in range(b):
                                    kx = pz - Ob[k + 1, 1]
                                    kz = -(px - Ob[k + 1, 0])
                                    Jv[j, k] += jx * (gv00 * kx + gv01 * kz) + jz * (gv11 * kz)
                                    Jq[j, k] += jx * (gp01 * kz) + jz * (gp11 * kz)
                        for j in range(nj):
                            acc = g * rhs[j]
                            for k in range(nj):
                                acc -= M[j, k] * (vi[k] - vh[k])
                            res[j] = acc
                        for j in range(nj):
                            for k in range(nj):
                                M[j, k] = M[j, k] - g * Jv[j, k] - g * g * Jq[j, k]
                        _solve(M, res, dv)
                        for j in range(nj):
                            vi[j] += dv[j]
                        if track:
                            # the track deflection follows the final velocity (linearised)
                            for e in range(ne):
                                if dud[e] != 0.0:
                                    dr = 0.0
                                    for j in range(sole_body[e]):
                                        dr += (pe[e, 0] - Ob[j + 1, 0]) * dv[j]
                                    ut_new[e] += dud[e] * dr
                    if with_energy:
                        # clamp power with the step's accelerations (v_{n+1} - v_n) / h
                        fcx = 0.0
                        fcz = 0.0
                        tc = 0.0
                        for b in range(nb):
                            ax = AR[b, 0]
                            az = AR[b, 1]
                            alb = al[b]
                            for j in range(b):
                                qdd = (vi[j] - v[j]) / h
                                ax += qdd * (R[b, 1] - Ob[j + 1, 1])
                                az -= qdd * (R[b, 0] - Ob[j + 1, 0])
                                alb += qdd
                            m = body_mass[b]
                            fcx += m * ax
                            fcz += m * (az + STANDARD_GRAVITY)
                            rx = R[b, 0] - bs[0]
                            rz = R[b, 1] - bs[1]
                            tc += m * (ax * rz - (az + STANDARD_GRAVITY) * rx) + body_inertia[b] * alb
                        for e in range(ne):
                            fcx -= fe[e, 0]
                            fcz -= fe[e, 1]
                            tc -= fe[e, 0] * (pe[e, 1] - bs[1]) - fe[e, 1] * (pe[e, 0] - bs[0])
                        wc += h * (fcx * bs[3] + fcz * bs[4] + tc * bs[5])
                    for j in range(nj):
                        qp[j] = q[j]
                        vp[j] = v[j]
                        v[j] = vi[j]
                        q[j] = qh[j] + g * vi[j]
                        dj += h * damping[j] * v[j] * v[j]
                    dc += h * p_cdamp
                    df += h * p_fric
                    dtk += h * p_track
                    if track:
                        for e in range(ne):
                            utp[e] = ut[e]
                            ut[e] = ut_new[e]
                    for e in range(ne):
                        if regime[e] != regime_old[e] or (regime[e] >= 2
                                                          and i - onset[e] <= window):
                            changed = True
                if attempt == 0 and changed and refine > 1 and i > 1:
                    # the contact law changes regime or slides in this step: redo it in sub-steps
                    for j in range(nj):
                        q[j] = q_save[j]
                        v[j] = v_save[j]
                        qp[j] = qp_save[j]
                        vp[j] = vp_save[j]
                    for e in range(ne):
                        ut[e] = ut_save[e]
                        utp[e] = utp_save[e]
                    n_here = refine
                    continue
                break
            if n_here > 1:
                for j in range(nj):
                    qp[j] = q_save[j]
                    vp[j] = v_save[j]
                for e in range(ne):
                    utp[e] = ut_save[e]
            have_history = True
            if grf_driven:
                # the split of the measured GRF for the next step: the model's normal forces;
                # none (sole off the model ground): keep the last split, or the lowest element
                tot = 0.0
                for e in range(ne):
                    tot += max(fn_model[e], 0.0)
                if tot > 0.0:
                    for e in range(ne):
                        wgt[e] = max(fn_model[e], 0.0) / tot
                elif np.sum(wgt) == 0.0:
                    wgt[np.argmax(dep_model)] = 1.0
            for e in range(ne):
                if regime_old[e] == 0 and regime[e] > 0:
                    onset[e] = i
                regime_old[e] = regime[e]
            w_clamp += wc
            d_joint += dj
            d_contact += dc
            d_friction += df
            d_track += dtk
            for j in range(nj):
                if not (math.isfinite(q[j]) and abs(q[j]) < 10.0):
                    return STATUS_DIVERGED, i
        if i % nsub == 0:
            # ---- outputs at a sample time, from the state itself ----
            s_idx = i // nsub
            for c in range(ncol):
                bs[c] = base[i, c]
            _kinematics(bs, q, v, hinge, com0, Ob, vO, aO, phi, cph, sph, om, al, R, VR, AR)
            e_contact = 0.0
            for e in range(ne):
                b = sole_body[e]
                cx, cz = _body_point(b, sole_geom[e, 0], sole_geom[e, 1], hinge, Ob, cph, sph)
                if cz > reach[e] and not grf_driven:  # far above the ground
                    grf[s_idx, e, 0] = 0.0
                    grf[s_idx, e, 1] = 0.0
                    state[s_idx, e] = 0
                    if track and with_energy:
                        e_contact += 0.5 * kt * ut[e] * ut[e]
                    continue
                (px, pz, fx, fz, depth, rate, slip, kn, cn, mu, dmu, fel) = sole_contact(
                    contact, cx, cz, sph[b] * ce[e] + cph[b] * se[e],
                    cph[b] * ce[e] - sph[b] * se[e], sole_geom[e, 2], sole_geom[e, 3],
                    Ob[b, 0], Ob[b, 1], vO[b, 0], vO[b, 1], om[b], ground_vx)
                depth_c = depth
                if track:
                    fz, _fel, _w = track_state_force(contact, depth, rate, ut[e])
                    mu = 0.0
                    if fz > 0.0:
                        mu, _dmu = friction(contact, slip)
                    fx = -mu * fz
                    depth_c = depth - ut[e]
                if grf_driven:
                    fx = bs[GRF_X_COLUMN] * wgt[e]
                    fz = bs[GRF_Z_COLUMN] * wgt[e]
                elif utilised:
                    fx = bs[UTILISED_COLUMN] * fz
                grf[s_idx, e, 0] = fx
                grf[s_idx, e, 1] = fz
                if depth_c <= 0.0:
                    state[s_idx, e] = 0
                elif abs(slip) <= vc:
                    state[s_idx, e] = 1
                else:
                    state[s_idx, e] = 2
                if with_energy:
                    e_contact += contact_elastic_energy(contact, depth_c)
                    if track:
                        e_contact += 0.5 * kt * ut[e] * ut[e]
            tx, tz = _body_point(tip_body, tip[0], tip[1], hinge, Ob, cph, sph)
            dist[s_idx] = math.hypot(tx - bs[0], tz - bs[1])
            spring = 0.0
            for j in range(nj):
                qa = q[j]
                qout[s_idx, j] = qa
                tau[s_idx, j] = -(stiffness[j] * qa + stiffness_quadratic[j] * qa * abs(qa)
                                  + damping[j] * v[j])
                spring += 0.5 * stiffness[j] * qa * qa + stiffness_quadratic[j] * abs(qa) ** 3 / 3.0
            if with_energy:
                kin = 0.0
                pot = 0.0
                for b in range(nb):
                    kin += 0.5 * body_mass[b] * (VR[b, 0] ** 2 + VR[b, 1] ** 2)
                    kin += 0.5 * body_inertia[b] * om[b] ** 2
                    pot += body_mass[b] * STANDARD_GRAVITY * R[b, 1]
                energy[s_idx, 0] = w_clamp
                energy[s_idx, 1] = kin
                energy[s_idx, 2] = pot
                energy[s_idx, 3] = spring
                energy[s_idx, 4] = e_contact
                energy[s_idx, 5] = d_joint
                energy[s_idx, 6] = d_contact
                energy[s_idx, 7] = d_friction
                energy[s_idx, 8] = d_track
    return STATUS_OK, -1


@njit(cache=True, parallel=True)
def simulate_batch_parallel(model, drive, params, solver, out, status):
    """Many parameter sets over numba threads (``prange``); results identical to the serial one.

    ``params`` :class:`JointParams` of (n_sets, nj) arrays; ``out`` :class:`KernelOutputs` with a
    leading n_sets axis; ``status`` (n_sets, 2) int64 receives :func:`simulate_prescribed`'s
    return value per set.
    """
    for s in prange(params.stiffness.shape[0]):
        st, at = simulate_prescribed(
            model, drive,
            JointParams(params.stiffness[s], params.damping[s], params.stiffness_quadratic[s]),
            solver,
            KernelOutputs(out.grf[s], out.dist[s], out.qout[s], out.tau[s], out.state[s],
                          out.energy[s]))
        status[s, 0] = st
        status[s, 1] = at


@njit(cache=True)
def simulate_batch_serial(model, drive, params, solver, out, status):
    """The sets one after the other in one compiled call (no per-set dispatch cost).

    Arguments as :func:`simulate_batch_parallel`.
    """
    for s in range(params.stiffness.shape[0]):
        st, at = simulate_prescribed(
            model, drive,
            JointParams(params.stiffness[s], params.damping[s], params.stiffness_quadratic[s]),
            solver,
            KernelOutputs(out.grf[s], out.dist[s], out.qout[s], out.tau[s], out.state[s],
                          out.energy[s]))
        status[s, 0] = st
        status[s, 1] = at


refresh_stale_caches(globals())
