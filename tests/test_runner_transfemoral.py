"""The transfemoral runner: seed 002's athlete on seed 001's body, a passive
3S80-class prosthetic knee on the residual thigh, the category's blade sphere."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from bladelab.errors import ModelError, SpecError
from bladelab.runner import build_runner
from bladelab.runner.kernel import forces, mujoco_views
from bladelab.runner.model import contact_heights
from bladelab.runner.params import default_runner_params, runner_params_from_dict
from bladelab.runner.prosthetic_knee import ProstheticKnee
from bladelab.runner.simulate import leg_names


@pytest.fixture(scope="module")
def runner():
    return build_runner("transfemoral")


def test_the_model_has_a_prosthetic_knee_and_residual_hip_muscles(runner):
    amputee = build_runner("amputee")
    assert runner.total_mass == pytest.approx(58.3, rel=1e-12)  # seed 002's athlete
    assert "ankle_angle_r" not in runner.dof_names and "socket_angle_r" not in runner.dof_names
    assert runner.dof_names.count("knee_angle_r") == 1
    right = {m for m in runner.muscle_names if m.endswith("_r")} - {
        f"{t}_r" for t in ("rect_abd", "int_obl", "erect_sp")}
    assert right == {"glut_max_r", "iliopsoas_r"}
    left = [m for m in runner.muscle_names if m.endswith("_l")]
    assert left == [m for m in amputee.muscle_names if m.endswith("_l")]
    assert runner.contact_names == ("heel_l", "toe_l", "blade_r")
    assert runner.params.blade == "Cat4" and leg_names(runner) == ("intact", "prosthetic")
    # the knee unit, pylon and blade hang from the residual femur, below the knee axis
    shank = runner.mj_model.body("prosthesis_r")
    assert runner.mj_model.body(int(shank.parentid[0])).name == "femur_r"
    assert runner.segment_mass("prosthesis_r") == pytest.approx(3.2 * 58.3 / 77.34, rel=1e-9)
    # standing: every contact touches; the 3 cm longer prosthetic leg stands with a bent knee
    assert contact_heights(runner, runner.stand_qpos) == pytest.approx(0.0, abs=1e-12)
    assert runner.stand_qpos[runner.dof("knee_angle_r")] < 0.0


def _passive_torque(runner, q_knee: float, qd_knee: float) -> float:
    """The forward kernel's passive torque at the prosthetic knee [N·m]."""
    m = runner.mj_model
    d = mujoco.MjData(m)
    j = runner.dof("knee_angle_r")
    d.qpos[:] = runner.stand_qpos
    d.qpos[1] += 0.5  # in the air: no contact forces
    d.qpos[j], d.qvel[j] = q_knee, qd_knee
    mujoco.mj_forward(m, d)
    mp, cp = runner.muscle_params, runner.contact_params
    nm, nc = mp.shape[0], cp.shape[0]
    ms = np.zeros((nm, 4))
    ms[:, 0], ms[:, 1] = 0.01, mp[:, 1]
    lig = np.zeros(m.nv)
    arrays = (mp, ms, np.zeros((nm, 2)), np.zeros((runner.path_points.shape[0], 3)),
              np.zeros(nm), runner.path_points, runner.path_start, cp, np.zeros((nc, 1)),
              runner.joint_params, np.zeros((nc, 7)), lig)
    forces(mujoco_views(d), arrays, d.subtree_com[1].copy(), 2.5e-4)
    return float(lig[j])


@pytest.mark.parametrize("q_deg", [-60.0, -20.0, 0.5])
@pytest.mark.parametrize("qd", [-6.0, -0.5, 0.5, 6.0])
def test_the_knee_is_the_3s80_law_in_the_runners_sign(runner, q_deg, qd):
    """knee_angle_r is negative in flexion, the 3S80 law (bladelab.runner.prosthetic_knee,
    numba, used by the design evaluator) positive: τ_runner(q, q̇) = −τ_3S80(−q, −q̇); flexing
    (q̇ < 0) meets the flexion damping, extending the extension damping, and past the
    hyperextension stop (q > 0) the stop pushes back."""
    knee = runner.params.prosthetic_knee
    assert knee == ProstheticKnee(stop_damping=10.0)  # the parameter set's bumper
    q = math.radians(q_deg)
    expected = -knee.torque(-q, -qd)
    if q > 0:  # the runner's ligament law: the stop pushes and never pulls
        stop = -knee.stop_stiffness * q - knee.stop_damping * qd
        expected = -knee.assist_stiffness * q + min(stop, 0.0) - (
            knee.flexion_damping if qd < 0 else knee.extension_damping) * qd
    assert _passive_torque(runner, q, qd) == pytest.approx(expected, rel=1e-12, abs=1e-12)
    if q_deg == -20.0:  # the two dampings differ, so the sense of motion is seen
        assert knee.flexion_damping != knee.extension_damping


def test_knee_parameters_are_read_from_the_parameter_set():
    data = default_runner_params("transfemoral").model_dump()
    data["prosthetic_knee"]["flexion_damping"] = 4.0
    runner = build_runner(runner_params_from_dict(data))
    assert _passive_torque(runner, math.radians(-30.0), -2.0) == pytest.approx(
        -ProstheticKnee(flexion_damping=4.0, stop_damping=10.0).torque(math.radians(30.0), 2.0),
        rel=1e-12)
    data["prosthetic_knee"]["assist_rest_angle"] = 0.1
    with pytest.raises(SpecError, match="assist_rest_angle"):
        build_runner(runner_params_from_dict(data))


