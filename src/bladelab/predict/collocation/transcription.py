"""Trapezoidal direct collocation of one periodic stride (the NLP, CasADi MX + IPOPT).

The stride (left touch-down to the next; both legs move, so an asymmetric amputee is
represented whole) is cut into ``n`` equal intervals of the free period ``T``. At every node
k = 0..n the NLP holds the states x = (q, q̇, a, F̃ₜ) — coordinates, speeds, muscle
activations, tendon forces normalised by F_max — and the controls u = (q̈, e, dF̃ₜ/dt) —
accelerations (implicit multibody dynamics), excitations, tendon-force rates (De Groote et al.
2016). Constraints:

- trapezoidal defects ``x_{k+1} − x_k − h/2·(ẋ_k + ẋ_{k+1})`` with ``h = T/n`` and
  ``ẋ = (q̇, q̈, ȧ(e, a), dF̃ₜ/dt)``;
- path residuals at k = 0..n−1 (node n repeats node 0): the multibody dynamics
  ``M(q)·q̈ + C(q, q̇) − τ(q, q̇, F̃ₜ) = 0`` for every dof (the pelvis's three unactuated) and
  the Hill equilibrium of every muscle, both from :class:`StrideDynamics`;
- periodicity: node n equals node 0 (states and controls) except pelvis_tx, advanced by the
  stride length ``d``; pelvis_tx = 0 at node 0;
- the speed: ``d = v·T`` (prescribed speed) or ``d`` free (maximum speed);
- optionally, alternating steps (``step_phase_tolerance``): the centre of each leg's vertical
  ground force over the stride (its circular mean, :func:`step_phase`) half a stride ± the
  tolerance after the other leg's, which rules out a gallop (both stances close together,
  then one long flight), and each leg carrying a stance (a one-legged hop ruled out);
- optionally, a minimum peak flexion of named knees (``knee_flexion_min``, people's swing
  knee: :mod:`~bladelab.predict.collocation.swing_knee`), a smooth maximum over the nodes.

Objective (a setting, :class:`StrideWeights`): prescribed speed — metabolic energy per
distance and body mass (cost of transport [J/(kg·m)]) plus time-averaged mean cubed activation
and mean squared acceleration [(rad/s²)²] terms with small weights; maximum speed — the negative
mean speed [m/s] plus the same effort terms. Every integral is the trapezoidal rule on the mesh.

Variables are scaled (:class:`VariableScales`) so that IPOPT sees numbers of order one.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import casadi as ca
import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.compiled import compiled_node, compiling_enabled
from bladelab.predict.collocation.progress import ProgressRelay
from bladelab.predict.collocation.stride_guess import (
    COLLOCATION_SOURCE,
    StrideGuess,
    periodic_derivative,
)
from bladelab.predict.collocation.stride_problem import (
    FORCE_RATE_SCALE,
    METABOLIC_SQUARED_SCALE,
    PASSIVE_TORQUE_SCALE,
    StrideDynamics,
    StrideWeights,
    VariableScales,
)
from bladelab.predict.collocation.swing_knee import peak_flexion_rows
from bladelab.predict.collocation.symmetry import stride_mirror, symmetrized, symmetry_rows

__all__ = [
    "NLPSolution",
    "StrideDynamics",
    "StrideNLP",
    "StrideWeights",
    "VariableScales",
    "alternation_rows",
    "step_phase",
]


@dataclass(frozen=True)
class NLPSolution:
    """The solution (or the last iterate) of a stride NLP.

    Arrays have n + 1 rows (nodes at ``time``); ``tendon_force`` is normalised by F_max.
    ``multipliers``: IPOPT's multipliers of the variable bounds and of the constraints of the
    scaled NLP at this point (None where unknown), the dual half of a warm start.
    ``timings`` [s unless named]: ``build_s`` (building the solver; 0 when reused), each NLP
    function's time (``nlp_f_s``, ``nlp_g_s``, ...) and calls (``calls_nlp_f``, ...), their
    sum ``functions_s``, ``ipopt_own_s`` (the rest of ``wall_s``: IPOPT's own linear algebra
    and line search) and ``peak_memory_MB`` (the process's peak resident memory after the
    solve [MB], where the platform tells).
    """

    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    activation: np.ndarray
    tendon_force: np.ndarray
    qdd: np.ndarray
    excitation: np.ndarray
    tendon_force_rate: np.ndarray
    period: float
    objective: float
    objective_terms: dict[str, float]
    success: bool
    status: str
    iterations: int
    wall_s: float
    timings: dict[str, float] = field(default_factory=dict)
    max_violation: float = math.nan
    worst_constraints: tuple[tuple[str, float], ...] = ()
    multipliers: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def speed(self) -> float:
        """Mean forward speed [m/s]."""
        return float((self.q[-1, 0] - self.q[0, 0]) / self.period)

    def to_guess(self, source: str = COLLOCATION_SOURCE) -> StrideGuess:
        """This solution as an initial guess (:class:`~bladelab.predict.collocation.stride_guess.
        StrideGuess`, muscle states included): a warm start for another problem or mesh."""
        return StrideGuess(source, self.period, self.q, self.qd, self.activation,
                           self.tendon_force, qdd=self.qdd, excitation=self.excitation,
                           tendon_force_rate=self.tendon_force_rate,
                           multipliers=self.multipliers)


#: Added to the squared force centroids [BW²] of :func:`alternation_rows` so that their norm stays
#: differentiable at 0 (a leg without stance).
_CENTROID_EPS = 1e-8
#: The least force centroid |C_j| [BW] of each leg under the alternating-steps constraint:
#: about a quarter of a leg's share in running (0.42–0.53 BW measured on the human body's
#: strides), so that a one-legged hop (|C| = 0 on one leg, where the phase constraint holds
#: up to ε) is ruled out with it.
MIN_CENTROID_BW = 0.1


def _peak_memory_mb() -> float | None:
    """The process's peak resident memory so far [MB] (``getrusage``), None where the
    platform does not tell; after a solve, an upper bound of that solve's peak."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    peak = float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10  # bytes / KiB


