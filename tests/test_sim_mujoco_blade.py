"""The one MuJoCo blade builder: per-segment bodies and merged rigid links describe the same
blade (mass, centre of mass, sole and tip sites), with the requested names and springs."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bladelab.blade import multilink_blade
from bladelab.sim.mujoco_blade import BladeNames, add_blade_bodies, lowest_sole_z, rigid_links


def _compiled(blade, **options):
    spec = mujoco.MjSpec()
    clamp = spec.worldbody.add_body(name="clamp", pos=[0.1, 0.0, 0.9])
    handles = add_blade_bodies(clamp, blade, **options)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    return model, data, handles


@pytest.fixture(scope="module")
def blade():
    return multilink_blade("xtreme", n_links=4)


def test_merged_links_and_segments_describe_the_same_blade(blade):
    seg_m, seg_d, seg_h = _compiled(blade, capsule_radius=0.006)
    link_m, link_d, link_h = _compiled(blade, merge_rigid_links=True)
    assert len(seg_h.bodies) == blade.n_segments and seg_m.ngeom == blade.n_segments
    assert len(link_h.bodies) == len(blade.joints) + 1 == len(rigid_links(blade))
    assert link_m.ngeom == 0
    assert seg_m.njnt == link_m.njnt == len(blade.joints)
    for m in (seg_m, link_m):
        assert m.body_subtreemass[m.body("clamp").id] == pytest.approx(blade.mass, rel=1e-12)
    np.testing.assert_allclose(seg_d.subtree_com[1], link_d.subtree_com[1], atol=1e-12)
    for e in range(len(blade.soles)):
        np.testing.assert_allclose(seg_d.site_xpos[seg_m.site(f"sole{e}").id],
                                   link_d.site_xpos[link_m.site(f"sole{e}").id], atol=1e-12)
        centre = blade.soles[e].center
        np.testing.assert_allclose(seg_d.site_xpos[seg_m.site(f"sole{e}").id],
                                   [0.1 + centre[0], 0.0, 0.9 + centre[1]], atol=1e-12)
    np.testing.assert_allclose(seg_d.site_xpos[seg_m.site("tip").id],
                               [0.1 + blade.tip[0], 0.0, 0.9 + blade.tip[1]], atol=1e-12)


def test_names_origin_and_springs(blade):
    K = np.arange(1.0, len(blade.joints) + 1) * 100.0
    D = np.full(len(blade.joints), 2.0)
    names = BladeNames(body="b{index}", joint="h{index}", sole="s{index}", tip=None)
    m, d, h = _compiled(blade, origin=(0.0, -0.2), merge_rigid_links=True, stiffness=K,
                        damping=D, names=names)
    assert h.tip is None and m.nsite == len(blade.soles)
    for i in range(len(blade.joints)):
        jid = m.joint(f"h{i}").id
        assert m.jnt_stiffness[jid] == K[i] and m.dof_damping[m.jnt_dofadr[jid]] == D[i]
    np.testing.assert_allclose(d.site_xpos[m.site("s0").id][[0, 2]],
                               [0.1 + blade.soles[0].center[0], 0.7 + blade.soles[0].center[1]],
                               atol=1e-12)
    m, _, _ = _compiled(blade)
    assert np.all(m.jnt_stiffness == 0.0) and np.all(m.dof_damping == 0.0)
    assert lowest_sole_z(blade) < min(s.center[1] for s in blade.soles)
