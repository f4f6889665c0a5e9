"""People's joint angles as a reference of the predictive objective."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import SpecError
from bladelab.predict.collocation.people import (
    PROSTHETIC_JOINTS,
    people_joint_angles,
    people_reference,
)
from bladelab.predict.collocation.settings import (
    PEOPLE_REFERENCE,
    CollocationSettings,
    people_term,
)

ABLE_DOFS = ("pelvis_tx", "pelvis_tz", "pelvis_tilt", "hip_flexion_l", "knee_angle_l",
             "ankle_angle_l", "mtp_angle_l", "hip_flexion_r", "knee_angle_r", "ankle_angle_r",
             "mtp_angle_r", "lumbar_extension")
AMPUTEE_DOFS = ("pelvis_tx", "pelvis_tz", "pelvis_tilt", "hip_flexion_l", "knee_angle_l",
                "ankle_angle_l", "mtp_angle_l", "hip_flexion_r", "knee_angle_r",
                "socket_angle_r", "lumbar_extension")


def test_people_run_with_a_deep_swing_and_a_push_off():
    """The packaged curves are people's running at 3.5 m/s (Novacheck 1998; Fukuchi et al.
    2017): a swing knee of about 100°, a plantarflexed ankle at toe-off, a hip from about 45°
    of flexion to 10–15° of extension; knee flexion negative in the model's signs."""
    curves = people_joint_angles()
    assert set(curves) == {"hip_flexion", "knee_angle", "ankle_angle"}
    assert all(c.shape == (100,) for c in curves.values())
    assert 95 < -np.degrees(curves["knee_angle"].min()) < 120
    assert np.degrees(curves["ankle_angle"].min()) < -20
    assert 35 < np.degrees(curves["hip_flexion"].max()) < 55
    assert -20 < np.degrees(curves["hip_flexion"].min()) < -5
    # the heel strike is the first sample: the knee is near its straightest there and flexes
    assert -np.degrees(curves["knee_angle"][0]) < 20
    assert curves["knee_angle"][10] < curves["knee_angle"][0]


def _people_stride(dofs, phase: float, n: int = 50) -> np.ndarray:
    curves = people_joint_angles()
    frac = np.linspace(0.0, 1.0, n + 1)
    q = np.random.default_rng(3).normal(size=(n + 1, len(dofs)))
    for j, name in enumerate(dofs):
        base, side = name.rsplit("_", 1)
        if base in curves and side in "lr":
            shift = phase + (0.5 if side == "r" else 0.0)
            q[:, j] = np.interp(np.mod(frac - shift, 1.0), np.arange(100) / 100, curves[base],
                                period=1.0)
    return q


@pytest.mark.parametrize("phase", [0.0, 0.3, 0.8125])
def test_the_reference_is_shifted_to_the_start_s_phase(phase):
    q = _people_stride(ABLE_DOFS, phase)
    q_ref, dofs, found = people_reference(ABLE_DOFS, q)
    assert found == pytest.approx(phase, abs=1.0 / 400)
    assert dofs == ("hip_flexion_l", "knee_angle_l", "ankle_angle_l", "hip_flexion_r",
                    "knee_angle_r", "ankle_angle_r")
    cols = [ABLE_DOFS.index(d) for d in dofs]
    np.testing.assert_allclose(q_ref[:, cols], q[:, cols], atol=0.02)
    others = [j for j in range(len(ABLE_DOFS)) if j not in cols]
    np.testing.assert_array_equal(q_ref[:, others], q[:, others])


def test_a_prosthetic_leg_tracks_only_the_joints_it_has():
    q = _people_stride(AMPUTEE_DOFS, 0.1)
    _, dofs, _ = people_reference(AMPUTEE_DOFS, q)
    assert "ankle_angle_r" not in dofs and "socket_angle_r" not in dofs
    assert {"hip_flexion_r", "knee_angle_r", "ankle_angle_l"} <= set(dofs)
    with pytest.raises(SpecError, match="ankle_angle_r"):
        people_reference(AMPUTEE_DOFS, q, dofs=("ankle_angle_r",))
    # the transfemoral runner's right knee is a prosthetic knee: never people's
    transfemoral = tuple(d for d in AMPUTEE_DOFS if d != "socket_angle_r")
    _, dofs, _ = people_reference(transfemoral, _people_stride(transfemoral, 0.1),
                                  exclude=PROSTHETIC_JOINTS["transfemoral"])
    assert "knee_angle_r" not in dofs and "knee_angle_l" in dofs


def test_a_start_of_the_wrong_shape_is_refused():
    with pytest.raises(SpecError, match="nodes"):
        people_reference(ABLE_DOFS, np.zeros((51, 3)))


def test_people_term_settings():
    assert people_term(0.0) == {}
    s = CollocationSettings(**people_term(10.0))
    assert s.reference == PEOPLE_REFERENCE and s.reference_weight == 10.0
    assert s.reference_key() == (PEOPLE_REFERENCE, 10.0, None)
    assert not s.same_problem(CollocationSettings())


def test_a_given_phase_is_kept_rather_than_fitted():
    """A stride solved against the reference moved towards it, so its best fit moved too: a
    solve from it passes the phase it was solved with."""
    q = _people_stride(ABLE_DOFS, 0.3)
    q_ref, _, phase = people_reference(ABLE_DOFS, q, phase=1.05)
    assert phase == pytest.approx(0.05)
    again, _, _ = people_reference(ABLE_DOFS, _people_stride(ABLE_DOFS, 0.05), phase=0.05)
    np.testing.assert_allclose(q_ref[:, 3:6], again[:, 3:6], rtol=1e-12, atol=1e-12)
    with pytest.raises(SpecError, match="phase"):
        people_reference(ABLE_DOFS, q, phase=float("nan"))
