"""The stable-gait acceptance of a reflex gait, re-simulated from its parameter file.

A reflex gait that survives only its own floating-point path, its own start or no change of
speed is not a prediction (docs/predictive.md, "Robust evaluation"). Judged runs
(:func:`acceptance_runs`, with :func:`~bladelab.predict.reflex.verify.verify_solution`):

- the nominal run, and :data:`COPIES` copies with the parameters moved by :data:`COPY_JITTER`
  (relative, along directions no optimiser saw);
- starts at initial speeds :data:`START_CHANGE` above and below the file's.

A judged run meets the acceptance (:func:`meets_acceptance`) when it runs the whole time with
:func:`~bladelab.predict.reflex.verify.verify_solution`'s gait criteria (speed, flight,
alternating steps, power balance), no swinging foot strikes the ground above
:data:`STRIKE_LIMIT_BW` body weights, and the mean pelvis tilt lies inside the objective's
window (seed 001: −16…−2°). Pushes (forward speed × (1 ± :data:`PUSH_CHANGE`) at
:data:`PUSH_PHASES` phases of a stride) are simulated too, not judged:
they measure the size of the gait's basin. So are the nominal runs at finer time steps
(``refined``): reported beside the verdict, not part of it (measured 2026-11-27: no gait of the
first-order scheme runs at half its step; the Newmark scheme's gaits are the first to be
checked).
"""

from __future__ import annotations

from pathlib import Path

from bladelab.predict.reflex.objective import MIN_PUSH_DURATION, ObjectiveSettings
from bladelab.predict.reflex.verify import verify_solution

__all__ = ["COPIES", "COPY_JITTER", "PUSH_CHANGE", "PUSH_PHASES", "START_CHANGE",
           "STRIKE_LIMIT_BW", "acceptance_runs", "judged_runs", "meets_acceptance"]

#: An accepted gait survives 4 copies moved by 1e-3 ...
COPIES = 4
COPY_JITTER = 1e-3
#: ... and a ±5 % change of the initial speed; no swinging foot above 0.2 body weights.
START_CHANGE = 0.05
STRIKE_LIMIT_BW = 0.2
#: The pushes that measure the basin (relative change of forward speed, phases of a stride).
PUSH_CHANGE = 0.02
PUSH_PHASES = 5


def acceptance_runs(path: str | Path, duration: float = 10.0, *, pushes: bool = True,
                    speed: float | str | None = None, refined: int = 0) -> dict:
    """:func:`~bladelab.predict.reflex.verify.verify_solution`'s result for the parameter file
    ``path`` re-simulated for ``duration`` [s] as above (pushes when ``pushes`` and
    ``duration`` is at least :data:`~bladelab.predict.reflex.objective.MIN_PUSH_DURATION`;
    ``"pushed"`` is otherwise empty), at ``speed`` [m/s] (default the file's prescribed speed;
    ``"reached"``: the nominal run's mean speed, rounded to 0.01 m/s, so that a gait is judged
    at its own speed; every judged run's mean speed must lie within 0.1 m/s of it), and with
    ``refined`` = n the nominal run at the time step halved 1…n times (``"refined"``, not
    judged);
    ``"judged_at_m_per_s"`` is that speed, ``"simulations"`` counts the runs and
    ``"accepted"`` says whether every judged run meets the acceptance."""
    pushes = pushes and duration >= MIN_PUSH_DURATION
    out = verify_solution(path, speed=speed, duration=duration, jittered_copies=COPIES,
                          jitter=COPY_JITTER,
                          initial_speed_change=START_CHANGE,
                          push_change=PUSH_CHANGE if pushes else 0.0, push_phases=PUSH_PHASES,
                          refined_step=refined)
    out.setdefault("pushed", [])
    out.setdefault("refined", [])
    out["simulations"] = 1 + sum(len(out[k]) for k in ("jittered", "initial_speed", "pushed",
                                                         "refined"))
    out["accepted"] = all(meets_acceptance(c) for _, c in judged_runs(out))
    return out


def judged_runs(out: dict) -> list[tuple[str, dict]]:
    """(name, run) of every judged run of :func:`acceptance_runs`' result ``out``."""
    judged = [("nominal", {**out, "ok": out.get("nominal_ok", out["ok"])})]
    judged += [(f"copy {k + 1}, moved by {COPY_JITTER:g}", c)
               for k, c in enumerate(out["jittered"])]
    judged += [(f"start {c['initial_speed_m_per_s']:.3f} m/s", c)
               for c in out["initial_speed"]]
    return judged


def meets_acceptance(run: dict, window: tuple[float, float] | None = None) -> bool:
    """Whether one re-simulated run (a :func:`verify_solution` result or one of its copies)
    meets the stable-gait acceptance; ``window``: pelvis tilt [deg], default the objective's."""
    lo, hi = window or ObjectiveSettings().pelvis_tilt_range_deg
    return bool(run["ok"] and run["swing_contact_peak_bw"] <= STRIKE_LIMIT_BW
                and lo <= run["pelvis_tilt_mean_deg"] <= hi)