def test_the_transfemoral_runner_wears_a_multilink_blade_below_its_knee():
    """The design's blades (seed 002 varies their shape) mount under the knee unit: the total
    mass is kept, the blade's links hang from the prosthesis below the knee, and it stands."""
    from bladelab.blade import load_blade

    blade = load_blade("xtreme-cat5").build()
    runner = build_runner("transfemoral", blade_model=blade)
    assert runner.total_mass == pytest.approx(58.3, rel=1e-12)
    assert "knee_angle_r" in runner.dof_names and "blade_joint0" in runner.dof_names
    soles = [c for c in runner.contact_names if c.startswith("blade_sole")]
    assert len(soles) == len(blade.soles) >= 1
    m = runner.mj_model
    link = m.body(m.jnt_bodyid[m.joint("blade_joint0").id])
    parents = set()
    b = link.id
    while b:
        b = int(m.body_parentid[b])
        parents.add(m.body(b).name)
    assert {"prosthesis_r", "femur_r"} <= parents
    assert runner.segment_mass("prosthesis_r") == pytest.approx(
        3.2 * 58.3 / 77.34 - blade.mass, rel=1e-9)
    assert contact_heights(runner, runner.stand_qpos).min() == pytest.approx(0.0, abs=1e-12)
    j = runner.dof("knee_angle_r")
    np.testing.assert_array_equal(runner.joint_params[j],
                                  ProstheticKnee(stop_damping=10.0).joint_row())
    with pytest.raises(ModelError, match="amputee"):
        build_runner("able", blade_model=blade)


def test_a_myodesis_makes_the_hamstrings_and_rectus_femoris_hip_muscles_of_the_residual_limb():
    """With ``myodesis``, the residual limb's hamstrings and rectus femoris end on the distal
    femur where their tibial insertion lies with the knee straight: their lengths and hip moment
    arms are the intact leg's with its knee straight, and the prosthetic knee moves neither."""
    data = default_runner_params("transfemoral").model_dump()
    data["myodesis"] = True
    runner = build_runner(runner_params_from_dict(data))
    right = {m for m in runner.muscle_names if m.endswith("_r")} - {
        f"{t}_r" for t in ("rect_abd", "int_obl", "erect_sp")}
    assert right == {"glut_max_r", "iliopsoas_r", "hamstrings_r", "rect_fem_r"}
    m = runner.mj_analysis_model
    d = mujoco.MjData(m)

    def lengths(hip_deg: float, knee_deg: float) -> dict[str, float]:
        d.qpos[:] = 0.0
        for side in ("l", "r"):
            d.qpos[m.joint(f"hip_flexion_{side}").qposadr[0]] = math.radians(hip_deg)
        d.qpos[m.joint("knee_angle_r").qposadr[0]] = math.radians(knee_deg)
        mujoco.mj_forward(m, d)
        return {n: float(d.ten_length[m.tendon(n).id])
                for n in ("hamstrings_l", "hamstrings_r", "rect_fem_l", "rect_fem_r")}

    for hip in (-20.0, 0.0, 40.0, 80.0):
        straight, bent = lengths(hip, 0.0), lengths(hip, -90.0)
        for name in ("hamstrings", "rect_fem"):
            assert straight[f"{name}_r"] == pytest.approx(straight[f"{name}_l"], rel=1e-12)
            assert bent[f"{name}_r"] == pytest.approx(straight[f"{name}_r"], rel=1e-12)
    # the hamstrings extend the hip, the rectus femoris flexes it
    assert lengths(40.0, 0.0)["hamstrings_r"] > lengths(0.0, 0.0)["hamstrings_r"]
    assert lengths(40.0, 0.0)["rect_fem_r"] < lengths(0.0, 0.0)["rect_fem_r"]


def test_the_residual_limbs_muscles_take_their_own_strength():
    """``residual_muscle_strength`` scales the residual limb's Fmax by muscle type and nothing
    else: the intact leg's same muscles, the residual muscles not named and every other
    muscle parameter stay; the metabolic muscle mass follows Fmax. Unknown muscles and
    factors outside (0, 2] are refused by name."""
    from bladelab.runner.metabolics import MB_MASS, metabolic_params
    from bladelab.runner.muscle import MP_FMAX

    data = default_runner_params("transfemoral", body="human").model_dump()
    base = build_runner(runner_params_from_dict(data))
    data["residual_muscle_strength"] = {"hamstrings": 0.5, "glut_max": 0.85}
    weak = build_runner(runner_params_from_dict(data))
    assert weak.muscle_names == base.muscle_names
    want = {"hamstrings_r": 0.5, "glut_max_r": 0.85}
    for i, name in enumerate(base.muscle_names):
        factor = want.get(name, 1.0)
        assert weak.muscle_params[i, MP_FMAX] == pytest.approx(
            factor * base.muscle_params[i, MP_FMAX], rel=1e-12), name
        np.testing.assert_array_equal(np.delete(weak.muscle_params[i], MP_FMAX),
                                      np.delete(base.muscle_params[i], MP_FMAX))
        assert (metabolic_params(weak)[i, MB_MASS] / metabolic_params(base)[i, MB_MASS]
                == pytest.approx(factor, rel=1e-12)), name
    for bad, match in (({"soleus": 0.5}, "unknown residual limb muscle"),
                       ({"iliopsoas": 0.0}, "within \\(0, 2\\]")):
        data["residual_muscle_strength"] = bad
        with pytest.raises(SpecError, match=match):
            runner_params_from_dict(data)
