"""The settings of one stride solve: :class:`CollocationSettings` (mesh, speed, objective
weights, constraints, reference term and IPOPT options), checked when made and stored with each
solution (:meth:`CollocationSettings.to_dict`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from bladelab.errors import SpecError
from bladelab.predict import defaults
from bladelab.predict.collocation.dynamics import COORDINATE_BOUNDS_DEG
from bladelab.predict.collocation.running_bands import ANCHOR_SPEEDS_MPS, reference_band
from bladelab.predict.collocation.stride_problem import StrideWeights
from bladelab.predict.collocation.transcription import PERIOD_BOUNDS_S

__all__ = ["HESSIANS", "PEOPLE_REFERENCE", "SWING_KNEE_RANGE_DEG", "CollocationSettings",
           "people_settings", "people_term"]

#: IPOPT Hessian options (:meth:`~bladelab.predict.collocation.transcription.StrideNLP.solve`).
HESSIANS = ("limited-memory", "exact")
#: The largest constraint violation of a last iterate that is polished (``polish_iter``): a
#: stride near feasibility that lacks optimality (measured 2026-11-29: from a transfemoral
#: stride stalled at 6.6e-6 the exact Hessian converged in 81 iterations, 69 s).
POLISH_MAX_VIOLATION = 1e-4
#: ``CollocationSettings.reference`` naming people's measured joint angles, not a file.
PEOPLE_REFERENCE = "people"
#: Allowed range of ``CollocationSettings.swing_knee_min_deg`` [deg]: up to the knee's range
#: of motion in running (the coordinate's bound is 150°).
SWING_KNEE_RANGE_DEG = (10.0, 140.0)


def _weights_from_dict(data, where: str) -> StrideWeights:
    if isinstance(data, StrideWeights):
        return data
    if not isinstance(data, dict):
        raise SpecError(f"expected a mapping of objective weights, got {type(data).__name__}",
                        where=where)
    known = {f.name for f in fields(StrideWeights)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise SpecError(f"unknown objective weight(s) {', '.join(unknown)}", where=where,
                        hint=f"known: {', '.join(sorted(known))}")
    try:
        return StrideWeights(**{k: float(v) for k, v in data.items()})
    except (TypeError, ValueError):
        raise SpecError("objective weights must be numbers", where=where) from None


@dataclass(frozen=True)
class CollocationSettings:
    """Settings of one stride solve.

    Attributes
    ----------
    mesh_intervals
        Mesh intervals n of the stride (trapezoidal collocation, n + 1 nodes).
    speed_m_per_s
        Prescribed mean speed [m/s]; None: the maximum-speed problem.
    weights
        Objective weights of the predictive stage (:class:`StrideWeights`); None: cost of
        transport 1, activation 1, acceleration 0.1 at a prescribed speed; speed 1,
        activation 1, acceleration 0.1 and no metabolic term for the maximum speed.
    tracking_weight
        Weight of the joint-angle tracking term of the tracking stage [1/rad²].
    grf_tracking_weight
        Weight of the tracking stage's vertical-ground-force term [1/BW²], used when the guess
        carries a force pattern (``StrideGuess.vertical_grf_bw``; every guess function gives
        one). Measured: with angles alone the stage met the Fukuchi angles with a one-legged
        hop and the template with 20-BW bounds; with the force pattern, alternating stances.
    track_first
        Run the tracking stage before the predictive one (module docstring).
    hessian
        IPOPT's Hessian: ``"limited-memory"`` (L-BFGS, adaptive barrier) or ``"exact"``.
    tol
        IPOPT's convergence tolerance [-].
    max_iter
        IPOPT's iteration limit per stage.
    polish_iter
        IPOPT's iteration limit of the polish: a predictive stage on L-BFGS that runs out of
        iterations near a feasible point (violation at most :data:`POLISH_MAX_VIOLATION`) is
        solved on from its last iterate and multipliers with the exact Hessian, and the
        polished stride is kept if it converges (measured 2026-11-29: a transtibial runner
        wearing a multi-link blade on the human body stood 6,000 L-BFGS iterations on a
        feasible stride without converging; the polish converged in 116 iterations, 157 s).
        0: no polish.
    warm_start_mu
        IPOPT's initial barrier parameter when the predictive stage starts from a collocation
        solution (a warm start: speed continuation, maximum speed, ``--guess solution.json``),
        with ``bound_push`` = ``bound_frac`` = 1e-8 so that the start is not pushed away from
        the bounds it sits on; None (default): IPOPT's defaults (mu_init 0.1, bound_push and
        bound_frac 0.01). Neither is better everywhere (measured 2026-11-25, mesh 50): amputee
        Cat6 4 → 4.2 m/s reached objective 2.708 with 1e-4 and 3.323 with the defaults; Cat5
        4 → 5 m/s reached a cost of transport of 3.33 with 1e-4 and 2.89 with the defaults,
        and the maximum speeds of Cat4/Cat5 were 6.99/7.32 m/s with 1e-4 against 7.53/7.71
        m/s. The landscape has local optima 15–25 % apart along a continuation; the two
        settings are two starts (docs/collocation.md).
    swing_clearance_m
        Keep every swinging foot or blade at least this high above the ground [m]: a path
        constraint on each contact while it moves forward faster than the pelvis
        (:func:`~bladelab.predict.collocation.dynamics.swing_clearance`); 0 (default): none.
        The "toe clearance as a constraint" setting (the transfemoral runner's blade
        grazed the ground in swing without it).
    knee_moment_min_nm
        Keep the external extension moment of the prosthetic contacts' ground forces about the
        prosthetic knee at or above this [N·m] at every node (seed 002's knee-buckling
        constraint, :func:`~bladelab.predict.collocation.dynamics.knee_extension_moment`;
        at most 0, since the moment is 0 in swing); None (default): no constraint. Transfemoral
        runner only.
    knee_flexion_max_loaded_deg
        Keep the prosthetic knee within this flexion [deg] of straight while its blade
        carries load (a path constraint weighted by the blade's vertical force,
        :func:`~bladelab.predict.collocation.dynamics.knee_straight_while_loaded`): the
        straight stance from which ``knee_moment_min_nm`` at 0 becomes reachable
        (docs/design.md); None (default): no constraint. Transfemoral runner only.
    prosthetic_load_max_bw
        Keep the prosthetic leg's vertical ground force at or below this many body weights at
        every node (:func:`~bladelab.predict.collocation.dynamics.prosthetic_load_margin`):
        the load a residual limb tolerates in its socket, which the body's rigid socket does
        not price; None (default): no limit. Amputee and transfemoral runners.
    blade_backward_euler
        Transcribe a multi-link blade's joints by backward Euler instead of the trapezoidal
        rule (``StrideDynamics.backward_euler_dofs``): its links' modes (about 300 Hz) are
        resolved by no mesh, and with the trapezoidal rule they ring from node to node
        (measured 2026-11-26 on the transfemoral design stride: blade-joint accelerations
        alternating ±1500 rad/s², sole friction forces and the knee moment alternating in
        sign from node to node). Backward Euler damps them: first-order accurate, it lags and
        damps the blade's own motion by O(h) (docs/design.md). No effect without such a blade.
    pelvis_tilt_range_deg
        (lo, hi) [deg]: keep the pelvis tilt inside this range at every node (bounds; forward
        lean negative), e.g. seed 001's window (-16, -2) the reflex gaits' acceptance asks for;
        None (default): the coordinate's own bounds (-60, 30). A stride the reflex
        controller tracks (``bladelab predict --track``) passes its lean on: the Cat6 4 m/s
        stride without it leans -17.8° on average (docs/collocation.md).
    step_phase_tolerance
        Keep the steps alternating: the centre of the right (prosthetic) leg's stance at half
        a stride ± this fraction of the stride after the left (intact) leg's (the circular
        means of their vertical ground forces,
        :func:`~bladelab.predict.collocation.alternating_steps.step_phase`); a constraint of the
        predictive stage. None (default): free. Runners with a transfemoral amputation step
        with the same step frequency on both legs (nine athletes on running-specific
        prostheses at 30–70 % of their maximum speed, ISBS proceedings 36, 2018) and their
        peak forces are most symmetric at their preferred step frequency (Kobayashi et al.
        2022, J NeuroEng Rehabil); the transfemoral runner on the human body, free, gallops
        instead (docs/runner-model.md).
    stride_time_range_s
        (lo, hi) [s]: keep the stride time (the period) inside this range, a constraint of
        every stage (the NLP's period bounds); lo = hi fixes it. For an athlete whose cadence
        was measured: the stride time is then imposed, not predicted, and the report says so.
        None (default): the NLP's own bounds
        (:data:`~bladelab.predict.collocation.transcription.PERIOD_BOUNDS_S`), the stride
        time free. The human body's free strides are 5–15 % quicker than people's
        (docs/collocation.md, "The stride time").
    stride_time_people
        True: keep the stride time within people's band at the prescribed speed
        (:func:`~bladelab.predict.collocation.running_bands.reference_band`, "stride time":
        0.64–0.78 s at 3.5 m/s, 0.40–0.55 s at 9 m/s, linear between), for an athlete whose
        cadence was not measured; imposed, not predicted, as ``stride_time_range_s``, which
        it excludes. Each speed of a continuation gets its own band. In the maximum-speed
        problem, whose speed is the unknown, the band moves with the stride's speed (two
        constraint rows, :attr:`period_band`); predict's maximum speed leaves it free
        (:func:`~bladelab.predict.collocation.continuation.max_speed_settings`). False
        (default): free.
    swing_knee_min_deg
        Keep the peak flexion of every knee that is a person's (not a transfemoral runner's
        prosthetic knee) at or above this [deg] over the stride, a constraint of the
        predictive stage (a smooth maximum over the nodes,
        :mod:`~bladelab.predict.collocation.swing_knee`); people's value, 108.5° (two runners
        at 3.5 m/s, :data:`bladelab.predict.defaults.SWING_KNEE_MIN_DEG`), is the default of
        the human body's able and transtibial runners through ``bladelab predict``
        (:func:`people_settings`): the body's own swing is 15–20° shallower than
        people's and its stride quicker (docs/collocation.md, "People's swing knee"). A
        prescription from measured running, reported with every answer. None (default): free.
    symmetric
        Each leg does what the other did half a stride earlier (bilateral symmetry, as
        PredSim imposes it by solving half a gait cycle;
        :mod:`~bladelab.predict.collocation.symmetry`): a constraint of the predictive
        stage, for a runner whose legs are mirror images (the able runner) and an even
        number of mesh intervals. False (default): each leg free.
    reference, reference_weight, reference_dofs
        ``"people"`` (:data:`PEOPLE_REFERENCE`): people's measured hip, knee and ankle angles
        at 3.5 m/s (:mod:`bladelab.predict.collocation.people`), ``reference_weight``
        [1/rad²] × their time-averaged mean squared deviation, no stride-time term; the
        human body's gait term (docs/collocation.md). Or a collocation solution file of the
        same runner whose joint angles the predictive stage stays near: ``reference_weight``
        [1/rad²] × the time-averaged mean squared deviation of the coordinates
        ``reference_dofs`` (None: pelvis tilt and every joint) from the reference's, on the
        normalised stride, plus the same weight × ln(T/T_ref)²
        of the stride time T against the reference's (the cadence: measured 2026-11-26, with
        the angles alone the design strides split into 0.51 s and 0.59 s strides, both
        within 7° of the reference's angles). Weight 0 (default): none, the gait
        is predicted freely. The design study's "athlete keeps their technique" setting
        (docs/design.md): without it the optimum's split of the horizontal impulse between
        the legs is barely determined and depends on the start. The problem's identity
        (:meth:`same_problem`) holds the reference's file name, not its folder.
    """

    mesh_intervals: int = defaults.MESH_INTERVALS
    speed_m_per_s: float | None = defaults.SPEED_M_PER_S
    weights: StrideWeights | None = None
    tracking_weight: float = 100.0
    grf_tracking_weight: float = 10.0
    track_first: bool = True
    hessian: str = "limited-memory"
    tol: float = 1e-4
    max_iter: int = defaults.MAX_ITER
    polish_iter: int = defaults.POLISH_ITER
    warm_start_mu: float | None = None
    swing_clearance_m: float = 0.0
    knee_moment_min_nm: float | None = None
    knee_flexion_max_loaded_deg: float | None = None
    prosthetic_load_max_bw: float | None = None
    blade_backward_euler: bool = False
    pelvis_tilt_range_deg: tuple[float, float] | None = None
    step_phase_tolerance: float | None = None
    stride_time_range_s: tuple[float, float] | None = None
    stride_time_people: bool = False
    swing_knee_min_deg: float | None = None
    symmetric: bool = False
    reference: str | None = None
    reference_weight: float = 0.0
    reference_dofs: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        n = self.mesh_intervals
        if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 4:
            raise SpecError(f"need an integer of at least 4 mesh intervals, got {n!r}",
                            where="mesh_intervals")
        object.__setattr__(self, "mesh_intervals", int(n))
        v = self.speed_m_per_s
        if v is not None:
            if isinstance(v, bool) or not isinstance(v, int | float) or not (
                    math.isfinite(v) and v > 0):
                raise SpecError(f"speed must be > 0 m/s or None (maximum speed), got {v!r}",
                                where="speed_m_per_s")
            object.__setattr__(self, "speed_m_per_s", float(v))
        if self.weights is None:
            w = (StrideWeights(metabolic=1.0, activation=1.0, acceleration=0.1)
                 if v is not None else
                 StrideWeights(metabolic=0.0, activation=1.0, acceleration=0.1, speed=1.0))
        else:
            w = _weights_from_dict(self.weights, "weights")
        object.__setattr__(self, "weights", w)
        self._check_weight("tracking_weight", "tracking weight")
        self._check_weight("grf_tracking_weight", "force tracking weight")
        if not isinstance(self.track_first, bool):
            raise SpecError(f"expected true or false, got {self.track_first!r}",
                            where="track_first")
        if self.hessian not in HESSIANS:
            raise SpecError(f"unknown Hessian option {self.hessian!r}", where="hessian",
                            hint=" or ".join(HESSIANS))
        if isinstance(self.tol, bool) or not isinstance(self.tol, int | float) or not (
                math.isfinite(self.tol) and self.tol > 0):
            raise SpecError(f"tolerance must be > 0, got {self.tol!r}", where="tol")
        object.__setattr__(self, "tol", float(self.tol))
        mi = self.max_iter
        if isinstance(mi, bool) or not isinstance(mi, int | np.integer) or mi < 1:
            raise SpecError(f"need at least 1 iteration, got {mi!r}", where="max_iter")
        object.__setattr__(self, "max_iter", int(mi))
        pi = self.polish_iter
        if isinstance(pi, bool) or not isinstance(pi, int | np.integer) or pi < 0:
            raise SpecError(f"need a number of iterations >= 0, got {pi!r}", where="polish_iter")
        object.__setattr__(self, "polish_iter", int(pi))
        mu = self.warm_start_mu
        if mu is not None:
            if isinstance(mu, bool) or not isinstance(mu, int | float) or not (
                    math.isfinite(mu) and mu > 0):
                raise SpecError(f"the warm-start barrier must be > 0 or None, got {mu!r}",
                                where="warm_start_mu")
            object.__setattr__(self, "warm_start_mu", float(mu))

        sc = self.swing_clearance_m
        if isinstance(sc, bool) or not isinstance(sc, int | float) or not (
                math.isfinite(sc) and 0 <= sc < 0.5):
            raise SpecError(f"swing clearance must be within [0, 0.5) m, got {sc!r}",
                            where="swing_clearance_m")
        object.__setattr__(self, "swing_clearance_m", float(sc))
        km = self.knee_moment_min_nm
        if km is not None:
            if isinstance(km, bool) or not isinstance(km, int | float) or not (
                    math.isfinite(km) and km <= 0):
                raise SpecError(f"the knee moment minimum must be <= 0 N·m or None, got {km!r}",
                                where="knee_moment_min_nm",
                                hint="the moment is 0 while the prosthesis is off the ground")
            object.__setattr__(self, "knee_moment_min_nm", float(km))
        kf = self.knee_flexion_max_loaded_deg
        if kf is not None:
            if isinstance(kf, bool) or not isinstance(kf, int | float) or not (
                    math.isfinite(kf) and 0 <= kf <= 90):
                raise SpecError(f"the loaded knee's flexion limit must be within [0, 90] deg "
                                f"or None, got {kf!r}", where="knee_flexion_max_loaded_deg")
            object.__setattr__(self, "knee_flexion_max_loaded_deg", float(kf))
        pl = self.prosthetic_load_max_bw
        if pl is not None:
            if isinstance(pl, bool) or not isinstance(pl, int | float) or not (
                    math.isfinite(pl) and 0 < pl <= 20):
                raise SpecError(f"the prosthetic load limit must be within (0, 20] body weights "
                                f"or None, got {pl!r}", where="prosthetic_load_max_bw",
                                hint="e.g. 3: the prosthetic leg's vertical force at most 3 BW")
            object.__setattr__(self, "prosthetic_load_max_bw", float(pl))
        if not isinstance(self.blade_backward_euler, bool):
            raise SpecError(f"expected true or false, got {self.blade_backward_euler!r}",
                            where="blade_backward_euler")
        sp = self.step_phase_tolerance
        if sp is not None:
            if isinstance(sp, bool) or not isinstance(sp, int | float) or not (
                    math.isfinite(sp) and 0 < sp < 0.5):
                raise SpecError(f"the step phase tolerance must be within (0, 0.5) of the "
                                f"stride or None, got {sp!r}", where="step_phase_tolerance",
                                hint="0.1: the other leg's stance 40-60 % of the stride later")
            object.__setattr__(self, "step_phase_tolerance", float(sp))
        sk = self.swing_knee_min_deg
        if sk is not None:
            lo, hi = SWING_KNEE_RANGE_DEG
            if isinstance(sk, bool) or not isinstance(sk, int | float) or not (
                    math.isfinite(sk) and lo <= sk <= hi):
                raise SpecError(f"the swing knee's minimum flexion must be within [{lo:g}, "
                                f"{hi:g}] deg or None, got {sk!r}", where="swing_knee_min_deg",
                                hint="people flex about 108° at 3.5 m/s; None: free")
            object.__setattr__(self, "swing_knee_min_deg", float(sk))
        if not isinstance(self.symmetric, bool):
            raise SpecError(f"expected true or false, got {self.symmetric!r}",
                            where="symmetric")
        if self.symmetric and self.mesh_intervals % 2:
            raise SpecError(f"a symmetric stride needs an even number of mesh intervals, got "
                            f"{self.mesh_intervals}", where="mesh_intervals",
                            hint="e.g. 50 or 100")
        self._check_tilt_range()
        self._check_stride_time_range()
        self._check_stride_time_people()
        self._check_reference()

    def _check_tilt_range(self) -> None:
        """``pelvis_tilt_range_deg``: None or (lo, hi) [deg] with lo < hi inside the pelvis
        tilt's own bounds."""
        self._check_range("pelvis_tilt_range_deg", "the pelvis tilt range", "deg",
                          COORDINATE_BOUNDS_DEG["pelvis_tilt"],
                          "seed 001's window is -16, -2 (forward lean negative)")

    def _check_stride_time_range(self) -> None:
        """``stride_time_range_s``: None or (lo, hi) [s] with lo <= hi inside the NLP's own
        period bounds."""
        self._check_range("stride_time_range_s", "the stride time range", "s", PERIOD_BOUNDS_S,
                          "e.g. 0.64, 0.78 (people at 3.5 m/s); lo = hi fixes it",
                          equal_ok=True)

    def _check_stride_time_people(self) -> None:
        """``stride_time_people``: a bool; with a prescribed speed and no stride time range."""
        if not isinstance(self.stride_time_people, bool):
            raise SpecError(f"expected true or false, got {self.stride_time_people!r}",
                            where="stride_time_people")
        if not self.stride_time_people:
            return
        if self.stride_time_range_s is not None:
            raise SpecError("people's stride time and a stride time range are two ways to "
                            "impose one stride time: give one", where="stride_time_people",
                            hint="drop the range, or stride_time_people false")

    def _check_range(self, name: str, what: str, unit: str, bounds: tuple[float, float],
                     hint: str, *, equal_ok: bool = False) -> None:
        """A range field: None or two finite numbers (lo, hi) within ``bounds``, lo < hi (lo <=
        hi with ``equal_ok``), stored as a tuple of floats."""
        tr = getattr(self, name)
        if tr is None:
            return
        lo_all, hi_all = bounds
        ordered = (lambda lo, hi: lo <= hi) if equal_ok else (lambda lo, hi: lo < hi)
        ok = (not isinstance(tr, str | bytes) and len(tr) == 2
              and all(isinstance(v, int | float) and not isinstance(v, bool)
                      and math.isfinite(v) for v in tr)
              and lo_all <= tr[0] and tr[1] <= hi_all and ordered(tr[0], tr[1]))
        if not ok:
            op = "<=" if equal_ok else "<"
            raise SpecError(f"{what} must be (lo, hi) [{unit}] with {lo_all:g} <= lo {op} hi <= "
                            f"{hi_all:g}, got {tr!r}", where=name, hint=hint)
        object.__setattr__(self, name, (float(tr[0]), float(tr[1])))

    @property
    def period_bounds_s(self) -> tuple[float, float]:
        """(lo, hi) [s] of the stride time in the NLP: people's band at the speed with
        :attr:`stride_time_people` (to 1 µs), else :attr:`stride_time_range_s`, else
        :data:`~bladelab.predict.collocation.transcription.PERIOD_BOUNDS_S`."""
        if self.stride_time_people and self.speed_m_per_s is not None:
            lo, hi, _ = reference_band("stride time", self.speed_m_per_s)
            return round(lo, 6), round(hi, 6)
        return self.stride_time_range_s or PERIOD_BOUNDS_S

    @property
    def period_band(self) -> tuple[float, ...] | None:
        """The maximum-speed problem with :attr:`stride_time_people`: people's stride-time
        band at the anchor speeds, ``(v0, lo0, hi0, v1, lo1, hi1)`` [m/s, s]
        (:class:`~bladelab.predict.collocation.transcription.StrideNLP`'s ``period_band``);
        else None."""
        if not (self.stride_time_people and self.speed_m_per_s is None):
            return None
        return tuple(x for v in ANCHOR_SPEEDS_MPS
                     for x in (v, *reference_band("stride time", v)[:2]))

    @property
    def imposed_stride_time(self) -> str | None:
        """The imposed stride time as text with its unit ("0.7 s" when fixed, "0.64–0.78 s"
        for a range, "people's band at 4 m/s, 0.618–0.759 s"), or None when it is free."""
        if self.stride_time_people and self.speed_m_per_s is None:
            return "people's band at the stride's speed"
        if self.stride_time_people:
            lo, hi = self.period_bounds_s
            return f"people's band at {self.speed_m_per_s:g} m/s, {lo:.3g}–{hi:.3g} s"
        r = self.stride_time_range_s
        if r is None:
            return None
        return f"{r[0]:g} s" if r[0] == r[1] else f"{r[0]:g}–{r[1]:g} s"

    def _check_weight(self, name: str, what: str) -> None:
        """A weight field: a finite number >= 0, stored as float."""
        w = getattr(self, name)
        if isinstance(w, bool) or not isinstance(w, int | float) or not (
                math.isfinite(w) and w >= 0):
            raise SpecError(f"{what} must be >= 0, got {w!r}", where=name)
        object.__setattr__(self, name, float(w))

    def _check_reference(self) -> None:
        self._check_weight("reference_weight", "the reference weight")
        rw = self.reference_weight
        if self.reference is not None:
            object.__setattr__(self, "reference", str(self.reference))
        if rw > 0 and self.reference is None:
            raise SpecError("a reference weight needs a reference solution", where="reference",
                            hint="give the solution file whose joint angles to stay near, "
                                 f"or '{PEOPLE_REFERENCE}' for people's measured angles")
        dofs = self.reference_dofs
        if dofs is not None:
            if isinstance(dofs, str) or not all(isinstance(d, str) for d in dofs) or not dofs:
                raise SpecError(f"expected a list of coordinate names, got {dofs!r}",
                                where="reference_dofs")
            object.__setattr__(self, "reference_dofs", tuple(dofs))

    @property
    def max_speed(self) -> bool:
        """True for the maximum-speed problem."""
        return self.speed_m_per_s is None

    def to_dict(self) -> dict:
        out = asdict(self)
        out["weights"] = self.weights.to_dict()
        if self.reference_dofs is not None:
            out["reference_dofs"] = list(self.reference_dofs)
        if self.pelvis_tilt_range_deg is not None:
            out["pelvis_tilt_range_deg"] = list(self.pelvis_tilt_range_deg)
        if self.stride_time_range_s is not None:
            out["stride_time_range_s"] = list(self.stride_time_range_s)
        return out

    @classmethod
    def from_dict(cls, data: dict) -> CollocationSettings:
        """Settings from :meth:`to_dict`'s mapping; an unknown key raises SpecError naming it
        (missing keys take their defaults)."""
        if not isinstance(data, dict):
            raise SpecError(f"expected a mapping of settings, got {type(data).__name__}",
                            where="settings")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise SpecError(f"unknown setting(s) {', '.join(unknown)}", where="settings",
                            hint=f"known: {', '.join(sorted(known))}")
        return cls(**data)

    def same_problem(self, other: CollocationSettings) -> bool:
        """True if ``other`` poses the same NLP (mesh, speed, weights, swing clearance, knee
        moment bound, loaded knee's flexion limit, prosthetic load limit, blade transcription,
        pelvis tilt range, alternating steps, stride time range, swing knee, symmetry);
        solver options
        (Hessian, tolerance, iterations) and the tracking stage may differ."""
        return self._problem() == other._problem()

    def _problem(self) -> tuple:
        return (self.mesh_intervals, self.speed_m_per_s, self.weights, self.swing_clearance_m,
                self.knee_moment_min_nm, self.knee_flexion_max_loaded_deg,
                self.prosthetic_load_max_bw, self.blade_backward_euler,
                self.pelvis_tilt_range_deg, self.step_phase_tolerance, self.symmetric,
                self.stride_time_range_s, self.stride_time_people,
                self.swing_knee_min_deg) + self.reference_key()

    def reference_key(self) -> tuple:
        """(reference file name, weight, coordinates), or () without a reference term."""
        if not self.reference_weight:
            return ()
        return (Path(self.reference).name, self.reference_weight, self.reference_dofs)


def people_term(weight: float) -> dict:
    """The :class:`CollocationSettings` fields of people's joint-angle term at ``weight``
    [1/rad²] (none at 0)."""
    return {"reference": PEOPLE_REFERENCE, "reference_weight": weight} if weight else {}


def people_settings(body: str, people_weight: float | None = None,
                    swing_knee_deg: float | None = None, kind: str = "able") -> dict:
    """The :class:`CollocationSettings` fields of what the predicted strides of a runner
    ``kind`` on ``body`` take from measured running: people's joint angles at
    ``people_weight`` [1/rad²] (:func:`bladelab.predict.defaults.people_weight_for`) and
    people's swing knee at ``swing_knee_deg`` [deg]
    (:func:`bladelab.predict.defaults.swing_knee_for`; 0: none); None: the defaults (both
    on the human body, but no swing knee for the transfemoral runner; neither on seed
    001's)."""
    return {**people_term(defaults.people_weight_for(body, people_weight)),
            "swing_knee_min_deg": defaults.swing_knee_for(body, swing_knee_deg, kind)}
