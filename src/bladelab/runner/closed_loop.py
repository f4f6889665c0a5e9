"""The reflex controller's step inside the compiled time loop, with the objective's running sums.

:func:`control_step` is called by :func:`bladelab.runner.kernel.run_loop` before the forces of
every step when the loop is closed (``runner.objective.simulate_controlled``): delayed sensors,
gait states per leg, excitations (:mod:`bladelab.runner.controller`), and the sums the objective
needs (metabolic energy, knee-load and pelvis-tilt penalties, touch-downs).
"""

from __future__ import annotations

import math

from numba import njit

from bladelab.runner.controller import compute_excitations, push_sensors, update_gait_states
from bladelab.runner.metabolics import total_metabolic_rate


@njit(cache=True)
def control_step(k, dt, mj, arrays, control):
    """One controller step at step ``k`` (time ``k·dt`` [s]); writes the excitations ``u``.

    ``control`` = (table, p, hist, cs, mb, ix, thresholds, body_weight, body_mass, leg_length,
    acc, td, knee_idx, itilt, ranges, pen) (built by ``runner.objective``); running sums go to
    ``acc``: metabolic energy [J], knee penalty·s, tilt penalty·s, number of touch-downs, and
    the touch-downs' time [s] and pelvis x [m] to ``td``.
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
        knee_idx,
        itilt,
        ranges,
        pen,
    ) = control
    nm = ms.shape[0]
    nq = qpos.shape[0]
    push_sensors(hist, cs, ms, mp, qpos, qvel)
    s0, s1 = cs[0], cs[1]
    update_gait_states(cs, crec, cp, qpos, ix, body_weight, thresholds, leg_length)
    for leg in range(2):
        old = s0 if leg == 0 else s1
        if cs[leg] == 0.0 and old >= 3.0:  # swing/landing -> early stance: touch-down
            n = int(acc[3])
            if n < td.shape[0]:
                td[n, 0] = k * dt
                td[n, 1] = qpos[ix]
                acc[3] += 1.0
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
