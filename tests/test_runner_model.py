"""Runner model: masses, muscle strengths, blade categories and parameter-file errors.

Expected values are typed from seed 001's tables (Table 2.1, 2.2, 2.3), not from the code's.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import yaml

from bladelab.errors import BladelabError, SpecError
from bladelab.runner import (
    blade_catalogue,
    build_runner,
    contact_heights,
    default_runner_params,
    load_runner_params,
    runner_params_from_dict,
)
from bladelab.runner.geometry import TORSO_MUSCLES
from bladelab.runner.layout import CP_LEG, JP_EA, JP_EB

G = 9.81

# seed 001 Table 2.1 [kg]
TABLE_2_1 = {
    "torso": 35.40,
    "pelvis": 13.09,
    "femur": 11.93,
    "tibia": 4.31,
    "calcaneus": 1.25,
    "tibia_amputated": 2.22,
    "prosthesis": 1.30,
}
# seed 001 Table 2.2, Fmax [N]. The soleus row reads 7188 N, but eq. 2.1 with the row's own
# phi = 0.06 and l0 = 0.05 m gives 60 * 0.06 * 11095 / 5 = 7988 N: the table's digit is
# transposed (every other row matches eq. 2.1 to within 1 N). We test eq. 2.1's 7988 N.
TABLE_2_2_FMAX = {
    "glut_max": 5434,
    "iliopsoas": 4660,
    "rect_fem": 2277,
    "vasti": 13563,
    "hamstrings": 7023,
    "bifemsh": 654,
    "soleus": 7988,
    "gastroc": 6129,
    "tib_ant": 2717,
    "rect_abd": 800,
    "erect_sp": 3305,
    "int_obl": 2663,
}
# seed 001 Table 2.3 [kN/m]
TABLE_2_3 = {"Cat4": 21.2, "Cat5": 24.23, "Cat6": 27.3, "Cat6High": 30.3, "Cat7": 33.3}


@pytest.fixture(scope="module")
def amputee():
    return build_runner("amputee")


@pytest.fixture(scope="module")
def able():
    return build_runner("able")


def test_amputee_structure(amputee):
    m = amputee.mj_model
    assert m.nbody - 1 == 8  # 8 segments
    assert m.nv == 10  # 10 dof
    assert len(amputee.muscle_names) == 21
    intact = [
        n
        for n in amputee.muscle_names
        if n.endswith("_l") and "abd" not in n and "obl" not in n and "erect" not in n
    ]
    prosth = [
        n
        for n in amputee.muscle_names
        if n.endswith("_r") and "abd" not in n and "obl" not in n and "erect" not in n
    ]
    assert len(intact) == 9 and len(prosth) == 6
    assert not {"gastroc_r", "soleus_r", "tib_ant_r"} & set(amputee.muscle_names)
    assert amputee.contact_names == ("heel_l", "toe_l", "blade_r")


def test_segment_masses_equal_table(amputee, able):
    t = TABLE_2_1
    expected_amp = {
        "torso": t["torso"],
        "pelvis": t["pelvis"],
        "femur_l": t["femur"],
        "femur_r": t["femur"],
        "tibia_l": t["tibia"],
        "calcn_l": t["calcaneus"],
        "tibia_res_r": t["tibia_amputated"],
        "prosthesis_r": t["prosthesis"],
    }
    for name, mass in expected_amp.items():
        assert amputee.segment_mass(name) == pytest.approx(mass, rel=1e-9), name
    assert amputee.total_mass == pytest.approx(81.43, abs=1e-6)  # seed §2.1
    assert able.total_mass == pytest.approx(83.47, abs=1e-6)  # 83.5 kg in seed §2.1
    assert able.segment_mass("tibia_r") == pytest.approx(t["tibia"])
    # sagittal inertia (lab y = OpenSim z) of the prosthesis
    m = amputee.mj_model
    assert m.body_inertia[m.body("prosthesis_r").id][1] == pytest.approx(0.0370)
    assert m.body_inertia[m.body("torso").id][1] == pytest.approx(1.4800)


def test_muscle_fmax_equals_table(amputee):
    fmax = dict(zip(amputee.muscle_names, amputee.muscle_params[:, 0], strict=True))
    for name, value in fmax.items():
        mtype = name.rsplit("_", 1)[0]
        assert value == pytest.approx(TABLE_2_2_FMAX[mtype], abs=1.0), name


def test_athlete_scaling():
    data = default_runner_params("amputee").model_dump()
    data["athlete"] = {"body_mass_kg": 70.0, "height_m": 1.70}
    r = build_runner(runner_params_from_dict(data))
    assert r.total_mass == pytest.approx(70.0)
    # eq. 2.1 scaled: volume ∝ mass, l_opt ∝ height
    ref = build_runner("amputee")
    ratio = (70.0 / 81.43) / (1.70 / 1.80)
    np.testing.assert_allclose(r.muscle_params[:, 0], ref.muscle_params[:, 0] * ratio)
    assert r.stand_qpos[1] == pytest.approx(ref.stand_qpos[1] * 1.70 / 1.80, rel=0.02)


def test_prosthetic_leg_three_cm_longer(amputee):
    q = np.zeros(amputee.mj_model.nq)
    h = contact_heights(amputee, q)
    assert h[:2].min() - h[2] == pytest.approx(0.03, abs=1e-9)
    # standing pose: every contact on the ground
    np.testing.assert_allclose(contact_heights(amputee, amputee.stand_qpos), 0.0, atol=1e-6)


def test_muscle_paths_have_plausible_moment_arms(amputee):
    """Hip extensors/flexors, knee extensors and the soleus act in the right direction."""
    m = amputee.mj_analysis_model
    d = mujoco.MjData(m)
    d.qpos[:] = amputee.stand_qpos
    mujoco.mj_forward(m, d)
    moment = np.zeros((m.nu, m.nv))
    mujoco.mju_sparse2dense(
        moment, d.actuator_moment, d.moment_rownnz, d.moment_rowadr, d.moment_colind
    )

    def arm(muscle, dof):  # d l_mtu / d q [m/rad]
        return moment[m.actuator(muscle).id, amputee.dof(dof)]

    assert arm("glut_max_l", "hip_flexion_l") > 0.02  # lengthens with flexion: extensor
    assert arm("iliopsoas_l", "hip_flexion_l") < -0.01  # flexor
    # knee flexion is q < 0: an extensor lengthens as q decreases (dl/dq < 0)
    assert arm("vasti_l", "knee_angle_l") < -0.02
    assert arm("bifemsh_l", "knee_angle_l") > 0.01  # knee flexor
    assert arm("soleus_l", "ankle_angle_l") > 0.02  # lengthens with dorsiflexion: plantarflexor
    assert arm("tib_ant_l", "ankle_angle_l") < -0.01
    assert arm("erect_sp_l", "lumbar_extension") < -0.02  # shortens with extension: extensor
    assert arm("rect_abd_l", "lumbar_extension") > 0.05


@pytest.mark.parametrize("category", list(TABLE_2_3))
def test_blade_sphere_follows_hertz_and_category_stiffness(category):
    runner = build_runner("amputee", blade=category)
    row = runner.contact_params[runner.contact_names.index("blade_r")]
    k = row[3]
    radius = row[2]
    assert radius == 0.1464
    e = runner.blade_modulus
    bw = 81.43 * G
    # eq. 2.3: F = 4/3 * sqrt(R) * E * dy^1.5 over a range of compressions
    from bladelab.contact import hunt_crossley_force

    for dy in (0.005, 0.02, 0.05):
        f = hunt_crossley_force(dy, 0.0, k, 1.5, row[4])
        assert f == pytest.approx(4.0 / 3.0 * math.sqrt(0.1464) * e * dy**1.5, rel=1e-12)
    # linearised stiffness at body-weight load = the category's kN/m (within 5 %)
    dy_bw = (bw / k) ** (2.0 / 3.0)
    h = 1e-6
    k_lin = (
        hunt_crossley_force(dy_bw + h, 0.0, k, 1.5, 0.0)
        - hunt_crossley_force(dy_bw - h, 0.0, k, 1.5, 0.0)
    ) / (2 * h)
    assert k_lin == pytest.approx(TABLE_2_3[category] * 1e3, rel=0.05)


def test_catalogue_has_table_values():
    cat = blade_catalogue()
    assert set(cat) == set(TABLE_2_3)
    for name, knm in TABLE_2_3.items():
        assert cat[name].stiffness_n_per_m == pytest.approx(knm * 1e3)
    assert cat["Cat6"].body_mass_range_kg == (78.0, 83.0)
    assert cat["Cat6"].e_table == pytest.approx(804130.0)


def _write(tmp_path, mutate):
    data = default_runner_params("amputee").model_dump()
    data["athlete"] = dict(data["athlete"])
    data["segments"] = {k: dict(v) for k, v in data["segments"].items()}
    data["muscle_types"] = {k: dict(v) for k, v in data["muscle_types"].items()}
    mutate(data)
    path = tmp_path / "params.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_good_parameter_file_loads(tmp_path):
    path = _write(tmp_path, lambda d: None)
    assert load_runner_params(path).kind == "amputee"


def test_a_parameter_file_extends_another_by_replacing_its_top_level_keys(tmp_path):
    """A variant states only what differs: its keys replace the base file's, the rest is the
    base's; a missing base file, a loop and a non-name are named errors."""
    base = _write(tmp_path, lambda d: None)
    (tmp_path / "heavier.yaml").write_text(
        "extends: params.yaml\nathlete: {body_mass_kg: 90.0, height_m: 1.9}\n")
    heavy, plain = load_runner_params(tmp_path / "heavier.yaml"), load_runner_params(base)
    assert heavy.athlete.body_mass_kg == 90.0 and heavy.athlete.height_m == 1.9
    assert heavy.muscle_types == plain.muscle_types and heavy.segments == plain.segments
    (tmp_path / "twice.yaml").write_text("extends: heavier.yaml\nblade: Cat4\n")
    twice = load_runner_params(tmp_path / "twice.yaml")
    assert twice.blade == "Cat4" and twice.athlete.body_mass_kg == 90.0
    (tmp_path / "orphan.yaml").write_text("extends: nowhere.yaml\n")
    with pytest.raises(BladelabError, match="nowhere.yaml"):
        load_runner_params(tmp_path / "orphan.yaml")
    (tmp_path / "a.yaml").write_text("extends: b.yaml\n")
    (tmp_path / "b.yaml").write_text("extends: a.yaml\n")
    with pytest.raises(SpecError, match="loop"):
        load_runner_params(tmp_path / "a.yaml")
    (tmp_path / "bad.yaml").write_text("extends: [1, 2]\n")
    with pytest.raises(SpecError) as err:
        load_runner_params(tmp_path / "bad.yaml")
    assert err.value.where == "extends"


