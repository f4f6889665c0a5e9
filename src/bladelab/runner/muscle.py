"""Hill-type muscle–tendon units with activation dynamics and a compliant tendon (numba).

A Geyer & Herr (2010) / Millard (2012, damped equilibrium) class model, normalised by the
maximum isometric force ``Fmax``, the optimal fibre length ``l_opt`` and the maximum contraction
velocity ``v_max`` (column ``MP_VMAX``, in optimal fibre lengths per second: 10 l_opt/s unless
the parameter set says otherwise):

- activation ``da/dt = (u − a)·r`` with ``r = 100 /s`` when rising and ``25 /s`` when falling
  (SCONE's H0918 integrator settings), ``a`` kept in [0.01, 1];
- active force–length ``f_l(l̃) = exp(ln(0.05)·|(l̃ − 1)/0.56|³)`` (Geyer 2010);
- force–velocity, ``ṽ = v/v_max`` (> 0 lengthening): ``(1 + ṽ)/(1 − 4ṽ)`` when shortening
  (Hill, a/F0 = 0.25; 0 at ṽ = −1), ``1.5 − 0.5/(1 + 10ṽ)`` when lengthening (1.5·Fmax eccentric
  plateau, slope continuous at 0);
- passive fibre ``f_p = ((l̃ − 1)/e₀)²`` for l̃ > 1 (e₀ = 0.6 unless the parameter set says
  otherwise, column ``MP_PSTRAIN``); fibre damping ``β·ṽ`` with β = 0.1 (Millard);
- tendon ``f_t = (ε/ε_ref)²`` for strain ε > 0, ε_ref the strain at Fmax per muscle (column
  ``MP_TSTRAIN``; Geyer 2010's 4 % unless the parameter set says otherwise);
- pennation at constant fibre height ``l_ce·sin α = l_opt·sin α₀``.

The active force can be stronger than the force that normalises the tendon and passive curves:
``s·a·f_l·f_v`` with the muscle's active strength ``s`` (column ``MP_ACTIVE``, 1 unless the
parameter set gives an active specific tension), so that a literature specific tension raises
what the fibre can do without stiffening the tendon or the passive tissue.

Equilibrium ``(s·a·f_l·f_v + f_p + β·ṽ)·cos α = f_t`` is solved for the fibre velocity each step,
implicitly (backward Euler in the fibre length, Newton), so the fibre stays stable at any
activation with the explicit multibody step. The tendon force is a function of the state
(``l_mtu``, ``l_ce``); the muscle power is ``F_t·v_mtu`` (seed 001 eq. 2.12).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bladelab.numba_cache import refresh_stale_caches

#: The default maximum shortening velocity [optimal fibre lengths/s] (Zajac 1989's 10; the
#: parameter set may give another, column ``MP_VMAX``).
V_MAX_OPT_PER_S = 10.0
ACTIVATION_RATE = 100.0
DEACTIVATION_RATE = 25.0
MIN_ACTIVATION = 0.01
FIBER_DAMPING = 0.1
TENDON_REF_STRAIN = 0.04
PASSIVE_STRAIN = 0.6
FL_WIDTH = 0.56  # Geyer's force–length width [optimal lengths]
FV_SHORTENING = 4.0  # Hill's shortening branch (1 + ṽ)/(1 − 4ṽ), a/F0 = 0.25
FV_LENGTHENING = 10.0  # lengthening branch 1.5 − 0.5/(1 + 10ṽ)
FV_ECCENTRIC = 1.5  # eccentric force plateau [Fmax]
_LN_005 = math.log(0.05)

# The compiled functions use numpy's error model: no division here can have a zero divisor
# (every denominator is bounded away from 0), so results are those of Python's model, without
# its ZeroDivisionError checks in the Newton loop (measured: muscle_step ~1/3 cheaper).

# muscle_step: ``_nrt=False``, no reference counting per step (bladelab.runner.kernel); the
# functions it calls inherit it.

# Columns of the muscle parameter array ``mp`` (one row per muscle): Fmax [N] (the force that
# normalises the tendon curve and the passive fibre force), l_opt [m], l_ts [m], pennation
# [rad], tendon strain at Fmax [-], active strength [-] (the active fibre force is
# a·f_l·f_v·Fmax times it; bladelab.runner.params.RunnerParams.active_specific_tension),
# passive fibre strain at Fmax [-] (the passive curve's e₀), maximum shortening velocity
# [l_opt/s] (bladelab.runner.params.RunnerParams.max_shortening_velocity_lopt_per_s).
MP_FMAX, MP_LOPT, MP_LTS, MP_PENN, MP_TSTRAIN, MP_ACTIVE, MP_PSTRAIN = 0, 1, 2, 3, 4, 5, 6
MP_VMAX = 7
#: Columns of the muscle parameter array.
MP_COLUMNS = 8
# Columns of the muscle state array ``ms``.
MS_ACT, MS_LCE, MS_VCE, MS_FORCE = 0, 1, 2, 3


@njit(cache=True, error_model="numpy")
def force_length(l_norm: float) -> float:
    """Active force–length factor f_l [-] of the normalised fibre length."""
    x = abs((l_norm - 1.0) / FL_WIDTH)
    return math.exp(_LN_005 * x * x * x)


@njit(cache=True, error_model="numpy")
def force_velocity(v_norm: float) -> float:
    """Force–velocity factor f_v [-] of the normalised fibre velocity (> 0 lengthening)."""
    if v_norm <= 0.0:
        if v_norm <= -1.0:
            return 0.0
        return (1.0 + v_norm) / (1.0 - FV_SHORTENING * v_norm)
    return FV_ECCENTRIC - (FV_ECCENTRIC - 1.0) / (1.0 + FV_LENGTHENING * v_norm)


@njit(cache=True, error_model="numpy")
def _force_velocity_slope(v_norm: float) -> float:
    if v_norm <= 0.0:
        if v_norm <= -1.0:
            return 0.0
        d = 1.0 - 4.0 * v_norm
        return 5.0 / (d * d)
    d = 1.0 + 10.0 * v_norm
    return 5.0 / (d * d)


@njit(cache=True, error_model="numpy")
def passive_force(l_norm: float, strain: float = PASSIVE_STRAIN) -> float:
    """Passive fibre force f_p [-] of the normalised fibre length; ``strain``: the fibre
    strain at which it reaches Fmax (e₀)."""
    if l_norm <= 1.0:
        return 0.0
    x = (l_norm - 1.0) / strain
    return x * x


@njit(cache=True, error_model="numpy")
def tendon_force(strain: float, ref_strain: float = TENDON_REF_STRAIN) -> float:
    """Tendon force f_t [-] of the tendon strain; ``ref_strain`` is the strain at Fmax."""
    if strain <= 0.0:
        return 0.0
    x = strain / ref_strain
    return x * x


@njit(cache=True, error_model="numpy")
def _cos_pennation(l_ce: float, l_opt: float, penn0: float) -> float:
    return _cos_pennation_of_height(l_ce, l_opt * math.sin(penn0))


@njit(cache=True, error_model="numpy")
def _cos_pennation_of_height(l_ce: float, h: float) -> float:
    """cos α at fibre length ``l_ce`` [m] for the constant fibre height ``h = l_opt·sin α₀``
    [m] (:func:`_cos_pennation` with the sine computed once). Unpennate fibres (``h`` = 0,
    half of H0918's muscles) skip the division and root: the same 1.0."""
    if h == 0.0:
        return 1.0
    s = h / max(l_ce, 1e-6)
    if s > 0.99:
        s = 0.99
    return math.sqrt(1.0 - s * s)


@njit(cache=True, error_model="numpy")
def tendon_force_of_state(
    l_mtu: float,
    l_ce: float,
    fmax: float,
    l_opt: float,
    l_ts: float,
    penn0: float,
    ref_strain: float = TENDON_REF_STRAIN,
) -> float:
    """Tendon force [N] given the MTU length [m] and fibre length [m]."""
    return _tendon_force_of_height(l_mtu, l_ce, fmax, l_opt * math.sin(penn0), l_ts, ref_strain)


@njit(cache=True, error_model="numpy")
def _tendon_force_of_height(l_mtu: float, l_ce: float, fmax: float, height: float,
                            l_ts: float, ref_strain: float) -> float:
    """:func:`tendon_force_of_state` [N] for the fibre height ``height = l_opt·sin α₀`` [m]
    (computed once per muscle by :func:`muscle_step`)."""
    l_t = l_mtu - l_ce * _cos_pennation_of_height(l_ce, height)
    return fmax * tendon_force((l_t - l_ts) / l_ts, ref_strain)


@njit(cache=True, error_model="numpy")
def equilibrium_fiber_length(
    l_mtu: float,
    act: float,
    l_opt: float,
    l_ts: float,
    penn0: float,
    ref_strain: float = TENDON_REF_STRAIN,
    active: float = 1.0,
    passive_strain: float = PASSIVE_STRAIN,
) -> float:
    """Fibre length [m] in static equilibrium (ṽ = 0) at activation ``act`` (bisection);
    ``active``: the muscle's active strength (:data:`MP_ACTIVE`), ``passive_strain`` its
    passive curve's e₀ (:data:`MP_PSTRAIN`)."""
    lo = 0.3 * l_opt
    hi = min(2.0 * l_opt, max(l_mtu - 0.5 * l_ts, 0.31 * l_opt))
    if hi <= lo:
        return lo
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        c = _cos_pennation(mid, l_opt, penn0)
        ln = mid / l_opt
        f_fib = (active * act * force_length(ln) + passive_force(ln, passive_strain)) * c
        f_ten = tendon_force((l_mtu - mid * c - l_ts) / l_ts, ref_strain)
        if f_fib > f_ten:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def fibre_heights(mp: np.ndarray) -> np.ndarray:
    """The constant fibre heights ``l_opt·sin α₀`` [m] of the muscles ``mp`` (the values
    :func:`muscle_step` computes each step: Python's ``math.sin`` is the same libm ``sin``)."""
    return np.array([row[MP_LOPT] * math.sin(row[MP_PENN]) for row in mp], dtype=float)


def equilibrium_fiber_lengths(mp: np.ndarray, l_mtu, activation) -> np.ndarray:
    """Fibre lengths [m] of the muscles ``mp`` (one row each) in static equilibrium
    (:func:`equilibrium_fiber_length`) at their MTU lengths ``l_mtu`` [m] and activations
    ``activation`` [-] (one per muscle, or one for all)."""
    l_mtu = np.asarray(l_mtu, dtype=float)
    act = np.broadcast_to(np.asarray(activation, dtype=float), l_mtu.shape)
    return np.array([equilibrium_fiber_length(l_mtu[i], act[i], *mp[i, MP_LOPT:MP_VMAX])
                     for i in range(mp.shape[0])], dtype=float)


@njit(cache=True, error_model="numpy", _nrt=False)
def muscle_step(
    mp: np.ndarray, ms: np.ndarray, l_mtu: np.ndarray, u: np.ndarray, dt: float,
    tol: float = 1e-8, height: np.ndarray | None = None, l_prev: np.ndarray | None = None,
    v_mtu: np.ndarray | None = None,
) -> None:
    """Advance all muscles by one step and store their tendon forces.

    ``mp`` (n, 8): Fmax [N], l_opt [m], l_ts [m], pennation α₀ [rad], tendon strain at Fmax
    [-], active strength [-] (:data:`MP_ACTIVE`), passive strain at Fmax [-]
    (:data:`MP_PSTRAIN`), maximum shortening velocity [l_opt/s] (:data:`MP_VMAX`). ``ms``
    (n, 4) in/out:
    activation, fibre length [m], fibre velocity [m/s], tendon force [N] (the force to apply
    during this step, computed from the state at the step's start). ``l_mtu`` [m], ``u`` [-]
    excitations in [0, 1]. ``tol``: the Newton iteration on the normalised fibre velocity stops
    after a step smaller than this (1e-8 by default; the implicit scheme uses 1e-6: 2.4
    instead of 3.3 iterations per muscle and step at 1 ms, measured). ``height`` [m]: the fibre
    heights ``l_opt·sin α₀`` (:func:`fibre_heights`) when the caller keeps them between steps
    (the same values: one ``sin`` per muscle and step less); None computes them here.

    Second order (the Newmark scheme, :mod:`bladelab.runner.implicit`): with ``l_prev`` (the
    fibre lengths [m] of the previous step, in/out; 0 where there is none yet) the fibre takes
    a BDF2 step, ``l' = (4·l − l_prev)/3 + (2/3)·dt·v'``, in equilibrium with the MTU length
    at the step's end, ``l_mtu + dt·v_mtu`` [m, m/s]. Without them: implicit Euler against
    the step's start length (first order).
    """
    if mp.shape[1] <= MP_VMAX:
        raise ValueError("muscle parameters need 8 columns (the last three: active strength, "
                         "passive strain at Fmax, maximum shortening velocity)")
    n = mp.shape[0]
    for i in range(n):
        fmax = mp[i, MP_FMAX]
        l_opt = mp[i, MP_LOPT]
        l_ts = mp[i, MP_LTS]
        penn0 = mp[i, MP_PENN]
        eref = mp[i, MP_TSTRAIN]
        active = mp[i, MP_ACTIVE]
        e0 = mp[i, MP_PSTRAIN]
        act = ms[i, MS_ACT]
        l_ce = ms[i, MS_LCE]
        lm = l_mtu[i]
        if height is None:
            h = l_opt * math.sin(penn0)  # as tendon_force_of_state computes it
        else:
            h = height[i]
        ms[i, MS_FORCE] = _tendon_force_of_height(lm, l_ce, fmax, h, l_ts, eref)
        # fibre: implicit Euler (or BDF2), Newton on the normalised velocity
        base = l_ce
        step_dt = dt
        if l_prev is not None:
            if v_mtu is not None:
                lm = lm + dt * v_mtu[i]
            if l_prev[i] > 0.0:
                base = (4.0 * l_ce - l_prev[i]) / 3.0
                step_dt = dt * (2.0 / 3.0)
            l_prev[i] = l_ce
        vscale = mp[i, MP_VMAX] * l_opt
        v = ms[i, MS_VCE] / vscale
        for _ in range(6):
            l_new = base + step_dt * v * vscale
            if l_new < 0.2 * l_opt:
                l_new = 0.2 * l_opt
            c = _cos_pennation_of_height(l_new, h)
            ln = l_new / l_opt
            fl = force_length(ln)
            strain = (lm - l_new * c - l_ts) / l_ts
            g = (
                active * act * fl * force_velocity(v) + passive_force(ln, e0) + FIBER_DAMPING * v
            ) * c - tendon_force(strain, eref)
            dft = 2.0 * strain / (eref * eref) if strain > 0.0 else 0.0
            dfp = 2.0 * (ln - 1.0) / (e0 * e0) if ln > 1.0 else 0.0
            dg = (active * act * fl * _force_velocity_slope(v) + FIBER_DAMPING) * c + (
                step_dt * vscale) * (
                dfp * c / l_opt + dft * c * c / l_ts
            )
            step = g / dg
            v -= step
            if abs(step) < tol:
                break
        l_new = base + step_dt * v * vscale
        if l_new < 0.2 * l_opt:
            l_new = 0.2 * l_opt
        ms[i, MS_LCE] = l_new
        ms[i, MS_VCE] = v * vscale
        # activation dynamics
        ui = min(max(u[i], 0.0), 1.0)
        rate = ACTIVATION_RATE if ui > act else DEACTIVATION_RATE
        act += dt * rate * (ui - act)
        ms[i, MS_ACT] = min(max(act, MIN_ACTIVATION), 1.0)


refresh_stale_caches(globals())
