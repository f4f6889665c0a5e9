"""Muscle metabolic energy rate after Uchida et al. (2016), the Umberger (2003) model as modified
for running (seed 001 eq. 2.5).

Per muscle, rates per kilogram of muscle [W/kg] (Umberger et al. 2003; Uchida et al. 2016):

- ``A = u`` if the excitation ``u`` exceeds the activation ``a``, else ``(u + a)/2``;
- activation and maintenance heat ``ḣ_AM = (1.28·FT + 25)·A^0.6·S``, FT = fast-twitch fibres in %;
  for fibres longer than optimal ``ḣ_AM·(0.4 + 0.6·f_l)``;
- shortening heat (``ṽ = v_ce/l_opt`` < 0, in optimal lengths per second)
  ``ḣ_S = (−α_ST·ṽ·(100 − FT)/100 − α_FT·ṽ·FT/100)·A²·S`` with ``α_ST = 100/v_max,ST``,
  ``α_FT = 153/v_max,FT``, ``v_max,ST = v_max/(1 + 1.5·FT/100)``, ``v_max,FT = 2.5·v_max,ST``
  (``v_max`` the muscle model's, column ``MP_VMAX``: 10 l_opt/s unless set); times ``f_l``
  for fibres longer than optimal;
  lengthening heat ``ḣ_L = α_L·ṽ·A·S`` with ``α_L = 4·α_ST``;
- total heat ``ḣ_AM + ḣ_SL`` not below 1 W/kg (Umberger's floor);
- mechanical work rate ``ẇ = −F_ce·v_ce / m`` with the active fibre force ``F_ce`` — negative work
  (lengthening) included (Uchida 2016);
- the muscle's total ``heat + ẇ`` not below 0 (Uchida 2016 with Umberger 2010's
  "forbid negative total power", as OpenSim's Umberger2010 probe does it by raising the shortening
  heat): a lengthening muscle absorbing work costs nothing, but it earns no energy back. Without
  this floor, absorbed work is refunded one to one, and an optimiser makes every stance a
  high-force stretch–shortening cycle (measured in collocation: 5 body-weight, 0.12 s contacts
  at 3.5 m/s, ``docs/collocation.md``);
- ``S = 1.5`` (aerobic), muscle mass ``m = ρ·V`` with ``V = Fmax·l_opt/σ`` (σ = the model's specific
  tension, so V is the muscle's volume of seed 001 eq. 2.1) and ρ = 1059.7 kg/m³.

Whole body: ``Ė = basal·body mass + Σ_i Ė_i`` with basal 1.51 W/kg (Umberger 2003).

**Bhargava et al. (2004)**, the model of PredSim (Falisse et al. 2019), selected by a parameter
set's ``metabolic_model: bhargava2004``; per muscle, in W, with the slow-twitch fraction
``r = 1 − FT/100``:

- recruitment by excitation: slow ``r·sin(πu/2)``, fast ``(1 − r)·(1 − cos(πu/2))`` (slow
  fibres first: the fast fibres, dearer per kilogram, are recruited at high excitations);
- activation heat ``m·(40·slow + 133·fast)``, maintenance heat ``m·g(l̃)·(74·slow + 111·fast)``
  with ``g`` 0.5 below l̃ = 0.5, rising linearly to 1 at l̃ = 1, falling to 0 at l̃ = 1.5
  (OpenSim's default curve);
- shortening heat ``−α·v_ce`` with ``α = 0.16·F_iso + 0.18·F_fibre`` while shortening and
  ``0.157·F_fibre`` while lengthening (a negative heat), ``F_iso = a·f_l·F_max`` (the active
  strength's), ``F_fibre`` the active plus passive fibre force: the heat grows with the force;
- mechanical work rate ``−F_ce·v_ce`` while shortening only (PredSim's default: absorbed work
  is not credited);
- the muscle's total not below 0 (its shortening heat raised), its heat not below 1 W/kg; no
  aerobic scale.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.muscle import (
    MP_ACTIVE,
    MP_FMAX,
    MP_LOPT,
    MP_PSTRAIN,
    MP_VMAX,
    V_MAX_OPT_PER_S,
    force_length,
    passive_force,
)

MUSCLE_DENSITY = 1059.7  # kg/m^3
BASAL_RATE_W_PER_KG = 1.51
AEROBIC_SCALE = 1.5
MIN_HEAT_RATE_W_PER_KG = 1.0
# Fast-twitch fibre percentage per muscle type (Johnson et al. 1973, as tabulated in
# Uchida et al. 2016's supplementary models; rounded; torso muscles 50 %).
FAST_TWITCH_PERCENT = {
    "glut_max": 45.0,
    "iliopsoas": 50.0,
    "rect_fem": 62.0,
    "vasti": 50.0,
    "hamstrings": 35.0,
    "bifemsh": 35.0,
    "soleus": 20.0,
    "gastroc": 50.0,
    "tib_ant": 30.0,
}
#: Bhargava et al. (2004)'s activation and maintenance heat constants [W/kg] of slow- and
#: fast-twitch fibres.
BHARGAVA_ACTIVATION_W_PER_KG = (40.0, 133.0)
BHARGAVA_MAINTENANCE_W_PER_KG = (74.0, 111.0)
# Columns of the metabolic parameter array (one row per muscle): mass, fast-twitch percentage,
# model (0 Uchida 2016, 1 Bhargava 2004; a two-column array is Uchida's).
MB_MASS, MB_FT, MB_MODEL = 0, 1, 2
#: The models of ``RunnerParams.metabolic_model`` by their code in ``MB_MODEL``.
METABOLIC_MODELS = ("uchida2016", "bhargava2004")


def metabolic_params(model, *, specific_tension_pa: float | None = None) -> np.ndarray:
    """(n_muscles, 3): muscle mass [kg], fast-twitch percentage and metabolic model code
    (:data:`METABOLIC_MODELS`) of a runner model.

    The mass is the muscle's strongest isometric force (Fmax times its active strength,
    ``MP_ACTIVE``) over ``specific_tension_pa`` [Pa], times l_opt and the density, as Uchida et
    al. (2016), PredSim and SCONE compute it from a model's maximum isometric force;
    ``specific_tension_pa`` defaults to the model's (``params.specific_tension_N_per_cm2``).
    """
    if specific_tension_pa is None:
        specific_tension_pa = model.params.specific_tension_N_per_cm2 * 1e4
    mp = model.muscle_params
    out = np.zeros((mp.shape[0], 3))
    out[:, MB_MODEL] = METABOLIC_MODELS.index(model.params.metabolic_model)
    for i, name in enumerate(model.muscle_names):
        base = name.rsplit("_", 1)[0]
        out[i, MB_MASS] = (MUSCLE_DENSITY * mp[i, MP_FMAX] * mp[i, MP_ACTIVE] * mp[i, MP_LOPT]
                           / specific_tension_pa)
        out[i, MB_FT] = FAST_TWITCH_PERCENT.get(base, 50.0)
    return out


@njit(cache=True)
def muscle_metabolic_rate(
    u: float,
    a: float,
    l_norm: float,
    v_norm: float,
    f_ce: float,
    v_ce: float,
    mass: float,
    ft: float,
    vmax: float = V_MAX_OPT_PER_S,
) -> float:
    """Metabolic rate [W] of one muscle (see module docstring).

    ``u`` excitation, ``a`` activation [-]; ``l_norm`` fibre length / l_opt; ``v_norm`` fibre
    velocity in l_opt/s (< 0 shortening); ``f_ce`` active fibre force [N]; ``v_ce`` fibre velocity
    [m/s]; ``mass`` muscle mass [kg]; ``ft`` fast-twitch percentage; ``vmax`` the muscle's
    maximum shortening velocity [l_opt/s].
    """
    big_a = u if u > a else 0.5 * (u + a)
    if big_a < 0.0:
        big_a = 0.0
    f_iso = force_length(l_norm)
    h_am = (1.28 * ft + 25.0) * big_a**0.6 * AEROBIC_SCALE
    if l_norm > 1.0:
        h_am *= 0.4 + 0.6 * f_iso
    vmax_st = vmax / (1.0 + 1.5 * ft / 100.0)
    vmax_ft = 2.5 * vmax_st
    alpha_st = 100.0 / vmax_st
    alpha_ft = 153.0 / vmax_ft
    if v_norm <= 0.0:
        h_sl = (
            (-alpha_st * v_norm * (100.0 - ft) / 100.0 - alpha_ft * v_norm * ft / 100.0)
            * big_a
            * big_a
            * AEROBIC_SCALE
        )
        if l_norm > 1.0:
            h_sl *= f_iso
    else:
        h_sl = 4.0 * alpha_st * v_norm * big_a * AEROBIC_SCALE
    heat = h_am + h_sl
    if heat < MIN_HEAT_RATE_W_PER_KG:
        heat = MIN_HEAT_RATE_W_PER_KG
    w = -f_ce * v_ce / mass
    total = heat + w
    if total < 0.0:  # no energy earned back from absorbed work (Umberger 2010, Uchida 2016)
        total = 0.0
    return total * mass


@njit(cache=True)
def bhargava_muscle_rate(
    u: float,
    a: float,
    l_norm: float,
    v_ce: float,
    f_ce: float,
    f_passive: float,
    f_iso: float,
    mass: float,
    ft: float,
) -> float:
    """Metabolic rate [W] of one muscle after Bhargava et al. (2004) (module docstring).

    ``u`` excitation, ``a`` activation [-] (unused: the heats follow the excitation, as
    PredSim's); ``l_norm`` fibre length / l_opt; ``v_ce`` fibre velocity [m/s] (< 0
    shortening); ``f_ce`` active and ``f_passive`` passive fibre force [N]; ``f_iso`` the
    isometric force at this activation and length [N]; ``mass`` [kg]; ``ft`` fast-twitch %.
    """
    slow_fraction = 1.0 - ft / 100.0
    slow = slow_fraction * math.sin(0.5 * math.pi * u)
    fast = (1.0 - slow_fraction) * (1.0 - math.cos(0.5 * math.pi * u))
    h_act = mass * (BHARGAVA_ACTIVATION_W_PER_KG[0] * slow
                    + BHARGAVA_ACTIVATION_W_PER_KG[1] * fast)
    if l_norm <= 0.5:
        g = 0.5
    elif l_norm <= 1.0:
        g = l_norm
    elif l_norm <= 1.5:
        g = 3.0 - 2.0 * l_norm
    else:
        g = 0.0
    h_main = mass * g * (BHARGAVA_MAINTENANCE_W_PER_KG[0] * slow
                         + BHARGAVA_MAINTENANCE_W_PER_KG[1] * fast)
    if v_ce <= 0.0:
        alpha = 0.16 * f_iso + 0.18 * (f_ce + f_passive)
        work = -f_ce * v_ce
    else:
        alpha = 0.157 * (f_ce + f_passive)
        work = 0.0
    h_short = -alpha * v_ce
    heat = h_act + h_main + h_short
    if heat + work < 0.0:  # the shortening heat is raised until the total is 0
        heat = -work
    if heat < MIN_HEAT_RATE_W_PER_KG * mass:
        heat = MIN_HEAT_RATE_W_PER_KG * mass
    return heat + work


@njit(cache=True)
def total_metabolic_rate(u, ms, mp, mb, body_mass):
    """Whole-body metabolic rate [W]: basal + Σ muscles, from excitations ``u``, muscle states
    ``ms`` (activation, l_ce, v_ce, F_t), muscle parameters ``mp`` and ``mb`` (:func:`metabolic_params`)."""
    total = BASAL_RATE_W_PER_KG * body_mass
    for i in range(ms.shape[0]):
        lopt = mp[i, 1]
        a = ms[i, 0]
        ln = ms[i, 1] / lopt
        # active fibre force along the fibre: tendon force / cos(pennation) less the passive part
        h = lopt * math.sin(mp[i, 3])
        s = min(h / max(ms[i, 1], 1e-6), 0.99)
        cosp = math.sqrt(1.0 - s * s)
        fp = passive_force(ln, mp[i, MP_PSTRAIN])
        f_ce = max(ms[i, 3] / cosp - fp * mp[i, 0], 0.0)
        if mb.shape[1] > MB_MODEL and mb[i, MB_MODEL] == 1.0:
            f_iso = a * mp[i, 0] * mp[i, MP_ACTIVE] * force_length(ln)
            total += bhargava_muscle_rate(u[i], a, ln, ms[i, 2], f_ce, fp * mp[i, 0], f_iso,
                                          mb[i, 0], mb[i, 1])
            continue
        total += muscle_metabolic_rate(
            u[i], a, ln, ms[i, 2] / lopt, f_ce, ms[i, 2], mb[i, 0], mb[i, 1], mp[i, MP_VMAX]
        )
    return total


__all__ = [
    "BASAL_RATE_W_PER_KG",
    "METABOLIC_MODELS",
    "bhargava_muscle_rate",
    "FAST_TWITCH_PERCENT",
    "metabolic_params",
    "muscle_metabolic_rate",
    "total_metabolic_rate",
]


refresh_stale_caches(globals())
