"""Export of a runner trajectory: OpenSim .mot files (coordinates, external loads) read back by
a plain parser and, where installed, by OpenSim itself; the states CSV; the ExternalLoads XML."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bladelab.errors import InputFileError
from bladelab.runner import build_runner, simulate_runner
from bladelab.runner.export import (
    OPENSIM_PELVIS_ORIGIN_M,
    leg_ground_force,
    read_mot,
    write_opensim,
)
from conftest import SCONE_H0918
from test_runner_analyses import STANCES, _synthetic


@pytest.fixture(scope="module")
def run():
    """0.3 s of the amputee landing and running on with constant excitations."""
    model = build_runner("amputee")
    return simulate_runner(model, duration=0.3, excitations=0.1, initial_state="gait",
                           initial_speed=2.0, fall_height=-math.inf)


@pytest.fixture(scope="module")
def files(run, tmp_path_factory):
    return write_opensim(run, tmp_path_factory.mktemp("export") / "out")


def test_mot_files_read_back_with_a_plain_parser(run, files):
    model = run.model
    header, coords = read_mot(files["coordinates"])
    assert header["name"] == "coordinates" and header["version"] == "1"
    assert header["inDegrees"] == "yes"
    assert int(header["nRows"]) == len(run.time) == len(coords)
    assert int(header["nColumns"]) == coords.shape[1]
    assert list(coords.columns[:4]) == ["time", "pelvis_tilt", "pelvis_tx", "pelvis_ty"]
    assert "pelvis_tz" not in coords.columns  # OpenSim's vertical translation is pelvis_ty
    np.testing.assert_allclose(coords.time, run.time, rtol=1e-8)
    for dof in ("pelvis_tilt", "hip_flexion_l", "knee_angle_r", "socket_angle_r"):
        np.testing.assert_allclose(coords[dof], np.degrees(run.qpos[:, model.dof(dof)]),
                                   rtol=1e-7, atol=1e-9)
    tilt = run.qpos[:, model.dof("pelvis_tilt")]
    np.testing.assert_allclose(
        coords.pelvis_ty,
        run.qpos[:, model.dof("pelvis_tz")] + OPENSIM_PELVIS_ORIGIN_M * np.sin(tilt), rtol=1e-7)
    header, grf = read_mot(files["grf"])
    assert int(header["nRows"]) == len(run.time)
    for side, leg in (("l", 0), ("r", 1)):
        fx, fz, cop = leg_ground_force(run, leg)
        np.testing.assert_allclose(grf[f"ground_force_{side}_vx"], fx, rtol=1e-7, atol=1e-6)
        np.testing.assert_allclose(grf[f"ground_force_{side}_vy"], fz, rtol=1e-7, atol=1e-6)
        np.testing.assert_allclose(grf[f"ground_force_{side}_px"], cop, rtol=1e-7, atol=1e-9)
        for col in (f"ground_force_{side}_vz", f"ground_torque_{side}_x"):
            assert (grf[col] == 0).all()
    assert grf["ground_force_r_vy"].max() > 0  # the blade landed


def test_states_csv_and_external_loads(run, files):
    states = pd.read_csv(files["states"])
    assert len(states) == len(run.time)
    for col in ("time_s", "pelvis_tx_m", "knee_angle_l_rad", "hip_flexion_r_speed_rad_per_s",
                "vasti_l_activation", "vasti_l_tendon_force_N", "vasti_l_fiber_length_m",
                "blade_r_Fz_N", "blade_r_compression_m", "socket_angle_r_passive_torque_Nm"):
        assert col in states.columns, col
    i = run.model.muscle_names.index("vasti_l")
    np.testing.assert_allclose(states.vasti_l_tendon_force_N, run.muscles[:, i, 3], rtol=1e-8)
    loads = ET.parse(files["external_loads"]).getroot().find("ExternalLoads")
    assert loads.findtext("datafile") == "grf.mot"
    forces = {f.get("name"): f for f in loads.iter("ExternalForce")}
    assert forces["grf_l"].findtext("applied_to_body") == "calcn_l"
    assert forces["grf_r"].findtext("applied_to_body") == "prosthesis_r"
    assert forces["grf_r"].findtext("force_identifier") == "ground_force_r_v"


def test_every_keeps_every_nth_sample_and_bad_files_are_named(run, tmp_path):
    paths = write_opensim(run, tmp_path / "x", every=3)
    _, coords = read_mot(paths["coordinates"])
    np.testing.assert_allclose(coords.time, run.time[::3], rtol=1e-8)
    with pytest.raises(ValueError, match="every"):
        write_opensim(run, tmp_path / "y", every=0)
    bad = tmp_path / "bad.mot"
    bad.write_text("name\nversion=1\ntime\tq\n0\t1\n")
    with pytest.raises(InputFileError, match="endheader"):
        read_mot(bad)


def test_the_centre_of_pressure_keeps_the_moment_of_the_contact_forces():
    model = build_runner("amputee")
    res = _synthetic(model, stances=STANCES)
    legs = model.contact_params[:, 6]
    heel, toe = np.flatnonzero(legs == 0)
    i = np.searchsorted(res.time, 0.2)
    res.contacts[i, heel, [0, 1, 2, 3]] = (50.0, 300.0, 1.0, -0.004)
    res.contacts[i, toe, [0, 1, 2, 3]] = (150.0, 900.0, 1.2, -0.002)
    fx, fz, cop = leg_ground_force(res, 0)
    assert fx[i] == 200.0 and fz[i] == 1200.0
    moment = (1.0 * 300 + 0.004 * 50) + (1.2 * 900 + 0.002 * 150)  # Σ x·Fz − z·Fx
    assert cop[i] * fz[i] == pytest.approx(moment)


def test_opensim_reads_the_export_and_poses_its_model_as_bladelab(files, tmp_path,
                                                                  monkeypatch):
    if "casadi" in sys.modules and not os.environ.get("BLADELAB_FRESH_INTERPRETER"):
        # OpenSim's Moco library clashes with a casadi package already loaded in this process
        # (undefined casadi symbol on import): run this test alone in a fresh interpreter
        node = f"{Path(__file__).resolve()}::test_opensim_reads_the_export_and_poses_its_model_as_bladelab"
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", node],
                              env={**os.environ, "BLADELAB_FRESH_INTERPRETER": "1"},
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stdout[-3000:]
        return
    osim = pytest.importorskip("opensim", reason="OpenSim not installed (pip install .[bench])")
    monkeypatch.chdir(tmp_path)  # OpenSim writes opensim.log into the current folder
    table = osim.TimeSeriesTable(str(files["coordinates"]))
    _, coords = read_mot(files["coordinates"])
    assert list(table.getColumnLabels()) == list(coords.columns[1:])
    assert table.getNumRows() == len(coords)
    knee = table.getDependentColumn("knee_angle_l").to_numpy()
    np.testing.assert_allclose(knee, coords.knee_angle_l, rtol=1e-9)
    grf = osim.Storage(str(files["grf"]))
    assert grf.getSize() == len(coords) and grf.getColumnLabels().getSize() == 19
    loads = osim.ExternalLoads(str(files["external_loads"]), True)
    assert loads.getSize() == 2 and loads.getDataFileName() == "grf.mot"
    # the able runner's exported pose put into SCONE's H0918 OpenSim model: same segments
    model = osim.Model(str(SCONE_H0918 / "H0918M_osim4.osim"))
    state = model.initSystem()
    able = build_runner("able")
    res = simulate_runner(able, duration=0.05, excitations=0.1, initial_state="gait",
                          initial_speed=2.0, fall_height=-math.inf)
    from bladelab.runner.export import opensim_coordinates

    pose = opensim_coordinates(res).iloc[-1]
    coordinate_set = model.getCoordinateSet()
    for k in range(coordinate_set.getSize()):
        c = coordinate_set.get(k)
        c.setValue(state, math.radians(pose[c.getName()]) if c.getMotionType() == 1
                   else pose[c.getName()], False)
    model.realizePosition(state)
    import mujoco

    data = mujoco.MjData(able.mj_model)
    data.qpos[:] = res.qpos[-1]
    mujoco.mj_kinematics(able.mj_model, data)
    for body in ("pelvis", "femur_r", "tibia_l", "calcn_r", "calcn_l"):
        b = model.getBodySet().get(body)
        p = b.findStationLocationInGround(state, b.getMassCenter())
        lab = data.xipos[able.mj_model.body(body).id]
        # OpenSim (x forward, y up, z right) = bladelab (x, z, −y)
        np.testing.assert_allclose([p.get(0), p.get(1), p.get(2)], [lab[0], lab[2], -lab[1]],
                                   atol=1e-6)
