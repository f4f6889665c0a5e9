"""``bladelab simulate``: output CSV, literature units at the edge, clear errors."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from bladelab import units
from bladelab.blade import load_blade
from bladelab.cli import main
from bladelab.sim import prepare, simulate
from bladelab.sim.synthetic import generate_stance
from bladelab.trial.stance import read_stance_csv, write_stance_csv


@pytest.fixture(scope="module")
def stance_csv(tmp_path_factory):
    blade = load_blade("xtreme").build()
    stance, _ = generate_stance(blade, speed_mps=6.0, body_mass_kg=70.0)
    path = tmp_path_factory.mktemp("stance") / "stance.csv"
    write_stance_csv(stance, path)
    return path


def test_simulate_writes_csv_with_units(stance_csv, tmp_path):
    out = tmp_path / "sim.csv"
    rc = main(["simulate", "--blade", "xtreme", "--stance", str(stance_csv), "--K", "18",
               "--D", "0.3", "--out", str(out)])
    assert rc == 0
    table = pd.read_csv(out, comment="#")
    for col in ("time_s", "grf_x_N", "grf_z_N", "distance_m", "deflection_deg_j1", "torque_Nm_j1"):
        assert col in table.columns
    # same numbers as the API with K, D converted from N·m/deg
    expected = simulate(prepare(load_blade("xtreme").build(), read_stance_csv(stance_csv)),
                        stiffness=units.stiffness_per_deg_to_per_rad(18.0),
                        damping=units.damping_per_deg_to_per_rad(0.3))
    np.testing.assert_allclose(table["grf_z_N"], expected.grf_z, rtol=1e-6, atol=1e-3)
    np.testing.assert_allclose(table["deflection_deg_j1"], np.rad2deg(expected.deflection[:, 0]),
                               rtol=1e-6, atol=1e-6)
    header = out.read_text().splitlines()[:8]
    assert "# K_Nm_per_deg: 18" in header


def test_stance_with_gap_exits_2_without_output(stance_csv, tmp_path, capsys):
    lines = stance_csv.read_text().splitlines()
    data_start = next(i for i, line in enumerate(lines) if line.startswith("time,")) + 1
    fields = lines[data_start + 30].split(",")
    fields[3] = ""  # clamp_z missing
    lines[data_start + 30] = ",".join(fields)
    bad = tmp_path / "gap.csv"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "sim.csv"
    rc = main(["simulate", "--blade", "xtreme", "--stance", str(bad), "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("error:") and "clamp_z" in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("args, where", [
    (["--K", "abc"], "--K"),
    (["--K", "18,20"], "--K"),
    (["--D", "-1"], "--D"),
    (["--engine", "opensim"], "--engine"),
])
def test_bad_options_exit_2(stance_csv, tmp_path, capsys, args, where):
    out = tmp_path / "sim.csv"
    rc = main(["simulate", "--blade", "xtreme", "--stance", str(stance_csv), "--out", str(out),
               *args])
    err = capsys.readouterr().err
    assert rc == 2 and where in err and "Traceback" not in err
    assert not out.exists()
