"""Seed 001's per-stride quantities of a collocation solution (``analyses.stride_analyses``),
checked against computations of our own from the stored node arrays of a converged solution
(amputee Cat6 at 4 m/s, 50 mesh intervals): the centre of mass and the contact points'
velocities by MuJoCo, the muscle and passive joint torques by the collocation model's moment
arms and passive law. With ``refine=1`` the analyses' samples are the nodes, so the numbers
must agree to round-off; with the default refinement they must satisfy physics (energy
balance of the periodic stride, work of the ground force on the centre of mass, the blade's
elastic energy)."""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pytest

from bladelab.errors import SpecError
from bladelab.predict.collocation import build_collocation_model
from bladelab.predict.collocation.analyses import (
    SCONE_BASAL_W_PER_KG,
    SCONE_SPECIFIC_TENSION_PA,
    cost_of_transport,
    stride_analyses,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.runner.layout import CP_BLADE, CP_BODY, CP_EXP, CP_K

SOLUTION = (Path(__file__).resolve().parents[1] / "benchmarks" / "collocation" / "study-4mps"
            / "amputee-Cat6" / "speed-4.json")
THRESHOLD_N = 20.0  # a leg is loaded above this vertical force (the analyses' threshold) [N]
# joint coordinate -> (joint, leg) in the keys
JOINTS = {"hip_flexion_l": ("hip", "intact"), "knee_angle_l": ("knee", "intact"),
          "ankle_angle_l": ("ankle", "intact"), "hip_flexion_r": ("hip", "prosthetic"),
          "knee_angle_r": ("knee", "prosthetic"), "socket_angle_r": ("socket", "prosthetic")}


@pytest.fixture(scope="module")
def case():
    sol = CollocationSolution.read(SOLUTION)
    runner = runner_from_spec(sol.model_spec)
    cm = build_collocation_model(runner)
    return sol, runner, cm


@pytest.fixture(scope="module")
def nodes(case):
    """Per node (n + 1 rows): time [s], leg vertical forces [N], COM height [m] and vertical
    speed [m/s], muscle + passive generalised forces [N, N·m], each contact's power [W] and
    penetration [m]."""
    sol, runner, cm = case
    q, qd, ft = sol.nlp.q, sol.nlp.qd, sol.nlp.tendon_force
    n1 = q.shape[0]
    m = runner.mj_model
    d = mujoco.MjData(m)
    fmax = runner.muscle_params[:, 0]
    nc = runner.contact_params.shape[0]
    com_z, com_vz = np.zeros(n1), np.zeros(n1)
    tau = np.zeros((n1, m.nv))
    power, depth = np.zeros((n1, nc)), np.zeros((n1, nc))
    jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for k in range(n1):
        d.qpos[:], d.qvel[:] = q[k], qd[k]
        mujoco.mj_forward(m, d)
        mujoco.mj_subtreeVel(m, d)
        com_z[k], com_vz[k] = d.subtree_com[0, 2], d.subtree_linvel[0, 2]
        tau[k] = (np.asarray(cm.moment_arms(q[k])).T @ (ft[k] * fmax)
                  + np.asarray(cm.passive(q[k], qd[k])).ravel())
        points = np.asarray(cm.contacts(q[k], qd[k])[1])
        for c in range(nc):
            mujoco.mj_jac(m, d, jp, jr, np.array([points[c, 0], 0.0, points[c, 1]]),
                          int(runner.contact_params[c, CP_BODY]))
            v = jp @ qd[k]  # the body's material point at the contact point
            f = sol.contact_forces[k, c]
            power[k, c] = f[0] * v[0] + f[1] * v[2]
            depth[k, c] = max(-points[c, 1], 0.0)
    legs = sol.contact_legs
    fz = np.stack([sol.contact_forces[:, legs == j, 1].sum(axis=1) for j in (0, 1)], axis=1)
    return {"t": sol.nlp.time, "fz": fz, "com_z": com_z, "com_vz": com_vz, "tau": tau,
            "power": power, "depth": depth}


@pytest.fixture(scope="module")
def at_nodes(case):
    sol, runner, cm = case
    return stride_analyses(sol, runner, refine=1, cm=cm)


@pytest.fixture(scope="module")
def refined(case):
    sol, runner, cm = case
    return stride_analyses(sol, runner, cm=cm)


def _tiled(a: np.ndarray) -> np.ndarray:
    """Node values of three strides (3n + 1 rows) from one periodic stride (n + 1 rows)."""
    n = a.shape[0] - 1
    return np.concatenate([a[:n]] * 3 + [a[:1]])


def _middle_stance(loaded: np.ndarray, n: int) -> tuple[int, int]:
    """(first loaded, first unloaded) index of the loaded stretch that starts in the middle
    stride of tiled node values."""
    first = next(i for i in range(n, 2 * n) if loaded[i] and not loaded[i - 1])
    stop = first
    while loaded[stop]:
        stop += 1
    return first, stop


def test_keys_name_the_legs_joints_and_units(at_nodes, refined):
    assert at_nodes.keys() == refined.keys()
    units = ("_kN_per_m", "_W_per_kg", "_J", "_pct", "_J_per_kg_m", "_N", "_Nm")
    assert all(k.endswith(units) for k in refined), [k for k in refined if not k.endswith(units)]
    assert not any("left" in k or "right" in k for k in refined)
    for joint, leg in [*JOINTS.values(), ("rsp", "prosthetic")]:
        for sign in ("positive", "negative"):
            assert f"{sign}_power_{joint}_{leg}_W_per_kg" in refined
    assert "positive_power_ankle_prosthetic_W_per_kg" not in refined
    for key in ("leg_stiffness_intact_kN_per_m", "leg_energy_stored_prosthetic_J",
                "leg_recoil_intact_pct", "leg_energy_generated_total_J",
                "blade_energy_stored_J", "blade_energy_returned_J", "blade_hysteresis_J",
                "blade_recoil_pct", "positive_power_total_W_per_kg", "socket_force_max_N",
                "socket_moment_max_Nm"):
        assert math.isfinite(refined[key]), key
    assert all(v <= 0 for k, v in refined.items() if k.startswith("negative_power_"))
    assert all(v >= 0 for k, v in refined.items() if k.startswith("positive_power_"))


def test_able_model_has_left_and_right_legs_and_no_blade():
    from collocation_fake import fake_solution

    runner, cm, sol = fake_solution("able", 12)
    out = stride_analyses(sol, runner, refine=2, cm=cm)
    assert "positive_power_ankle_left_W_per_kg" in out and "leg_stiffness_right_kN_per_m" in out
    assert not any(k.startswith("blade_") or "intact" in k for k in out)
    with pytest.raises(SpecError, match="refine"):
        stride_analyses(sol, runner, refine=0, cm=cm)


def test_joint_powers_at_the_nodes_are_torque_times_speed_over_one_stride(case, nodes,
                                                                          at_nodes):
    """P± = ∫ max(±τ·q̇, 0) dt / (T·m) over the stride, τ the muscle (rᵀ·F) and passive
    torque; the RSP's is the blade contact's power F·v."""
    sol, runner, _ = case
    t, qd = nodes["t"], sol.nlp.qd
    scale = sol.period_s * runner.total_mass  # [s·kg]
    powers = {JOINTS[name]: nodes["tau"][:, j] * qd[:, j]
              for j, name in enumerate(runner.dof_names) if name in JOINTS}
    blade = runner.contact_params[:, CP_BLADE] == 1
    powers["rsp", "prosthetic"] = nodes["power"][:, blade].sum(axis=1)
    for (joint, leg), p in powers.items():
        pos = np.trapezoid(np.maximum(p, 0.0), t) / scale
        neg = np.trapezoid(np.minimum(p, 0.0), t) / scale
        assert at_nodes[f"positive_power_{joint}_{leg}_W_per_kg"] == pytest.approx(
            pos, rel=1e-6, abs=1e-9), joint
        assert at_nodes[f"negative_power_{joint}_{leg}_W_per_kg"] == pytest.approx(
            neg, rel=1e-6, abs=1e-9), joint
    total = sum(np.trapezoid(np.maximum(p, 0.0), t) for p in powers.values()) / scale
    assert at_nodes["positive_power_total_W_per_kg"] == pytest.approx(total, rel=1e-6)


def test_joint_works_close_the_energy_balance_of_the_periodic_stride(case, nodes, refined):
    """Over a periodic stride the kinetic and potential energies return to their start, so the
    work of the joints (and the RSP) plus that of everything else — the feet's contacts, the
    muscles and ligaments of the trunk and pelvis — is zero. The stride satisfies the dynamics
    at every node; what remains is the quadrature of a 50-interval mesh, well under 1 % of the
    positive work."""
    sol, runner, _ = case
    t, qd = nodes["t"], sol.nlp.qd
    scale = sol.period_s * runner.total_mass
    joints = (refined["positive_power_total_W_per_kg"]
              + refined["negative_power_total_W_per_kg"]) * scale  # [J]
    others = [j for j, name in enumerate(runner.dof_names) if name not in JOINTS]
    rest = np.trapezoid((nodes["tau"][:, others] * qd[:, others]).sum(axis=1), t)
    feet = runner.contact_params[:, CP_BLADE] == 0
    contact = np.trapezoid(nodes["power"][:, feet].sum(axis=1), t)
    positive = refined["positive_power_total_W_per_kg"] * scale
    assert positive > 100.0  # [J]: a running stride, not an empty one
    assert abs(joints + rest + contact) < 0.01 * positive


def test_leg_energy_is_the_ground_force_work_on_the_centre_of_mass(case, nodes, at_nodes,
                                                                     refined):
    """Stored: −∫F_z dz while the COM descends, generated: ∫F_z dz while it rises, over the
    leg's stance in the middle stride. At the nodes exactly so; refined, their difference is
    the work ∫F_z·ż dt of the node values within the quadrature of a 50-interval mesh (5 % of
    the energies)."""
    sol, _, _ = case
    n = sol.nlp.q.shape[0] - 1
    z, vz = _tiled(nodes["com_z"]), _tiled(nodes["com_vz"])
    h = sol.period_s / n
    for j, leg in enumerate(sol.leg_names):
        fz = _tiled(nodes["fz"][:, j])
        first, stop = _middle_stance(fz > THRESHOLD_N, n)
        dz = np.diff(z[first:stop + 1])
        f = 0.5 * (fz[first:stop] + fz[first + 1:stop + 1])
        stored = -np.sum(f * np.minimum(dz, 0.0))
        generated = np.sum(f * np.maximum(dz, 0.0))
        assert at_nodes[f"leg_energy_stored_{leg}_J"] == pytest.approx(stored, rel=1e-6)
        assert at_nodes[f"leg_energy_generated_{leg}_J"] == pytest.approx(generated, rel=1e-6)
        work = np.trapezoid(fz[first - 1:stop + 1] * vz[first - 1:stop + 1], dx=h)
        s, g = refined[f"leg_energy_stored_{leg}_J"], refined[f"leg_energy_generated_{leg}_J"]
        assert g - s == pytest.approx(work, abs=0.05 * (s + g)), leg
        assert refined[f"leg_hysteresis_{leg}_J"] == pytest.approx(abs(s - g))
        assert refined[f"leg_recoil_{leg}_pct"] == pytest.approx(100 * min(s, g) / max(s, g))
    assert refined["leg_energy_generated_total_J"] == pytest.approx(
        refined["leg_energy_generated_intact_J"] + refined["leg_energy_generated_prosthetic_J"])


def test_leg_stiffness_is_peak_force_over_leg_compression(case, nodes, at_nodes):
    """K_leg = F_peak/ΔL with ΔL = Δy + L0·(1 − cos θ), sin θ = v·t_c/(2·L0) (seed 001
    eq. 2.19–2.21): between F_peak/(Δy + the largest L0·(1 − cos θ) of a leg 0.8–1.2 m long)
    and F_peak/Δy, with F_peak, the COM drop Δy, the stance time t_c and the forward speed v
    from the nodes."""
    sol, _, _ = case
    n = sol.nlp.q.shape[0] - 1
    z = _tiled(nodes["com_z"])
    h = sol.period_s / n
    for j, leg in enumerate(sol.leg_names):
        fz = _tiled(nodes["fz"][:, j])
        first, stop = _middle_stance(fz > THRESHOLD_N, n)
        peak = fz[first:stop].max()
        drop = z[first] - z[first:stop].min()
        tc = (stop - first) * h
        length = 0.8  # [m]: the shortest leg gives the largest L0·(1 − cos θ)
        theta = math.asin(sol.mean_speed_mps * tc / (2 * length))
        k = at_nodes[f"leg_stiffness_{leg}_kN_per_m"] * 1e3  # [N/m]
        assert peak / (drop + length * (1 - math.cos(theta))) <= k <= peak / drop, leg


def test_blade_stores_at_least_its_elastic_energy_and_returns_less(case, nodes, refined):
    """One compression and one recovery of the blade per stance: the stored energy is at least
    the elastic k·δ^(n+1)/(n+1) at the largest penetration δ of the nodes (the damping adds
    force while it compresses) and at most F_peak·δ; Hunt–Crossley damping loses energy, so
    less comes back than went in."""
    _, runner, _ = case
    blade = np.flatnonzero(runner.contact_params[:, CP_BLADE] == 1)
    assert blade.size == 1
    b = int(blade[0])
    k, expo = runner.contact_params[b, CP_K], runner.contact_params[b, CP_EXP]
    depth = nodes["depth"][:, b].max()
    peak = case[0].contact_forces[:, b, 1].max()
    stored, returned = refined["blade_energy_stored_J"], refined["blade_energy_returned_J"]
    assert k * depth ** (expo + 1) / (expo + 1) <= stored <= peak * depth
    assert 0.0 < returned < stored
    assert refined["blade_hysteresis_J"] == pytest.approx(stored - returned)
    assert refined["blade_recoil_pct"] == pytest.approx(100 * returned / stored)


def test_the_cost_of_transport_is_the_solution_s_own_and_scone_s_differs_by_mass_and_basal(
        case):
    """:func:`cost_of_transport` at the model's own muscle masses and basal rate is the cost
    the NLP integrated (another path through the same smooth model); SCONE's accounting
    changes the basal term by exactly (1.51 − 1.2) W/kg over the stride, and on seed 001's
    body (masses from 60 N/cm²) adds muscle cost: SCONE counts 2.4 times the muscle mass."""
    sol, runner, cm = case
    mass = float(runner.total_mass)
    j = list(sol.dof_names).index("pelvis_tx")
    distance = float(sol.nlp.q[-1, j] - sol.nlp.q[0, j])
    own = cost_of_transport(sol, runner, cm=cm)
    assert own == pytest.approx(sol.metabolic_energy_J / (mass * distance), rel=1e-9)
    basal_only = cost_of_transport(sol, runner, basal_w_per_kg=SCONE_BASAL_W_PER_KG, cm=cm)
    assert own - basal_only == pytest.approx(
        (1.51 - SCONE_BASAL_W_PER_KG) * sol.period_s / distance, rel=1e-9)
    scone = cost_of_transport(sol, runner, specific_tension_pa=SCONE_SPECIFIC_TENSION_PA,
                              basal_w_per_kg=SCONE_BASAL_W_PER_KG, cm=cm)
    assert runner.params.specific_tension_N_per_cm2 == 60.0  # seed 001's body
    assert scone > 1.3 * basal_only
