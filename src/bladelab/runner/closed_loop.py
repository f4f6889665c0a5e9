"""The reflex controller's step inside the compiled time loop, with the objective's running sums.

:func:`control_step` is called by :func:`bladelab.runner.kernel.run_loop` before the forces of
every step when the loop is closed (``runner.objective.simulate_controlled``): delayed sensors,
gait states per leg, excitations (:mod:`bladelab.runner.controller`), and the sums the objective
needs (metabolic energy, knee-load and pelvis-tilt penalties, touch-downs).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from bladelab.runner.controller import compute_excitations, push_sensors, update_gait_states
from bladelab.runner.metabolics import total_metabolic_rate
from bladelab.runner.model import CP_LEG

TOUCHDOWN_LOAD_N = 20.0  # a leg is loaded above this vertical GRF [N] (runner.analyses)
TOUCHDOWN_MIN_GAP_S = 0.05  # a new contact after a shorter unloaded gap is a bounce [s]
TOUCHDOWN_MIN_CONTACT_S = 0.03  # a shorter contact is a brief touch, not a step [s]
LEGLOAD_COLUMNS = 5  # per leg: loaded now, unloaded since [s], contact start [s], its x, pending


@njit(cache=True)
def _count_touchdowns(t, x_pelvis, crec, cp, legload, acc, td):
    """Record the touch-downs of the objective's steps from the legs' vertical GRF, online, as
    :func:`bladelab.runner.analyses.contact_mask` does offline (SCONE's GaitMeasure also counts
    steps from foot contacts): a contact starts when the leg's force rises above
    ``TOUCHDOWN_LOAD_N`` after at least ``TOUCHDOWN_MIN_GAP_S`` unloaded (a shorter gap is a
    bounce of the same contact) and is a step once it has lasted ``TOUCHDOWN_MIN_CONTACT_S``
    (a shorter one is a brief touch, ignored). ``legload`` (2, LEGLOAD_COLUMNS) keeps each
    leg's state; ``crec`` holds the previous step's contact forces. The touch-down's time [s],
    pelvis x [m] and leg go to ``td``, their number to ``acc[3]``."""
    force = np.zeros(2)
    for c in range(cp.shape[0]):
        force[int(cp[c, CP_LEG])] += crec[c, 1]
    for leg in range(2):
        loaded = force[leg] > TOUCHDOWN_LOAD_N
        if loaded and legload[leg, 0] == 0.0:  # rising edge
            legload[leg, 0] = 1.0
            if t - legload[leg, 1] >= TOUCHDOWN_MIN_GAP_S:
                legload[leg, 2] = t
                legload[leg, 3] = x_pelvis
                legload[leg, 4] = 1.0
        elif not loaded and legload[leg, 0] == 1.0:  # falling edge
            legload[leg, 0] = 0.0
            if legload[leg, 4] == 1.0:
                legload[leg, 4] = 0.0  # a brief touch: the leg stays unloaded since before it
            else:
                legload[leg, 1] = t
        if legload[leg, 4] == 1.0 and loaded and t - legload[leg, 2] >= TOUCHDOWN_MIN_CONTACT_S:
            legload[leg, 4] = 0.0
            n = int(acc[3])
            if n < td.shape[0]:
                td[n, 0] = legload[leg, 2]
                td[n, 1] = legload[leg, 3]
                td[n, 2] = leg
                acc[3] += 1.0


@njit(cache=True)
def control_step(k, dt, mj, arrays, control):
    """One controller step at step ``k`` (time ``k·dt`` [s]); writes the excitations ``u``.

    ``control`` = (table, p, hist, cs, mb, ix, thresholds, body_weight, body_mass, leg_length,
    acc, td, legload, knee_idx, itilt, ranges, pen) (built by ``runner.objective``); running
    sums go to ``acc``: metabolic energy [J], knee penalty·s, tilt penalty·s, number of
    touch-downs, and the touch-downs' time [s], pelvis x [m] and leg (0 left, 1 right) to ``td``
    (:func:`_count_touchdowns`).
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
        legload,
        knee_idx,
        itilt,
        ranges,
        pen,
    ) = control
    nm = ms.shape[0]
    nq = qpos.shape[0]
    push_sensors(hist, cs, ms, mp, qpos, qvel)
    update_gait_states(cs, crec, cp, qpos, ix, body_weight, thresholds, leg_length)
    _count_touchdowns(k * dt, qpos[ix], crec, cp, legload, acc, td)
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