def step_phase(leg_forces: np.ndarray) -> float:
    """The right (prosthetic) leg's stance after the left (intact) leg's [fraction of the
    stride, 0–1]: the difference of the circular means of the legs' vertical ground forces
    ``leg_forces`` (n nodes of one period, without the repeated last node; columns left,
    right) [N]. 0.5 for alternating steps of equal time; near 0 or 1 for a gallop."""
    f = np.asarray(leg_forces, float)
    ph = np.exp(2j * np.pi * np.arange(f.shape[0]) / f.shape[0])
    c = ph @ f
    return float(np.angle(c[1] * np.conj(c[0])) / (2 * np.pi) % 1.0)


def alternation_rows(legs, body_weight: float, tolerance: float):
    """The alternating-steps constraint rows (each ≤ 0) of the legs' vertical forces ``legs``
    (2, n nodes of one period) [N] and the body weight [N]: with the legs' force centroids
    C_j = Σ_k F_j,k·e^{2πik/n} / (n·BW), Re(C₀·C̄₁) + cos(2π·tolerance)·|C₀|·|C₁| ≤ 0, i.e.
    the phase between them within π ± 2π·tolerance (:func:`step_phase` within 0.5 ±
    tolerance); and :data:`MIN_CENTROID_BW`² − |C_j|² ≤ 0 for each leg."""
    n = legs.shape[1]
    k = 2 * np.pi * np.arange(n) / n
    a = ca.mtimes(legs, ca.DM(np.cos(k))) / (n * body_weight)
    b = ca.mtimes(legs, ca.DM(np.sin(k))) / (n * body_weight)
    sq = [a[j] ** 2 + b[j] ** 2 for j in (0, 1)]
    norm = [ca.sqrt(v + _CENTROID_EPS) for v in sq]
    phase = a[0] * a[1] + b[0] * b[1] + math.cos(2 * math.pi * tolerance) * norm[0] * norm[1]
    return ca.vertcat(phase, MIN_CENTROID_BW**2 - sq[0], MIN_CENTROID_BW**2 - sq[1])


def _node_pairs(values):
    """Σ over the mesh intervals of (value at the start + value at the end) of a (1, n + 1)
    row of node values: the trapezoidal rule's sum, times h/2 for an integral."""
    return ca.sum2(values[:, :-1]) + ca.sum2(values[:, 1:])


#: IPOPT's stop at an acceptable level, on every L-BFGS solve: five iterations in a row
#: feasible to 1e-5 (scaled constraints), complementarity below 1e-3 and the objective
#: changing by less than 1e-5 of itself per iteration. Near a solution L-BFGS's dual
#: infeasibility wanders between 1e-2 and 1 and dips below ``tol`` only now and then, so about
#: half of a solve's iterations went on the last 0.01 % of its objective (measured on warm and
#: cold starts: 15–55 % fewer iterations, objectives within 0.033 %;
#: benchmarks/collocation_speed/README.md "Stopping a solve when the objective stalls").
STALL_STOP_OPTIONS = {
    "ipopt.acceptable_tol": 1.0,
    "ipopt.acceptable_iter": 5,
    "ipopt.acceptable_obj_change_tol": 1e-5,
    "ipopt.acceptable_constr_viol_tol": 1e-5,
    "ipopt.acceptable_compl_inf_tol": 1e-3,
}

#: IPOPT's L-BFGS Hessian of a predictive stage (:func:`~bladelab.predict.collocation.solve.
#: predict_stride` adds these options to every L-BFGS stage but the tracking stage): the
#: low-rank update held in the augmented system itself (``extended``: 2m more rows, one
#: factorisation and one back solve per step) instead of IPOPT's default Sherman-Morrison
#: route, whose 2m extra back solves per iteration were most of a solve's time; history m = 4.
#: Measured (benchmarks/collocation_speed/README.md, "The low-rank update inside the augmented
#: system"): three warm starts of the amputee Cat6 stride 58-61 against 88 ms per iteration,
#: 33 s against 57 s in all, objectives within 0.1 %; the category study with three starts
#: 932 against 1,505 s of solver time. The tracking stage keeps IPOPT's default: with these
#: options the template's tracking stage did not converge in 3,000 iterations.
PREDICTIVE_LBFGS_OPTIONS = {
    "ipopt.limited_memory_aug_solver": "extended",
    "ipopt.limited_memory_max_history": 4,
}

#: IPOPT options of a solve started from a solution's primal and dual values (its
#: multipliers): the barrier starts small and the point stays where it is, so that a solve
#: at the start's own speed ends at once and a continuation step stays on the start's branch
#: (measured, benchmarks/collocation_speed/README.md: the amputee Cat6 stride at 4 m/s again in
#: 0 iterations instead of 613; 4 -> 4.2 m/s in 197 instead of 574). mu_init 1e-3, 1e-4 and
#: 1e-5 gave the same iterates.
DUAL_WARM_START_OPTIONS = {
    "ipopt.warm_start_init_point": "yes",
    "ipopt.mu_init": 1e-4,
    "ipopt.warm_start_bound_push": 1e-9,
    "ipopt.warm_start_bound_frac": 1e-9,
    "ipopt.warm_start_slack_bound_push": 1e-9,
    "ipopt.warm_start_slack_bound_frac": 1e-9,
    "ipopt.warm_start_mult_bound_push": 1e-9,
}

