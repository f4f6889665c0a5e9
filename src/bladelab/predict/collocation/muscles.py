"""Muscle–tendon dynamics for collocation (De Groote et al. 2016) as CasADi (SX) expressions.

States per muscle: activation ``a`` [-] and normalised tendon force ``F̃_T = F_T/Fmax`` [-];
controls: excitation ``u`` [-] and the tendon-force derivative ``dF̃_T/dt`` [1/s]. The fibre
velocity is implicit: from (l_MT, v_MT, F̃_T, dF̃_T/dt) the tendon length and velocity follow
from the tendon curve, the fibre length and velocity from the constant-thickness pennation
geometry, and the collocation problem imposes the fibre–tendon equilibrium

    (a·f_l(l̃)·f_v(ṽ) + f_p(l̃) + β·ṽ)·cos α − F̃_T = 0        (:func:`equilibrium_residual`)

as an algebraic constraint. Curves and constants are those of the forward Hill model
(:mod:`bladelab.runner.muscle`): Geyer's force–length (exact, C²), the Hill/eccentric
force–velocity (its two rational branches blended smoothly), the quadratic passive and tendon
curves (with a softplus at their onset, which makes the tendon curve invertible for F̃_T > 0),
fibre damping β = 0.1, ``v_max`` (the column ``MP_VMAX``, 10 l_opt/s unless set), and the
100 /s up, 25 /s down activation rates with a smooth switch. Parameters per muscle:
``RunnerModel.muscle_params`` (Fmax [N], l_opt [m], l_ts [m], pennation α₀ [rad], ...).
Arrays are column vectors over the muscles.

Domain (bounds for the NLP): ``F̃_T > 0`` (the inverse tendon curve diverges at 0; 1e-3 is a
good lower bound), ``−1 ≤ ṽ ≤ 1``, ``0.01 ≤ a ≤ 1`` and ``0 ≤ u ≤ 1`` (the forward model's).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from bladelab.predict.collocation.smooth import Smoothing, sigmoid, softplus, softplus_inverse
from bladelab.runner.muscle import (
    ACTIVATION_RATE,
    DEACTIVATION_RATE,
    FIBER_DAMPING,
    FL_WIDTH,
    FV_ECCENTRIC,
    FV_LENGTHENING,
    FV_SHORTENING,
    MP_ACTIVE,
    MP_FMAX,
    MP_LOPT,
    MP_LTS,
    MP_PENN,
    MP_PSTRAIN,
    MP_TSTRAIN,
    MP_VMAX,
    PASSIVE_STRAIN,
    TENDON_REF_STRAIN,
)


def tendon_force_curve(strain, smoothing: Smoothing, ref_strain=TENDON_REF_STRAIN):
    """Normalised tendon force [-] of the tendon strain [-]: ``(softplus(ε)/ε_ref)²``,
    ``ref_strain`` ε_ref the strain at Fmax."""
    return (softplus(strain, smoothing.tendon_strain) / ref_strain) ** 2


def tendon_strain(ft, smoothing: Smoothing, ref_strain=TENDON_REF_STRAIN):
    """Tendon strain [-] at normalised tendon force ``ft`` > 0 (inverse of the tendon curve)."""
    return softplus_inverse(ref_strain * ca.sqrt(ft), smoothing.tendon_strain)


def force_length(l_norm):
    """Active force–length factor [-] (Geyer 2010, exactly the forward model's)."""
    x = ca.fabs((l_norm - 1.0) / FL_WIDTH)
    return ca.exp(math.log(0.05) * x * x * x)


def force_velocity(v_norm, smoothing: Smoothing):
    """Force–velocity factor [-] of the normalised fibre velocity (> 0 lengthening).

    The forward branches are ``(1 + ṽ)/(1 − 4ṽ)`` (ṽ ≤ 0) and ``(1 + 15ṽ)/(1 + 10ṽ)``
    (ṽ > 0, i.e. 1.5 − 0.5/(1 + 10ṽ)); both are ``(1 + α·ṽ)/(1 + β·ṽ)``, so one smooth curve
    blends the coefficients with a sigmoid: no pole, C∞, the exact branch away from 0.
    """
    s = sigmoid(v_norm, smoothing.force_velocity)
    k = FV_SHORTENING + FV_LENGTHENING
    num = 1.0 + (1.0 + (FV_ECCENTRIC * FV_LENGTHENING - 1.0) * s) * v_norm
    den = 1.0 + (-FV_SHORTENING + k * s) * v_norm
    return num / den


def passive_force(l_norm, smoothing: Smoothing, strain=PASSIVE_STRAIN):
    """Passive fibre force [-]: ``(softplus(l̃ − 1)/e₀)²``, e₀ = ``strain`` (a number or one
    per muscle)."""
    return (softplus(l_norm - 1.0, smoothing.passive_length) / strain) ** 2


def fiber_kinematics(mp: np.ndarray, l_mt, v_mt, ft, dft, smoothing: Smoothing):
    """Fibre length [m], fibre velocity [m/s] and cos(pennation) [-] of every muscle.

    Parameters
    ----------
    mp
        ``RunnerModel.muscle_params`` (n, 5).
    l_mt, v_mt
        Muscle–tendon lengths [m] and lengthening velocities [m/s] (n,).
    ft, dft
        Normalised tendon forces [-] and their time derivatives [1/s] (n,).
    """
    l_ts = ca.DM(mp[:, MP_LTS])
    height = ca.DM(mp[:, MP_LOPT] * np.sin(mp[:, MP_PENN]))
    ref = ca.DM(mp[:, MP_TSTRAIN])
    w = smoothing.tendon_strain
    s = ref * ca.sqrt(ft)
    l_t = l_ts * (1.0 + softplus_inverse(s, w))
    # dε/dF̃ = dε/ds · ds/dF̃, with dε/ds = 1/(1 − e^{−s/w}) and ds/dF̃ = ε_ref/(2√F̃)
    v_t = l_ts * (-1.0 / ca.expm1(-s / w)) * ref / (2.0 * ca.sqrt(ft)) * dft
    along = l_mt - l_t  # fibre length projected on the tendon line
    l_m = ca.sqrt(along * along + height * height)
    return l_m, along * (v_mt - v_t) / l_m, along / l_m


def equilibrium_residual(mp: np.ndarray, a, ft, dft, l_mt, v_mt, smoothing: Smoothing):
    """Fibre–tendon equilibrium residual [-] (n,), zero on a consistent trajectory.

    ``(s·a·f_l·f_v + f_p + β·ṽ)·cos α − F̃_T`` with the fibre state of :func:`fiber_kinematics`,
    the active strength s (``MP_ACTIVE``), the passive curve's e₀ (``MP_PSTRAIN``) and ṽ in
    the muscle's maximum shortening velocity (``MP_VMAX``); ``a`` activation [-], other
    arguments as there.
    """
    l_opt = ca.DM(mp[:, MP_LOPT])
    strength = ca.DM(mp[:, MP_ACTIVE])
    e0 = ca.DM(mp[:, MP_PSTRAIN])
    l_m, v_m, cos_a = fiber_kinematics(mp, l_mt, v_mt, ft, dft, smoothing)
    ln, vn = l_m / l_opt, v_m / (ca.DM(mp[:, MP_VMAX]) * l_opt)
    fibre = (strength * a * force_length(ln) * force_velocity(vn, smoothing)
             + passive_force(ln, smoothing, e0))
    return (fibre + FIBER_DAMPING * vn) * cos_a - ft


def tendon_forces(mp: np.ndarray, ft):
    """Tendon forces [N] (n,) of normalised tendon forces ``ft``."""
    return ca.DM(mp[:, MP_FMAX]) * ft


def activation_rate(u, a, smoothing: Smoothing):
    """Activation derivative [1/s]: ``(u − a)·r`` with r from 25 /s (u < a) to 100 /s (u > a)
    through a sigmoid of ``u − a``."""
    e = u - a
    rate = DEACTIVATION_RATE + (ACTIVATION_RATE - DEACTIVATION_RATE) * sigmoid(e, smoothing.activation)
    return e * rate
