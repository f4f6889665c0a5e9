"""What the speed-continuation drivers report and return
(:mod:`bladelab.predict.collocation.continuation`).

- :class:`ContinuationProgress`: one progress report (a solve started, converged, failed, read
  back, refined, or one start kept of several);
- :class:`SolveRecord`: one solve (solved now or read back) and its table row;
- :class:`ContinuationResult`: every solve of one continuation, in order;
- :func:`table_columns` (the order of a table's columns, :data:`TABLE_COLUMNS` with the legs'
  columns) and :func:`speed_floor_columns` (a maximum-speed solve's floor).

Speeds in m/s; a row's units are in its column names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from bladelab.predict.collocation.solve import SolveProgress
from bladelab.predict.collocation.starts import (
    START_COLUMNS,
    StartOutcome,
    candidate,
    start_columns,
)
from bladelab.predict.collocation.stored import model_label

__all__ = [
    "ON_FLOOR_TOL_MPS",
    "TABLE_COLUMNS",
    "ContinuationProgress",
    "ContinuationResult",
    "SolveRecord",
    "speed_floor_columns",
    "table_columns",
]

#: Columns of a table row in order; the per-leg columns (``contact_time_<leg>_s``,
#: ``peak_vertical_grf_<leg>_bw``) follow ``contact_time_s`` in :data:`_LEGS` order.
TABLE_COLUMNS = (
    "model", "blade", "problem", "prescribed_speed_mps", "converged", "status",
    "mean_speed_mps", "cost_of_transport_J_per_kg_m", "stride_time_s", "contact_time_s",
    "flight_fraction", "step_phase", "dynamics_residual_pct", "iterations", "wall_s",
    "mesh_intervals", "file",
)
_LEGS = ("intact", "prosthetic", "left", "right")
_PER_LEG = ("contact_time_{}_s", "peak_vertical_grf_{}_bw")


@dataclass(frozen=True)
class ContinuationProgress:
    """One progress report of the drivers.

    Attributes
    ----------
    model
        :func:`model_label` of the model.
    problem
        ``"<v> m/s"`` or ``"maximum speed"``.
    event
        ``"read"`` (a converged file read back, ``path``), ``"start"`` (a solve starts;
        ``message`` names its warm start), ``"solve"`` (a :class:`SolveProgress` of the solve in
        ``solve``), ``"converged"`` or ``"failed"`` (``path``: the file written; ``message``:
        the result), ``"refine"`` (a failed speed is tried again after an intermediate one,
        named in ``message``), ``"kept"`` (several starts: the one kept, ``path``, and every
        start's objective in ``message``).
    path
        The file concerned, if any.
    message
        Text for the event.
    solve
        The solver's own report (event ``"solve"``).
    """

    model: str
    problem: str
    event: str
    path: Path | None = None
    message: str = ""
    solve: SolveProgress | None = None


@dataclass(frozen=True)
class SolveRecord:
    """One solve of a driver (solved now or read back).

    Attributes
    ----------
    problem
        ``"speed"`` (prescribed) or ``"max-speed"``.
    speed_mps
        The prescribed speed [m/s]; None for the maximum speed.
    solution
        The :class:`CollocationSolution` (a best iterate when not converged).
    path
        The file it is in.
    solved
        False when it was read back from ``path`` (nothing solved).
    starts
        Several starts: every start's :class:`StartOutcome`, in order (``solution`` and
        ``path`` are the kept one's); empty with one start.
    """

    problem: str
    speed_mps: float | None
    solution: object
    path: Path
    solved: bool
    starts: tuple[StartOutcome, ...] = ()

    @property
    def converged(self) -> bool:
        return bool(self.solution.converged)

    def row(self, relative_to: str | Path | None = None) -> dict:
        """The table row (module docstring); ``file`` relative to ``relative_to`` if given."""
        sol = self.solution
        summary = sol.summary()
        path = self.path
        if relative_to is not None:
            try:
                path = self.path.relative_to(relative_to)
            except ValueError:
                pass
        row = {
            "model": model_label(sol.model_spec),
            "blade": sol.model_spec["blade"] or "",
            "problem": self.problem,
            "prescribed_speed_mps": self.speed_mps,
            "converged": summary["converged"],
            "status": summary["status"],
        }
        skip = {"converged", "status", "iterations", "wall_s"}
        row.update({k: v for k, v in summary.items() if k not in skip})
        row.update({"iterations": summary["iterations"], "wall_s": summary["wall_s"],
                    "mesh_intervals": sol.settings.mesh_intervals, "file": str(path)})
        if self.problem == "max-speed":
            row.update(speed_floor_columns(sol))
        if self.starts:
            kept = next(o.label for o in self.starts if o.path == self.path)
            row.update(start_columns([candidate(o.label, o.solution) for o in self.starts],
                                     kept))
        return row

    @property
    def files(self) -> tuple[Path, ...]:
        """Every file of the record: the kept one, and each start's."""
        return (self.path, *(o.path for o in self.starts if o.path != self.path))


@dataclass(frozen=True)
class ContinuationResult:
    """What :func:`speed_continuation` did: one record per speed reached, in order (the last one
    did not converge when the continuation stopped early).

    Attributes
    ----------
    speeds
        The prescribed speeds asked for [m/s], in order.
    records
        :class:`SolveRecord` of each speed reached, intermediate speeds of a refined step
        included, in the order solved.
    """

    speeds: tuple[float, ...]
    records: tuple[SolveRecord, ...]

    @property
    def complete(self) -> bool:
        """True if every prescribed speed converged."""
        done = {f"{r.speed_mps:g}" for r in self.records if r.converged}
        return all(f"{v:g}" in done for v in self.speeds)

    @property
    def failed(self) -> SolveRecord | None:
        """The speed that did not converge (where the continuation stopped), or None."""
        return next((r for r in self.records if not r.converged), None)

    @property
    def last_converged_speed(self) -> float | None:
        """The last prescribed speed [m/s] that converged (in the order solved), or None."""
        done = [r.speed_mps for r in self.records if r.converged]
        return done[-1] if done else None

    @property
    def fastest(self) -> SolveRecord | None:
        """The converged record of the highest prescribed speed, or None."""
        done = [r for r in self.records if r.converged]
        return max(done, key=lambda r: r.speed_mps) if done else None

    def rows(self, relative_to: str | Path | None = None) -> list[dict]:
        """Table rows (:meth:`SolveRecord.row`), one per speed reached."""
        return [r.row(relative_to) for r in self.records]

    def table(self):
        """The rows as a pandas DataFrame, columns in :func:`table_columns` order."""
        rows = self.rows()
        return pd.DataFrame(rows, columns=table_columns(rows))


#: A maximum speed within this of its floor [m/s] is on it (IPOPT's tolerance, not a stride).
ON_FLOOR_TOL_MPS = 1e-3


def speed_floor_columns(sol) -> dict:
    """A maximum-speed solve's ``speed_floor_mps`` (:attr:`CollocationSolution.speed_floor_mps`,
    empty where unknown) and ``on_speed_floor`` (its mean speed within
    :data:`ON_FLOOR_TOL_MPS` of the floor: the speed is the floor's, not the model's
    fastest)."""
    floor = sol.speed_floor_mps
    on = (floor is not None and sol.converged
          and sol.mean_speed_mps - floor <= ON_FLOOR_TOL_MPS)
    return {"speed_floor_mps": "" if floor is None else floor, "on_speed_floor": bool(on)}


def table_columns(rows: Sequence[dict]) -> list[str]:
    """Column order of table rows: :data:`TABLE_COLUMNS` with the per-leg columns of the legs
    present after ``contact_time_s``, then ``warnings`` and the several-start columns
    (:data:`~bladelab.predict.collocation.starts.START_COLUMNS`, ``objective_<start>`` after
    ``objective``) of rows that have them, then any other key."""
    keys: list[str] = []
    for row in rows:
        keys.extend(k for k in row if k not in keys)
    legs = [fmt.format(leg) for fmt in _PER_LEG for leg in _LEGS
            if fmt.format(leg) in keys]
    head = list(TABLE_COLUMNS)
    i = head.index("contact_time_s") + 1
    cols = head[:i] + legs + head[i:]
    per_start = [k for k in keys if k.startswith("objective_")]
    block = ["warnings", *START_COLUMNS[:3], *per_start, *START_COLUMNS[3:]]
    cols += [k for k in block if k in keys]
    return cols + [k for k in keys if k not in cols]
