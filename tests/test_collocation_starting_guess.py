"""The initial guess named by a word: the stored stride of the human body."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml

from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.starting_guess import (
    STORED_STRIDES,
    first_origin,
    make_guess,
    resolve_guess,
    stored_stride_path,
)
from bladelab.runner import build_runner, default_runner_params, runner_params_from_dict
from bladelab.runner.params import RUNNER_DATA_DIR

N = 20


@pytest.mark.parametrize(("kind", "blade"), [("able", None), ("amputee", "Cat6"),
                                             ("amputee", "Cat4")])
def test_stored_is_the_shipped_stride_of_the_human_body(kind, blade):
    """Every kind with a stored stride starts from it on the human body, any blade category;
    the stride is the file's own (the solver resamples it to its mesh)."""
    runner = build_runner(kind, blade=blade, body="human")
    path = stored_stride_path(runner)
    assert path == RUNNER_DATA_DIR / "collocation" / STORED_STRIDES[kind]
    stored = CollocationSolution.read(path)
    assert stored.model_spec["model"] == kind and stored.model_spec["body"] == "human"
    assert stored.converged
    guess = make_guess(runner, "stored", n=N, speed=4.0)
    assert path.name in guess.source
    np.testing.assert_array_equal(guess.q, stored.nlp.q)


def test_another_athlete_of_the_human_body_starts_from_its_stored_stride():
    """Mass, height, muscle strength, the fibres' velocity and the residual limb scale the same
    body: its shipped stride is the start."""
    from bladelab.runner.scaling import athlete_params

    params = athlete_params(default_runner_params("amputee", blade="Cat5", body="human"),
                            body_mass_kg=64.0, height_m=1.70, muscle_strength=1.3,
                            max_shortening_velocity=12.0, residual_limb_length_m=0.15,
                            thigh_length_m=0.42)
    runner = build_runner(params)
    path = stored_stride_path(runner)
    assert path == RUNNER_DATA_DIR / "collocation" / STORED_STRIDES["amputee"]
    own = make_guess(build_runner("amputee", body="human"), "stored", n=N, speed=4.0)
    scaled = make_guess(runner, "stored", n=N, speed=4.0)
    assert own.multipliers is not None and scaled.multipliers is None  # another problem's
    names = list(own.dof_names)
    # the pelvis at the athlete's height, raised by the longer thighs: hip to sole 0.42 m +
    # 0.43 × 1.70 / 1.80 + the foot's 0.057 × 1.70 / 1.80, against the height-scaled model's
    foot = 0.01195 + 0.015 + 0.03
    leg = (0.42 + (0.43 + foot) * 1.70 / 1.80) / ((0.396 + 0.43 + foot) * 1.70 / 1.80)
    for name, factor in (("pelvis_tx", 1.70 / 1.80), ("pelvis_tz", 1.70 / 1.80 * leg)):
        j = names.index(name)
        np.testing.assert_allclose(scaled.q[:, j], own.q[:, j] * factor, rtol=1e-9)
    j = names.index("knee_angle_l")  # angles as they were
    np.testing.assert_array_equal(scaled.q[:, j], own.q[:, j])
    assert "scaled to the athlete" in scaled.source


def test_stored_falls_back_to_the_trial_elsewhere_and_says_so():
    """Seed 001's body, the transfemoral runner and a changed parameter set have no stored
    stride: the measured trial, its source naming the fallback."""
    changed = yaml.safe_load(default_runner_params("able", body="human").model_dump_json())
    changed["muscle_types"]["vasti"]["tendon_slack_length_m"] = 0.146
    for runner in (build_runner("able"), build_runner("transfemoral", body="human"),
                   build_runner(runner_params_from_dict(changed))):
        assert stored_stride_path(runner) is None
        guess = make_guess(runner, "stored", n=N, speed=3.5)
        assert "trial" in guess.source and "no stored stride" in guess.source
    assert resolve_guess("stored") == "stored"


def test_stored_strides_hold_their_provenance_in_the_folder_readme():
    readme = (RUNNER_DATA_DIR / "collocation" / "README.md").read_text()
    for name in STORED_STRIDES.values():
        assert f"`{name}`" in readme
        data = json.loads((RUNNER_DATA_DIR / "collocation" / name).read_text())
        assert data["kind"] == "collocation-solution"


def test_a_guess_names_the_first_origin_of_a_chain_of_solutions():
    chain = ("collocation solution b.json (collocation solution a.json (RBDS001runT35.c3d: "
             "mean of 41 left-leg cycles at 3.5 m/s)), stride ≥ 0.4 s)")
    assert first_origin(chain) == "RBDS001runT35.c3d: mean of 41 left-leg cycles at 3.5 m/s"
    once = "collocation solution c.json (first started from template stride at 4 m/s)"
    assert first_origin(once) == "template stride at 4 m/s"
    assert first_origin("the trial") == "the trial"
