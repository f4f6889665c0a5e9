"""Sole–ground contact for the planar kernel: ellipse geometry, the normal laws with their
derivatives, stick-slip friction and the compliant track layer in series with the contact.

All functions are numba ``njit`` with ``inline="always"``: they are inlined into the kernel's step
at numba-IR level (a separately compiled call with array arguments cost more than the physics).
``contact`` is the chain's contact vector (:class:`bladelab.sim.chain.Chain`): law code, k, c,
transition width, exponent, dissipation, μ_s, μ_k, v_c, track stiffness k_t (0 = rigid ground),
track damping c_t. Equations: ``docs/blade-model.md`` (Contact geometry and law; Compliant track
layer).
"""

from __future__ import annotations

import math

from numba import njit

from bladelab.contact import (
    hunt_crossley_force,
    smooth_spring_damper_force,
    smoothstep,
    stick_slip_friction_coefficient,
)
from bladelab.numba_cache import refresh_stale_caches


@njit(cache=True, inline="always", error_model="numpy")
def normal_force(contact, depth, rate):
    """Normal force, ∂F/∂depth, ∂F/∂rate and the elastic part of the force (for energy)."""
    law = int(contact[0])
    k = contact[1]
    if law == 0:
        c = contact[2]
        w = contact[3]
        force = smooth_spring_damper_force(depth, rate, k, c, w)
        if force <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        if w > 0.0:
            u = depth / w
            s = smoothstep(u)
            ds = 6.0 * u * (1.0 - u) / w if u < 1.0 else 0.0
        else:
            s = 1.0
            ds = 0.0
        return force, ds * (k * depth + c * rate) + s * k, s * c, s * k * depth
    n = contact[4]
    d = contact[5]
    force = hunt_crossley_force(depth, rate, k, n, d)
    if force <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    dn = depth**n
    return force, n * k * depth ** (n - 1.0) * (1.0 + 1.5 * d * rate), 1.5 * d * k * dn, k * dn


@njit(cache=True, inline="always", error_model="numpy")
def contact_elastic_energy(contact, depth):
    """Energy [J] stored by the elastic part of the normal law at penetration ``depth`` [m]."""
    if depth <= 0.0:
        return 0.0
    k = contact[1]
    if int(contact[0]) == 0:
        w = contact[3]
        if w <= 0.0:
            return 0.5 * k * depth * depth
        if depth < w:
            return k * (0.75 * depth**4 / w**2 - 0.4 * depth**5 / w**3)
        return 0.35 * k * w * w + 0.5 * k * (depth * depth - w * w)
    n = contact[4]
    return k * depth ** (n + 1.0) / (n + 1.0)


@njit(cache=True, inline="always", error_model="numpy")
def law_affine(contact, dc):
    """The normal law at contact penetration ``dc`` written as F = E + B·rate (before the
    no-adhesion clip): returns (E, B, ∂E/∂dc, ∂B/∂dc)."""
    if dc <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    k = contact[1]
    if int(contact[0]) == 0:
        c = contact[2]
        w = contact[3]
        if w > 0.0:
            u = dc / w
            s = smoothstep(u)
            ds = 6.0 * u * (1.0 - u) / w if u < 1.0 else 0.0
        else:
            s = 1.0
            ds = 0.0
        return s * k * dc, s * c, ds * k * dc + s * k, ds * c
    n = contact[4]
    d = contact[5]
    dn = dc**n
    ddn = n * dc ** (n - 1.0)
    return k * dn, 1.5 * d * k * dn, k * ddn, 1.5 * d * k * ddn


@njit(cache=True, inline="always", error_model="numpy")
def _series_contact(contact, depth, rate, u, uh, g):
    """The contact law on the track deflected by ``u`` [m] (u̇ = (u − ``uh``)/``g``): force
    [N] (0 when the law pulls), its derivatives by the contact's penetration and rate (0 then),
    the law's elastic part and u̇ [m/s]."""
    w = (u - uh) / g
    e_el, bb, de, db = law_affine(contact, depth - u)
    fc = e_el + bb * (rate - w)
    if fc > 0.0:
        return fc, de + db * (rate - w), bb, e_el, w
    return 0.0, 0.0, 0.0, e_el, w


