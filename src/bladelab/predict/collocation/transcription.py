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
  ground force over the stride (its circular mean,
  :func:`~bladelab.predict.collocation.alternating_steps.step_phase`) half a stride ± the
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
import time
from collections.abc import Callable
from dataclasses import replace

import casadi as ca
import numpy as np

from bladelab.errors import SpecError
from bladelab.predict.collocation.alternating_steps import alternation_rows
from bladelab.predict.collocation.compiled import compiled_node, compiling_enabled
from bladelab.predict.collocation.ipopt_options import solver_options
from bladelab.predict.collocation.nlp_solution import (
    NLPSolution,
    constraint_violations,
    solve_timings,
)
from bladelab.predict.collocation.progress import ProgressRelay
from bladelab.predict.collocation.stride_guess import periodic_derivative
from bladelab.predict.collocation.stride_node import (
    control_names,
    leg_forces_function,
    node_bounds,
    node_function,
    node_scales,
    path_names,
    state_names,
)
from bladelab.predict.collocation.stride_problem import (
    StrideDynamics,
    StrideWeights,
    VariableScales,
)
from bladelab.predict.collocation.swing_knee import peak_flexion_rows
from bladelab.predict.collocation.symmetry import stride_mirror, symmetrized, symmetry_rows

__all__ = ["PERIOD_BOUNDS_S", "StrideNLP"]


def _node_pairs(values):
    """Σ over the mesh intervals of (value at the start + value at the end) of a (1, n + 1)
    row of node values: the trapezoidal rule's sum, times h/2 for an integral."""
    return ca.sum2(values[:, :-1]) + ca.sum2(values[:, 1:])


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
        Keep the legs' stances alternating: the right leg's
        :func:`~bladelab.predict.collocation.alternating_steps.step_phase` within 0.5 ± this
        [fraction of the stride] (needs ``StrideDynamics.leg_vertical_grf``;
        :func:`~bladelab.predict.collocation.alternating_steps.alternation_rows`); None: free.
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
        metabolic rate, inequalities, vertical force, squared metabolic rate, force rate)``
        (:func:`~bladelab.predict.collocation.stride_node.node_function`), mapped over the
        ``n + 1`` nodes to build the NLP.
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
        self.sx, self.su = sx, su = node_scales(d, s)
        w = self.weights
        node = node_function(d, w, sx, su)
        self.n_ineq = int(node.numel_out(4))
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
        states, controls = state_names(d), control_names(d)
        self._g_names = (
            [f"defect {nm_}@{k}" for k in range(m) for nm_ in states]
            + [f"path {nm_}@{k}" for k in range(m) for nm_ in path_names(d)]
            + [f"periodicity {states[i]}" for i in keep]
            + [f"periodicity {nm_}" for nm_ in controls]
        )
        if self.symmetric:
            self._mirror = stride_mirror(d, node, self.sx)
            g.append(symmetry_rows(X, U, *self._mirror, itx))
            self._g_names += (
                [f"symmetry {nm_}@{k}" for k in range(m, n) for nm_ in states]
                + [f"symmetry {nm_}@{k}" for k in range(m, n) for nm_ in controls])
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
            legs = leg_forces_function(d, sx).map(n)(X[:, :n])
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

    # -- bounds and guess ---------------------------------------------------------------
    def bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(lbx, ubx, lbg, ubg) of the scaled NLP."""
        d, n = self.dyn, self.n
        itx = d.dof_names.index("pelvis_tx")
        lx, ux, lu, uu = node_bounds(d, self.min_activation, self.min_tendon_force,
                                     self.max_tendon_force)
        lX = np.tile((lx / self.sx)[:, None], (1, n + 1))
        uX = np.tile((ux / self.sx)[:, None], (1, n + 1))
        lX[itx, :], uX[itx, :] = -np.inf, np.inf
        lX[itx, 0] = uX[itx, 0] = 0.0
        lU = np.tile((lu / self.su)[:, None], (1, n + 1))
        uU = np.tile((uu / self.su)[:, None], (1, n + 1))
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
        and these duals with :data:`~bladelab.predict.collocation.ipopt_options.
        DUAL_WARM_START_OPTIONS` (under ``options``). With L-BFGS the solve ends at
        :data:`~bladelab.predict.collocation.ipopt_options.STALL_STOP_OPTIONS`' acceptable
        level where it comes before ``tol`` (status ``Solved_To_Acceptable_Level``, a success).
        The options: :func:`~bladelab.predict.collocation.ipopt_options.solver_options`.
        """
        if hessian not in ("limited-memory", "exact"):
            raise SpecError(f"unknown Hessian option {hessian!r}", where="hessian",
                            hint="limited-memory or exact")
        if hessian == "exact" and self.compiled:
            raise SpecError("the exact Hessian needs the interpreted node function",
                            where="hessian", hint="build the StrideNLP with compiled=False")
        if speed is not None and not (speed > 0 and math.isfinite(speed)):
            raise SpecError(f"speed must be > 0 m/s, got {speed}", where="speed")
        opts = solver_options(max_iter=max_iter, tol=tol, hessian=hessian,
                              print_level=print_level, expand=not self.compiled,
                              warm_duals=multipliers is not None, options=options)
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
        max_violation, worst = constraint_violations(lbg, ubg, gval, self._g_names)
        timings = solve_timings(stats, wall, t_build, self.compile_s)
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
            max_violation=max_violation, worst_constraints=worst,
        )

    def energy_and_distance(self, sol: NLPSolution) -> tuple[float, float]:
        """Metabolic energy [J] over the stride and the stride length [m]."""
        Xs = np.hstack([sol.q, sol.qd, sol.activation, sol.tendon_force]).T / self.sx[:, None]
        Us = np.hstack([sol.qdd, sol.excitation, sol.tendon_force_rate]).T / self.su[:, None]
        e, dist = self._energy(Xs, Us, sol.period / self.scales.period)
        return float(e), float(dist)

