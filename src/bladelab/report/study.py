"""The study report: ``bladelab report STUDY_DIR`` -> ``STUDY_DIR/report/index.html``.

Reads ``study.yaml`` and ``results.sqlite`` (written by ``bladelab identify STUDY_DIR``), re-reads
every identified trial's stance, simulates it at its K*, D* with the default kernel, computes the
mechanics of the measured and simulated stances, runs the statistics of seed 000 §3.6 and writes
one self-contained page with:

- nRMSE of GRF and distance per group, individual trials (mean ± SD) and group mean curves
  (seed 000 Tables 1–2), per amputation level and per category group;
- K* and D* per group and speed band with 95 % confidence intervals (Fig. 3);
- GRF and distance over contact (0–100 % from touch-down to toe-off, or the stance window with
  ``window="stance"``), measured vs simulated, group mean ± SD (Figs. 1–2);
- GRF–Δθ hysteresis loops and K_c vs compression per group (§3.4–3.5), peak mechanics table;
- the statistics table (Mann–Whitney U, Kruskal–Wallis + Dunn–Bonferroni, speed bands);
- the cost landscape J(K, D) around the optimum of one trial (identifiability);
- recovered vs true parameters when the study folder holds ``ground_truth.csv``;
- the settings, versions and seed.

Groups are "<TF|TT|...> cat <category>" from each trial's athlete (amputation level) and blade
category.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bladelab import sim
from bladelab.blade import load_blade
from bladelab.errors import DataError, InputFileError
from bladelab.identify.cost import StanceCost
from bladelab.identify.formulations import DEFAULT_FORMULATION, formulation_drive
from bladelab.identify.identifiability import cost_landscape
from bladelab.mechanics import PLAUSIBLE_EFFICIENCY_PCT, mechanics_table, stance_mechanics
from bladelab.parameters import JOINT_PARAMETERS
from bladelab.report import figures, tables
from bladelab.report.builder import Report, ReportTable
from bladelab.report.study_quality import add_flagged_section, flag_column, row_quality
from bladelab.report.study_sections import add_sensitivity_section, add_truth_section
from bladelab.sim import DEFAULT_DT
from bladelab.stats import athlete_means, compare_groups, speed_band, summarize, unit_of_analysis
from bladelab.study.spec import RESULTS_FILE, load_study
from bladelab.study.store import ResultsStore
from bladelab.study.tasks import read_trial_stance
from bladelab.trial import blade_kinematics, read_c3d

__all__ = ["StudyReport", "build_study_report"]

_AMPUTATION_ABBR = {
    "transtibial": "TT", "transfemoral": "TF", "knee_disarticulation": "KD",
    "bilateral_transtibial": "BTT", "bilateral_transfemoral": "BTF", "other": "other",
}


_MECH_COLUMNS = {  # the page's mechanics table: column -> header (the CSV keeps every column)
    "trial": "trial", "source": "source", "speed_pct_pb": "speed [% PB]",
    "peak_force_N": "peak F [N]", "peak_compression_mm": "peak Δd [mm]",
    "Kc_at_peak_compression_kN_per_m": "K_c at peak Δd [kN/m]",
    "peak_Kc_kN_per_m": "peak K_c [kN/m]", "Kc_threshold_mm": "K_c from Δd ≥ [mm]",
    "peak_angular_deformation_deg": "peak Δθ [deg]", "energy_stored_J": "E stored [J]",
    "energy_returned_J": "E returned [J]", "efficiency_pct": "η [%]",
    "efficiency_plausible": "η plausible",
}


@dataclasses.dataclass(frozen=True)
class StudyReport:
    """What :func:`build_study_report` wrote.

    Attributes
    ----------
    index
        Path of ``index.html``.
    n_trials
        Trials in the report (identified successfully).
    n_failed
        Trials whose identification failed (listed in the report) or whose stance could not be
        re-read.
    landscape_trial
        Trial of the cost landscape.
    n_flagged
        Reported trials flagged by their identification's quality.
    flagged_in_statistics
        Whether they were kept in the group statistics (``include_flagged``).
    """

    index: Path
    n_trials: int
    n_failed: int
    landscape_trial: str
    n_flagged: int = 0
    flagged_in_statistics: bool = False

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {"index": str(self.index), "n_trials": self.n_trials, "n_failed": self.n_failed,
                "landscape_trial": self.landscape_trial, "n_flagged": self.n_flagged,
                "flagged_in_statistics": self.flagged_in_statistics}



def _sim_default_dt() -> float:
    """The kernel's default time step [s], used for every re-simulation in the report."""
    return DEFAULT_DT