@njit(cache=True, inline="always", error_model="numpy")
def track_contact(contact, depth, rate, uh, g):
    """Normal force through a massless track layer in series with the contact law.

    The track surface is pressed down by u ≥ 0 [m] (a spring k_t = ``contact[9]`` [N/m] and
    damper c_t = ``contact[10]`` [N·s/m]); the sole penetrates the deflected surface by
    δ_c = ``depth`` − u at the rate ``rate`` − u̇. The force is the same in both:
    F = F_c(δ − u, δ̇ − u̇) = k_t u + c_t u̇. ``u`` is integrated implicitly,
    u = ``uh`` + ``g``·u̇ (BDF2: uh = (4u_n − u_{n−1})/3, g = 2h/3; Euler: uh = u_n, g = h), so
    the step solves one monotone scalar equation (safeguarded Newton).

    Returns (F, ∂F/∂δ, ∂F/∂δ̇, E, u, u̇, du/dδ̇) where ∂F/∂δ and ∂F/∂δ̇ are the series
    (effective) derivatives, E the elastic part of the contact law at δ_c (for the energy terms)
    and du/dδ̇ the change of u per change of the penetration rate along the step
    (δ = δ̂ + g·δ̇).
    """
    kt = contact[9]
    ct = contact[10]
    a = kt + ct / g  # d(track force)/du along the step
    b0 = ct * uh / g  # track force = a·u − b0
    lo = b0 / a  # the track relaxes on its own: zero force
    hi = max(depth, lo)
    u = min(max(uh, lo), hi)
    for _it in range(60):
        fc, kc, cc, _, _ = _series_contact(contact, depth, rate, u, uh, g)
        r = fc - (a * u - b0)
        if r > 0.0:
            lo = u
        else:
            hi = u
        slope = kc + cc / g + a
        un = u + r / slope
        if not (lo <= un <= hi):
            un = 0.5 * (lo + hi)
        if abs(un - u) <= 1e-14 + 1e-11 * abs(u):
            break
        u = un
    _, kc, cc, e_el, w = _series_contact(contact, depth, rate, u, uh, g)
    slope = kc + cc / g + a
    force = a * u - b0
    if force < 0.0:
        force = 0.0
    return force, a * kc / slope, a * cc / slope, e_el, u, w, (g * kc + cc) / slope


@njit(cache=True, inline="always", error_model="numpy")
def track_state_force(contact, depth, rate, u):
    """Force [N], elastic part E of the contact law and track rate u̇ [m/s] at a state (δ, δ̇, u).

    From F_c(δ − u, δ̇ − u̇) = k_t u + c_t u̇ (affine in u̇); without any damping (c = c_t = 0)
    the force is the contact law's elastic force at δ − u.
    """
    kt = contact[9]
    ct = contact[10]
    e_el, bb, _de, _db = law_affine(contact, depth - u)
    if bb + ct > 0.0:
        w = (e_el + bb * rate - kt * u) / (bb + ct)
        fc = e_el + bb * (rate - w)
        if fc <= 0.0:
            w = -kt * u / ct if ct > 0.0 else 0.0
            fc = 0.0
        return fc, e_el, w
    return e_el, e_el, 0.0


@njit(cache=True, inline="always", error_model="numpy")
def friction(contact, slip):
    """Signed μ of the stick-slip law at ``slip`` and ∂μ/∂slip (0 where friction is off)."""
    mus = contact[6]
    if mus <= 0.0:
        return 0.0, 0.0
    muk = contact[7]
    vc = contact[8]
    mu = stick_slip_friction_coefficient(slip, mus, muk, vc)
    dmu = 0.0
    speed = abs(slip)
    if speed < vc:
        dmu = mus / vc
    elif speed < 1.5 * vc:
        h = 1e-3 * vc
        dmu = (stick_slip_friction_coefficient(slip + h, mus, muk, vc)
               - stick_slip_friction_coefficient(slip - h, mus, muk, vc)) / (2.0 * h)
    return mu, dmu


@njit(cache=True, inline="always", error_model="numpy")
def sole_contact(contact, cx, cz, s, c, a, b, ox, oz, vox, voz, om, ground_vx):
    """Force of the ground on one sole ellipse (lab frame, rigid ground at z = 0).

    ``(cx, cz)`` centre [m], ``s, c`` sine and cosine of the absolute angle ψ of the ellipse's
    x axis about +y,
    ``a, b`` semi-axes [m]; ``(ox, oz)``, ``(vox, voz)`` a point of the carrying body and its
    velocity, ``om`` the body's angular velocity [rad/s]; ``ground_vx`` the ground's velocity.

    Returns (px, pz, fx, fz, depth, rate, slip, kn, cn, mu, dmu, f_elastic): the lowest point,
    the force, penetration [m] and its rate, slip velocity, ∂Fn/∂depth, ∂Fn/∂rate, μ (signed),
    ∂μ/∂slip and the elastic part of the normal force.
    """
    nrm = math.sqrt(a * a * s * s + b * b * c * c)
    px = cx + s * c * (a * a - b * b) / nrm
    pz = cz - nrm
    depth = -pz
    # material velocity of the lowest point
    vpx = vox + om * (pz - oz)
    vpz = voz - om * (px - ox)
    rate = -vpz
    slip = vpx - ground_vx
    if depth <= 0.0:
        return px, pz, 0.0, 0.0, depth, rate, slip, 0.0, 0.0, 0.0, 0.0, 0.0
    fn, kn, cn, fel = normal_force(contact, depth, rate)
    mu = 0.0
    dmu = 0.0
    if fn > 0.0:
        mu, dmu = friction(contact, slip)
    return px, pz, -mu * fn, fn, depth, rate, slip, kn, cn, mu, dmu, fel


refresh_stale_caches(globals())
