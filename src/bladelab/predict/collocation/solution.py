"""A collocation solution of one stride: its file, its summary and its trajectory.

:class:`CollocationSolution` holds an :class:`~bladelab.predict.collocation.nlp_solution.
NLPSolution` (the node values) with what is needed to read it without solving again: the
settings, the model (``{"model": "able" | "amputee", "blade": "Cat6" | None}``), where the
initial guess came from, the tracking stage's status, and values derived once from the model
at the nodes: contact forces of the collocation model per contact [N], the leg of each
contact, the metabolic energy over the stride [J] and the dynamic consistency with the forward
model (:mod:`bladelab.predict.collocation.consistency`).

The file (JSON, written atomically by :func:`bladelab._io.write_json`; its fields:
:mod:`~bladelab.predict.collocation.solution_file`) has ``"kind": "collocation-solution"`` for
a converged solve and ``"collocation-best-iterate"`` for the last iterate of one that did not
converge; ``bladelab report`` renders only the former.

:meth:`CollocationSolution.summary` gives the numbers of ``bladelab predict --method
collocation --json``; :meth:`CollocationSolution.to_runner_result` the stride, repeated, as a
:class:`~bladelab.runner.RunnerResult`, so that the forward simulation's analyses and the
predictive report work on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bladelab._io import read_json, write_json
from bladelab.errors import DataError, SpecError
from bladelab.predict.collocation.alternating_steps import step_phase
from bladelab.predict.collocation.consistency import dynamics_residual
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.nodes import (
    evaluate_nodes,
    force_zigzag_steps,
    on_fine_grid,
    periodic_runs,
)
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution_file import (
    BEST_ITERATE_KIND,
    FORMAT_VERSION,
    SOLUTION_KIND,
    solution_arguments,
    solution_fields,
)
from bladelab.predict.collocation.stored import check_model_spec, runner_from_spec
from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE, StrideGuess
from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S, StrideNLP
from bladelab.runner.layout import CP_LEG
from bladelab.runner.simulate import RunnerResult, leg_names

__all__ = [
    "BEST_ITERATE_KIND",
    "FORMAT_VERSION",
    "SOLUTION_KIND",
    "CollocationSolution",
]

#: Vertical force of a leg above which it is in contact [N] (the forward analyses' threshold).
CONTACT_THRESHOLD_N = 20.0
#: A peak vertical ground force above this [body weights] is flagged by
#: :meth:`CollocationSolution.gait_warnings`. Measured running peaks reach 2–3 BW at 3–5 m/s
#: and about 5 BW at top sprint speed (impact transients included); the collocation optima
#: that reached 10–17 BW (amputee Cat4 at 5 m/s, able at 5 m/s from a warm start) are not
#: gaits a person could run. Our decision (2026-11-25); a flagged solve loses to a clean one
#: among several starts.
PEAK_GRF_WARNING_BW = 8.0
#: A dynamics residual against the forward model above this [% of the peak generalised
#: force] is flagged by :meth:`CollocationSolution.gait_warnings`: the stride is then the gait
#: of the smoothed model only. Clean solves measure 0.4–2.4 %; strides that placed a node where
#: the smooth and forward contact laws differed (a blade sole's onset, fixed on 2026-11-26)
#: reached 9–48 %. Our decision.
RESIDUAL_WARNING_PCT = 5.0
#: A leg's vertical ground force that zigzags up and down by at least
#: :data:`ZIGZAG_STEP_BW` body weights over this many consecutive node steps
#: (:func:`~bladelab.predict.collocation.nodes.force_zigzag_steps`) is flagged by
#: :meth:`CollocationSolution.gait_warnings`: the mesh does not resolve the stance, and its
#: force peaks are the mesh's. Measured (benchmarks/human_body/sprint-vasti16, "Twice and four
#: times the mesh"): runs of 1–3 on every stored stride at 2.5–5.5 m/s on 50 intervals and at
#: 5.75–8 m/s on 100–200; 8 and 10 on the 50-interval strides at 8.25 and 5.75 m/s, whose
#: peaks (5.6 and 2.6 BW) and objective (+75 %) moved on 100 intervals. Our decision.
ZIGZAG_STEPS = 5
ZIGZAG_STEP_BW = 0.25
#: A leg whose vertical force never reaches this [body weights] does not carry the body: the
#: stride is a one-legged hop with the other foot brushing the ground (flagged by
#: :meth:`CollocationSolution.gait_warnings`). Every running and walking stance peaks above
#: it (people: 2.2-3 BW at 3.5 m/s, about 1.2 BW walking); measured on 2026-12-07: an
#: amputee sprinter's stride from a 4 m/s start hopped on its blade at 6 BW, the intact foot
#: brushing the ground at 0.03 BW, which the contact count alone (20 N) passed. Our decision.
LOAD_BEARING_BW = 1.0
#: Above this vertical force [body weights] a leg counts as loaded for the zigzag.
ZIGZAG_LOADED_BW = 0.05
#: Samples per mesh interval of the linear interpolation used for contact and flight times.
_FINE = 50

@dataclass(frozen=True, eq=False)
class CollocationSolution:
    """A solved (or the last iterate of an unsolved) stride, with its settings and model.

    Attributes
    ----------
    nlp
        The node values and IPOPT's report (:class:`NLPSolution`).
    settings
        :class:`~bladelab.predict.collocation.settings.CollocationSettings`.
    model_spec
        ``{"model": "able" | "amputee", "blade": name | None}``.
    guess_source
        Where the initial guess came from.
    stage
        The stage of ``nlp``: ``"predictive"`` or ``"tracking"`` (a tracking stage that did not
        converge ends the solve).
    tracking
        The tracking stage's ``success``, ``status``, ``iterations``, ``wall_s`` [s],
        ``objective``, ``max_violation``; None when there was none.
    dof_names, muscle_names
        Column names of the node arrays.
    contact_forces
        (n + 1, n_contacts, 2): friction and normal force [N] of each contact of the
        collocation model at the nodes.
    contact_legs
        (n_contacts,) leg of each contact (0 left/intact, 1 right/prosthetic).
    leg_names
        Names of legs 0 and 1: (left, right) or (intact, prosthetic).
    body_mass_kg, body_weight_N
        Of the model.
    metabolic_energy_J
        Metabolic energy over the stride [J] (the collocation's smooth metabolic model).
    residual
        The dynamic-consistency breakdown
        (:meth:`~bladelab.predict.collocation.consistency.DynamicsResidual.to_dict`, the
        forward friction taken as ``"coulomb"``), with ``bristle_residual_pct``: the same
        residual with the forward bristle's state reconstructed along the stride [%].
    reference_phase
        Where people's joint angles start on the stride (fraction of the cycle), or None.
    speed_floor_mps
        Of a maximum-speed solve, the mean speed [m/s] its stride was held at or above (a
        speed at which a stride of the model is known), None without one; a solve whose mean
        speed equals it found no faster stride it preferred.
    """

    nlp: object
    settings: CollocationSettings
    model_spec: dict
    guess_source: str
    stage: str
    tracking: dict | None
    dof_names: tuple[str, ...]
    muscle_names: tuple[str, ...]
    contact_forces: np.ndarray
    contact_legs: np.ndarray
    leg_names: tuple[str, str]
    body_mass_kg: float
    body_weight_N: float
    metabolic_energy_J: float
    residual: dict = field(default_factory=dict)
    reference_phase: float | None = None
    speed_floor_mps: float | None = None

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_nlp(cls, runner, nlp, *, settings: CollocationSettings, model_spec: dict,
                 guess_source: str, stage: str = "predictive", tracking: dict | None = None,
                 metabolic_energy_J: float | None = None, cm=None,
                 reference_phase: float | None = None,
                 speed_floor_mps: float | None = None) -> CollocationSolution:
        """A solution from an :class:`NLPSolution` of ``runner``: evaluates the contact forces
        and the dynamic consistency at the nodes (and the metabolic energy over the stride [J],
        :meth:`StrideNLP.energy_and_distance` on the solution's mesh, when not given)."""
        spec = check_model_spec(model_spec)
        if runner.kind != spec["model"]:
            raise SpecError(f"the runner is the {runner.kind} model, the spec says "
                            f"{spec['model']}", where="model_spec")
        if stage not in ("predictive", "tracking"):
            raise SpecError(f"unknown stage {stage!r}", where="stage",
                            hint="predictive or tracking")
        cm = cm if cm is not None else build_collocation_model(runner)
        q = np.asarray(nlp.q, float)
        if q.shape[1] != cm.nv or np.asarray(nlp.tendon_force).shape[1] != cm.n_muscles:
            raise DataError(f"node arrays of {q.shape[1]} coordinates, the model has {cm.nv}",
                            where="q", hint="the solution is not of this runner model")
        ev = evaluate_nodes(cm, q, np.asarray(nlp.qd, float), np.asarray(nlp.tendon_force, float),
                       np.asarray(nlp.tendon_force_rate, float))
        if metabolic_energy_J is None:  # the NLP's own trapezoidal rule: one definition
            metabolic_energy_J = StrideNLP(stride_dynamics(cm), n=q.shape[0] - 1, speed=None,
                                           compiled=False).energy_and_distance(nlp)[0]
        res = dynamics_residual(nlp, runner, cm=cm).to_dict()
        res["bristle_residual_pct"] = dynamics_residual(nlp, runner, cm=cm, friction="bristle").pct
        return cls(
            nlp=nlp, settings=settings, model_spec=spec, guess_source=str(guess_source),
            stage=stage, tracking=None if tracking is None else dict(tracking),
            dof_names=tuple(runner.dof_names), muscle_names=tuple(runner.muscle_names),
            contact_forces=ev["forces"],
            contact_legs=runner.contact_params[:, CP_LEG].astype(int),
            leg_names=leg_names(runner),
            body_mass_kg=float(runner.total_mass), body_weight_N=float(runner.body_weight),
            metabolic_energy_J=float(metabolic_energy_J), residual=res,
            reference_phase=None if reference_phase is None else float(reference_phase),
            speed_floor_mps=None if speed_floor_mps is None else float(speed_floor_mps),
        )

    # -- derived numbers ------------------------------------------------------------------
    @property
    def converged(self) -> bool:
        """True if the predictive stage converged (IPOPT's success)."""
        return bool(self.nlp.success) and self.stage == "predictive"

    @property
    def kind(self) -> str:
        """The file kind: :data:`SOLUTION_KIND` or :data:`BEST_ITERATE_KIND`."""
        return SOLUTION_KIND if self.converged else BEST_ITERATE_KIND

    @property
    def period_s(self) -> float:
        """Stride time [s]."""
        return float(self.nlp.period)

    @property
    def stride_length_m(self) -> float:
        """Pelvis travel over the stride [m]."""
        i = self.dof_names.index("pelvis_tx")
        return float(self.nlp.q[-1, i] - self.nlp.q[0, i])

    @property
    def mean_speed_mps(self) -> float:
        """Mean forward speed [m/s]."""
        return self.stride_length_m / self.period_s

    @property
    def cost_of_transport_J_per_kg_m(self) -> float:
        """Metabolic energy per body mass and distance [J/(kg·m)]."""
        d = self.stride_length_m
        return self.metabolic_energy_J / (self.body_mass_kg * d) if d > 0 else math.nan

    @property
    def dynamics_residual_pct(self) -> float:
        """Largest inverse-dynamics difference from the forward model's forces, % of peak."""
        v = self.residual.get("dynamics_residual_pct")
        return math.nan if v is None else float(v)

    def leg_vertical_force(self) -> np.ndarray:
        """(n + 1, 2) vertical ground force of legs 0 and 1 at the nodes [N]."""
        return self._leg_force(1)

    def leg_horizontal_force(self) -> np.ndarray:
        """(n + 1, 2) horizontal (friction, forward positive) ground force of legs 0 and 1 at
        the nodes [N]."""
        return self._leg_force(0)

    def _leg_force(self, axis: int) -> np.ndarray:
        f = self.contact_forces[:, :, axis]
        return np.stack([f[:, self.contact_legs == leg].sum(axis=1) for leg in (0, 1)], axis=1)

    def contact_phases(self, threshold_n: float = CONTACT_THRESHOLD_N) -> dict:
        """Per leg: stance time [s] (the longest loaded stretch of the periodic stride),
        contacts per stride (count) and peak vertical force [N]; and the flight fraction (of
        the stride with neither leg loaded) [-]. Loaded: vertical force above ``threshold_n``
        [N], the node values interpolated linearly."""
        fz = self.leg_vertical_force()
        n = fz.shape[0] - 1
        loaded = on_fine_grid(fz, _FINE) > threshold_n
        dt = self.period_s / (n * _FINE)
        legs = {}
        for j, name in enumerate(self.leg_names):
            runs = [length for _, length in periodic_runs(loaded[:, j])]
            legs[name] = {"contact_time_s": float(max(runs, default=0) * dt),
                          "contacts": len(runs),
                          "peak_vertical_grf_N": float(fz[:, j].max())}
        return {"legs": legs, "flight_fraction": float(np.mean(~loaded.any(axis=1)))}

    def gait_warnings(self) -> list[str]:
        """What makes this converged stride no running gait, in words (empty if nothing):
        a leg that never touches the ground or never carries the body
        (:data:`LOAD_BEARING_BW`: a one-legged hop), a leg that touches it more
        than once per stride (a swinging foot striking the ground, or a bounce), a peak
        vertical force above :data:`PEAK_GRF_WARNING_BW`, a leg's vertical force that zigzags
        from node to node (:data:`ZIGZAG_STEPS`), no flight phase, a dynamics residual
        above :data:`RESIDUAL_WARNING_PCT`, or a stride time on a bound of the NLP
        (:data:`~bladelab.predict.collocation.transcription.PERIOD_BOUNDS_S`). Measured on 2026-11-25: the amputee Cat6 at 4 m/s
        from the Fukuchi trial's guess converged to a hop on the intact leg at the 0.4 s
        bound."""
        ph = self.contact_phases()
        weight = self.body_weight_N
        out = [f"the {leg} leg never touches the ground (a one-legged hop, not running)"
               for leg in self.leg_names if ph["legs"][leg]["contacts"] == 0]
        out += [f"the {leg} leg never carries the body: its peak vertical force is "
                f"{peak / weight:.2f} body weights (below {LOAD_BEARING_BW:g}: a one-legged "
                "hop, the other foot only brushing the ground)"
                for leg in self.leg_names if ph["legs"][leg]["contacts"] > 0
                and (peak := ph["legs"][leg]["peak_vertical_grf_N"]) < LOAD_BEARING_BW * weight]
        out += [f"the {leg} leg touches the ground {ph['legs'][leg]['contacts']} times per "
                "stride (a swinging foot strikes the ground, or the stance bounces)"
                for leg in self.leg_names if ph["legs"][leg]["contacts"] > 1]
        out += [f"the {leg} leg's peak vertical force is {peak / weight:.1f} body weights "
                f"(above {PEAK_GRF_WARNING_BW:g}: an impact no runner survives)"
                for leg in self.leg_names
                if (peak := ph["legs"][leg]["peak_vertical_grf_N"]) > PEAK_GRF_WARNING_BW * weight]
        if ph["flight_fraction"] <= 0.0:
            out.append("no flight phase (not running)")
        for bound in PERIOD_BOUNDS_S:
            if math.isclose(self.period_s, bound, rel_tol=1e-3):
                out.append(f"the stride time sits on its bound ({bound:g} s)")
        fz = self.leg_vertical_force()[:-1] / weight
        out += [f"the {leg} leg's vertical force zigzags from node to node over {steps} steps "
                "(the mesh does not resolve the stance: solve it on more intervals, e.g. "
                "--mesh 100)"
                for j, leg in enumerate(self.leg_names)
                if (steps := force_zigzag_steps(fz[:, j], ZIGZAG_STEP_BW, ZIGZAG_LOADED_BW)) >= ZIGZAG_STEPS]
        residual = self.dynamics_residual_pct
        if residual > RESIDUAL_WARNING_PCT:  # nan (not recorded) is not flagged
            out.append(f"the dynamics residual against the forward model is {residual:.1f} % "
                       f"(above {RESIDUAL_WARNING_PCT:g} %: the smoothed model's gait only)")
        return out

    def summary(self) -> dict:
        """The numbers ``bladelab predict --method collocation --json`` prints.

        ``converged``; ``status`` (IPOPT's, of the stage that ended the solve);
        ``mean_speed_mps``, ``stride_time_s``, ``cost_of_transport_J_per_kg_m``;
        ``contact_time_s`` (mean over the legs) and per leg ``contact_time_<leg>_s`` [s];
        ``peak_vertical_grf_<leg>_bw`` [body weights]; ``flight_fraction`` (of the stride);
        ``step_phase`` (the second leg's stance centre after the first's, as a fraction of
        the stride: 0.5 for alternating steps of equal time, near 0 or 1 for a gallop;
        :func:`~bladelab.predict.collocation.alternating_steps.step_phase`);
        ``dynamics_residual_pct``; ``iterations`` and ``wall_s`` [s] of both stages together
        (tracking + predictive); ``warnings`` (:meth:`gait_warnings`, joined by "; ", empty
        if none). Legs: left/right (able) or intact/prosthetic (amputee).
        """
        ph = self.contact_phases()
        times = [ph["legs"][leg]["contact_time_s"] for leg in self.leg_names]
        tr = self.tracking or {}
        its = int(self.nlp.iterations) + (int(tr.get("iterations", 0))
                                          if self.stage == "predictive" else 0)
        wall = float(self.nlp.wall_s) + (float(tr.get("wall_s", 0.0))
                                         if self.stage == "predictive" else 0.0)
        out = {
            "converged": self.converged,
            "status": str(self.nlp.status),
            "mean_speed_mps": self.mean_speed_mps,
            "stride_time_s": self.period_s,
            "cost_of_transport_J_per_kg_m": self.cost_of_transport_J_per_kg_m,
            "contact_time_s": float(np.mean(times)),
        }
        for leg, t in zip(self.leg_names, times, strict=True):
            out[f"contact_time_{leg}_s"] = t
        for leg in self.leg_names:
            out[f"peak_vertical_grf_{leg}_bw"] = (ph["legs"][leg]["peak_vertical_grf_N"]
                                                  / self.body_weight_N)
        out["flight_fraction"] = ph["flight_fraction"]
        out["step_phase"] = step_phase(self.leg_vertical_force()[:-1])
        out["dynamics_residual_pct"] = self.dynamics_residual_pct
        out["iterations"] = its
        out["wall_s"] = wall
        out["warnings"] = "; ".join(self.gait_warnings())
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                for k, v in out.items()}

    # -- conversions ----------------------------------------------------------------------
    def to_guess(self, source: str | None = None) -> StrideGuess:
        """This solution as an initial guess (muscle states included); its source marks it as
        a collocation solution, so :func:`~bladelab.predict.collocation.solve.predict_stride`
        goes straight to the predictive stage."""
        text = source or f"{COLLOCATION_SOURCE} ({self.guess_source})"
        if not text.startswith(COLLOCATION_SOURCE):
            text = f"{COLLOCATION_SOURCE}: {text}"
        return replace(self.nlp.to_guess(text), dof_names=self.dof_names,
                       muscle_names=self.muscle_names, reference_phase=self.reference_phase)

    def to_runner_result(self, n_strides: int = 3, *, refine: int = 1, runner=None, cm=None):
        """The stride repeated ``n_strides`` times as a :class:`~bladelab.runner.RunnerResult`
        (pelvis_tx advanced by the stride length each time), for the forward analyses and the
        predictive report.

        Between nodes, ``refine`` − 1 extra samples per interval: coordinates on the
        trapezoidal rule's quadratic (q̇ linear), muscle states and controls linear. At every
        sample the collocation model gives the MTU lengths and velocities [m, m/s], fibre
        lengths and velocities [m, m/s], contact forces [N], points [m], point velocities
        [m/s] (of the body's material point at the contact point, as the forward kernel records
        them) and compression [m] (the depth of the contact point below the ground), and the
        ligament, socket and blade-joint torques [N·m]. ``dt`` of the result is the sample
        spacing [s]; ``fell`` is False.

        ``runner``: the model (built from :attr:`model_spec` if None); ``cm`` its collocation
        model (built if None).
        """
        if isinstance(n_strides, bool) or int(n_strides) != n_strides or n_strides < 1:
            raise SpecError(f"need at least 1 stride, got {n_strides!r}", where="n_strides")
        if isinstance(refine, bool) or int(refine) != refine or refine < 1:
            raise SpecError(f"need refine >= 1, got {refine!r}", where="refine")
        n_strides, refine = int(n_strides), int(refine)
        runner = runner if runner is not None else runner_from_spec(self.model_spec)
        if tuple(runner.dof_names) != self.dof_names:
            raise DataError("the runner's coordinates are not the solution's",
                            where="runner", hint="use the model the solution was solved for")
        cm = cm if cm is not None else build_collocation_model(runner)
        s = self.nlp
        q, qd = np.asarray(s.q, float), np.asarray(s.qd, float)
        n = q.shape[0] - 1
        period = self.period_s
        h = period / n
        tau = np.arange(refine) * h / refine  # offsets within an interval [s]
        k = np.repeat(np.arange(n), refine)
        tt = np.tile(tau, n)
        k = np.concatenate([np.tile(k, n_strides), [n]])
        tt = np.concatenate([np.tile(tt, n_strides), [0.0]])
        stride = np.concatenate([np.repeat(np.arange(n_strides), n * refine),
                                 [n_strides - 1]])
        nxt = np.minimum(k + 1, n)
        w = (tt / h)[:, None]
        dv = qd[nxt] - qd[k]
        qs = q[k] + qd[k] * tt[:, None] + dv * (tt * tt / (2 * h))[:, None]
        qds = qd[k] + dv * w
        itx = self.dof_names.index("pelvis_tx")
        qs[:, itx] += stride * self.stride_length_m

        def lin(a):
            a = np.asarray(a, float)
            return a[k] + (a[nxt] - a[k]) * w

        act, ft = lin(s.activation), lin(s.tendon_force)
        exc, dft = lin(s.excitation), lin(s.tendon_force_rate)
        time = stride * period + k * h + tt
        ev = evaluate_nodes(cm, qs, qds, ft, dft)
        fmax = runner.muscle_params[:, 0]
        muscles = np.stack([act, ev["l_m"], ev["v_m"], ft * fmax], axis=2)
        mtu = np.stack([ev["l_mt"], ev["v_mt"]], axis=2)
        f, p, pv = ev["forces"], ev["points"], ev["point_velocities"]
        depth = np.maximum(-p[:, :, 1], 0.0)
        contacts = np.concatenate([f, p, pv, depth[:, :, None]], axis=2)
        return RunnerResult(
            model=runner, time=time, qpos=qs, qvel=qds, muscles=muscles, mtu=mtu,
            excitation=exc, contacts=contacts, ligament=ev["passive"], dt=h / refine,
            fell=False, requested_duration=n_strides * period,
        )

    # -- file -----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The file's content (:mod:`~bladelab.predict.collocation.solution_file`)."""
        return solution_fields(self)

    def write(self, path: str | Path) -> Path:
        """Write the solution (or best iterate) as JSON, atomically: an interruption leaves
        no half-written file. Returns the path."""
        path = Path(path)
        write_json(path, self.to_dict())
        return path

    @classmethod
    def read(cls, path: str | Path) -> CollocationSolution:
        """Read a file written by :meth:`write`.

        Raises
        ------
        InputFileError
            The file is missing or not JSON.
        DataError
            A field is missing or of the wrong kind or shape (the error names the file and the
            field).
        """
        path = Path(path)
        data = read_json(path, what="collocation solution",
                         hint="give a solution.json or best_iterate.json of 'bladelab predict "
                              "--method collocation'")
        return cls.from_dict(data, file=path)

    @classmethod
    def from_dict(cls, data, *, file: str | Path | None = None) -> CollocationSolution:
        """A solution from :meth:`to_dict`'s mapping; errors as :meth:`read`."""
        return cls(**solution_arguments(data, file))