def _blade_model(ref: str, folder: Path):
    p = Path(ref)
    if p.suffix in (".yaml", ".yml") and not p.is_absolute():
        p = folder / p
        return load_blade(p).build()
    return load_blade(ref).build()


def _measured_tip(file: Path, stance) -> np.ndarray | None:
    """Tip marker (n, 3) [m] on the stance's samples, from a C3D trial (None for a stance CSV)."""
    if file.suffix.lower() != ".c3d":
        return None
    from scipy import interpolate

    trial = read_c3d(file)
    t0 = float(stance.metadata.get("window_start_s", 0.0))
    t = stance.time + t0
    kin = blade_kinematics(trial, cutoff=_num(stance.metadata.get("marker_cutoff_Hz"), 20.0),
                           span=(max(t[0] - 0.3, 0.0), t[-1] + 0.3))
    return interpolate.CubicSpline(kin.time, kin.tip, axis=0)(t)


def _num(value, default):
    try:
        return float(value)
    except (TypeError, ValueError):
        return default


def _sim_theta_offset(model, q: np.ndarray) -> np.ndarray | None:
    """Clamp-frame tip (n, 2) [m] of a single-hinge blade deflected by q [rad] (None otherwise)."""
    if len(model.joints) != 1 or q.ndim != 2 or q.shape[1] != 1:
        return None
    hinge = np.asarray(model.points[model.joints[0].point], float)
    r = np.asarray(model.tip, float) - hinge
    c, s = np.cos(q[:, 0]), np.sin(q[:, 0])
    # rotation about +y: (x, z) -> (cos q x + sin q z, -sin q x + cos q z)
    return np.column_stack([hinge[0] + c * r[0] + s * r[1], hinge[1] - s * r[0] + c * r[1]])


