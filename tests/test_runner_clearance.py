"""Swing clearance (:mod:`bladelab.runner.clearance`) on the shipped amputee reflex gait, whose
blade strikes the ground in every swing: against the simulation's own contact depths and its
strikes (:func:`bladelab.runner.analyses.swing_contacts`)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bladelab.predict.reflex.controller import read_parameters
from bladelab.predict.reflex.objective import simulate_controlled
from bladelab.predict.reflex.optimize import runner_and_layout, stored_settings
from bladelab.runner.analyses import stances, swing_contacts
from bladelab.runner.clearance import swing_clearance
from bladelab.runner.layout import CP_BLADE
from bladelab.runner.params import REFLEX_STARTS_DIR

SHIPPED = REFLEX_STARTS_DIR / "amputee-Cat6-3.5.json"


@pytest.fixture(scope="module")
def run():
    data = json.loads(SHIPPED.read_text())
    runner, layout = runner_and_layout(data["model"], data["blade"])
    settings = stored_settings(data, speed=3.5, duration=10.0, nominal=True)
    ev, res = simulate_controlled(runner, read_parameters(SHIPPED, layout), layout=layout,
                                  settings=settings, record_every=2)
    assert not ev.fell
    return res


def test_one_swing_between_consecutive_stances(run):
    c = swing_clearance(run)
    st = stances(run)
    for leg in ("intact", "prosthetic"):
        assert (c.leg == leg).sum() == (st.leg == leg).sum() - 1
    assert (c.liftoff_s < c.at_s).all() and (c.at_s < c.touchdown_s).all()


def test_the_deepest_point_is_the_kernels_contact_depth(run):
    # the clearance comes from MuJoCo's kinematics of the recorded poses; the depth from the
    # simulation's own contact kernel: at the deepest point of each blade swing they agree
    c = swing_clearance(run)
    blade = int(np.flatnonzero(run.model.contact_params[:, CP_BLADE] == 1)[0])
    for _, row in c[c.leg == "prosthetic"].iterrows():
        i = int(np.argmin(np.abs(run.time - row.at_s)))
        assert row.min_clearance_m < 0  # this gait's blade strikes in every swing
        assert run.contacts[i, blade, 6] == pytest.approx(-row.min_clearance_m, abs=1e-6)


def test_every_strike_lies_in_a_swing_that_goes_into_the_ground(run):
    c = swing_clearance(run)
    strikes = swing_contacts(run)
    assert len(strikes) > 5
    inside = 0
    for _, s in strikes.iterrows():
        mine = c[(c.leg == s.leg) & (c.liftoff_s <= s.start) & (s.start <= c.touchdown_s)]
        legs = c[c.leg == s.leg]
        if not legs.liftoff_s.min() < s.start < legs.touchdown_s.max():
            continue  # before the first complete stance's lift-off or after the last touch-down
        inside += 1
        assert len(mine) == 1
        row = mine.iloc[0]
        assert row.min_clearance_m < 0
        assert s.start <= row.at_s <= s.start + s.duration
    assert inside >= len(strikes) - 2
