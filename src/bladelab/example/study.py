"""The synthetic example study: seed 000's cohort, made reproducibly from a seed.

Cohort (seed 000 §2): a transfemoral athlete ``TF1`` (65 kg, 1.80 m, personal best 8.0 m/s) on
the C-shaped category-2 blade (``xceed-cat2``) in four pylon configurations A–D, and a
transtibial athlete ``TT1`` (76 kg, personal best 9.0 m/s) on the J-shaped blade in categories
4, 5 and 6 (``xtreme-cat4/5/6``); 50 trials: per TF configuration 3 at 50–70 % and 2 at 100 %
of the personal best, per TT category 6 at 50–70 % and 4 at 100 %.

Each trial is simulated by a model RICHER than the one identified
(:func:`bladelab.sim.synthetic.generate_stance`, MuJoCo point-mass runner carrying the blade):

- a deflection-dependent (stiffening) hinge, τ = −(K·q + K2·q·|q|) − D·q̇, with K2 chosen so the
  stiffness is ``k2_rise`` (15 %) higher at 20° deflection;
- optionally the compliance spread over ``n_links − 1`` hinges (multi-link blade, equal springs
  n_j·K in series);
- a softer ground (contact stiffness × ``contact_stiffness_factor``), standing in for a
  compliant track (the synthetic runner, ``bladelab.sim.generate_stance``, does not take the
  series track layer that ``prepare`` supports, so the surface compliance goes into the contact);
- touch-down conditions that vary from trial to trial (leg angle ±1°, vertical speed ±0.05 m/s);
- the measurement of :mod:`bladelab.example.measurement`: clamp cluster and tip markers at
  100 Hz with 1 mm noise, two force plates at 1000 Hz with 1 % noise, random touch-down phase,
  about half of the stances across the edge between the two plates.

The ground truth (K, D per trial in N·m/deg and N·m·s/deg, K2, the touch-down conditions and what
the stance looked like) goes to ``ground_truth.csv`` beside ``study.yaml``; ``trials/*.c3d`` hold
the recordings. See ``docs/example-study.md``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from bladelab import __version__, units
from bladelab._io import atomic_open, atomic_path
from bladelab.blade import load_blade, multilink_blade
from bladelab.errors import BladelabError, DataError
from bladelab.example.measurement import extend_flight, measure_stance
from bladelab.executors import make_executor
from bladelab.sim.synthetic import generate_stance

__all__ = [
    "COHORT",
    "ExampleStudy",
    "GeneratorSettings",
    "TrialPlan",
    "default_example_dir",
    "generate_trial",
    "is_complete",
    "make_example_study",
    "plan_trials",
    "read_ground_truth",
]

GENERATOR_VERSION = 2
MANIFEST = "generator.json"
GROUND_TRUTH = "ground_truth.csv"

#: The cohort: athletes, their personal bests [m/s] and blades (seed 000 §2).
COHORT: dict[str, dict[str, Any]] = {
    "TF1": {
        "amputation": "transfemoral", "mass_kg": 65.0, "height_m": 1.80, "side": "left",
        "personal_best_mps": 8.0,
        "blades": {"xceed-cat2": {"category": 2, "K": 15.0, "D": 0.18}},
        "configurations": {"A": 0.48, "B": 0.50, "C": 0.52, "D": 0.54},  # pylon [m]
        "slow_per_cell": 3, "fast_per_cell": 2,
    },
    "TT1": {
        "amputation": "transtibial", "mass_kg": 76.0, "height_m": None, "side": "right",
        "personal_best_mps": 9.0,
        "blades": {
            "xtreme-cat4": {"category": 4, "K": 16.5, "D": 0.30},
            "xtreme-cat5": {"category": 5, "K": 18.0, "D": 0.34},
            "xtreme-cat6": {"category": 6, "K": 19.5, "D": 0.38},
        },
        "configurations": {},
        "pylon_m": 0.50,
        "slow_per_cell": 6, "fast_per_cell": 4,
    },
}


@dataclasses.dataclass(frozen=True)
class GeneratorSettings:
    """How the example trials are made (see the module docstring).

    Attributes
    ----------
    k2_rise
        Relative stiffness increase of the hinge at 20° deflection (sets K2).
    n_links
        Rigid links of the generating blade (1: the blade's own single hinge).
    contact_stiffness_factor, contact_damping_factor
        Ground contact stiffness and damping relative to the blade's contact model (a compliant,
        little-damped surface: without it the whole runner's landing speed meets the contact
        damper and the GRF jumps to 1–2 kN within 1 ms of touch-down).
    marker_rate_hz, marker_noise_m, force_noise_frac
        Measurement (see :func:`bladelab.example.measurement.measure_stance`).
    analog_rate_hz
        Force-plate rate [Hz].
    dt, sample_rate_hz
        MuJoCo step [s] and the clean stance's sampling rate [Hz].
    flight_s
        Flight recorded before and after the stance [s].
    """

    k2_rise: float = 0.15
    n_links: int = 1
    contact_stiffness_factor: float = 0.5
    contact_damping_factor: float = 0.1
    marker_rate_hz: float = 100.0
    marker_noise_m: float = 1e-3
    force_noise_frac: float = 0.01
    analog_rate_hz: float = 1000.0
    dt: float = 1e-5
    sample_rate_hz: float = 2000.0
    flight_s: float = 0.3

    def to_dict(self) -> dict[str, Any]:
        """Plain dictionary."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class TrialPlan:
    """One planned trial and its ground truth (edge units)."""

    trial_id: str
    athlete: str
    amputation: str
    mass_kg: float
    blade: str
    category: int
    configuration: str | None
    pylon_length_m: float
    speed_pct_pb: float
    speed_mps: float
    K_Nm_per_deg: float
    D_Nms_per_deg: float
    touchdown_angle_deg: float
    touchdown_vertical_speed_mps: float
    across_plates: bool
    seed: int

    def to_dict(self) -> dict[str, Any]:
        """Plain dictionary."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class ExampleStudy:
    """What :func:`make_example_study` did.

    Attributes
    ----------
    folder
        The study folder.
    n_trials
        Trials in the study.
    generated
        False when an existing complete study was reused.
    wall_s
        Wall-clock time [s].
    """

    folder: Path
    n_trials: int
    generated: bool
    wall_s: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {"folder": str(self.folder), "n_trials": self.n_trials,
                "generated": self.generated, "wall_s": self.wall_s}


def default_example_dir() -> Path:
    """``examples/sprint-study`` under the current working directory (read when called; never
    inside the installation)."""
    return Path.cwd() / "examples" / "sprint-study"


def _touchdown(speed_mps: float) -> tuple[float, float]:
    """Nominal leg angle [deg] and vertical speed [m/s] at touch-down for a running speed.

    A flatter, softer landing at sprint speed keeps the peak force of the point-mass runner near
    the published range (DESIGN.md, "Realistic stances"); see docs/example-study.md.
    """
    angle = -(22.0 - 0.9 * (speed_mps - 4.0))
    vz = -0.55 + 0.05 * (speed_mps - 4.0)
    return angle, vz


def plan_trials(seed: int = 0, *, n_trials: int | None = None) -> list[TrialPlan]:
    """The example study's trials with their ground truth, deterministic for ``seed``.

    Parameters
    ----------
    seed
        Study seed.
    n_trials
        Keep only this many trials, spread over all groups (for tests); None: all 50.
    """
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 5]))
    plans: list[TrialPlan] = []
    for athlete, a in COHORT.items():
        configs = a["configurations"] or {None: a["pylon_m"]}
        for blade, b in a["blades"].items():
            for config, pylon in configs.items():
                pcts = [float(rng.uniform(50.0, 70.0)) for _ in range(a["slow_per_cell"])]
                pcts += [100.0] * a["fast_per_cell"]
                for pct in pcts:
                    frac = pct / 100.0
                    speed = a["personal_best_mps"] * frac * float(rng.normal(1.0, 0.01))
                    K = b["K"] * (1.06 - 0.10 * frac) * float(rng.normal(1.0, 0.03))
                    D = b["D"] * (0.95 + 0.10 * frac) * float(rng.normal(1.0, 0.05))
                    ang, vz = _touchdown(speed)
                    cell = f"{athlete}_{config or 'cat' + str(b['category'])}"
                    idx = sum(p.trial_id.startswith(cell) for p in plans) + 1
                    plans.append(TrialPlan(
                        trial_id=f"{cell}_{idx:02d}", athlete=athlete,
                        amputation=a["amputation"], mass_kg=a["mass_kg"], blade=blade,
                        category=b["category"], configuration=config, pylon_length_m=pylon,
                        speed_pct_pb=round(pct, 1), speed_mps=round(speed, 3),
                        K_Nm_per_deg=round(K, 3), D_Nms_per_deg=round(D, 4),
                        touchdown_angle_deg=round(ang + float(rng.normal(0.0, 1.0)), 2),
                        touchdown_vertical_speed_mps=round(vz + float(rng.normal(0.0, 0.05)), 3),
                        across_plates=bool(rng.random() < 0.5),
                        seed=int(rng.integers(0, 2**31 - 1)),
                    ))
    if n_trials is not None and n_trials < len(plans):
        # spread over the cells: every k-th trial
        idx = np.linspace(0, len(plans) - 1, int(n_trials)).round().astype(int)
        plans = [plans[i] for i in idx]
    return plans


def _true_blade(plan: dict, settings: dict):
    spec = load_blade(plan["blade"])
    n_links = int(settings["n_links"])
    K, D = plan["K_Nm_per_deg"], plan["D_Nms_per_deg"]
    if n_links > 1:
        model = multilink_blade(spec, n_links=n_links, K_Nm_per_deg=K * (n_links - 1),
                                D_Nms_per_deg=D * (n_links - 1))
    else:
        model = spec.build().with_joint_parameters(
            np.array([units.stiffness_per_deg_to_per_rad(K)]),
            np.array([units.damping_per_deg_to_per_rad(D)]))
    q_ref = math.radians(20.0)
    joints = tuple(
        dataclasses.replace(j, stiffness_quadratic=settings["k2_rise"] * j.stiffness / q_ref)
        for j in model.joints
    )
    model = dataclasses.replace(model, joints=joints)
    return model.with_contact(
        stiffness=model.contact.stiffness * settings["contact_stiffness_factor"],
        damping=model.contact.damping * settings["contact_damping_factor"])


def generate_trial(payload: dict) -> dict:
    """Simulate, record and write one example trial (a top-level task for the executors).

    ``payload``: ``plan`` (:meth:`TrialPlan.to_dict`), ``settings``
    (:meth:`GeneratorSettings.to_dict`), ``path`` (the C3D file to write). Returns the
    ground-truth row of the trial.
    """
    plan, s = payload["plan"], payload["settings"]
    model = _true_blade(plan, s)
    clean, truth = generate_stance(
        model, speed_mps=plan["speed_mps"], body_mass_kg=plan["mass_kg"],
        touchdown_angle_deg=plan["touchdown_angle_deg"],
        touchdown_vertical_speed_mps=plan["touchdown_vertical_speed_mps"],
        pylon_length_m=plan["pylon_length_m"], dt=s["dt"], sample_rate=s["sample_rate_hz"],
        margin_s=0.005,
    )
    tip = np.column_stack([truth["tip_x"], np.zeros_like(truth["tip_x"]), truth["tip_z"]])
    rng = np.random.default_rng(plan["seed"])
    loaded = np.flatnonzero(clean.grf_z > 20.0)
    boundary = None
    if plan["across_plates"]:
        boundary = float(tip[loaded[0], 0]) - 0.05 + float(rng.normal(0.0, 0.02))
    long, tip_long = extend_flight(clean, tip=tip, before_s=s["flight_s"], after_s=s["flight_s"])
    rec = measure_stance(long, tip=tip_long, marker_rate_hz=s["marker_rate_hz"],
                         analog_rate_hz=s["analog_rate_hz"], marker_noise_m=s["marker_noise_m"],
                         force_noise_frac=s["force_noise_frac"], plate_boundary_x=boundary,
                         seed=rng)
    # the lab's origin: put the first plate's far corner near x = 1 m of the walkway
    rec.write_c3d(payload["path"], metadata={
        "athlete": plan["athlete"], "side": COHORT[plan["athlete"]]["side"],
        "blade": plan["blade"], "category": str(plan["category"]),
        "speed_pct_pb": plan["speed_pct_pb"],
    })
    on2 = float(np.max(np.abs(rec.platforms[1]["force"][:, 2]))) > 50.0
    k2 = s["k2_rise"] * plan["K_Nm_per_deg"] / 20.0  # N·m/deg per deg of deflection
    return {
        **{k: plan[k] for k in ("trial_id", "athlete", "amputation", "blade", "category",
                                "configuration", "speed_pct_pb", "speed_mps")},
        "K_Nm_per_deg": plan["K_Nm_per_deg"], "D_Nms_per_deg": plan["D_Nms_per_deg"],
        "K2_Nm_per_deg2": round(k2, 5),
        # secant stiffness τ/q of the stiffening hinge at its peak deflection [N·m/deg]
        "K_secant_peak_Nm_per_deg": round(plan["K_Nm_per_deg"] * (
            1.0 + s["k2_rise"] * abs(truth["min_deflection_deg"]) / 20.0), 3),
        "n_links": s["n_links"],
        "contact_stiffness_factor": s["contact_stiffness_factor"],
        "contact_damping_factor": s["contact_damping_factor"],
        "pylon_length_m": plan["pylon_length_m"], "mass_kg": plan["mass_kg"],
        "touchdown_angle_deg": plan["touchdown_angle_deg"],
        "touchdown_vertical_speed_mps": plan["touchdown_vertical_speed_mps"],
        "marker_rate_Hz": s["marker_rate_hz"], "marker_noise_m": s["marker_noise_m"],
        "force_noise_frac": s["force_noise_frac"], "plates_loaded": 2 if on2 else 1,
        "contact_time_s": truth["contact_time_s"], "peak_grf_z_N": round(truth["peak_grf_z_N"], 1),
        "max_compression_m": round(truth["max_compression_m"], 4),
        "min_deflection_deg": round(truth["min_deflection_deg"], 2),
        "max_sole_slip_m": round(truth["max_sole_slip_m"], 5),
        "pitch_touchdown_deg": round(truth["pitch_touchdown_deg"], 2),
        "pitch_toeoff_deg": round(truth["pitch_toeoff_deg"], 2),
        "seed": plan["seed"],
    }


def _manifest(seed: int, settings: GeneratorSettings, plans: list[TrialPlan]) -> dict:
    return {"generator_version": GENERATOR_VERSION, "seed": int(seed),
            "settings": settings.to_dict(), "trials": [p.trial_id for p in plans]}


def is_complete(folder: str | Path, *, seed: int = 0, settings: GeneratorSettings | None = None,
                n_trials: int | None = None) -> bool:
    """Whether ``folder`` holds a complete example study made with these inputs."""
    folder = Path(folder)
    man = folder / MANIFEST
    if not man.is_file():
        return False
    try:
        found = json.loads(man.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError):
        return False
    settings = settings or GeneratorSettings()
    want = _manifest(seed, settings, plan_trials(seed, n_trials=n_trials))
    if found != want:
        return False
    files = [folder / "study.yaml", folder / GROUND_TRUTH]
    files += [folder / "trials" / f"{t}.c3d" for t in want["trials"]]
    return all(f.is_file() for f in files)


def _study_yaml(plans: list[TrialPlan], seed: int) -> dict:
    athletes = []
    for aid, a in COHORT.items():
        entry = {"id": aid, "mass_kg": a["mass_kg"], "amputation": a["amputation"],
                 "side": a["side"]}
        if a["height_m"]:
            entry["height_m"] = a["height_m"]
        athletes.append(entry)
    blades = [{"id": name, "blade": name, "category": b["category"]}
              for a in COHORT.values() for name, b in a["blades"].items()]
    configs = [{"id": c, "pylon_height_m": p, "description": f"TF1 pylon configuration {c}"}
               for c, p in COHORT["TF1"]["configurations"].items()]
    trials = []
    for p in plans:
        t = {"id": p.trial_id, "file": f"trials/{p.trial_id}.c3d", "athlete": p.athlete,
             "blade": p.blade, "speed_pct_pb": p.speed_pct_pb, "stance": 1}
        if p.configuration:
            t["configuration"] = p.configuration
        trials.append(t)
    return {"name": "bladelab example sprint study (synthetic)", "seed": int(seed),
            "athletes": athletes, "blades": blades, "configurations": configs, "trials": trials,
            "identification": {"optimizer": "pso", "max_evals": 600, "identifiability": True}}


def make_example_study(
    out_dir: str | Path | None = None,
    *,
    seed: int = 0,
    force: bool = False,
    jobs: int = 2,
    n_trials: int | None = None,
    settings: GeneratorSettings | None = None,
    progress: bool = True,
) -> ExampleStudy:
    """Generate (or reuse) the example study in ``out_dir``.

    Parameters
    ----------
    out_dir
        Study folder (default :func:`default_example_dir`).
    seed
        Study seed: the same seed gives the same files' content.
    force
        Regenerate even if a complete study with the same inputs is there.
    jobs
        Worker processes.
    n_trials
        A reduced study with this many trials (tests); None: all 50.
    settings
        Generator settings (default :class:`GeneratorSettings`).
    progress
        Show a progress bar.

    Returns
    -------
    ExampleStudy

    Raises
    ------
    BladelabError
        A trial could not be generated (the message names it); nothing half-written is left as
        a complete study (the manifest is written last).
    """
    from tqdm import tqdm

    t0 = time.perf_counter()
    folder = Path(out_dir) if out_dir is not None else default_example_dir()
    settings = settings or GeneratorSettings()
    plans = plan_trials(seed, n_trials=n_trials)
    if not force and is_complete(folder, seed=seed, settings=settings, n_trials=n_trials):
        return ExampleStudy(folder, len(plans), False, time.perf_counter() - t0)
    if folder.exists() and not folder.is_dir():
        raise DataError("exists and is not a folder", file=folder, hint="choose another OUT_DIR")
    trials_dir = folder / "trials"
    trials_dir.mkdir(parents=True, exist_ok=True)
    (folder / MANIFEST).unlink(missing_ok=True)
    # results of an older study do not belong to the new trials
    for stale in ("results.sqlite", "results.sqlite-wal", "results.sqlite-shm"):
        (folder / stale).unlink(missing_ok=True)
    if (folder / "report").is_dir():
        shutil.rmtree(folder / "report")
    keep = {f"{p.trial_id}.c3d" for p in plans}
    for old in trials_dir.glob("*.c3d"):
        if old.name not in keep:
            old.unlink()
    sd = settings.to_dict()
    payloads = [{"plan": p.to_dict(), "settings": sd, "path": str(trials_dir / f"{p.trial_id}.c3d")}
                for p in plans]
    rows: list[dict | None] = [None] * len(plans)
    failures = []
    ex = make_executor("local" if jobs > 1 else "serial", max(1, jobs))
    with tqdm(total=len(plans), desc="generating trials", unit="trial", disable=not progress,
              leave=False) as bar:
        for i, status, value in ex.run(generate_trial, payloads):
            if status == "ok":
                rows[i] = value
            else:
                failures.append(f"{plans[i].trial_id}: {value}")
            bar.update(1)
    if failures:
        raise BladelabError(f"{len(failures)} example trial(s) failed: {'; '.join(failures[:3])}",
                            where="bladelab example make",
                            hint="report this as a bug with the seed used")
    truth = pd.DataFrame(rows)
    with atomic_open(folder / GROUND_TRUTH, "w") as fh:
        fh.write("# bladelab example study: ground truth of the synthetic trials "
                 f"(generator v{GENERATOR_VERSION}, bladelab {__version__}, seed {seed})\n")
        fh.write(f"# generator settings: {json.dumps(sd, sort_keys=True)}\n")
        truth.to_csv(fh, index=False, lineterminator="\n")
    with atomic_open(folder / "study.yaml", "w") as fh:
        fh.write("# Synthetic example study made by `bladelab example make` (see "
                 "docs/example-study.md).\n")
        yaml.safe_dump(_study_yaml(plans, seed), fh, sort_keys=False)
    with atomic_path(folder / MANIFEST) as tmp:
        Path(tmp).write_text(json.dumps(_manifest(seed, settings, plans), indent=1), encoding="utf-8")
    return ExampleStudy(folder, len(plans), True, time.perf_counter() - t0)


def read_ground_truth(folder: str | Path) -> pd.DataFrame:
    """``ground_truth.csv`` of a study folder (comment lines skipped)."""
    path = Path(folder) / GROUND_TRUTH
    if not path.is_file():
        raise DataError("no ground truth", file=path,
                        hint="only studies made by `bladelab example make` have one")
    return pd.read_csv(path, comment="#")