def _clamp_to_lab(stance, local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(stance.clamp_pitch, float)
    c, s = np.cos(p), np.sin(p)
    x = stance.clamp_x + c * local[:, 0] + s * local[:, 1]
    z = stance.clamp_z - s * local[:, 0] + c * local[:, 1]
    return x, z


def _landscape_figure(df: pd.DataFrame, k_opt: float, d_opt: float, title: str):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    K = np.unique(df["K"].to_numpy())
    D = np.unique(df["D"].to_numpy())
    J = df.pivot_table(index="K", columns="D", values="cost").reindex(index=K, columns=D).to_numpy()
    fig = Figure(figsize=(6.4, 4.4))
    ax = fig.add_subplot(1, 1, 1)
    k_par, d_par = JOINT_PARAMETERS["K"], JOINT_PARAMETERS["D"]
    kd, dd = k_par.to_edge(K), d_par.to_edge(D)
    cs = ax.contourf(dd, kd, J * 100.0, levels=20, cmap="viridis")
    ax.contour(dd, kd, J * 100.0, levels=10, colors="white", linewidths=0.4, alpha=0.6)
    fig.colorbar(cs, ax=ax, label="cost J [%]")
    ax.plot([d_opt], [k_opt], marker="*", color="#d62728", markersize=14, label="identified optimum")
    ax.set_xlabel(f"D [{d_par.edge_unit}]")
    ax.set_ylabel(f"K [{k_par.edge_unit}]")
    ax.set_title(title)
    ax.legend(loc="upper right")
    fig.tight_layout()
    return fig


def build_study_report(
    study_dir: str | Path,
    *,
    trial: str | None = None,
    variant: str | None = None,
    out_dir: str | Path | None = None,
    landscape_points: int = 15,
    progress: bool = True,
    include_flagged: bool = False,
    window: str = "contact",
) -> StudyReport:
    """Write the study report ``STUDY_DIR/report/index.html`` (see the module docstring).

    Parameters
    ----------
    study_dir
        Study folder (``study.yaml`` + ``results.sqlite``).
    trial
        Trial id of the cost landscape (default: the first identified trial).
    variant
        Model variant of the results to report (default ``linear`` if present, else the first).
    out_dir
        Report folder (default ``STUDY_DIR/report``).
    landscape_points
        Grid points per axis of the cost landscape.
    progress
        Show a progress bar while simulating.
    window
        Time normalisation of the GRF and distance curves and the nRMSE tables: ``"contact"``
        (seed 000: 0–100 % from touch-down to toe-off) or ``"stance"`` (the whole window).
    include_flagged
        Keep flagged trials (:mod:`bladelab.identify.quality`) in the group statistics; by
        default they are left out (and still listed and marked).

    Raises
    ------
    InputFileError
        No ``study.yaml`` or no ``results.sqlite`` yet ("run bladelab identify STUDY_DIR first").
    DataError
        No successfully identified trial, or an unknown ``trial``/``variant``.
    """
    from tqdm import tqdm

    if window not in ("contact", "stance"):
        raise DataError(f"unknown window {window!r}", where="--window", hint="contact or stance")
    study, folder = load_study(study_dir)
    db = folder / RESULTS_FILE
    if not db.is_file():
        raise InputFileError("no identification results yet", file=db,
                             hint=f"run `bladelab identify {study_dir}` first")
    with ResultsStore(db) as store:
        results = store.table()
    if results.empty:
        raise DataError("results.sqlite holds no results", file=db,
                        hint=f"run `bladelab identify {study_dir}` first")
    variants = list(dict.fromkeys(results["variant"]))
    if variant is None:
        variant = "linear" if "linear" in variants else variants[0]
    elif variant not in variants:
        raise DataError(f"no results of variant {variant!r}", file=db, where="--variant",
                        hint=f"variants in the results: {', '.join(variants)}")
    results = results[results["variant"] == variant]
    failed = results[results["status"] != "ok"]
    ok = results[results["status"] == "ok"].set_index("trial_id")
    trials = {t.id: t for t in study.trials if t.id in ok.index}
    if not trials:
        raise DataError("no trial was identified successfully", file=db,
                        hint=f"see `bladelab results {study_dir}` for the errors")
    if trial is not None and trial not in trials:
        raise DataError(f"trial {trial!r} has no identification result", where="--trial",
                        hint=f"identified trials: {', '.join(list(trials)[:8])} ...")
    landscape_id = trial or next(iter(trials))

    measured: dict[str, list] = {}
    simulated: dict[str, list] = {}
    by_level_m: dict[str, list] = {}
    by_level_s: dict[str, list] = {}
    mech_m: dict[str, list] = {}
    mech_s: dict[str, list] = {}
    rows = []
    problems: list[tuple[str, str]] = [(str(r.trial_id), str(r.error)) for r in failed.itertuples()]
    landscape = None
    flagged_ids: set[str] = set()
    formulations: set[str] = set()
    for tid, t in tqdm(trials.items(), desc="simulating", unit="trial", disable=not progress,
                       leave=False):
        r = ok.loc[tid]
        athlete = study.athlete(t.athlete)
        entry = study.blade(t.blade)
        level = _AMPUTATION_ABBR.get(athlete.amputation, athlete.amputation)
        group = f"{level} cat {entry.category}" if entry.category is not None else f"{level} {t.blade}"
        file = folder / t.file
        try:
            stance = read_trial_stance(str(file), t.stance)
            settings = json.loads(r["settings_json"]) if r.get("settings_json") else {}
            model = _blade_model(entry.blade, folder)
            if settings.get("joint") is not None:
                model = dataclasses.replace(model, joints=(dataclasses.replace(
                    model.joints[0], point=int(settings["joint"])),))
            K = JOINT_PARAMETERS["K"].from_edge(float(r["K_Nm_per_deg"]))
            D = JOINT_PARAMETERS["D"].from_edge(float(r["D_Nms_per_deg"]))
            k2 = r.get("K2_Nm_per_deg2")
            K2 = 0.0 if k2 is None or not np.isfinite(k2) else JOINT_PARAMETERS["K2"].from_edge(k2)
            formulation = settings.get("formulation", DEFAULT_FORMULATION)
            problem = sim.prepare(model, stance, drive=formulation_drive(formulation))
            formulations.add(formulation)
            res = sim.simulate(problem, stiffness=K, damping=D, stiffness_quadratic=K2)
        except Exception as err:  # noqa: BLE001 - one bad trial must not stop the report
            problems.append((tid, f"re-simulation failed: {err}"))
            continue
        meta = {**stance.metadata, "trial": tid}
        m_st = dataclasses.replace(stance, metadata=meta)
        s_st = dataclasses.replace(stance, grf_x=res.grf_x, grf_z=res.grf_z,
                                   distance=res.distance, metadata=meta)
        for d, key, val in ((measured, group, m_st), (simulated, group, s_st),
                            (by_level_m, level, m_st), (by_level_s, level, s_st)):
            d.setdefault(key, []).append(val)
        hinge = tuple(model.points[model.joints[0].point])
        try:
            tip = _measured_tip(file, stance)
        except Exception:  # noqa: BLE001 - the loops are optional
            tip = None
        mm = stance_mechanics(m_st, tip_x=None if tip is None else tip[:, 0],
                              tip_z=None if tip is None else tip[:, 2], hinge=hinge)
        # the simulated stance: K_c from the same Δd as its measured one (above the noise)
        same = {"min_compression": mm.compression_threshold, "noise_factor": 0.0}
        local = _sim_theta_offset(model, res.deflection)
        if local is not None:
            sx, sz = _clamp_to_lab(stance, local)
            ms = stance_mechanics(s_st, tip_x=sx, tip_z=sz, hinge=hinge, **same)
        else:
            ms = stance_mechanics(s_st, **same)
        mech_m.setdefault(group, []).append(dataclasses.replace(mm, metadata={**mm.metadata, "trial": tid, "group": group, "source": "measured"}))
        mech_s.setdefault(group, []).append(dataclasses.replace(ms, metadata={**ms.metadata, "trial": tid, "group": group, "source": "simulated"}))
        is_flagged, why = row_quality(r)
        if is_flagged:
            flagged_ids.add(tid)
        rows.append({
            "flagged": is_flagged, "flags": why,
            "trial_id": tid, "athlete": t.athlete, "amputation": level, "group": group,
            "blade": t.blade, "category": entry.category, "configuration": t.configuration,
            "speed_pct_pb": t.speed_pct_pb if t.speed_pct_pb is not None else r.get("speed_pct_pb"),
            **{c: r.get(c) for c in ("K_Nm_per_deg", "D_Nms_per_deg", "K_ci_low_Nm_per_deg",
                                     "K_ci_high_Nm_per_deg", "D_ci_low_Nms_per_deg",
                                     "D_ci_high_Nms_per_deg", "KD_correlation",
                                     "nrmse_grf_pct", "nrmse_distance_pct", "cost",
                                     "evaluations", "wall_s", "peak_force_mismatch_pct")},
        })
        if tid == landscape_id:
            cost = StanceCost.from_stance(stance, weights=tuple(settings.get("weights", (0.5, 0.5))),
                                          grf_components=tuple(settings.get("grf_components", ("z",))))

            def fun_batch(X, problem=problem, cost=cost):
                out = sim.simulate_batch(problem, X[:, 0:1], X[:, 1:2])
                return cost.evaluate(grf_z=out.grf_z, grf_x=out.grf_x,
                                     distance=out.distance).cost

            box = np.array([[0.4 * K, 1.6 * K], [0.05 * D, 3.0 * D]])
            landscape = (cost_landscape(fun_batch, [K, D], box, n=landscape_points, rel_span=0.4),
                         float(r["K_Nm_per_deg"]), float(r["D_Nms_per_deg"]))
    if not rows:
        raise DataError("no identified trial could be re-simulated", where="report",
                        hint="; ".join(f"{t}: {m}" for t, m in problems[:3]))
    per_trial = pd.DataFrame(rows)
    per_trial["speed_band"] = speed_band(per_trial["speed_pct_pb"].astype(float))
    per_trial["flagged"] = per_trial["flagged"].astype(object)
    kept_ids = set(per_trial["trial_id"]) if include_flagged else set(per_trial["trial_id"]) - flagged_ids
    grouped = per_trial[per_trial["trial_id"].isin(kept_ids)]  # the rows of group statistics

    def kept(groups: dict) -> dict:
        out = {g: [v for v in items if v.metadata.get("trial") in kept_ids]
               for g, items in groups.items()}
        return {g: v for g, v in out.items() if v}

    span_words = ("measured contact (touch-down to toe-off: vertical GRF > 20 N; a simulated "
                  "stance on the contact of its measured one)" if window == "contact"
                  else "stance window (flight before and after contact included)")
    left_out = "" if include_flagged or not flagged_ids else (
        f" {len(flagged_ids)} flagged trial(s) are left out (see Flagged trials).")

    rep = Report(
        "Blade characterisation: study report", subtitle=f"{study.name} — {folder}",
        settings={"study": str(folder), "variant": variant,
                  "identification": study.identification.model_dump(mode="json"),
                  "simulation": {"engine": "kernel", "dt_s": _sim_default_dt(),
                                 "formulation": ", ".join(sorted(formulations))},
                  "landscape_trial": landscape_id, "trials_reported": len(per_trial),
                  "trials_failed": len(problems), "trials_flagged": len(flagged_ids),
                  "curve_window": window,
                  "include_flagged": include_flagged},
        seed=study.seed,
    )
    gt_path = folder / "ground_truth.csv"
    synthetic = gt_path.is_file()
    intro = (f"{len(per_trial)} trials identified ({variant} spring model, formulation "
             f"{', '.join(sorted(formulations))}) and re-simulated the same way at their K*, D* with "
             f"the blade kernel; groups are amputation level and blade category.")
    if synthetic:
        intro += ("\n\nThis study folder holds ground_truth.csv: its trials are SYNTHETIC, made by "
                  "`bladelab example make` with a richer model than the one identified (see "
                  "docs/example-study.md). The recovered-vs-true section compares the two.")
    if problems:
        intro += "\n\nNot reported: " + "; ".join(f"{t} ({m})" for t, m in problems[:10])
    if flagged_ids:
        intro += (f"\n\n{len(flagged_ids)} of {len(per_trial)} trials are flagged (poorly "
                  "determined or poorly fitted; see Flagged trials) and "
                  + ("kept in" if include_flagged else "left out of") + " the group statistics.")
    overview = per_trial[["trial_id", "group", "configuration", "speed_pct_pb", "K_Nm_per_deg",
                          "D_Nms_per_deg", "nrmse_grf_pct", "nrmse_distance_pct"]].copy()
    overview.insert(1, "quality", flag_column(per_trial["flagged"]))
    rep.add_section("Overview", text=intro,
                    tables=[ReportTable("Trials", overview, "trials", csv=per_trial)])
    add_flagged_section(rep, per_trial, include_flagged=include_flagged)

    # nRMSE tables (seed 000 Tables 1-2): amputation levels, then category groups
    for signal, title in (("grf", "nRMSE of the GRF (Table 1)"),
                          ("distance", "nRMSE of the characteristic distance (Table 2)")):
        win = {"signal": signal, "window": window}
        tr = pd.concat([tables.trial_nrmse(kept(by_level_m), kept(by_level_s), **win),
                        tables.trial_nrmse(kept(measured), kept(simulated), **win)],
                       ignore_index=True)
        mc = pd.concat([tables.mean_curve_nrmse(kept(by_level_m), kept(by_level_s), **win),
                        tables.mean_curve_nrmse(kept(measured), kept(simulated), **win)],
                       ignore_index=True)
        num = tables.nrmse_table(tr, mc, signal=signal)
        rep.add_section(title, text=f"Over the {span_words}.{left_out}", tables=[ReportTable(title, tables.nrmse_table(tr, mc, signal=signal,
                                                                             formatted=True),
                                                   f"nrmse-{signal}", csv=num)])
    rep.add_section(
        "GRF and distance vs time",
        text="Measured (solid) and simulated at K*, D* (dashed): group mean ± SD over stances "
             f"normalised to 0–100 % of the {span_words} (seed 000 Figs. 1–2; --window "
             f"{'stance' if window == 'contact' else 'contact'} for the other). Flagged trials: "
             "grey dotted lines." + left_out,
        figures=[("Vertical GRF, measured vs simulated",
                  figures.time_series_bands(measured, simulated, signal="grf", window=window,
                                            flagged=flagged_ids, include_flagged=include_flagged)),
                 ("Characteristic distance, measured vs simulated",
                  figures.time_series_bands(measured, simulated, signal="distance", window=window,
                                            flagged=flagged_ids, include_flagged=include_flagged))],
    )
    summary = summarize(grouped, values=["K_Nm_per_deg", "D_Nms_per_deg"],
                        by=["group", "speed_band"],
                        lower_limits={"K_Nm_per_deg": 0.0, "D_Nms_per_deg": 0.0})
    n_clipped = int(summary[["K_Nm_per_deg_ci_clipped", "D_Nms_per_deg_ci_clipped"]].sum().sum())
    rep.add_section(
        "K* and D* per group and speed band",
        text="Bars: mean; whiskers: 95 % t confidence interval of the mean (seed 000 Fig. 3)."
             + left_out + (f" {n_clipped} lower limit(s) fell below 0, which is not physical for "
                           "a stiffness or a damping: clipped at 0 and marked ‡."
                           if n_clipped else ""),
        figures=[("K* and D* per group and speed band", figures.parameter_bars(summary))],
        tables=[ReportTable("K* and D* per group and speed band",
                            tables.parameter_summary_display(summary), "parameters", csv=summary)],
    )
    mt = mechanics_table([m for v in mech_m.values() for m in v] +
                         [m for v in mech_s.values() for m in v])
    mt["flagged"] = mt["trial"].isin(flagged_ids)
    mt["peak_compression_mm"] = 1e3 * mt["peak_compression_m"]
    mt_display = mt[[c for c in _MECH_COLUMNS if c in mt]].rename(columns=_MECH_COLUMNS)
    mt_display.insert(1, "quality", flag_column(mt["flagged"]))
    measured_mt = mt[mt["source"] == "measured"]
    th = measured_mt["Kc_threshold_mm"]
    eta = measured_mt["efficiency_pct"]
    lo_eta, hi_eta = PLAUSIBLE_EFFICIENCY_PCT
    rep.add_section(
        "Blade mechanics",
        text="GRF–Δθ hysteresis loops (loading solid, unloading dashed) and equivalent compressive "
             "stiffness K_c vs compression Δd per group (seed 000 §3.4–3.5), measured stances; "
             "then the simulated ones. Δθ of measured stances comes from the tip marker. "
             "Flagged trials: grey dotted lines, marked in the table."
             f"\n\nK_c = GRF/Δd is shown only where Δd is above the measurement noise: Δd ≥ "
             "max(5 mm, 10 × the robust SD of the distance before touch-down), here "
             f"{th.min():.1f}–{th.max():.1f} mm (median {th.median():.1f} mm, dash-dotted line), "
             "so that the distance noise (and the uncertainty of d0 it causes) moves K_c by at "
             "most 10 %; a simulated stance uses the threshold of its measured one. Near "
             "touch-down Δd → 0 and GRF/Δd is not defined. Seed 000 reports K_c at peak "
             "compression (18–32 kN/m), the column 'K_c at peak Δd'; 'peak K_c' is the largest "
             "value above the threshold, reached early in loading on these stances."
             f"\n\nPlausibility of the energies: E stored and E returned are areas of the "
             "vertical-GRF–Δd loop. Force and clamp–tip distance are not work-conjugate (the GRF "
             "acts at a contact point that rolls along the sole, and the clamp rotates), so they "
             "are indices of the loop's shape, not the blade's strain energy, and their "
             "efficiency η is not the blade's energy return: carbon-fibre blades return most of "
             f"the energy they store. Measured η here is {eta.min():.0f}–{eta.max():.0f} %; "
             f"{int((~measured_mt['efficiency_plausible']).sum())} of {len(measured_mt)} stances "
             f"lie outside {lo_eta:.0f}–{hi_eta:.0f} % ('η plausible' = no): read η as a "
             "comparison between groups, not as an energy return.",
        figures=[("GRF vs angular deformation, measured",
                  figures.hysteresis_loops(mech_m, flagged=flagged_ids)),
                 ("K_c vs compression, measured",
                  figures.compressive_stiffness_curves(mech_m, flagged=flagged_ids)),
                 ("GRF vs angular deformation, simulated",
                  figures.hysteresis_loops(mech_s, flagged=flagged_ids))],
        tables=[ReportTable("Peak mechanics per stance", mt_display, "mechanics", csv=mt)],
    )
    unit = unit_of_analysis(grouped, athlete="athlete", groups=("amputation", "group"))
    tested = grouped if unit.unit == "trial" else athlete_means(
        grouped, values=["K_Nm_per_deg", "D_Nms_per_deg"], by=("amputation", "group", "speed_band"))
    st = compare_groups(tested, amputation="amputation", category="group",
                        speed="speed_pct_pb")
    rep.add_section(
        "Statistics",
        text="Mann–Whitney U between amputation levels, Kruskal–Wallis with Dunn–Bonferroni "
             "across groups, Mann–Whitney U between speed bands (≥ 90 % vs < 90 % PB); α = 0.05; "
             f"effect size r (seed 000 §3.6). {len(grouped)} of {len(per_trial)} trials "
             + ("tested." if unit.unit == "trial" else
                f"averaged into {len(tested)} athlete means (per group and speed band).")
             + left_out + "\n\n" + unit.statement,
        tables=[ReportTable("Statistical tests", tables.stats_display(st), "statistics", csv=st)]
        if len(st) else [],
    )
    if landscape is not None:
        df, k_opt, d_opt = landscape
        grid = df.assign(K_Nm_per_deg=JOINT_PARAMETERS["K"].to_edge(df["K"]),
                         D_Nms_per_deg=JOINT_PARAMETERS["D"].to_edge(df["D"]))[
                             ["K_Nm_per_deg", "D_Nms_per_deg", "cost"]]
        rep.add_section(
            "Identifiability",
            text=f"Cost J(K, D) on a {landscape_points} × {landscape_points} grid around the "
                 f"optimum of trial {landscape_id} (choose another with --trial). An elongated "
                 "valley means K and D compensate each other.",
            figures=[(f"Cost landscape of {landscape_id}",
                      _landscape_figure(df, k_opt, d_opt, f"cost landscape: {landscape_id}"))],
            tables=[ReportTable(
                f"Cost landscape of {landscape_id} (grid minimum; the whole grid in the CSV)",
                grid.nsmallest(1, "cost").assign(K_identified_Nm_per_deg=k_opt,
                                                 D_identified_Nms_per_deg=d_opt),
                "landscape", csv=grid)],
        )
    add_sensitivity_section(rep, formulations)
    if synthetic:
        add_truth_section(rep, per_trial, gt_path, kept_ids=kept_ids,
                          include_flagged=include_flagged)
    index = rep.write(Path(out_dir) if out_dir is not None else folder / "report")
    return StudyReport(index=Path(index), n_trials=len(per_trial), n_failed=len(problems),
                       landscape_trial=landscape_id, n_flagged=len(flagged_ids),
                       flagged_in_statistics=include_flagged)
