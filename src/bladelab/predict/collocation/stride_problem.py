"""What a stride NLP is made of: the model's node functions (:class:`StrideDynamics`), the
objective's weights (:class:`StrideWeights`) and the variable scales (:class:`VariableScales`).
The NLP itself: :mod:`bladelab.predict.collocation.transcription`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import casadi as ca
import numpy as np

__all__ = ["FORCE_RATE_SCALE", "METABOLIC_SQUARED_SCALE", "PASSIVE_TORQUE_SCALE", "StrideDynamics",
           "StrideWeights", "VariableScales"]

#: Scale of :attr:`StrideWeights.passive` [(N·m)²]: a joint's 10 N·m counts 1.
PASSIVE_TORQUE_SCALE = 100.0
#: Scale of :attr:`StrideWeights.force_rate` [(1/s)²].
FORCE_RATE_SCALE = 100.0
#: Scale of :attr:`StrideWeights.metabolic_squared` [(W/kg)²·s/m].
METABOLIC_SQUARED_SCALE = 10.0


@dataclass(frozen=True)
class StrideDynamics:
    """What the transcription needs of a model: sizes, names, bounds and node functions.

    Attributes
    ----------
    dof_names, muscle_names
        Names in array order (``model.dof_names``, ``model.muscle_names``).
    mass, gravity
        Total mass [kg] and gravity [m/s²].
    residuals
        CasADi Function (q, q̇, q̈, a, F̃ₜ, dF̃ₜ/dt) -> (multibody residual (n_dof,) [N or N·m],
        Hill residual (n_muscles,) [-]).
    activation_rate
        CasADi Function (e, a) -> ȧ (n_muscles,) [1/s].
    metabolic_rate
        CasADi Function (q, q̇, a, F̃ₜ, dF̃ₜ/dt, e) -> whole-body metabolic rate [W].
    q_bounds, qd_bounds
        (n_dof, 2) bounds of coordinates [m, rad] and speeds [m/s, rad/s]; pelvis_tx's are
        set by the transcription.
    residual_scale
        (n_dof,) typical size of each multibody residual [N or N·m] (constraint scaling).
    inequalities, inequality_bounds
        Optional path inequalities: a CasADi Function (q, q̇, a, F̃ₜ, dF̃ₜ/dt) -> (n_ineq,) and
        their (n_ineq, 2) lower and upper bounds, imposed at every node (e.g. the normalised
        fibre velocities within [−1, 1], the domain of the force–velocity curve).
    static_tendon_force
        Optional ``(q (n+1, n_dof), a (n+1, n_muscles)) -> F̃ₜ`` in static equilibrium, used
        for initial guesses without muscle states.
    vertical_grf
        Optional CasADi Function (q, q̇) -> total vertical ground force [N] (for tracking a
        measured force).
    leg_vertical_grf
        Optional CasADi Function (q, q̇) -> the vertical ground force of each leg (2,) [N],
        left (intact) then right (prosthetic) (for the alternating-steps constraint).
    muscle_metabolic_rates
        Optional CasADi Function (q, q̇, a, F̃ₜ, dF̃ₜ/dt, e) -> metabolic rate of every muscle
        [W] (for :attr:`StrideWeights.metabolic_squared`).
    passive_joint_torques
        Optional CasADi Function (q, q̇) -> the limit torques of the body's own joints [N·m]
        (their ligaments and the hip capsule; for :attr:`StrideWeights.passive`).
    backward_euler_dofs
        Coordinates whose q and q̇ defects use the backward Euler rule
        ``x_{k+1} − x_k − h·ẋ_{k+1}`` instead of the trapezoidal one: stiff subsystems whose
        modes no mesh resolves (a multi-link blade's links, about 300 Hz), which the
        trapezoidal rule, A- but not L-stable, leaves ringing from node to node.
    interval_mean_inequalities
        Rows of ``inequalities`` imposed on each interval's mean of its two nodes' values
        instead of at the nodes: quantities made of contact forces, whose node values can
        alternate from node to node (a stance contact sliding ±1 mm each node, the
        trapezoidal rule's period-2 mode, its friction saturating ±μ·F_n) while the
        momentum balance integrates only their interval means.
    active_strength
        (n_muscles,) active strength of each muscle [-] (``MP_ACTIVE``); the upper bound of its
        normalised tendon force is ``max_tendon_force`` times it. None: 1 for every muscle.
    """

    dof_names: tuple[str, ...]
    muscle_names: tuple[str, ...]
    mass: float
    gravity: float
    residuals: ca.Function
    activation_rate: ca.Function
    metabolic_rate: ca.Function
    q_bounds: np.ndarray
    qd_bounds: np.ndarray
    residual_scale: np.ndarray
    inequalities: ca.Function | None = None
    inequality_bounds: np.ndarray | None = None
    static_tendon_force: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
    vertical_grf: ca.Function | None = None
    muscle_metabolic_rates: ca.Function | None = None
    passive_joint_torques: ca.Function | None = None
    leg_vertical_grf: ca.Function | None = None
    backward_euler_dofs: tuple[str, ...] = ()
    interval_mean_inequalities: tuple[int, ...] = ()
    active_strength: np.ndarray | None = None

    @property
    def nq(self) -> int:
        return len(self.dof_names)

    @property
    def nm(self) -> int:
        return len(self.muscle_names)


@dataclass(frozen=True)
class StrideWeights:
    """Weights of the objective's terms (dimensionless multipliers of the stated terms).

    Attributes
    ----------
    metabolic
        Cost of transport [J/(kg·m)] (prescribed speed; 0 in a maximum-speed problem unless
        set).
    activation
        Time-averaged mean cubed activation [-].
    acceleration
        Time-averaged mean squared joint acceleration, in (rad/s²)² / 1e4 (joints only).
    pelvis_acceleration
        Time-averaged mean squared pelvis acceleration: translations in (m/s²)² / 100 (so a
        1 g bounce counts about 1), tilt in (rad/s²)² / 1e4. Penalises the ground-force
        spikes that a stiff contact allows (the pelvis's vertical acceleration is the net
        vertical force over the body mass, to the segments' relative motion).
    speed
        Negative mean speed [m/s] (maximum-speed problem).
    metabolic_squared
        PredSim's metabolic term (Falisse et al. 2019; ``S.weights.E_exp = 2``): the squared
        metabolic rate of every muscle per body mass, summed, integrated over the stride and
        divided by the distance, in (W/kg)²·s/m / 10 (about 1 for this model's optimum at
        3.5 m/s). Squaring each muscle's rate makes a brief burst of high force cost more
        than the same energy spread over a longer contact, which the energy alone does not
        (the Umberger model's activation heat grows with A^0.6).
    force_rate
        Time-averaged mean squared rate of the normalised tendon forces, Σ_m (dF̃_m/dt)² / n_m,
        in (1/s)² / 100 (a muscle going from 0 to F_max in 0.1 s counts 1): the cost of
        rapid force development (Doke & Kuo 2007; van der Zee & Kuo 2021), which the energy
        models leave out; PredSim keeps a small weight on the same controls as a regulariser.
    passive
        Time-averaged mean squared limit torque of the body's own joints (hip, knee, ankle,
        toes, lumbar: their ligaments and the hip capsule, not the joint springs and dampers;
        not a prosthesis's joints), in (N·m)² / 100: PredSim's passive-torque term (Falisse et
        al. 2019, ``passMom``), which keeps the joints off their limits. Off by default
        (docs/collocation.md, "The stride NLP").
    """

    metabolic: float = 1.0
    activation: float = 1.0
    acceleration: float = 0.1
    pelvis_acceleration: float = 0.0
    speed: float = 1.0
    metabolic_squared: float = 0.0
    force_rate: float = 0.0
    passive: float = 0.0

    def to_dict(self) -> dict[str, float]:
        return asdict(self)


@dataclass(frozen=True)
class VariableScales:
    """Typical magnitudes: the NLP variables are the physical ones divided by these."""

    q: float = 1.0  # m, rad
    qd: float = 5.0  # m/s, rad/s
    qdd: float = 100.0  # m/s², rad/s²
    tendon_force_rate: float = 10.0  # 1/s
    period: float = 1.0  # s
