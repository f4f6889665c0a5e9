"""Swing clearance: how high a swinging leg's lowest contact point passes above the ground.

A strike of a swinging foot (:func:`bladelab.runner.analyses.swing_contacts`) says only that
it touched and how hard. The clearance says by how much a swing missed the ground, or how
deep it went in (negative), so it gives a margin where the strikes give a verdict: the
stable-gait acceptance's limit of 0.2 body weights is about 15 mm of the Cat6 blade's sphere
in the ground, its reflex gaits' strikes 23–25 mm (docs/predictive.md).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pandas as pd

from bladelab.runner.analyses import stances
from bladelab.runner.layout import CP_LEG
from bladelab.runner.model import contact_heights
from bladelab.runner.simulate import RunnerResult, leg_names

__all__ = ["swing_clearance"]


def swing_clearance(result: RunnerResult) -> pd.DataFrame:
    """One row per swing of a leg, from the lift-off of one of its stances to the touch-down
    of its next (:func:`~bladelab.runner.analyses.stances`): leg, liftoff_s, touchdown_s [s],
    min_clearance_m [m] (the lowest point of the leg's contact spheres over the swing;
    negative: in the ground, a strike or a scuff) and at_s [s] (when). The swing proper runs
    from the first sample at which the leg's lowest point is above the ground to the last
    one before the touch-down (a sphere still compressed below the stance threshold at lift-off
    or already touching before the touch-down is not a strike); a leg that never rises above
    the ground drags: its whole swing counts."""
    model = result.model
    names = leg_names(model)
    st = stances(result)
    data = mujoco.MjData(model.mj_model)
    # every sample's contact heights once: the two legs' swings overlap in the flight phases
    heights = np.array([contact_heights(model, q, data) for q in result.qpos])
    rows = []
    for leg in (0, 1):
        lowest = heights[:, model.contact_params[:, CP_LEG] == leg].min(axis=1)
        mine = st[st.leg == names[leg]].sort_values("touchdown_s")
        for (_, a), (_, b) in zip(mine.iloc[:-1].iterrows(), mine.iloc[1:].iterrows(),
                                  strict=True):
            idx = np.arange(int(a["stop"]), int(b["first"]))
            if len(idx) == 0:
                continue
            low = lowest[idx]
            above = np.flatnonzero(low > 0.0)
            if len(above):
                idx, low = idx[above[0]:above[-1] + 1], low[above[0]:above[-1] + 1]
            k = int(np.argmin(low))
            rows.append({"leg": names[leg], "liftoff_s": float(a["liftoff_s"]),
                         "touchdown_s": float(b["touchdown_s"]),
                         "min_clearance_m": float(low[k]),
                         "at_s": float(result.time[idx[k]])})
    cols = ["leg", "liftoff_s", "touchdown_s", "min_clearance_m", "at_s"]
    return pd.DataFrame(rows, columns=cols).sort_values("liftoff_s", ignore_index=True)
