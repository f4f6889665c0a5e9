"""The robustness section of a predictive report: the stable-gait acceptance, re-simulated
(:mod:`bladelab.predict.reflex.acceptance`: the judged runs, the pushes that measure the
gait's basin, and what a run must show)."""

from __future__ import annotations

import pandas as pd

from bladelab.predict.reflex.acceptance import (
    COPIES,
    COPY_JITTER,
    PUSH_CHANGE,
    PUSH_PHASES,
    START_CHANGE,
    STRIKE_LIMIT_BW,
    acceptance_runs,
    judged_runs,
    meets_acceptance,
)
from bladelab.predict.reflex.objective import MIN_PUSH_DURATION, ObjectiveSettings

__all__ = ["robustness_runs", "robustness_section"]

#: Re-simulations of a solution shown (:func:`~bladelab.predict.reflex.acceptance.acceptance_runs`).
robustness_runs = acceptance_runs


def robustness_section(rep, out: dict, duration: float) -> None:
    """Add the section of :func:`robustness_runs`' result ``out`` (runs of ``duration`` [s])."""
    pushes = bool(out["pushed"])
    window = ObjectiveSettings().pelvis_tilt_range_deg
    table = pd.DataFrame([_row(name, c, window) for name, c in judged_runs(out)])
    failed = [r["run"] for _, r in table.iterrows() if not r["meets the acceptance (yes/no)"]]
    tables = [("Judged runs (the stable-gait acceptance)", table)]
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
    verdict = ("Stable-gait acceptance: met by every judged run." if not failed else
               f"Stable-gait acceptance: not met by {len(failed)} of {len(table)} judged runs "
               f"({', '.join(failed[:4])}{', …' if len(failed) > 4 else ''}).")
    rep.add_section(
        "Robustness: copies, other starts and pushes",
        text=(f"{verdict} Each run below is simulated again for {duration:g} s from the "
              f"solution's parameters. Judged: the nominal run, {COPIES} copies with "
              f"the parameters moved by {COPY_JITTER:g} (relative, along directions no "
              f"optimiser saw) and starts at ±{100 * START_CHANGE:g} % of the initial speed. A "
              "run meets the acceptance when it runs the whole time with the gait "
              f"criteria (speed within 0.1 m/s of {_judged_speed(out)}, a flight phase in "
              "every stride, alternating steps, power-balance residual ≤ 2 %), no swinging "
              "foot strikes the "
              f"ground above {STRIKE_LIMIT_BW:g} body weights and its mean pelvis tilt lies in "
              f"{window[0]:g}…{window[1]:g}° (seed 001's window). {push_text}"),
        tables=tables,
    )


def _judged_speed(out: dict) -> str:
    """What the runs' speed is judged against: the speed the nominal run reached (a gait is
    judged at its own speed), or the prescribed one."""
    v = out["judged_at_m_per_s"]
    if out.get("judged_at_reached_speed"):
        return f"{v:.2f} m/s, the speed the nominal run reaches"
    return f"{v:.2f} m/s, the prescribed speed" + (" (the nominal run falls)" if out["fell"] else "")


def _row(name: str, c: dict, window: tuple[float, float]) -> dict:
    return {
        "run": name,
        "meets the acceptance (yes/no)": meets_acceptance(c, window),
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
