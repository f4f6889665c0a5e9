"""identify_stance on stances simulated by the MuJoCo reference engine (known K, D; 1 % noise),
spring models, spring locations, bad input, and the CLI."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from bladelab import units
from bladelab.blade import load_blade
from bladelab.cli import main
from bladelab.errors import DataError, OptimizationError
from bladelab.identify.bounds import make_bounds
from bladelab.identify.identify import (
    compare_spring_locations,
    compare_spring_models,
    identification_landscape,
    identify_stance,
)
from bladelab.sim.synthetic import generate_stance
from bladelab.trial import write_stance_csv

# (blade, K [N·m/deg], D [N·m·s/deg], speed [m/s]): seed 000's ranges 13–22 and 0.15–0.5
CASES = [
    ("xtreme-cat5", 18.0, 0.30, 8.0),
    ("xtreme-cat5", 14.0, 0.20, 6.0),
    ("xtreme-cat5", 21.0, 0.45, 5.0),
    ("xceed-cat2", 13.0, 0.15, 7.0),
    ("xceed-cat2", 16.0, 0.35, 8.5),
    ("xceed-cat2", 22.0, 0.50, 6.0),
]


def _stance(name, k, d, v, *, k2_ratio=0.0, seed=1):
    blade = load_blade(name).build()
    K, D = units.stiffness_per_deg_to_per_rad(k), units.damping_per_deg_to_per_rad(d)
    truth_blade = blade.with_joint_parameters(np.array([K]), np.array([D]), np.array([k2_ratio * K]))
    stance, _ = generate_stance(truth_blade, speed_mps=v, force_noise_frac=0.01, seed=seed)
    return blade, stance


@pytest.fixture(scope="module")
def stances():
    return {case: _stance(*case) for case in CASES}


@pytest.mark.parametrize("case", CASES, ids=[f"{c[0]}-K{c[1]}-D{c[2]}" for c in CASES])
def test_recovery_linear(stances, case):
    blade, stance = stances[case]
    _, k, d, _ = case
    ident = identify_stance(stance, blade, seed=3, identifiability=False)
    assert abs(ident.K_Nm_per_deg / k - 1) < 0.03
    assert abs(ident.D_Nms_per_deg / d - 1) < 0.15
    assert ident.evaluations == 600 and ident.nrmse_grf_pct < 5


def test_recovery_cmaes_and_ci(stances):
    blade, stance = stances[CASES[0]]
    ident = identify_stance(stance, blade, optimizer="cmaes", seed=0)
    assert abs(ident.K_Nm_per_deg / 18.0 - 1) < 0.03 and abs(ident.D_Nms_per_deg / 0.3 - 1) < 0.15
    lo, hi = ident.ci["K"]
    assert lo <= ident.K_Nm_per_deg <= hi and hi - lo < 0.2 * ident.K_Nm_per_deg
    assert -1 <= ident.KD_correlation <= 1
    d = ident.to_dict()
    for key in ("K_Nm_per_deg", "D_Nms_per_deg", "nrmse_grf_pct", "nrmse_distance_pct", "cost",
                "evaluations", "wall_s", "seed", "K_ci_Nm_per_deg", "D_ci_Nms_per_deg"):
        assert key in d
    json.dumps(d)
    grid = identification_landscape(stance, blade, ident, n=9, rel_span=0.2)
    assert len(grid) == 81 and list(grid.columns) == ["K_Nm_per_deg", "D_Nms_per_deg", "cost"]
    best = grid.loc[grid["cost"].idxmin()]
    # the identified point is the centre of the grid and the grid's lowest cost is next to it
    assert abs(best["K_Nm_per_deg"] / ident.K_Nm_per_deg - 1) <= 0.05 + 1e-9
    assert grid["cost"].min() >= ident.cost - 1e-3


def test_same_seed_same_result(stances):
    blade, stance = stances[CASES[1]]
    a = identify_stance(stance, blade, seed=5, identifiability=False, max_evals=200)
    b = identify_stance(stance, blade, seed=5, identifiability=False, max_evals=200)
    assert (a.K_Nm_per_deg, a.D_Nms_per_deg, a.cost) == (b.K_Nm_per_deg, b.D_Nms_per_deg, b.cost)


@pytest.mark.parametrize(("k2_ratio", "speed", "seed"), [(0.9, 7.0, 0), (0.5, 8.0, 1)])
def test_recovery_nonlinear_and_model_choice(k2_ratio, speed, seed):
    blade, stance = _stance("xtreme-cat5", 16.0, 0.30, speed, k2_ratio=k2_ratio, seed=seed)
    k2_true = k2_ratio * units.stiffness_per_deg_to_per_rad(16.0) * units.RAD_PER_DEG**2
    table = compare_spring_models(stance, blade, seed=1, identifiability=False)
    nl = table.set_index("model").loc["nonlinear"]
    assert abs(nl["K_Nm_per_deg"] / 16.0 - 1) < 0.03 and abs(nl["D_Nms_per_deg"] / 0.3 - 1) < 0.15
    assert abs(nl["K2_Nm_per_deg2"] / k2_true - 1) < 0.25
    assert bool(nl["preferred"])  # BIC picks the stiffening spring it was simulated with


def test_linear_truth_prefers_linear_model(stances):
    blade, stance = stances[CASES[1]]
    # the seed formulation: its contact law is the generator's, so a linear truth is exactly
    # representable (utilised friction approximates the per-element friction, and on clean data
    # BIC can then favour a tiny K2: see docs/robust-identification.md)
    table = compare_spring_models(stance, blade, seed=1, identifiability=False, formulation="seed")
    assert table.set_index("model").loc["linear", "preferred"]


def test_an_unconverged_search_is_taken_on_by_the_profiles(stances):
    blade, stance = stances[CASES[0]]
    ident = identify_stance(stance, blade, seed=0, max_evals=20)  # one PSO iteration
    # the profiles' lowest point became the estimate (said in a note), inside its interval
    assert any("estimate moved" in n and "N·m/deg" in n for n in ident.notes)
    assert abs(ident.K_Nm_per_deg / 18.0 - 1) < 0.03 and ident.quality.converged
    for name, value in (("K", ident.K_Nm_per_deg), ("D", ident.D_Nms_per_deg)):
        lo, hi = ident.ci[name]
        assert lo <= value <= hi
    row = ident.to_row()
    assert row["flagged"] == int(ident.quality.flagged) and row["converged"] == 1
    assert row["peak_force_measured_N"] > 1000 and "quality" in ident.to_dict()


def test_spring_location_prefers_the_true_hinge(stances):
    blade, stance = stances[CASES[3]]
    table = compare_spring_locations([stance], blade, points=(5, 6, blade.joints[0].point),
                                     max_evals=200)
    assert table.loc[table["best"], "joint_point"].item() == blade.joints[0].point


def test_bad_input(stances):
    blade, stance = stances[CASES[0]]
    no_contact = dataclasses.replace(stance, grf_z=np.zeros_like(stance.grf_z))
    with pytest.raises(DataError, match="no contact"):
        identify_stance(no_contact, blade)
    flat = dataclasses.replace(stance, distance=np.full_like(stance.distance, 0.45))
    with pytest.raises(DataError, match="distance column is constant"):
        identify_stance(flat, blade)
    with pytest.raises(OptimizationError, match="not below max"):
        identify_stance(stance, blade, bounds=make_bounds(k_nm_per_deg=(30, 10)))


def test_cli_stance_and_study(stances, tmp_path, capsys):
    blade, stance = stances[CASES[0]]
    csv = write_stance_csv(stance, tmp_path / "trials" / "s1.csv")
    assert main(["identify", str(csv), "--blade", "xtreme-cat5", "--json", "--no-ci",
                 "--seed", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert abs(out["K_Nm_per_deg"] / 18 - 1) < 0.03 and out["seed"] == 2
    assert main(["identify", str(csv)]) == 2
    assert "--blade is required" in capsys.readouterr().err
    flat = write_stance_csv(dataclasses.replace(stance, distance=np.full_like(stance.distance, 0.45)),
                            tmp_path / "flat.csv")
    assert main(["identify", str(flat), "--blade", "xtreme-cat5"]) == 2
    err = capsys.readouterr().err
    assert "distance column is constant" in err and "Traceback" not in err
    # a study of two trials, one of them missing
    (tmp_path / "study.yaml").write_text(
        "name: cli\nathletes: [{id: A, mass_kg: 70, amputation: transtibial}]\n"
        "blades: [{id: b, blade: xtreme-cat5, category: 5}]\n"
        "trials:\n  - {id: s1, file: trials/s1.csv, athlete: A, blade: b, speed_pct_pb: 100}\n"
        "  - {id: s2, file: trials/s2.csv, athlete: A, blade: b, speed_pct_pb: 60}\n")
    assert main(["identify", str(tmp_path), "--no-ci"]) == 1
    err = capsys.readouterr().err
    assert "failed: s2" in err and "s2.csv: file not found" in err
    assert main(["results", str(tmp_path), "--csv"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 3 and "K_Nm_per_deg" in lines[0]
    exported = tmp_path / "export" / "results.csv"
    exported.parent.mkdir()
    assert main(["results", str(tmp_path), "--output", str(exported)]) == 0
    assert "(2 rows)" in capsys.readouterr().err
    assert exported.read_text().strip().splitlines() == lines
    assert main(["results", str(tmp_path / "nowhere")]) == 2


def test_nonlinear_polish_estimate_inside_its_interval(tmp_path, capsys, monkeypatch):
    from bladelab.identify import identify as identify_module
    from bladelab.parameters import JOINT_PARAMETERS

    blade, stance = _stance("xtreme-cat5", 16.0, 0.30, 7.0, k2_ratio=0.9, seed=0)
    csv = write_stance_csv(stance, tmp_path / "nl.csv")
    args = ["identify", str(csv), "--blade", "xtreme-cat5", "--optimizer", "cmaes", "--polish",
            "--nonlinear", "--json"]

    def inside(d):
        for p in (JOINT_PARAMETERS[n] for n in ("K", "D", "K2")):
            lo, hi = d[p.ci_key]
            assert lo <= d[p.edge_key] <= hi, (p.name, lo, d[p.edge_key], hi)

    assert main(args) == 0
    inside(json.loads(capsys.readouterr().out))
    # a search that stops off the optimum in the long K–K2 valley (seen once: K* 14.09 with a 95 %
    # CI of [8.71, 10.45]): the profiles' lowest point becomes the estimate, said in a note
    real = identify_module.minimize

    def stopped_short(fun, box, **options):
        res = real(fun, box, **options)
        x = res.x.copy()
        x[0] *= 0.75  # K 25 % low, K2 where the search left it
        return dataclasses.replace(res, x=x, fun=float(fun(x[None, :])[0]))

    monkeypatch.setattr(identify_module, "minimize", stopped_short)
    assert main(args) == 0
    d = json.loads(capsys.readouterr().out)
    inside(d)
    assert any("estimate moved" in n for n in d["notes"])
    assert abs(d["K_Nm_per_deg"] / 16.0 - 1) < 0.05
    assert main(args[:-1]) == 0
    assert "note: estimate moved" in capsys.readouterr().out