#: Bounds of the free stride time [s] (a running stride at 3–10 m/s lies well inside).
PERIOD_BOUNDS_S = (0.4, 1.2)


class StrideNLP:
    """The collocation NLP of one periodic stride.

    Parameters
    ----------
    dynamics
        The model's node functions (:class:`StrideDynamics`).
    n
        Mesh intervals.
    speed
        Prescribed mean speed [m/s], or None for the maximum-speed problem.
    weights
        Objective weights.
    period_bounds
        Bounds of the stride time [s].
    period_band
        The maximum-speed problem only: ``(v0, lo0, hi0, v1, lo1, hi1)``, a band of the stride
        time [s] that moves with the stride's speed [m/s]: (lo0, hi0) at v0, (lo1, hi1) at v1,
        linear between and constant outside; two constraint rows ``lo(v) <= T <= hi(v)`` with
        ``v = d/T`` (people's stride time, whose speed this problem predicts). None: none.
    scales
        Variable scaling.
    min_activation
        Lower bound of activations and excitations [-] (the forward model's 0.01).
    min_tendon_force, max_tendon_force
        Bounds of the normalised tendon forces [-] (> 0: the inverse tendon curve of the
        De Groote formulation diverges at 0).
    tracking
        ``(q_ref, weight)`` or ``(q_ref, weight, dofs)``: add ``weight`` × the time-averaged
        mean squared deviation [rad²] of the joint angles from ``q_ref`` ((n + 1, n_dof),
        nodes of the mesh) — those named in ``dofs``, by default pelvis tilt and every joint
        (not the pelvis translations): a tracking problem that makes a guess dynamically
        consistent before the predictive solve, or a reference the predicted gait stays near.
    period_tracking
        ``(T_ref, weight)``: add ``weight`` × ln(T/T_ref)², the squared relative deviation of
        the stride time T from ``T_ref`` [s] (the reference's cadence).
    step_phase_tolerance
        Keep the legs' stances alternating: the right leg's :func:`step_phase` within
        0.5 ± this [fraction of the stride] (needs ``StrideDynamics.leg_vertical_grf``);
        None: free.
    symmetric
        Each leg does what the other did half a stride earlier
        (:mod:`~bladelab.predict.collocation.symmetry`; an even ``n``, legs that are mirror
        images).
    knee_flexion_min
        {knee coordinate: minimum [rad]}: keep each knee's smooth peak flexion over the stride
        at or above its minimum (:mod:`~bladelab.predict.collocation.swing_knee`); None: free.
    compiled
        Map the node function compiled to C (:mod:`~bladelab.predict.collocation.compiled`:
        cached on disk, the solver built without expanding the graph) instead of the
        interpreted SX function; None (default): compiled unless ``BLADELAB_COMPILE=0``. Falls
        back to the interpreted function, with a warning, when no compiler works. The exact
        Hessian needs the interpreted function (``compiled=False``).

    Attributes
    ----------
    compiled
        True when the NLP maps the compiled node function.
    compile_s
        Wall time [s] of compiling the node function, or of loading it from the cache.
    node
        The SX function of one mesh node, ``(x, u) -> (ẋ scaled, path residuals, effort,
        metabolic rate, inequalities, vertical force, squared metabolic rate, force rate)``,
        mapped over the ``n + 1`` nodes to build the NLP.
    """

    def __init__(
        self,
        dynamics: StrideDynamics,
        *,
        n: int = 50,
        speed: float | None = 3.5,
        weights: StrideWeights | None = None,
        period_bounds: tuple[float, float] = PERIOD_BOUNDS_S,
        period_band: tuple[float, ...] | None = None,
        scales: VariableScales | None = None,
        min_activation: float = 0.01,
        min_tendon_force: float = 1e-3,
        max_tendon_force: float = 3.0,
        tracking: tuple | None = None,
        grf_tracking: tuple[np.ndarray, float] | None = None,
        period_tracking: tuple[float, float] | None = None,
        step_phase_tolerance: float | None = None,
        symmetric: bool = False,
        knee_flexion_min: dict[str, float] | None = None,
        compiled: bool | None = None,
    ) -> None:
        if n < 4:
            raise SpecError(f"need at least 4 mesh intervals, got {n}", where="mesh intervals")
        if speed is not None and not (speed > 0 and math.isfinite(speed)):
            raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
        self._compile = compiling_enabled() if compiled is None else bool(compiled)
        self.dyn = dynamics
        self.n = int(n)
        self.speed = None if speed is None else float(speed)
        self.weights = weights or StrideWeights(metabolic=0.0 if speed is None else 1.0)
        self.scales = scales or VariableScales()
        self.period_bounds = tuple(float(b) for b in period_bounds)
        if period_band is not None:
            band = tuple(float(b) for b in period_band)
            if speed is not None:
                raise SpecError("a stride time band that moves with the speed is for the "
                                "maximum-speed problem", where="period band",
                                hint="a prescribed speed's band is its period bounds")
            if len(band) != 6 or not (0 < band[0] < band[3] and band[1] <= band[2]
                                      and band[4] <= band[5]):
                raise SpecError(f"expected (v0, lo0, hi0, v1, lo1, hi1) with v0 < v1 and "
                                f"lo <= hi, got {period_band!r}", where="period band")
            period_band = band
        self.period_band = period_band
        self.min_activation = float(min_activation)
        self.min_tendon_force = float(min_tendon_force)
        self.max_tendon_force = float(max_tendon_force)
        self.tracking = tracking
        self.grf_tracking = grf_tracking
        self.period_tracking = period_tracking
        if step_phase_tolerance is not None and not 0.0 < step_phase_tolerance < 0.5:
            raise SpecError(f"the step phase tolerance must be within (0, 0.5), got "
                            f"{step_phase_tolerance!r}", where="step phase tolerance")
        if step_phase_tolerance is not None and dynamics.leg_vertical_grf is None:
            raise SpecError("alternating steps need each leg's vertical ground force",
                            where="step phase tolerance",
                            hint="build the dynamics with stride_dynamics")
        self.step_phase_tolerance = step_phase_tolerance
        if symmetric and n % 2:
            raise SpecError(f"a symmetric stride needs an even number of mesh intervals, got "
                            f"{n}", where="mesh intervals")
        self.symmetric = bool(symmetric)
        unknown = sorted(set(knee_flexion_min or ()) - set(dynamics.dof_names))
        if unknown:
            raise SpecError(f"no coordinate {', '.join(unknown)} on this model",
                            where="knee flexion minimum")
        self.knee_flexion_min = dict(knee_flexion_min) if knee_flexion_min else None
        self._build()

    # -- layout -------------------------------------------------------------------------
    def _build(self) -> None:
        d, n, s = self.dyn, self.n, self.scales
        nq, nm = d.nq, d.nm
        self.nx = 2 * nq + 2 * nm
        self.nu = nq + 2 * nm
        sx = np.concatenate([np.full(nq, s.q), np.full(nq, s.qd), np.ones(nm), np.ones(nm)])
        su = np.concatenate([np.full(nq, s.qdd), np.ones(nm), np.full(nm, s.tendon_force_rate)])
        self.sx, self.su = sx, su

        xs = ca.SX.sym("x", self.nx)
        us = ca.SX.sym("u", self.nu)
        x, u = xs * sx, us * su
        q, qd = x[:nq], x[nq:2 * nq]
        a, fnt = x[2 * nq:2 * nq + nm], x[2 * nq + nm:]
        qdd, e, dfnt = u[:nq], u[nq:nq + nm], u[nq + nm:]
        r_mb, r_hill = d.residuals(q, qd, qdd, a, fnt, dfnt)
        adot = d.activation_rate(e, a)
        xdot_scaled = ca.vertcat(qd, qdd, adot, dfnt) / sx
        path = ca.vertcat(r_mb / d.residual_scale, r_hill)
        w = self.weights
        pelvis_scale = np.array([10.0 if n_ in ("pelvis_tx", "pelvis_tz") else 100.0
                                 for n_ in d.dof_names[:3]])
        effort = (w.activation * ca.sum1(a**3) / max(nm, 1)
                  + w.acceleration * ca.sumsqr(qdd[3:]) / max(nq - 3, 1) / 1e4
                  + w.pelvis_acceleration * ca.sumsqr(qdd[:3] / pelvis_scale) / 3)
        met = d.metabolic_rate(q, qd, a, fnt, dfnt, e)
        ineq = (d.inequalities(q, qd, a, fnt, dfnt) if d.inequalities is not None
                else ca.SX.zeros(0, 1))
        self.n_ineq = int(ineq.numel())
        fz = d.vertical_grf(q, qd) if d.vertical_grf is not None else ca.SX(0.0)
        if w.metabolic_squared:
            if d.muscle_metabolic_rates is None:
                raise SpecError("metabolic_squared needs the muscles' metabolic rates",
                                where="weights", hint="build the dynamics with stride_dynamics")
            per_kg = d.muscle_metabolic_rates(q, qd, a, fnt, dfnt, e) / d.mass
            met_sq = ca.sumsqr(per_kg) / METABOLIC_SQUARED_SCALE
        else:
            met_sq = ca.SX(0.0)
        frate = ca.sumsqr(dfnt) / max(nm, 1) / FORCE_RATE_SCALE
        if w.passive:
            if d.passive_joint_torques is None:
                raise SpecError("the passive-torque term needs the joints' passive torques",
                                where="weights", hint="build the dynamics with stride_dynamics")
            tau_p = d.passive_joint_torques(q, qd)
            passive = ca.sumsqr(tau_p) / max(int(tau_p.numel()), 1) / PASSIVE_TORQUE_SCALE
        else:
            passive = ca.SX(0.0)
        node = ca.Function("node", [xs, us],
                           [xdot_scaled, path, effort, met, ineq, fz, met_sq, frate, passive])
        self.node = node  # one node's functions (SX), mapped over the mesh below
        t0 = time.perf_counter()
        external = compiled_node(node) if self._compile else None
        self.compile_s = time.perf_counter() - t0  # compiling, or loading from the cache
        self.compiled = external is not None
        self._interpreted: StrideNLP | None = None
        fmap = (node if external is None else external).map(n + 1)

        X = ca.MX.sym("X", self.nx, n + 1)
        U = ca.MX.sym("U", self.nu, n + 1)
        T = ca.MX.sym("T")
        # the prescribed speed is a parameter of the NLP, so that one built (and expanded)
        # solver serves every speed of a continuation (building it takes 14-20 s at mesh 50)
        P = ca.MX.sym("speed")
        period = T * s.period
        h = period / n
        xdot, pth, eff, mets, ineqs, fzs, met_sqs, frates, passives = fmap(X, U)
        # θ-rule per state: ½ trapezoidal, 1 backward Euler (StrideDynamics.backward_euler_dofs)
        theta = np.full(self.nx, 0.5)
        for name in d.backward_euler_dofs:
            j = d.dof_names.index(name)
            theta[[j, nq + j]] = 1.0
        if np.all(theta == 0.5):
            defects = X[:, 1:] - X[:, :-1] - h / 2 * (xdot[:, 1:] + xdot[:, :-1])
        else:
            th = ca.repmat(ca.DM(theta), 1, n)
            defects = X[:, 1:] - X[:, :-1] - h * (th * xdot[:, 1:] + (1 - th) * xdot[:, :-1])
        itx = d.dof_names.index("pelvis_tx")
        distance = (X[itx, n] - X[itx, 0]) * sx[itx]
        # periodic: every state but pelvis_tx, which advances by the stride length `distance`
        keep = [i for i in range(self.nx) if i != itx]
        # the controls too: node n is node 0 one period later, and its controls enter the last
        # interval's defect, so free controls there would act as an impulse (measured: a
        # torque-driven 'gait' that never touched the ground, one flight phase closed by an
        # acceleration spike at the last node)
        periodic = ca.vertcat(X[keep, n] - X[keep, 0], U[:, n] - U[:, 0])
        # a symmetric stride: the second half's rows follow from the first half's (symmetry)
        self._imposed_nodes = m = n // 2 if self.symmetric else n
        g = [ca.vec(defects[:, :m]), ca.vec(pth[:, :m]), periodic]
        state_names = self._state_names()
        self._g_names = (
            [f"defect {nm_}@{k}" for k in range(m) for nm_ in state_names]
            + [f"path {nm_}@{k}" for k in range(m) for nm_ in self._path_names()]
            + [f"periodicity {state_names[i]}" for i in keep]
            + [f"periodicity {nm_}" for nm_ in self._control_names()]
        )
        if self.symmetric:
            self._mirror = stride_mirror(d, node, self.sx)
            g.append(symmetry_rows(X, U, *self._mirror, itx))
            self._g_names += (
                [f"symmetry {nm_}@{k}" for k in range(m, n) for nm_ in state_names]
                + [f"symmetry {nm_}@{k}" for k in range(m, n) for nm_ in self._control_names()])
        trap = _node_pairs(eff) / 2 * h  # ∫ effort dt
        energy = _node_pairs(mets) / 2 * h  # ∫ Ė dt [J]
        terms = {"effort": trap / period}
        if w.metabolic_squared:
            sq = _node_pairs(met_sqs) / 2 * h
            terms["metabolic_squared"] = w.metabolic_squared * sq / ca.fmax(distance, 1e-3)
        if w.force_rate:
            terms["force_rate"] = w.force_rate * _node_pairs(frates) / 2 * h / period
        if w.passive:
            terms["passive"] = w.passive * _node_pairs(passives) / 2 * h / period
        if self.speed is not None:
            g.append(distance - P * period)
            self._g_names.append("speed")
            if w.metabolic:  # a zero weight drops the term (0·H would spread any inf/NaN)
                terms["metabolic"] = w.metabolic * energy / (d.mass * P * period)
        else:
            terms["speed"] = -w.speed * distance / period
            # the stride is at least as fast as the parameter (a solve passes the speed of its
            # start, a stride that exists): the speed term is traded against effort, and from
            # a primal start IPOPT otherwise ended below strides it had been given (measured:
            # 3.2-4.3 m/s from a converged 5 m/s stride)
            g.append(distance - P * period)
            self._g_names.append("minimum speed")
            if w.metabolic:
                terms["metabolic"] = w.metabolic * energy / (d.mass * ca.fmax(distance, 1e-3))
            if self.period_band is not None:
                v0, lo0, hi0, v1, lo1, hi1 = self.period_band
                f = ca.fmin(ca.fmax((distance / period - v0) / (v1 - v0), 0.0), 1.0)
                g.append(period - (lo0 + f * (lo1 - lo0)))
                g.append(period - (hi0 + f * (hi1 - hi0)))
                self._g_names += ["stride time band (low)", "stride time band (high)"]
        if self.step_phase_tolerance is not None:
            legs = ca.Function("legs", [xs], [d.leg_vertical_grf(q, qd)]).map(n)(X[:, :n])
            g.append(alternation_rows(legs, d.mass * d.gravity, self.step_phase_tolerance))
            self._g_names += ["alternating steps"] + [f"stance of leg {j}" for j in (0, 1)]
        if self.knee_flexion_min:
            g.append(peak_flexion_rows(X[:, :n], sx, d.dof_names, self.knee_flexion_min))
            self._g_names += [f"peak flexion {k}" for k in self.knee_flexion_min]
        if self.tracking is not None:
            q_ref, weight, *dofs = self.tracking
            q_ref = np.asarray(q_ref, float)
            if q_ref.shape != (n + 1, nq):
                raise SpecError(f"tracking reference has shape {q_ref.shape}, the mesh needs "
                                f"{(n + 1, nq)}", where="tracking")
            rows = self._tracked_rows(dofs[0] if dofs else None)
            dev = ca.vertcat(*[(X[i, :] * sx[i] - q_ref[:, i].reshape(1, -1)) ** 2
                               for i in rows])
            per_node = ca.sum1(dev) / len(rows)
            terms["tracking"] = float(weight) * _node_pairs(per_node) / (2 * n)
        if self.period_tracking is not None:
            t_ref, weight = (float(v) for v in self.period_tracking)
            if not (t_ref > 0 and math.isfinite(t_ref)):
                raise SpecError(f"reference stride time must be > 0 s, got {t_ref}",
                                where="period tracking")
            terms["period_tracking"] = weight * ca.log(period / t_ref) ** 2
        if self.grf_tracking is not None:
            f_ref, weight = self.grf_tracking
            f_ref = np.asarray(f_ref, float).reshape(1, -1)
            if f_ref.shape != (1, n + 1):
                raise SpecError(f"force reference has {f_ref.size} values, the mesh needs "
                                f"{n + 1}", where="force tracking")
            bw = d.mass * d.gravity
            dev = ((fzs - f_ref) / bw) ** 2
            terms["grf_tracking"] = float(weight) * _node_pairs(dev) / (2 * n)
        if self.n_ineq:
            imposed = ineqs[:, :m]
            if d.interval_mean_inequalities:
                means = 0.5 * (ineqs[:, :m] + ineqs[:, 1:m + 1])
                imposed = ca.vertcat(*[means[i, :] if i in d.interval_mean_inequalities
                                       else imposed[i, :] for i in range(self.n_ineq)])
            g.append(ca.vec(imposed))
            self._g_names += [f"inequality {i}@{k}" for k in range(m) for i in range(self.n_ineq)]
        J = sum(terms.values())
        self._terms = ca.Function("terms", [X, U, T, P], list(terms.values()))
        self._term_names = tuple(terms)
        self._energy = ca.Function("energy", [X, U, T], [energy, distance])
        w_all = ca.veccat(X, U, T)
        self.nlp = {"x": w_all, "f": J, "g": ca.vertcat(*g), "p": P}
        self._solvers: dict[tuple, tuple[ca.Function, ProgressRelay]] = {}
        self.n_vars = int(w_all.numel())
        self.n_cons = int(self.nlp["g"].numel())

    def _tracked_rows(self, dofs) -> list[int]:
        """Rows of q that a tracking term follows: ``dofs`` by name (None: all but the
        pelvis translations)."""
        names = list(self.dyn.dof_names)
        if dofs is None:
            return list(range(2, len(names)))
        unknown = [d for d in dofs if d not in names]
        if unknown or not dofs:
            raise SpecError(f"cannot track {', '.join(unknown) or 'no coordinate'}",
                            where="tracking", hint=f"coordinates: {', '.join(names)}")
        return [names.index(d) for d in dofs]

    def _state_names(self) -> list[str]:
        d = self.dyn
        return ([f"q {n}" for n in d.dof_names] + [f"qd {n}" for n in d.dof_names]
                + [f"a {n}" for n in d.muscle_names] + [f"Ft {n}" for n in d.muscle_names])

    def _control_names(self) -> list[str]:
        d = self.dyn
        return ([f"qdd {n}" for n in d.dof_names] + [f"e {n}" for n in d.muscle_names]
                + [f"dFt {n}" for n in d.muscle_names])

    def _path_names(self) -> list[str]:
        d = self.dyn
        return [f"dynamics {n}" for n in d.dof_names] + [f"hill {n}" for n in d.muscle_names]

    # -- bounds and guess ---------------------------------------------------------------
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(lbx, ubx, lbg, ubg) of the scaled NLP."""
        d, n = self.dyn, self.n
        nq, nm = d.nq, d.nm
        itx = d.dof_names.index("pelvis_tx")
        lx = np.concatenate([d.q_bounds[:, 0], d.qd_bounds[:, 0], np.full(nm, self.min_activation),
                             np.full(nm, self.min_tendon_force)])
        strength = np.ones(nm) if d.active_strength is None else d.active_strength
        ux = np.concatenate([d.q_bounds[:, 1], d.qd_bounds[:, 1], np.ones(nm),
                             self.max_tendon_force * strength])
        lX = np.tile((lx / self.sx)[:, None], (1, n + 1))
        uX = np.tile((ux / self.sx)[:, None], (1, n + 1))
        lX[itx, :], uX[itx, :] = -np.inf, np.inf
        lX[itx, 0] = uX[itx, 0] = 0.0
        qdd_max = 1e4
        lu = np.concatenate([np.full(nq, -qdd_max), np.full(nm, self.min_activation),
                             np.full(nm, -1e3)]) / self.su
        uu = np.concatenate([np.full(nq, qdd_max), np.ones(nm), np.full(nm, 1e3)]) / self.su
        lU = np.tile(lu[:, None], (1, n + 1))
        uU = np.tile(uu[:, None], (1, n + 1))
        lT = self.period_bounds[0] / self.scales.period
        uT = self.period_bounds[1] / self.scales.period
        lbx = np.concatenate([lX.ravel(order="F"), lU.ravel(order="F"), [lT]])
        ubx = np.concatenate([uX.ravel(order="F"), uU.ravel(order="F"), [uT]])
        lbg, ubg = np.zeros(self.n_cons), np.zeros(self.n_cons)
        if self.speed is None:
            ubg[self._g_names.index("minimum speed")] = np.inf
        if self.period_band is not None:
            ubg[self._g_names.index("stride time band (low)")] = np.inf
            lbg[self._g_names.index("stride time band (high)")] = -np.inf
        if self.step_phase_tolerance is not None:
            i = self._g_names.index("alternating steps")
            lbg[i:i + 3] = -np.inf
        if self.knee_flexion_min:
            i = self._g_names.index(f"peak flexion {next(iter(self.knee_flexion_min))}")
            ubg[i:i + len(self.knee_flexion_min)] = np.inf
        if self.n_ineq:
            b = np.asarray(d.inequality_bounds, float)
            m = self._imposed_nodes
            lbg[-self.n_ineq * m:] = np.tile(b[:, 0], m)
            ubg[-self.n_ineq * m:] = np.tile(b[:, 1], m)
        return lbx, ubx, lbg, ubg

    def initial_vector(self, guess) -> np.ndarray:
        """The scaled NLP vector of a :class:`~bladelab.predict.collocation.stride_guess.
        StrideGuess` (resampled to the mesh; where the guess has no muscle states, activations
        0.05 and the tendon forces of static equilibrium, else 0.05; where it has no
        controls, accelerations and tendon-force rates by differentiating the speeds and
        forces, excitations equal to the activations)."""
        d, n = self.dyn, self.n
        g = guess.resample(n)
        act = g.activation if g.activation is not None else np.full((n + 1, d.nm), 0.05)
        if g.tendon_force is not None:
            ften = g.tendon_force
        elif d.static_tendon_force is not None:
            ften = d.static_tendon_force(g.q, act)
        else:
            ften = np.full((n + 1, d.nm), 0.05)
        act = np.clip(act, self.min_activation, 1.0)
        ften = np.clip(ften, self.min_tendon_force, self.max_tendon_force)
        qdd = (g.qdd if g.qdd is not None
               else periodic_derivative(np.vstack([g.qd[:-1], g.qd[:1]]), g.period))
        exc = act if g.excitation is None else g.excitation
        dft = (g.tendon_force_rate if g.tendon_force_rate is not None
               else periodic_derivative(np.vstack([ften[:-1], ften[:1]]), g.period))
        X = np.hstack([g.q, g.qd, act, ften]).T / self.sx[:, None]
        U = np.hstack([qdd, exc, dft]).T / self.su[:, None]
        if self.symmetric:
            X, U = symmetrized(X, U, *self._mirror, d.dof_names.index("pelvis_tx"))
        return np.concatenate([X.ravel(order="F"), U.ravel(order="F"),
                               [g.period / self.scales.period]])

    def initial_multipliers(self, guess) -> tuple[np.ndarray, np.ndarray] | None:
        """The multipliers a guess carries (:attr:`~bladelab.predict.collocation.stride_guess.
        StrideGuess.multipliers`) if they fit this NLP's variables and constraints, else
        None."""
        lam = guess.multipliers
        if lam is None:
            return None
        lam_x, lam_g = (np.asarray(v, float).ravel() for v in lam)
        if lam_x.size != self.n_vars or lam_g.size != self.n_cons:
            return None
        if not (np.isfinite(lam_x).all() and np.isfinite(lam_g).all()):
            return None
        return lam_x, lam_g

    # -- solve --------------------------------------------------------------------------
    def solve(self, x0: np.ndarray, *, max_iter: int = 3000, tol: float = 1e-4,
              hessian: str = "limited-memory", print_level: int = 0,
              options: dict | None = None, speed: float | None = None,
              progress: Callable[[int, float, float], None] | None = None,
              multipliers: tuple[np.ndarray, np.ndarray] | None = None) -> NLPSolution:
        """Solve with IPOPT: MUMPS with METIS ordering; ``hessian`` ``"limited-memory"``
        (L-BFGS with the adaptive barrier, as PredSim solves muscle-driven gaits; measured:
        the muscle-driven tracking stride converged in 671 iterations, while the exact Hessian
        stalled under inertia regularisation 1e7–1e10) or ``"exact"`` (monotone barrier;
        converges on problems without muscles, e.g. the toy and torque-driven strides).

        ``speed`` [m/s] is this solve's prescribed mean speed (default: the NLP's
        :attr:`speed`); in the maximum-speed problem, the speed the stride must at least
        reach (default 0: none). ``progress(iteration,
        objective, violation)`` is called after every IPOPT iteration. The IPOPT solver is
        built (expanded to SX, 14–20 s at mesh 50; 0.3 s with the compiled node) on the first
        solve with these options and
        reused by every later one, at any speed (``NLPSolution.timings["build_s"]`` is 0 then).

        ``multipliers`` (bounds, constraints; :meth:`initial_multipliers`): start from ``x0``
        and these duals with :data:`DUAL_WARM_START_OPTIONS` (under ``options``). With
        L-BFGS the solve ends at :data:`STALL_STOP_OPTIONS`' acceptable level where it comes
        before ``tol`` (status ``Solved_To_Acceptable_Level``, a success).
        """
        if hessian not in ("limited-memory", "exact"):
            raise SpecError(f"unknown Hessian option {hessian!r}", where="hessian",
                            hint="limited-memory or exact")
        if hessian == "exact" and self.compiled:
            raise SpecError("the exact Hessian needs the interpreted node function",
                            where="hessian", hint="build the StrideNLP with compiled=False")
        if speed is not None and not (speed > 0 and math.isfinite(speed)):
            raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
        opts = {
            "ipopt.max_iter": int(max_iter),
            "ipopt.tol": float(tol),
            "ipopt.constr_viol_tol": 1e-6,
            "ipopt.print_level": int(print_level),
            "ipopt.hessian_approximation": hessian,
            "ipopt.mu_strategy": "adaptive" if hessian == "limited-memory" else "monotone",
            "ipopt.linear_solver": "mumps",
            "ipopt.mumps_pivot_order": 5,  # METIS
            "ipopt.nlp_scaling_method": "gradient-based",
            "ipopt.sb": "yes",  # no banner
            # SX graph: about 10x faster iterations than MX (measured); a compiled node is an
            # external, which no SX graph holds
            "expand": not self.compiled,
            "print_time": False,
        }
        if hessian == "limited-memory":
            opts.update(STALL_STOP_OPTIONS)
        if multipliers is not None:
            opts.update(DUAL_WARM_START_OPTIONS)
        opts.update(options or {})
        t0 = time.perf_counter()
        solver, relay = self._solver(opts)
        t_build = time.perf_counter() - t0
        lbx, ubx, lbg, ubg = self.bounds()
        p = float(speed if speed is not None else (self.speed or 0.0))
        relay.calls, relay.target = 0, progress
        try:
            duals = {} if multipliers is None else {"lam_x0": multipliers[0],
                                                    "lam_g0": multipliers[1]}
            res = solver(x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, **duals)
        finally:
            relay.target = None
        wall = time.perf_counter() - t0
        stats = solver.stats()
        sol = self.unpack(np.asarray(res["x"]).ravel(), stats, wall, t_build, lbg, ubg,
                          np.asarray(res["g"]).ravel(), speed=p)
        return replace(sol, multipliers=(np.asarray(res["lam_x"], float).ravel(),
                                         np.asarray(res["lam_g"], float).ravel()))

    #: Solvers kept per NLP (each holds the expanded graph: about 0.3 GB at mesh 50).
    MAX_SOLVERS = 2

    def _solver(self, opts: dict) -> tuple[ca.Function, ProgressRelay]:
        """The IPOPT solver of these options, built once (the oldest is dropped beyond
        :attr:`MAX_SOLVERS`)."""
        key = tuple(sorted((k, repr(v)) for k, v in opts.items()))
        if key not in self._solvers:
            while len(self._solvers) >= self.MAX_SOLVERS:
                self._solvers.pop(next(iter(self._solvers)))
            relay = ProgressRelay(self)
            solver = ca.nlpsol("stride", "ipopt", self.nlp, {**opts, "iteration_callback": relay})
            self._solvers[key] = (solver, relay)
        return self._solvers[key]

    def interpreted(self) -> StrideNLP:
        """This NLP with the interpreted node function (itself if it has it): the same
        variables and constraints, for the exact Hessian."""
        if not self.compiled:
            return self
        if self._interpreted is None:
            self._interpreted = StrideNLP(
                self.dyn, n=self.n, speed=self.speed, weights=self.weights,
                period_bounds=self.period_bounds, period_band=self.period_band,
                scales=self.scales, min_activation=self.min_activation, min_tendon_force=self.min_tendon_force,
                max_tendon_force=self.max_tendon_force, tracking=self.tracking,
                grf_tracking=self.grf_tracking, period_tracking=self.period_tracking,
                step_phase_tolerance=self.step_phase_tolerance, symmetric=self.symmetric,
                knee_flexion_min=self.knee_flexion_min, compiled=False)
        return self._interpreted

    def unpack(self, w: np.ndarray, stats: dict, wall: float, t_build: float,
               lbg: np.ndarray, ubg: np.ndarray, gval: np.ndarray, *,
               speed: float | None = None) -> NLPSolution:
        """An :class:`NLPSolution` from the scaled vector and IPOPT's statistics (``speed``:
        the prescribed speed of the solve [m/s], default :attr:`speed`)."""
        d, n = self.dyn, self.n
        nq, nm = d.nq, d.nm
        nX, nU = self.nx * (n + 1), self.nu * (n + 1)
        X = w[:nX].reshape((self.nx, n + 1), order="F") * self.sx[:, None]
        U = w[nX:nX + nU].reshape((self.nu, n + 1), order="F") * self.su[:, None]
        T = float(w[-1]) * self.scales.period
        Xs = w[:nX].reshape((self.nx, n + 1), order="F")
        Us = w[nX:nX + nU].reshape((self.nu, n + 1), order="F")
        values = self._terms(Xs, Us, w[-1], speed if speed is not None else (self.speed or 0.0))
        if not isinstance(values, (list, tuple)):  # a Function of one output returns it bare
            values = [values]
        terms = [float(v) for v in values]
        viol = np.maximum(lbg - gval, gval - ubg)
        order = np.argsort(viol)[::-1][:5]
        timings = {"build_s": t_build, "compile_s": self.compile_s}
        for key in ("t_wall_nlp_f", "t_wall_nlp_g", "t_wall_nlp_grad_f", "t_wall_nlp_jac_g",
                    "t_wall_nlp_hess_l"):
            if key in stats:
                timings[key.replace("t_wall_", "") + "_s"] = float(stats[key])
        for key in ("n_call_nlp_f", "n_call_nlp_g", "n_call_nlp_grad_f", "n_call_nlp_jac_g",
                    "n_call_nlp_hess_l"):
            if key in stats:
                timings[key.replace("n_call_", "calls_")] = float(stats[key])
        functions = sum(v for k, v in timings.items() if k.startswith("nlp_"))
        timings["functions_s"] = functions
        timings["ipopt_own_s"] = max(0.0, float(wall) - t_build - functions)
        memory = _peak_memory_mb()
        if memory is not None:
            timings["peak_memory_MB"] = memory
        return NLPSolution(
            time=np.linspace(0.0, T, n + 1),
            q=X[:nq].T, qd=X[nq:2 * nq].T,
            activation=X[2 * nq:2 * nq + nm].T, tendon_force=X[2 * nq + nm:].T,
            qdd=U[:nq].T, excitation=U[nq:nq + nm].T, tendon_force_rate=U[nq + nm:].T,
            period=T, objective=float(sum(terms)),
            objective_terms=dict(zip(self._term_names, terms, strict=True)),
            success=bool(stats.get("success", False)),
            status=str(stats.get("return_status", "unknown")),
            iterations=int(stats.get("iter_count", -1)),
            wall_s=float(wall), timings=timings,
            max_violation=float(viol.max()) if viol.size else 0.0,
            worst_constraints=tuple((self._g_names[i], float(viol[i])) for i in order
                                    if viol[i] > 0),
        )

    def energy_and_distance(self, sol: NLPSolution) -> tuple[float, float]:
        """Metabolic energy [J] over the stride and the stride length [m]."""
        Xs = np.hstack([sol.q, sol.qd, sol.activation, sol.tendon_force]).T / self.sx[:, None]
        Us = np.hstack([sol.qdd, sol.excitation, sol.tendon_force_rate]).T / self.su[:, None]
        e, dist = self._energy(Xs, Us, sol.period / self.scales.period)
        return float(e), float(dist)

