"""The mesh-halving check of a predicted stride: the same problem on twice the mesh intervals.

A collocation stride is a solution of its mesh. Whether a number read from it (the cost of
transport, the stride time, a contact time, a force peak) belongs to the runner or to the
discretisation shows only when the mesh is refined: :func:`check_mesh` solves the same problem
(model, speed, weights, constraints) on ``factor`` × the intervals, started from the stride
(its primal values resampled, no tracking stage, IPOPT started as the library's warm starts
are: barrier 1e-4, bound push and fraction 1e-8, so that the start is not pushed off its bounds
and the solve stays on the stride's own branch; a maximum-speed problem keeps its stride's
speed as a floor, as every warm-started one does), and :class:`MeshCheck` compares the two,
quantity by quantity. With IPOPT's default start (barrier 0.1, bound push 0.01) the finer solve
can leave that branch: measured on the amputee with Cat5 at 4 m/s, it landed 5.6 % dearer at
100 intervals, where the warm start found the stride's own optimum 0.85 % dearer
(benchmarks/human_body/categories-people10/mesh-100/); with the bound push at 1e-8 the
barrier's start made no difference (0.1 and 1e-4 gave bit-identical strides at 5 m/s,
benchmarks/human_body/categories-people10-5mps/mesh-100/). The project's settling criterion
(docs/collocation.md, "Mesh refinement"): halving the mesh interval moves the objective and the
stride time by less than :data:`SETTLED_PCT` per cent.

A finer solve can also find a lower optimum that the stride's own mesh has too: started from
the stride, it ends where the finer problem's descent leads, which need not be the finer image
of the stride's basin. The **round trip** tells the two apart (:func:`round_trip`): the
stride's own problem solved again from the finer stride. Its difference from the stride is the
basin's (a lower objective: the stride was not its mesh's best), its difference from the finer
stride the mesh's own. Measured: the symmetric able stride at 3.5 m/s moved −7.4 % from 50 to
100 intervals, of which −0.19 % was the mesh's and the rest a lower optimum of the 50-interval
problem; the amputee with Cat6 at 4 m/s −1.18 % from 100 to 200, of which −0.14 % the mesh's
(benchmarks/human_body/symmetric/README.md).

``bladelab predict --method collocation --mesh-check`` runs it after the solve and keeps both
in the output folder (:func:`mesh_check_in_folder`): the finer stride in
``OUT/mesh-check/solution.json`` (``best_iterate.json`` if it did not converge) and the
comparison in ``OUT/mesh-check/mesh-check.json``, which the report shows beside the numbers,
and the round trip's stride in ``OUT/mesh-check/round-trip/``;
``bladelab sweep --method collocation --mesh-check`` does the same for every converged solve
(``<model>/mesh-check/<solve>/``). The answer stays the stride on the mesh asked for; the check
says how far to trust it.
"""

from __future__ import annotations