def test_unknown_category_is_a_clear_error(tmp_path):
    path = _write(tmp_path, lambda d: d.update(blade="Cat9"))
    with pytest.raises(SpecError) as err:
        load_runner_params(path)
    msg = str(err.value)
    assert "Cat9" in msg and "blade" in msg and "Cat6High" in msg and str(path) in msg


def test_negative_mass_is_a_clear_error(tmp_path):
    path = _write(tmp_path, lambda d: d["segments"]["pelvis"].update(mass_kg=-13.09))
    with pytest.raises(SpecError) as err:
        load_runner_params(path)
    msg = str(err.value)
    assert "segments.pelvis.mass_kg" in msg and "positive" in msg


def test_missing_muscle_is_a_clear_error(tmp_path):
    path = _write(tmp_path, lambda d: d["muscle_types"].pop("soleus"))
    with pytest.raises(SpecError) as err:
        load_runner_params(path)
    assert "soleus" in str(err.value) and "muscle_types" in str(err.value)


def test_missing_segment_and_bad_yaml(tmp_path):
    path = _write(tmp_path, lambda d: d["segments"].pop("prosthesis_r"))
    with pytest.raises(SpecError, match="prosthesis_r"):
        load_runner_params(path)
    bad = tmp_path / "bad.yaml"
    bad.write_text("kind: [able\n")
    with pytest.raises(BladelabError, match="YAML"):
        load_runner_params(bad)
    with pytest.raises(BladelabError, match="not found"):
        load_runner_params(tmp_path / "nope.yaml")


