"""Smooth whole-body metabolic rate for collocation: the forward model's Uchida et al. (2016) /
Umberger (2003) model (:mod:`bladelab.runner.metabolics`) with its switches made smooth.

The same equations and constants as the forward model; every ``if`` becomes a sigmoid of width
``w`` in the switching variable and every ``max`` a softplus:

- ``A = u`` when ``u > a``, else ``(u + a)/2``: blended by ``sigmoid(u − a, w_a)``;
- ``l̃ > 1`` factors (``0.4 + 0.6·f_l`` on the activation–maintenance heat, ``f_l`` on the
  shortening heat): blended by ``sigmoid(l̃ − 1, w_l)``;
- shortening (ṽ ≤ 0) and lengthening heat: blended by ``sigmoid(ṽ, w_v)``;
- the 1 W/kg floor of the heat rate: ``1 + softplus(heat − 1, w_h)``;
- ``A^0.6`` is smooth on the NLP's domain (A ≥ 0.01, the minimum activation).

Mechanical work rate ``−F_ce·v_ce`` with the active fibre force ``F_ce = F_T/cos α − f_p·F_max``
(negative work included, as Uchida 2016; ``F_ce`` floored smoothly at 0 as the forward model
clamps it), fibre state from
:func:`bladelab.predict.collocation.muscles.fiber_kinematics`; each muscle's total
``heat + work`` not below 0 (the forward model's floor): ``softplus(heat + work, w_t)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from bladelab.predict.collocation import muscles
from bladelab.predict.collocation.smooth import Smoothing, sigmoid, smooth_max0, softplus
from bladelab.runner.metabolics import (
    AEROBIC_SCALE,
    BASAL_RATE_W_PER_KG,
    BHARGAVA_ACTIVATION_W_PER_KG,
    BHARGAVA_MAINTENANCE_W_PER_KG,
    MB_FT,
    MB_MASS,
    MIN_HEAT_RATE_W_PER_KG,
    metabolic_params,
)
from bladelab.runner.muscle import MP_ACTIVE, MP_FMAX, MP_LOPT, MP_PSTRAIN, MP_VMAX

__all__ = ["MetabolicSmoothing", "bhargava_muscle_rates", "metabolic_rate",
           "muscle_metabolic_rates", "whole_body_rate"]


@dataclass(frozen=True)
class MetabolicSmoothing:
    """Widths of the metabolic model's smooth switches.

    Attributes
    ----------
    excitation
        In ``u − a`` [-].
    length
        In ``l̃ − 1`` [-] (optimal lengths).
    velocity
        In ``ṽ`` [l_opt/s].
    heat_w_per_kg
        Of the heat-rate floor [W/kg].
    total_w_per_kg
        Of the floor at 0 of a muscle's total rate (heat + work) [W/kg].
    """

    excitation: float = 0.01
    length: float = 0.01
    velocity: float = 0.05
    heat_w_per_kg: float = 0.1
    total_w_per_kg: float = 0.1


def metabolic_rate(runner, u, a, ft, dft, l_mt, v_mt, smoothing: Smoothing,
                   widths: MetabolicSmoothing | None = None):
    """Whole-body metabolic rate [W] (basal + Σ muscles) as a CasADi expression (arguments as
    :func:`muscle_metabolic_rates`)."""
    return whole_body_rate(runner, muscle_metabolic_rates(runner, u, a, ft, dft, l_mt, v_mt,
                                                          smoothing, widths))


def whole_body_rate(runner, rates):
    """Whole-body metabolic rate [W]: the basal rate of ``runner``'s mass plus the muscles'
    ``rates`` [W] (:func:`muscle_metabolic_rates`)."""
    return BASAL_RATE_W_PER_KG * float(np.sum(runner.mj_model.body_mass)) + ca.sum1(rates)


def muscle_metabolic_rates(runner, u, a, ft, dft, l_mt, v_mt, smoothing: Smoothing,
                           widths: MetabolicSmoothing | None = None, *,
                           specific_tension_pa: float | None = None):
    """Metabolic rate of every muscle [W] (n_muscles,) as a CasADi expression.

    Parameters
    ----------
    runner
        The :class:`~bladelab.runner.RunnerModel` (muscle and metabolic parameters).
    u, a, ft, dft
        Excitations, activations, normalised tendon forces and their rates (n_muscles,).
    l_mt, v_mt
        MTU lengths [m] and lengthening velocities [m/s] (n_muscles,).
    smoothing
        The model's smoothing (fibre kinematics, passive curve).
    widths
        Widths of the metabolic switches (default :class:`MetabolicSmoothing`).
    specific_tension_pa
        The specific tension [Pa] that turns the strongest force into muscle mass
        (:func:`bladelab.runner.metabolics.metabolic_params`); None: the model's.
    """
    if runner.params.metabolic_model == "bhargava2004":
        return bhargava_muscle_rates(runner, u, a, ft, dft, l_mt, v_mt, smoothing, widths,
                                     specific_tension_pa=specific_tension_pa)
    w = widths or MetabolicSmoothing()
    mp = runner.muscle_params
    mb = metabolic_params(runner, specific_tension_pa=specific_tension_pa)
    mass, ftp = ca.DM(mb[:, MB_MASS]), ca.DM(mb[:, MB_FT])
    l_opt = ca.DM(mp[:, MP_LOPT])
    l_m, v_m, cos_a = muscles.fiber_kinematics(mp, l_mt, v_mt, ft, dft, smoothing)
    ln = l_m / l_opt
    vn = v_m / l_opt  # optimal lengths per second (< 0 shortening)
    big_a = a + (u - a) * (0.5 + 0.5 * sigmoid(u - a, w.excitation))  # u if u > a else (u+a)/2
    f_iso = muscles.force_length(ln)
    long = sigmoid(ln - 1.0, w.length)
    h_am = (1.28 * ftp + 25.0) * big_a**0.6 * AEROBIC_SCALE
    h_am = h_am * (1.0 + long * (0.4 + 0.6 * f_iso - 1.0))
    vmax_st = ca.DM(mp[:, MP_VMAX]) / (1.0 + 1.5 * ftp / 100.0)
    alpha_st = 100.0 / vmax_st
    alpha_ft = 153.0 / (2.5 * vmax_st)
    h_short = (-alpha_st * vn * (100.0 - ftp) / 100.0 - alpha_ft * vn * ftp / 100.0) \
        * big_a**2 * AEROBIC_SCALE
    h_short = h_short * (1.0 + long * (f_iso - 1.0))
    h_long = 4.0 * alpha_st * vn * big_a * AEROBIC_SCALE
    lengthening = sigmoid(vn, w.velocity)
    heat = h_am + (1.0 - lengthening) * h_short + lengthening * h_long
    heat = MIN_HEAT_RATE_W_PER_KG + softplus(heat - MIN_HEAT_RATE_W_PER_KG, w.heat_w_per_kg)
    f_ce, _ = _fibre_forces(mp, ln, ft, cos_a, smoothing)
    work = -f_ce * v_m / mass
    total = softplus(heat + work, w.total_w_per_kg)
    return total * mass


def _fibre_forces(mp: np.ndarray, ln, ft, cos_a, smoothing: Smoothing):
    """(active, passive) fibre force [N] of every muscle from its normalised fibre length,
    tendon force and cos(pennation); the active one not below 0 (the forward model's clamp,
    reached off equilibrium only)."""
    fmax = ca.DM(mp[:, MP_FMAX])
    f_pas = muscles.passive_force(ln, smoothing, ca.DM(mp[:, MP_PSTRAIN])) * fmax
    return smooth_max0(fmax * ft / cos_a - f_pas, 1.0), f_pas


def _unit_ramp(x, width: float):
    """Smooth ``clip(x, 0, 1)``."""
    return softplus(x, width) - softplus(x - 1.0, width)


def bhargava_muscle_rates(runner, u, a, ft, dft, l_mt, v_mt, smoothing: Smoothing,
                          widths: MetabolicSmoothing | None = None, *,
                          specific_tension_pa: float | None = None):
    """Metabolic rate of every muscle [W] after Bhargava et al. (2004), as PredSim computes it
    (:mod:`bladelab.runner.metabolics`, ``bhargava_muscle_rate``, has the equations; arguments
    as :func:`muscle_metabolic_rates`). The switches are smooth: shortening against lengthening
    by ``sigmoid(ṽ, w_v)``, the floors by softplus, the maintenance heat's length dependence by
    smooth ramps of width ``w_l``."""
    w = widths or MetabolicSmoothing()
    mp = runner.muscle_params
    mb = metabolic_params(runner, specific_tension_pa=specific_tension_pa)
    mass, slow = ca.DM(mb[:, MB_MASS]), ca.DM(1.0 - mb[:, MB_FT] / 100.0)
    l_opt, fmax = ca.DM(mp[:, MP_LOPT]), ca.DM(mp[:, MP_FMAX])
    strength = ca.DM(mp[:, MP_ACTIVE])
    l_m, v_m, cos_a = muscles.fiber_kinematics(mp, l_mt, v_mt, ft, dft, smoothing)
    ln = l_m / l_opt
    slow_u = slow * ca.sin(0.5 * math.pi * u)
    fast_u = (1.0 - slow) * (1.0 - ca.cos(0.5 * math.pi * u))
    h_act = mass * (BHARGAVA_ACTIVATION_W_PER_KG[0] * slow_u
                    + BHARGAVA_ACTIVATION_W_PER_KG[1] * fast_u)
    g_len = (0.5 + 0.5 * _unit_ramp((ln - 0.5) / 0.5, w.length)
             - _unit_ramp((ln - 1.0) / 0.5, w.length))
    h_main = mass * g_len * (BHARGAVA_MAINTENANCE_W_PER_KG[0] * slow_u
                             + BHARGAVA_MAINTENANCE_W_PER_KG[1] * fast_u)
    f_ce, f_pas = _fibre_forces(mp, ln, ft, cos_a, smoothing)
    f_iso = a * fmax * strength * muscles.force_length(ln)
    lengthening = sigmoid(v_m / l_opt, w.velocity)
    alpha = (1.0 - lengthening) * (0.16 * f_iso + 0.18 * (f_ce + f_pas)) \
        + lengthening * 0.157 * (f_ce + f_pas)
    h_short = -alpha * v_m
    work = -(1.0 - lengthening) * f_ce * v_m  # positive work only
    # the muscle's total not below 0 (its shortening heat raised), its heat not below 1 W/kg
    total = mass * softplus((h_act + h_main + h_short + work) / mass, w.total_w_per_kg)
    heat = total - work
    heat = mass * (MIN_HEAT_RATE_W_PER_KG
                   + softplus(heat / mass - MIN_HEAT_RATE_W_PER_KG, w.heat_w_per_kg))
    return heat + work