import dataclasses
import math
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from bladelab._io import read_json, write_json
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.output_folder import (
    BEST_ITERATE_FILE,
    SOLUTION_FILE,
    read_stored,
    write_solve,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.solve import SolveProgress, predict_stride
from bladelab.predict.collocation.starts import BARRIER_MU
from bladelab.predict.collocation.stored import same_model_spec
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE

__all__ = ["MESH_CHECK_DIR", "MESH_CHECK_FILE", "ROUND_TRIP_DIR", "SETTLED_PCT", "MeshCheck",
           "check_mesh", "compare_meshes", "mesh_check_in_folder", "read_mesh_check",
           "round_trip", "with_round_trip"]

#: The check's sub-folder of a ``bladelab predict`` output folder.
MESH_CHECK_DIR = "mesh-check"
#: The comparison's file in a check's folder.
MESH_CHECK_FILE = "mesh-check.json"
#: The round trip's sub-folder of a check's folder.
ROUND_TRIP_DIR = "round-trip"
#: Largest change [%] of the objective and of the stride time that counts as settled.
SETTLED_PCT = 1.0
#: A round trip's objective this much [%] below the stride's: a lower optimum of its mesh;
#: this much above: a higher one (the round trip left the stride's basin).
LOWER_PCT = 0.1
#: The quantities that decide whether a stride has settled.
SETTLING_KEYS = ("objective", "stride_time_s")
_KIND = "collocation-mesh-check"


def _rows(sol: CollocationSolution) -> dict[str, tuple[str, str, float | None]]:
    """{key: (label, unit, value)} of the quantities compared, for one stride."""
    s = sol.summary()
    rows = {"objective": ("objective", "-", float(sol.nlp.objective)),
            "stride_time_s": ("stride time", "s", s["stride_time_s"]),
            "cost_of_transport_J_per_kg_m": ("cost of transport", "J/(kg·m)",
                                             s["cost_of_transport_J_per_kg_m"])}
    if sol.settings.speed_m_per_s is None:
        rows["mean_speed_mps"] = ("mean speed", "m/s", s["mean_speed_mps"])
    for leg in sol.leg_names:
        rows[f"contact_time_{leg}_s"] = (f"contact time, {leg} leg", "s",
                                         s[f"contact_time_{leg}_s"])
    for leg in sol.leg_names:
        rows[f"peak_vertical_grf_{leg}_bw"] = (f"peak vertical force, {leg} leg", "BW",
                                               s[f"peak_vertical_grf_{leg}_bw"])
    rows["flight_fraction"] = ("flight", "of the stride", s["flight_fraction"])
    return rows


@dataclass(frozen=True)
class MeshCheck:
    """A stride against the same problem solved on a finer mesh.

    Attributes
    ----------
    coarse_intervals, fine_intervals
        Mesh intervals of the stride and of the check [-].
    converged
        Whether the finer solve converged (if not, its numbers are a best iterate's).
    quantities
        ``{key: (label, unit, coarse value, fine value)}``: objective [-], stride time [s],
        cost of transport [J/(kg·m)], (maximum speed: mean speed [m/s]), contact time per leg
        [s], peak vertical ground force per leg [body weights], flight [fraction of the
        stride].
    fine_warnings
        The finer stride's gait warnings (empty if none).
    returned
        The round trip (:func:`round_trip`): ``{key: value}`` of the stride's own problem
        solved again from the finer stride, or None without one.
    returned_converged
        Whether the round trip converged.
    """

    coarse_intervals: int
    fine_intervals: int
    converged: bool
    quantities: dict[str, tuple[str, str, float | None, float | None]]
    fine_warnings: tuple[str, ...] = ()
    returned: dict[str, float | None] | None = None
    returned_converged: bool = False

    def change_pct(self, key: str) -> float | None:
        """Relative change [%] of one quantity from the stride's mesh to the finer one; None
        where a value is missing or the coarse one is 0."""
        _, _, coarse, fine = self.quantities[key]
        return _pct(coarse, fine)

    def round_trip_pct(self, key: str) -> tuple[float | None, float | None]:
        """(the round trip's stride against the stride [%]: the basin's part; the finer
        stride against the round trip's [%]: the mesh's own part) of one quantity; (None,
        None) without a round trip."""
        if self.returned is None:
            return None, None
        _, _, coarse, fine = self.quantities[key]
        back = self.returned.get(key)
        return _pct(coarse, back), _pct(back, fine)

    def describes(self, sol: CollocationSolution) -> bool:
        """True if this check was made of the stride ``sol`` (its mesh and objective), not of
        an earlier stride in the same folder."""
        coarse = self.quantities.get("objective", (None, None, None, None))[2]
        return (self.coarse_intervals == sol.settings.mesh_intervals and coarse is not None
                and math.isclose(coarse, float(sol.nlp.objective), rel_tol=1e-9))

    @property
    def settled(self) -> bool:
        """True if the finer solve converged without gait warnings and moved the objective
        and the stride time by less than :data:`SETTLED_PCT` per cent."""
        changes = [self.change_pct(k) for k in SETTLING_KEYS]
        return (self.converged and not self.fine_warnings
                and all(c is not None and abs(c) < SETTLED_PCT for c in changes))

    def verdict(self) -> str:
        """One sentence: settled or not, and why."""
        head = f"Mesh-halving check ({self.coarse_intervals} → {self.fine_intervals} intervals)"
        if not self.converged:
            return f"{head}: the finer solve did not converge, so the stride is not shown settled"
        moved = ", ".join(f"{self.quantities[k][0]} {_signed(self.change_pct(k))}"
                          for k in SETTLING_KEYS)
        if self.fine_warnings:
            return (f"{head}: {moved}; not settled: the finer stride has gait warnings "
                    f"({'; '.join(self.fine_warnings)})" + self._trip())
        if self.settled:
            return f"{head}: {moved}: settled (both below {SETTLED_PCT:g} %)" + self._trip()
        return (f"{head}: {moved}: not settled (the criterion is below {SETTLED_PCT:g} % "
                "for both)" + (self._trip() or "; read differences of this size between "
                               "strides as the mesh's"))

    def _trip(self) -> str:
        """The round trip's clause of the verdict ('' without one)."""
        if self.returned is None:
            return ""
        head = (f"; round trip (the {self.coarse_intervals}-interval problem again, from the "
                "finer stride)")
        if not self.returned_converged:
            return f"{head}: did not converge"
        parts = {k: self.round_trip_pct(k) for k in SETTLING_KEYS}
        own = ", ".join(f"{self.quantities[k][0]} {_signed(parts[k][1])}" for k in SETTLING_KEYS)
        change = parts["objective"][0]
        if change is not None and change > LOWER_PCT:
            return (f"{head}: objective {_signed(change)}: a higher optimum, the round trip "
                    "left the stride's basin and does not split the change")
        found = (f"objective {_signed(change)}: a lower optimum of the stride's own mesh, "
                 "which this stride is not" if change is not None and change < -LOWER_PCT
                 else f"objective {_signed(change)}: the stride's own optimum again")
        return f"{head}: {found}; the mesh's own part (finer against it): {own}"

    def table(self) -> list[tuple[str, str, str, str]]:
        """Rows (quantity with its unit, stride's mesh, finer mesh, change) as text."""
        out = []
        for key, (label, unit, coarse, fine) in self.quantities.items():
            out.append((f"{label} [{unit}]" if unit != "-" else label, _value(coarse),
                        _value(fine), _signed(self.change_pct(key))))
        return out

    def round_trip_table(self) -> list[tuple[str, str, str, str, str, str]]:
        """Rows (quantity with its unit, stride, round trip, its change against the stride,
        finer stride, the finer against the round trip) as text; [] without a round trip."""
        if self.returned is None:
            return []
        out = []
        for key, (label, unit, coarse, fine) in self.quantities.items():
            basin, own = self.round_trip_pct(key)
            out.append((f"{label} [{unit}]" if unit != "-" else label, _value(coarse),
                        _value(self.returned.get(key)), _signed(basin), _value(fine),
                        _signed(own)))
        return out

    def to_dict(self) -> dict:
        out = {"kind": _KIND, "coarse_intervals": self.coarse_intervals,
               "fine_intervals": self.fine_intervals, "converged": self.converged,
               "settled": self.settled, "settled_below_pct": SETTLED_PCT,
               "quantities": {k: {"label": lab, "unit": unit, "coarse": c, "fine": f,
                                  "change_pct": self.change_pct(k)}
                              for k, (lab, unit, c, f) in self.quantities.items()},
               "fine_warnings": list(self.fine_warnings)}
        if self.returned is not None:
            out["round_trip"] = {"converged": self.returned_converged,
                                 "values": dict(self.returned)}
        return out

    @classmethod
    def from_dict(cls, data: dict, *, file: Path | None = None) -> MeshCheck:
        if not isinstance(data, dict) or data.get("kind") != _KIND:
            raise InputFileError("is not a mesh-halving check", file=file,
                                 hint="written by bladelab predict --mesh-check")
        try:
            quantities = {str(k): (str(v["label"]), str(v["unit"]), _number(v["coarse"]),
                                   _number(v["fine"]))
                          for k, v in data["quantities"].items()}
            trip = data.get("round_trip")
            return cls(int(data["coarse_intervals"]), int(data["fine_intervals"]),
                       bool(data["converged"]), quantities,
                       tuple(str(w) for w in data.get("fine_warnings", ())),
                       None if trip is None else {str(k): _number(v)
                                                  for k, v in trip["values"].items()},
                       False if trip is None else bool(trip["converged"]))
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise InputFileError(f"a mesh-halving check with a missing or bad field ({err})",
                                 file=file, hint="run bladelab predict --mesh-check again "
                                                 "(--resume keeps the solves)") from None


def _pct(a: float | None, b: float | None) -> float | None:
    """Relative change [%] from ``a`` to ``b``; None where one is missing or ``a`` is 0."""
    if a is None or b is None or a == 0.0:
        return None
    return 100.0 * (b - a) / abs(a)


def _number(v) -> float | None:
    return None if v is None else float(v)


def _value(v: float | None) -> str:
    return "–" if v is None else f"{v:.4g}"


def _signed(pct: float | None) -> str:
    if pct is None:
        return "–"
    text = f"{pct:+.2f}" if abs(pct) >= 0.1 or pct == 0.0 else f"{pct:+.1g}"
    return f"{text} %".replace("-", "−")


def compare_meshes(coarse: CollocationSolution, fine: CollocationSolution) -> MeshCheck:
    """The :class:`MeshCheck` of a stride (``coarse``) against the same problem solved on a
    finer mesh (``fine``, converged or a best iterate).

    Raises
    ------
    SpecError
        The two are not the same problem on two meshes (model, speed, weights or
        constraints differ, or ``fine`` has no more intervals than ``coarse``).
    """
    a, b = coarse.settings, fine.settings
    if not same_model_spec(coarse.model_spec, fine.model_spec) or not dataclasses.replace(
            a, mesh_intervals=b.mesh_intervals).same_problem(b):
        raise SpecError("the two strides are not the same problem on two meshes",
                        where="mesh check", hint="solve the finer one with check_mesh")
    if b.mesh_intervals <= a.mesh_intervals:
        raise SpecError(f"the finer stride has {b.mesh_intervals} mesh intervals, the stride "
                        f"{a.mesh_intervals}", where="mesh check")
    rc, rf = _rows(coarse), _rows(fine)
    quantities = {k: (lab, unit, _finite(v), _finite(rf.get(k, (None, None, None))[2]))
                  for k, (lab, unit, v) in rc.items()}
    return MeshCheck(a.mesh_intervals, b.mesh_intervals, fine.converged, quantities,
                     tuple(fine.gait_warnings()))


def _finite(v) -> float | None:
    return float(v) if v is not None and math.isfinite(float(v)) else None


def _finer(sol: CollocationSolution, factor: int, max_iter: int | None):
    """The finer solve's settings (the round trip's with ``factor`` 1): ``factor`` × the
    intervals, the barrier started at
    :data:`~bladelab.predict.collocation.starts.BARRIER_MU` unless the stride's settings
    name a start (module docstring)."""
    mu = BARRIER_MU if sol.settings.warm_start_mu is None else sol.settings.warm_start_mu
    return dataclasses.replace(sol.settings, mesh_intervals=factor * sol.settings.mesh_intervals,
                               warm_start_mu=mu,
                               **({} if max_iter is None else {"max_iter": max_iter}))


def check_mesh(runner, sol: CollocationSolution, *, factor: int = 2,
               max_iter: int | None = None, start: CollocationSolution | None = None,
               progress: Callable[[SolveProgress], None] | None = None,
               ) -> tuple[CollocationSolution, MeshCheck]:
    """Solve ``sol``'s problem on ``factor`` × its mesh intervals from ``sol`` and compare
    (module docstring); ``max_iter``: IPOPT's iterations (None: the stride's setting);
    ``start``: a best iterate of the finer solve to continue from instead (None: the stride).
    Returns (the finer solve, its :class:`MeshCheck`).

    Raises
    ------
    SpecError
        ``factor`` is not an integer ≥ 2; ``sol`` is not a converged stride (a best iterate
        has no mesh to check).
    """
    if isinstance(factor, bool) or not isinstance(factor, int) or factor < 2:
        raise SpecError(f"the finer mesh needs a whole factor ≥ 2, got {factor!r}",
                        where="mesh check factor")
    if not sol.converged:
        raise SpecError("the stride did not converge: there is no solution to check",
                        where="mesh check", hint="converge the solve first (--resume)")
    settings = _finer(sol, factor, max_iter)
    guess = (start.to_guess() if start is not None else
             sol.to_guess(f"{COLLOCATION_SOURCE} on {sol.settings.mesh_intervals} intervals "
                          f"({sol.guess_source})"))
    fine = predict_stride(runner, settings, guess, model_spec=sol.model_spec, progress=progress)
    return fine, compare_meshes(sol, fine)


def round_trip(runner, sol: CollocationSolution, fine: CollocationSolution, *,
               max_iter: int | None = None, start: CollocationSolution | None = None,
               progress: Callable[[SolveProgress], None] | None = None,
               ) -> CollocationSolution:
    """The stride ``sol``'s own problem solved again from the finer stride ``fine`` (module
    docstring: the round trip), started as the finer solve was; ``start``: a best iterate of
    the round trip to continue from instead."""
    settings = _finer(sol, 1, max_iter)
    guess = (start.to_guess() if start is not None else
             fine.to_guess(f"{COLLOCATION_SOURCE} on {fine.settings.mesh_intervals} intervals "
                           "(the mesh-halving check)"))
    return predict_stride(runner, settings, guess, model_spec=sol.model_spec, progress=progress)


def with_round_trip(check: MeshCheck, back: CollocationSolution) -> MeshCheck:
    """``check`` with the round trip's stride ``back`` (:func:`round_trip`)."""
    return dataclasses.replace(check, returned={k: _finite(v) for k, (_, _, v)
                                                in _rows(back).items()},
                               returned_converged=back.converged)


def mesh_check_in_folder(folder: str | Path, runner, sol: CollocationSolution, *,
                         resume: bool = False, max_iter: int | None = None,
                         progress: Callable[[SolveProgress], None] | None = None,
                         round_trip_too: bool = True) -> MeshCheck:
    """:func:`check_mesh` (twice the intervals) of the stride ``sol``, kept in the check's own
    ``folder``: the finer solve as ``solution.json`` (``best_iterate.json`` if it did not
    converge) and the comparison as :data:`MESH_CHECK_FILE` (module docstring; a solve's
    folder keeps it in ``OUT/mesh-check/``). With ``resume``, a check already there that was
    made of this very stride (:meth:`MeshCheck.describes`) is read back if its finer solve
    converged (its comparison alone when the finer strides' files were removed, as committed
    studies do to save space), and continued from its best iterate if not; a check of another
    stride is made anew. With ``round_trip_too`` (default) and a converged finer solve, the
    round trip (:func:`round_trip`) as well, in :data:`ROUND_TRIP_DIR` (read back and continued
    the same way)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ok, best = folder / SOLUTION_FILE, folder / BEST_ITERATE_FILE
    fine_settings = _finer(sol, 2, max_iter)
    previous = read_mesh_check(folder) if resume else None
    if (previous is not None and previous.describes(sol) and previous.converged
            and not ok.exists() and not best.exists()):
        return previous  # a finished check whose finer strides were removed (to save space)
    done, iterate = ((None, None) if previous is None or not previous.describes(sol)
                     else read_stored(ok, best, sol.model_spec, fine_settings))
    if done is not None:
        fine, check = done, compare_meshes(sol, done)
    else:
        fine, check = check_mesh(runner, sol, max_iter=max_iter, start=iterate,
                                 progress=progress)
        write_solve(fine, ok, best)
    trip = folder / ROUND_TRIP_DIR
    if round_trip_too and check.converged:
        trip.mkdir(exist_ok=True)
        back_ok, back_best = trip / SOLUTION_FILE, trip / BEST_ITERATE_FILE
        back, back_iterate = ((None, None) if done is None else read_stored(
            back_ok, back_best, sol.model_spec, _finer(sol, 1, max_iter)))
        if back is None:
            back = round_trip(runner, sol, fine, max_iter=max_iter, start=back_iterate,
                              progress=progress)
            write_solve(back, back_ok, back_best)
        check = with_round_trip(check, back)
    elif trip.is_dir():  # a round trip of an earlier finer stride
        shutil.rmtree(trip)
    write_json(folder / MESH_CHECK_FILE, check.to_dict())
    return check


def read_mesh_check(folder: str | Path) -> MeshCheck | None:
    """The mesh-halving check kept in its ``folder`` (:func:`mesh_check_in_folder`), or None
    if there is none."""
    path = Path(folder) / MESH_CHECK_FILE
    if not path.is_file():
        return None
    return MeshCheck.from_dict(read_json(path, what="mesh-halving check"), file=path)