def _assert_same_centre_of_mass_standing(a, b) -> None:
    """Two runners standing have the same whole-body centre of mass, every contact on the
    ground."""
    centres = []
    for runner in (a, b):
        d = mujoco.MjData(runner.mj_model)
        d.qpos[:] = runner.stand_qpos
        mujoco.mj_forward(runner.mj_model, d)
        centres.append(d.subtree_com[0].copy())
        assert contact_heights(runner, runner.stand_qpos) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(centres[1], centres[0], atol=1e-12)


def test_toe_body_keeps_the_mass_and_adds_a_toe_hinge(able):
    """The ``toes`` body: same total mass and centre of mass as seed 001's (the toes' mass is
    taken from the calcaneus), a metatarsophalangeal hinge per foot with Sasaki et al. (2009)'s
    spring, a toe-tip sphere level with the ball sphere, and compliant Achilles tendons only."""
    from bladelab.runner.layout import JP_SD, JP_SDX, JP_SK
    from bladelab.runner.muscle import MP_TSTRAIN
    from bladelab.runner.params import ToeHinge

    toes = build_runner("able", body="toes")
    assert toes.total_mass == pytest.approx(able.total_mass, rel=1e-12)
    assert set(toes.dof_names) - set(able.dof_names) == {"mtp_angle_l", "mtp_angle_r"}
    assert toes.contact_names == ("heel_l", "toe_l", "toetip_l", "heel_r", "toe_r", "toetip_r")
    _assert_same_centre_of_mass_standing(able, toes)
    j = toes.dof("mtp_angle_l")
    assert toes.joint_params[j, JP_SK] == 25.0 and toes.joint_params[j, JP_SD] == 0.03
    stiff = build_runner(default_runner_params("able", body="toes").model_copy(
        update={"toe_hinge": ToeHinge(stiffness_Nm_per_rad=17.0, damping_Nms_per_rad=2.0)}))
    for side in ("l", "r"):
        row = stiff.joint_params[stiff.dof(f"mtp_angle_{side}")]
        assert (row[JP_SK], row[JP_SD], row[JP_SDX]) == (17.0, 2.0, 2.0)
    tip = toes.contact_params[toes.contact_names.index("toetip_l")]
    assert toes.mj_model.body(int(tip[1])).name == "toes_l"
    strain = dict(zip(toes.muscle_names, toes.muscle_params[:, MP_TSTRAIN], strict=True))
    assert strain["soleus_l"] == strain["gastroc_r"] == 0.08
    assert strain["vasti_l"] == 0.04 and set(able.muscle_params[:, MP_TSTRAIN]) == {0.04}
    # the toes turn the toe tip about the ball: 30° of toe extension lifts it off the ground
    q = toes.stand_qpos.copy()
    q[j] = np.radians(30.0)
    h = contact_heights(toes, q)
    assert h[toes.contact_names.index("toetip_l")] > 0.01
    assert h[toes.contact_names.index("toe_l")] == pytest.approx(0.0, abs=1e-12)


