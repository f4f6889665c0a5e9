"""The robustness section of a predictive report: issue 20's acceptance, re-simulated.

A reflex gait that survives only its own floating-point path, its own start or no change of
speed is not a prediction (docs/predictive.md, "Robust evaluation"). The section re-simulates
the solution shown (:func:`bladelab.predict.reflex.verify.verify_solution`):

- nominally, and as :data:`COPIES` copies with the parameters moved by :data:`COPY_JITTER`
  (relative, along directions no optimiser saw);
- from initial speeds :data:`START_CHANGE` above and below the file's;
- pushed once (forward speed × (1 ± :data:`PUSH_CHANGE`)) at :data:`PUSH_PHASES` phases of a
  stride: not part of the acceptance, the size of the gait's basin.

Issue 20's acceptance, judged per run: it runs the whole time with the shipped-solution
criteria (speed, flight, alternating steps, power balance), no swinging foot strikes the
ground above :data:`STRIKE_LIMIT_BW` body weights, and the mean pelvis tilt lies inside the
objective's window (seed 001: −16…−2°).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = ["COPIES", "COPY_JITTER", "PUSH_CHANGE", "START_CHANGE", "robustness_runs",
           "robustness_section"]

#: Issue 20: every shipped solution survives 4 copies moved by 1e-3 ...
COPIES = 4
COPY_JITTER = 1e-3
#: ... and a ±5 % change of the initial speed; no swinging foot above 0.2 body weights.
START_CHANGE = 0.05
STRIKE_LIMIT_BW = 0.2
#: The pushes that measure the basin (relative change of forward speed, phases of a stride).
PUSH_CHANGE = 0.02
PUSH_PHASES = 5


def robustness_runs(path: Path, duration: float) -> dict:
    """:func:`~bladelab.predict.reflex.verify.verify_solution`'s result for the parameter file
    ``path`` re-simulated for ``duration`` [s] as above (pushes only when ``duration`` is at
    least :data:`~bladelab.predict.reflex.objective.MIN_PUSH_DURATION`; ``"pushed"`` is then
    empty); ``"simulations"`` counts the runs."""
    from bladelab.predict.reflex.objective import MIN_PUSH_DURATION
    from bladelab.predict.reflex.verify import verify_solution

    pushes = duration >= MIN_PUSH_DURATION
    out = verify_solution(path, duration=duration, jittered_copies=COPIES, jitter=COPY_JITTER,
                          initial_speed_change=START_CHANGE,
                          push_change=PUSH_CHANGE if pushes else 0.0, push_phases=PUSH_PHASES)
    out.setdefault("pushed", [])
    out["simulations"] = 1 + sum(len(out[k]) for k in ("jittered", "initial_speed", "pushed"))
    return out


def robustness_section(rep, out: dict, duration: float) -> None:
    """Add the section of :func:`robustness_runs`' result ``out`` (runs of ``duration`` [s])."""
    from bladelab.predict.reflex.objective import MIN_PUSH_DURATION, ObjectiveSettings

    pushes = bool(out["pushed"])
    window = ObjectiveSettings().pelvis_tilt_range_deg
    judged = [("nominal", out)]
    judged += [(f"copy {k + 1}, moved by {COPY_JITTER:g}", c)
               for k, c in enumerate(out["jittered"])]
    judged += [(f"start {c['initial_speed_m_per_s']:.3f} m/s", c)
               for c in out["initial_speed"]]
    table = pd.DataFrame([_row(name, c, window) for name, c in judged])
    failed = [r["run"] for _, r in table.iterrows() if not r["meets the acceptance (yes/no)"]]
    tables = [("Judged runs (issue 20's acceptance)", table)]
    if pushes:
        pushed = pd.DataFrame([
            _row(f"push {100 * c['push_change']:+g} % at {c['push_time_s']:.1f} s", c, window)
            for c in out["pushed"]])
        survived = int(pushed["runs the whole time (yes/no)"].sum())
        tables.append(("Pushed runs (the gait's basin; not judged)", pushed))
        push_text = (f"Not judged: pushes that multiply the forward speed by 1 ± {PUSH_CHANGE:g} "
                     f"at {PUSH_PHASES} phases of a stride, the size of the gait's basin: "
                     f"{survived} of {len(pushed)} pushed runs keep running (their power "
                     "balance leaves out the push itself, which adds kinetic energy without "
                     "external work).")
    else:
        push_text = (f"No pushes: a re-simulation shorter than {MIN_PUSH_DURATION:g} s has no "
                     "room for one.")
    verdict = ("Issue 20's acceptance: met by every judged run." if not failed else
               f"Issue 20's acceptance: not met by {len(failed)} of {len(table)} judged runs "
               f"({', '.join(failed[:4])}{', …' if len(failed) > 4 else ''}).")
    rep.add_section(
        "Robustness: copies, other starts and pushes",
        text=(f"{verdict} Each run below is simulated again for {duration:g} s from the "
              f"solution's parameters. Judged (issue 20): the nominal run, {COPIES} copies with "
              f"the parameters moved by {COPY_JITTER:g} (relative, along directions no "
              f"optimiser saw) and starts at ±{100 * START_CHANGE:g} % of the initial speed. A "
              "run meets the acceptance when it runs the whole time with the shipped-solution "
              "criteria (speed within 0.1 m/s of the prescribed, a flight phase in every stride, "
              "alternating steps, power-balance residual ≤ 2 %), no swinging foot strikes the "
              f"ground above {STRIKE_LIMIT_BW:g} body weights and its mean pelvis tilt lies in "
              f"{window[0]:g}…{window[1]:g}° (seed 001's window). {push_text}"),
        tables=tables,
    )


def _row(name: str, c: dict, window: tuple[float, float]) -> dict:
    tilt_ok = window[0] <= c["pelvis_tilt_mean_deg"] <= window[1]
    strikes_ok = c["swing_contact_peak_bw"] <= STRIKE_LIMIT_BW
    return {
        "run": name,
        "meets the acceptance (yes/no)": bool(c["ok"] and strikes_ok and tilt_ok),
        "runs the whole time (yes/no)": not c["fell"],
        "simulated (s)": c["duration_s"],
        "mean speed (m/s)": c["mean_speed_m_per_s"],
        "strides without flight (count)": c["strides"] - c["strides_with_flight"],
        "same-leg steps (count)": c["same_leg_steps"],
        "power-balance residual (%)": c["power_balance_residual_pct"],
        "swing contacts (count)": c["swing_contacts"],
        "largest swing contact (BW)": c["swing_contact_peak_bw"],
        "pelvis tilt mean (deg)": c["pelvis_tilt_mean_deg"],
        "pelvis tilt range (deg)": f"{c['pelvis_tilt_min_deg']:.1f}…{c['pelvis_tilt_max_deg']:.1f}",
    }
