"""The reflex controller's step inside the compiled time loop, with the objective's running sums.

:func:`run_closed_loop` is the runner's time loop (:mod:`bladelab.runner.kernel`) with
:func:`control_step` called before the forces of every step
(:func:`bladelab.predict.reflex.objective.simulate_controlled`): delayed sensors,
gait states per leg, excitations (:mod:`bladelab.predict.reflex.controller`), and the sums the objective
needs (metabolic energy, knee-load and pelvis-tilt penalties, touch-downs).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bladelab.numba_cache import refresh_stale_caches
from bladelab.predict.reflex.controller import compute_excitations, push_sensors, update_gait_states
from bladelab.runner.analyses import MIN_STEP_S, STEP_LOAD_BW
from bladelab.runner.kernel import step_advance, step_begin, step_end
from bladelab.runner.layout import CP_LEG
from bladelab.runner.metabolics import total_metabolic_rate

STEP_STATE_SIZE = 5  # left loaded, right loaded, time [s] and leg of the last step, striking leg + 1


@njit(cache=True)
def _count_touchdowns(t, x_pelvis, crec, cp, body_weight, steps, acc, td):
    """Record the objective's steps as SCONE's GaitMeasure counts them, online: a step is a
    new contact of a leg (its vertical GRF rising to ``STEP_LOAD_BW`` body weights) more than
    ``MIN_STEP_S`` after the previous step (sooner contacts, e.g. a bounce, are not steps).
    A sooner new contact of the *other* leg (the swinging foot striking the ground just after
    the step) marks that step as struck, with the strike's peak vertical force (until that
    contact ends). ``steps`` = (left loaded, right loaded, time [s] and leg of the last step,
    striking leg + 1 while a strike lasts, else 0); ``crec`` holds the previous step's contact
    forces. Per step, ``td`` gets time [s], pelvis x [m], leg (0 left, 1 right) and the strike's
    peak [body weights] (0: not struck); ``acc[3]`` counts the steps
    (:func:`bladelab.runner.analyses.step_touchdowns` does the same offline)."""
    left = 0.0  # no array allocated in the hot loop
    right = 0.0
    for c in range(cp.shape[0]):
        if cp[c, CP_LEG] == 0.0:
            left += crec[c, 1]
        else:
            right += crec[c, 1]
    for leg in range(2):
        force = left if leg == 0 else right
        loaded = force >= STEP_LOAD_BW * body_weight
        n = int(acc[3])
        if loaded and steps[leg] == 0.0:
            if t - steps[2] > MIN_STEP_S:
                if n < td.shape[0]:
                    td[n, 0] = t
                    td[n, 1] = x_pelvis
                    td[n, 2] = leg
                    td[n, 3] = 0.0
                    acc[3] += 1.0
                steps[2] = t
                steps[3] = leg
                steps[4] = 0.0
            elif leg != steps[3] and 0 < n <= td.shape[0]:
                steps[4] = leg + 1.0
        if steps[4] == leg + 1.0:
            if loaded and 0 < n <= td.shape[0]:
                td[n - 1, 3] = max(td[n - 1, 3], force / body_weight)
            elif not loaded:
                steps[4] = 0.0
        steps[leg] = 1.0 if loaded else 0.0


@njit(cache=True)
def control_step(k, dt, mj, arrays, control):
    """One controller step at step ``k`` (time ``k·dt`` [s]); writes the excitations ``u``.

    ``control`` = (table, p, hist, cs, mb, ix, thresholds, body_weight, body_mass, leg_length,
    acc, td, steps, knee_idx, itilt, ranges, pen) (built by :mod:`bladelab.predict.reflex.objective`); running
    sums go to ``acc``: metabolic energy [J], knee penalty·s, tilt penalty·s, number of
    steps, and the steps to ``td`` (:func:`_count_touchdowns`).
    """
    qpos, qvel = mj[0], mj[1]
    mp, ms, _, _, u, _, _, cp, _, _, crec, lig = arrays
    (
        table,
        p,
        hist,
        cs,
        mb,
        ix,
        thresholds,
        body_weight,
        body_mass,
        leg_length,
        acc,
        td,
        steps,
        knee_idx,
        itilt,
        ranges,
        pen,
    ) = control
    nm = ms.shape[0]
    nq = qpos.shape[0]
    push_sensors(hist, cs, ms, mp, qpos, qvel)
    update_gait_states(cs, crec, cp, qpos, ix, body_weight, thresholds, leg_length)
    _count_touchdowns(k * dt, qpos[ix], crec, cp, body_weight, steps, acc, td)
    compute_excitations(u, table, p, hist, cs, nm, nq)
    acc[0] += total_metabolic_rate(u, ms, mp, mb, body_mass) * dt
    for j in range(knee_idx.shape[0]):
        tau = lig[knee_idx[j]]
        err = 0.0
        if tau < ranges[0]:
            err = ranges[0] - tau
        elif tau > ranges[1]:
            err = tau - ranges[1]
        acc[1] += (pen[0] * err + pen[1] * err * err) * dt
    tilt = qpos[itilt] * 180.0 / math.pi
    err = 0.0
    if tilt < ranges[2]:
        err = ranges[2] - tilt
    elif tilt > ranges[3]:
        err = tilt - ranges[3]
    acc[2] += (pen[0] * err + pen[1] * err * err) * dt


@njit(cache=True)
def run_closed_loop(
    f1, f2, mptr, dptr, n_steps, record_every, dt, iz, fall_height, mj, arrays, rec, control,
    imp, push,
):
    """The runner's compiled time loop (:func:`bladelab.runner.kernel.run_loop`) with the reflex
    controller: :func:`control_step` between MuJoCo's ``mj_step1`` and the forces of every step.
    ``push`` = (step, factor, dof): at that step (−1: never) the dof's velocity is multiplied by
    the factor (a push; :class:`~bladelab.predict.reflex.objective.ObjectiveSettings.push`).
    Stops after ``n_steps`` or at a fall; returns (last step, samples recorded, fell)."""
    root_com = np.zeros(3)
    k_rec = 0
    k = 0
    push_step = int(push[0])
    for k in range(n_steps + 1):
        if k == push_step:
            mj[1][int(push[2])] *= push[1]
        step_begin(f1, mptr, dptr, mj, root_com, imp)
        control_step(k, dt, mj, arrays, control)
        k_rec, fell = step_end(k, k_rec, record_every, dt, iz, fall_height, mj, arrays, rec,
                               root_com, imp)
        if fell:
            return k, k_rec, True
        if k == n_steps:
            break
        step_advance(f2, mptr, dptr, mj, imp, dt)
    return k, k_rec, False


refresh_stale_caches(globals())