def test_arch_adds_a_midtarsal_hinge_and_keeps_the_foot():
    """A foot with an arch: the forefoot (ball sphere and toes) turns on a midtarsal hinge with
    the arch's spring and damper; the foot's mass and centre of mass, the contacts standing and
    the coordinates but the two hinges stay the human body's. Turning the forefoot up (the
    arch compressed) lifts the heel off the ground with the ball on it."""
    from bladelab.runner.layout import JP_SD, JP_SDX, JP_SK
    from bladelab.runner.params import ArchSpring

    human = build_runner("able", body="human")
    params = default_runner_params("able", body="human")
    arch = build_runner(params.model_copy(update={"arch": ArchSpring(
        stiffness_Nm_per_rad=800.0, damping_Nms_per_rad=2.0)}))
    assert set(arch.dof_names) - set(human.dof_names) == {"midtarsal_angle_l",
                                                           "midtarsal_angle_r"}
    assert arch.contact_names == human.contact_names
    assert arch.total_mass == pytest.approx(human.total_mass, rel=1e-12)
    _assert_same_centre_of_mass_standing(human, arch)
    j = arch.dof("midtarsal_angle_l")
    assert tuple(arch.joint_params[j, [JP_SK, JP_SD, JP_SDX]]) == (800.0, 2.0, 2.0)
    ball = arch.contact_params[arch.contact_names.index("toe_l")]
    assert arch.mj_model.body(int(ball[1])).name == "forefoot_l"
    assert arch.mj_model.body(arch.mj_model.body("toes_l").parentid[0]).name == "forefoot_l"
    q = arch.stand_qpos.copy()
    q[j] = np.radians(10.0)  # the forefoot turned up about the hinge: the ball lifts
    h = contact_heights(arch, q)
    assert h[arch.contact_names.index("toe_l")] > 0.01
    assert h[arch.contact_names.index("heel_l")] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(BladelabError, match="toe segment"):
        runner_params_from_dict(default_runner_params("able").model_dump() | {"arch": {}})


