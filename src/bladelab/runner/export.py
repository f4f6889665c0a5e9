"""Write a runner simulation to a folder of CSV tables and a JSON summary.

``states.csv`` (coordinates and speeds), ``grf.csv`` (per leg), ``events.csv`` (touch-downs and
lift-offs), ``power_balance.csv``, ``muscles.csv`` and ``joint_powers.csv``; units are in the
column names. ``summary.json`` is :func:`bladelab.runner.analyses.summary`.
"""

from __future__ import annotations

from pathlib import Path

from bladelab._io import atomic_open, write_json
from bladelab.runner import analyses
from bladelab.runner.simulate import RunnerResult

__all__ = ["write_simulation"]


def write_simulation(result: RunnerResult, out: str | Path) -> dict:
    """Write ``result``'s tables and summary into the folder ``out`` (created; each file written
    atomically); returns the summary."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tables = {
        "states.csv": result.states(),
        "grf.csv": result.leg_grf(),
        "events.csv": analyses.gait_events(result),
        "power_balance.csv": analyses.power_balance(result),
        "muscles.csv": result.muscle_states(),
        "joint_powers.csv": analyses.joint_powers(result),
    }
    for name, df in tables.items():
        with atomic_open(out / name, "w", newline="") as fh:
            df.to_csv(fh, index=False)
    summary = analyses.summary(result)
    write_json(out / "summary.json", summary)
    return summary