def test_unknown_body_is_a_clear_error():
    with pytest.raises(SpecError, match="unknown body 'toe'"):
        build_runner("able", body="toe")


# SCONE's H0918 model (tests/data/scone-h0918/H0918.hfd), typed from the file: segment masses
# [kg] and the leg muscles' maximum isometric forces [N].
H0918_MASS = {"torso": 34.2366, "pelvis": 11.777, "femur": 9.3014, "tibia": 3.7075, "calcn": 1.25}
H0918_FMAX = {"hamstrings": 2594, "bifemsh": 804, "glut_max": 1944, "iliopsoas": 2342,
              "rect_fem": 1169, "vasti": 4530, "gastroc": 2241, "soleus": 3549, "tib_ant": 1759}


def test_human_body_is_h0918_scaled_to_a_75_kg_runner():
    """The ``human`` body: H0918's segment masses and muscle forces scaled to 75 kg and 1.80 m
    (masses and forces by 75 / 74.53: the height is the table's), a stronger active force, a
    toe segment, compliant Achilles tendons, the knee flexing to 140°."""
    runner = build_runner("able", body="human")
    table = H0918_MASS["torso"] + H0918_MASS["pelvis"] + 2 * sum(
        H0918_MASS[s] for s in ("femur", "tibia", "calcn"))
    ratio = 75.0 / table
    assert runner.total_mass == pytest.approx(75.0, rel=1e-12)
    assert runner.segment_mass("femur_l") == pytest.approx(H0918_MASS["femur"] * ratio)
    fmax = dict(zip(runner.muscle_names, runner.muscle_params[:, 0], strict=True))
    for name, force in H0918_FMAX.items():
        assert fmax[f"{name}_l"] == pytest.approx(force * ratio, rel=1e-12), name
    strain = dict(zip(runner.muscle_names, runner.muscle_params[:, 4], strict=True))
    assert strain["soleus_l"] == strain["gastroc_r"] == 0.08
    assert strain["vasti_l"] == 0.16 and strain["rect_fem_l"] == strain["glut_max_r"] == 0.049
    # active force at 30 N/cm² (people's strength, runner.strength) over the table's 25 N/cm²
    np.testing.assert_allclose(runner.muscle_params[:, 5], 30.0 / 25.0, rtol=1e-15)
    assert set(build_runner("able").muscle_params[:, 5]) == {1.0}  # seed 001: none
    e0 = dict(zip(runner.muscle_names, runner.muscle_params[:, 6], strict=True))
    assert e0["vasti_l"] == e0["hamstrings_r"] == 1.2 and e0["erect_sp_l"] == 0.6
    assert "mtp_angle_l" in runner.dof_names and "toetip_r" in runner.contact_names
    knee = runner.joint_params[runner.dof("knee_angle_l")]
    assert math.degrees(knee[0]) == pytest.approx(-140.0)


def test_human_body_scales_forces_by_mass_over_height():
    """Eq. 2.1's scaling holds for table forces too: Fmax ∝ m/h (volume ∝ mass, fibre length
    ∝ height)."""
    data = yaml.safe_load(default_runner_params("able", body="human").model_dump_json())
    data["athlete"] = {"body_mass_kg": 90.0, "height_m": 1.95}
    runner = build_runner(runner_params_from_dict(data))
    ref = build_runner("able", body="human")
    i = runner.muscle_names.index("vasti_l")
    expected = ref.muscle_params[i, 0] * (90.0 / 75.0) / (1.95 / 1.80)
    assert runner.muscle_params[i, 0] == pytest.approx(expected, rel=1e-12)
    assert runner.total_mass == pytest.approx(90.0, rel=1e-12)


@pytest.mark.parametrize("kind", ["amputee", "transfemoral"])
def test_human_body_builds_every_kind(kind):
    runner = build_runner(kind, body="human")
    assert "toetip_l" in runner.contact_names and "toetip_r" not in runner.contact_names
    assert runner.params.knee_flexion_limit_deg == 140.0
    h = contact_heights(runner, runner.stand_qpos)
    assert h.min() == pytest.approx(0.0, abs=1e-9)


def test_muscle_needs_exactly_one_strength(tmp_path):
    data = yaml.safe_load(default_runner_params("able").model_dump_json())
    data["muscle_types"]["vasti"]["max_isometric_force_N"] = 4000.0
    path = tmp_path / "both.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(SpecError, match="exactly one of volume_fraction and max_isometric"):
        load_runner_params(path)


def test_foot_contact_law_reaches_the_contact_spheres():
    """A parameter set's foot law is the one the contact rows carry (Hertz k = 4/3·E·√R)."""
    data = yaml.safe_load(default_runner_params("able").model_dump_json())
    data["foot_contact"] = {"plane_strain_modulus_N_per_m2": 1.0e6, "dissipation_s_per_m": 2.0,
                            "friction": 0.8}
    runner = build_runner(runner_params_from_dict(data))
    row = runner.contact_params[runner.contact_names.index("heel_l")]
    radius = row[2]
    assert row[3] == pytest.approx(4.0 / 3.0 * 1.0e6 * math.sqrt(radius), rel=1e-12)
    assert (row[4], row[5]) == (2.0, 0.8)


def test_capsule_moments_name_known_coordinates_and_default_to_none():
    """Seed 001's body has no capsule moment; a parameter set may give one per leg coordinate,
    and an unknown coordinate is refused naming it."""
    assert not build_runner("able").joint_params[:, JP_EA].any()
    data = yaml.safe_load(default_runner_params("able").model_dump_json())
    data["capsule_moments"] = {"knee_angle": {"moment_at_zero_Nm": -2.0, "rate_per_deg": 0.05}}
    runner = build_runner(runner_params_from_dict(data))
    row = runner.joint_params[runner.dof("knee_angle_r")]
    assert (row[JP_EA], row[JP_EB]) == (-2.0, pytest.approx(0.05 * 180.0 / math.pi))
    data["capsule_moments"] = {"elbow": {"moment_at_zero_Nm": 1.0, "rate_per_deg": 0.0}}
    with pytest.raises(SpecError, match="elbow"):
        runner_params_from_dict(data)


def test_athlete_params_scale_the_body_and_strengthen_only_the_active_force():
    """Mass and height scale segments and forces as eq. 2.1 does; the muscle strength
    multiplies the active force (MP_ACTIVE) and leaves Fmax, which sets the tendon and passive
    curves, alone; nothing given changes nothing."""
    from bladelab.runner.muscle import MP_ACTIVE, MP_FMAX
    from bladelab.runner.scaling import athlete_params

    base = default_runner_params("able", body="human")
    assert athlete_params(base) == base
    ref = build_runner(base)
    runner = build_runner(athlete_params(base, body_mass_kg=68.0, height_m=1.75,
                                         muscle_strength=1.5))
    assert runner.total_mass == pytest.approx(68.0, rel=1e-12)
    np.testing.assert_allclose(runner.muscle_params[:, MP_FMAX],
                               ref.muscle_params[:, MP_FMAX] * (68.0 / 75.0) / (1.75 / 1.80),
                               rtol=1e-12)
    np.testing.assert_allclose(runner.muscle_params[:, MP_ACTIVE],
                               ref.muscle_params[:, MP_ACTIVE] * 1.5, rtol=1e-12)
    for bad in (0.0, -1.0, float("inf")):
        with pytest.raises(SpecError) as err:
            athlete_params(base, muscle_strength=bad)
        assert err.value.where == "muscle_strength"
    with pytest.raises(SpecError):
        athlete_params(base, body_mass_kg=-5.0)


def test_the_maximum_shortening_velocity_is_every_muscle_s_and_nothing_else():
    """10 l_opt/s unless set (the MP_VMAX column of every muscle); an athlete's value replaces
    it and leaves every other muscle parameter as it was; outside 2–30 l_opt/s refused."""
    from bladelab.runner.muscle import MP_VMAX
    from bladelab.runner.scaling import athlete_params

    base = default_runner_params("amputee", body="human")
    ref = build_runner(base)
    assert set(ref.muscle_params[:, MP_VMAX]) == {10.0}
    fast = build_runner(athlete_params(base, max_shortening_velocity=15.0))
    assert set(fast.muscle_params[:, MP_VMAX]) == {15.0}
    np.testing.assert_array_equal(fast.muscle_params[:, :MP_VMAX], ref.muscle_params[:, :MP_VMAX])
    for bad in (1.0, 31.0, float("nan"), "fast"):
        with pytest.raises(SpecError) as err:
            athlete_params(base, max_shortening_velocity=bad)
        assert err.value.where == "athlete.max_shortening_velocity"


def test_the_residual_limb_s_length_moves_the_socket_and_keeps_the_leg_and_the_athlete():
    """A residual tibia of 12 or 35 cm (60 % = 25.8 cm unless set): the socket hinge sits that
    far below the knee; the residual tibia's mass follows its length and its inertia mass ×
    length²; the model still weighs the athlete's 73.24 kg, the straight prosthetic leg is as
    long (knee to ground) and the muscles are the same; a runner without a residual tibia, or
    a length outside 20–90 % of the tibia, is refused naming the field."""
    from bladelab.runner.scaling import athlete_params

    base = default_runner_params("amputee", body="human")
    table = {name: seg.mass_kg for name, seg in base.segments.items()}

    def measures(runner):
        m = runner.mj_model
        d = mujoco.MjData(m)
        res = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "tibia_res_r")
        pros = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "prosthesis_r")
        knee = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "knee_angle_r")
        q = np.zeros(m.nq)
        q[runner.dof("pelvis_tz")] = 1.0
        heights = contact_heights(runner, q, d)  # straight legs, upright pelvis
        lowest = heights[runner.contact_params[:, CP_LEG] == 1].min()
        return (m.body_mass[res], m.body_inertia[res][0], -m.body_pos[pros][2],
                d.xanchor[knee][2] - lowest)

    ref = build_runner(base)
    m_ref, i_ref, socket_ref, leg_ref = measures(ref)
    assert socket_ref == pytest.approx(0.6 * 0.43, rel=1e-12)
    for length in (0.12, 0.35):
        runner = build_runner(athlete_params(base, residual_limb_length_m=length))
        mass, inertia, socket, leg = measures(runner)
        k = length / socket_ref
        assert socket == pytest.approx(length, rel=1e-12)
        assert runner.total_mass == pytest.approx(73.24, rel=1e-12)
        # the other segments carry the difference: the athlete's mass over the table's
        others = sum(table.values()) - table["tibia_res_r"]
        ratio = 73.24 / (others + k * table["tibia_res_r"])
        assert mass == pytest.approx(k * table["tibia_res_r"] * ratio, rel=1e-12)
        assert inertia / mass == pytest.approx(k**2 * i_ref / m_ref, rel=1e-9)
        assert leg == pytest.approx(leg_ref, abs=1e-9)
        np.testing.assert_array_equal(runner.muscle_params, ref.muscle_params)
        assert contact_heights(runner, runner.stand_qpos).min() == pytest.approx(0.0, abs=1e-6)
    for bad in (0.05, 0.40, float("nan"), "long"):
        with pytest.raises(SpecError) as err:
            athlete_params(base, residual_limb_length_m=bad)
        assert err.value.where == "athlete.residual_limb_length_m"
    with pytest.raises(SpecError, match="no residual tibia"):
        athlete_params(default_runner_params("able", body="human"), residual_limb_length_m=0.2)


def test_the_prosthetic_leg_s_extra_length_lowers_the_blade_alone():
    """The prosthetic leg set 4.5 or 8 cm longer than the intact one (3 cm unless set): the
    straight prosthetic leg's lowest point drops by the difference, at 1.80 m and, the length
    being the athlete's own, at 1.70 m (3 cm scaled with the height); the intact leg, the mass
    and the muscles stay; the transfemoral runner's leg (its athlete 1.56 m) follows too; a length outside 0–10 cm (scaled with the height)
    or the able runner is refused naming the field."""
    from bladelab.runner.scaling import athlete_params

    def lowest(runner, leg):
        q = np.zeros(runner.mj_model.nq)
        q[runner.dof("pelvis_tz")] = 1.0
        heights = contact_heights(runner, q)  # straight legs, upright pelvis
        return heights[runner.contact_params[:, CP_LEG] == leg].min()

    for kind, height in (("amputee", None), ("amputee", 1.70), ("transfemoral", None)):
        base = default_runner_params(kind, body="human")
        if height is not None:
            base = athlete_params(base, height_m=height)
        ref = build_runner(base)
        for extra in (0.045, 0.08):
            runner = build_runner(athlete_params(base, prosthesis_extra_length_m=extra))
            ratio = base.athlete.height_m / 1.80  # the transfemoral athlete: 1.56 m
            assert lowest(ref, 1) - lowest(runner, 1) == pytest.approx(
                extra - 0.03 * ratio, abs=1e-9)
            assert lowest(runner, 0) == pytest.approx(lowest(ref, 0), abs=1e-12)
            assert runner.total_mass == pytest.approx(ref.total_mass, rel=1e-12)
            np.testing.assert_array_equal(runner.muscle_params, ref.muscle_params)
    base = default_runner_params("amputee", body="human")
    for bad in (-0.01, 0.11, float("nan"), "long"):
        with pytest.raises(SpecError) as err:
            athlete_params(base, prosthesis_extra_length_m=bad)
        assert err.value.where == "athlete.prosthesis_extra_length_m"
    with pytest.raises(SpecError, match="no prosthesis"):
        athlete_params(default_runner_params("able", body="human"),
                       prosthesis_extra_length_m=0.04)


def _neutral_tendon_lengths(runner) -> np.ndarray:
    """MuJoCo's muscle–tendon lengths [m] with every coordinate at 0 (standing straight)."""
    m = runner.mj_analysis_model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return d.ten_length.copy()


def test_thigh_and_shank_lengths_scale_their_segments_and_the_muscles_lengths():
    """Thighs of 0.459 m and shanks of 0.40 m (the model's 0.396 / 0.430 m at 1.80 m): the
    joint centres lie that far apart; segment masses stay; every muscle's optimal fibre and
    tendon slack lengths change as its muscle–tendon length standing straight does, as MuJoCo
    measures it (OpenSim's scaling rule); the trunk's muscles keep theirs; the amputee's
    straight prosthetic leg stays 3 cm longer than the intact one; out of 80–130 % refused."""
    from bladelab.runner.muscle import MP_LOPT, MP_LTS
    from bladelab.runner.scaling import athlete_params

    base = default_runner_params("able", body="human")
    ref = build_runner(base)
    runner = build_runner(athlete_params(base, thigh_length_m=0.459, shank_length_m=0.40))
    m = runner.mj_model
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)

    def anchor(name):
        return d.xanchor[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]

    for side in ("l", "r"):
        assert np.linalg.norm(anchor(f"hip_flexion_{side}") - anchor(f"knee_angle_{side}")) \
            == pytest.approx(0.459, rel=1e-9)
        assert np.linalg.norm(anchor(f"knee_angle_{side}") - anchor(f"ankle_angle_{side}")) \
            == pytest.approx(0.40, rel=1e-9)
    np.testing.assert_array_equal(m.body_mass, ref.mj_model.body_mass)
    ratio = _neutral_tendon_lengths(runner) / _neutral_tendon_lengths(ref)
    for col in (MP_LOPT, MP_LTS):
        np.testing.assert_allclose(runner.muscle_params[:, col] / ref.muscle_params[:, col],
                                   ratio, rtol=1e-9)
    trunk = [i for i, n in enumerate(runner.muscle_names) if n[:-2] in TORSO_MUSCLES]
    assert np.all(ratio[trunk] == pytest.approx(1.0, abs=1e-12))
    assert abs(ratio - 1.0).max() > 0.1  # the vasti cross the longer thigh

    amputee = build_runner(athlete_params(default_runner_params("amputee", body="human"),
                                          shank_length_m=0.40))
    q = np.zeros(amputee.mj_model.nq)
    q[amputee.dof("pelvis_tz")] = 1.0
    heights = contact_heights(amputee, q)
    legs = amputee.contact_params[:, CP_LEG]
    assert heights[legs == 0].min() - heights[legs == 1].min() == pytest.approx(0.03, abs=1e-9)
    for field, bad in (("thigh_length_m", 0.30), ("shank_length_m", 0.60)):
        with pytest.raises(SpecError) as err:
            athlete_params(base, **{field: bad})
        assert err.value.where == f"athlete.{field}"
