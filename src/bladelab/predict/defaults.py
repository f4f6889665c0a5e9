"""Defaults of the predict wing's settings, in a module that imports nothing.

The settings objects of :mod:`bladelab.predict.reflex` (``ObjectiveSettings``,
``optimize_controller``, ``run_sweep``, the tracking weight) and of
:mod:`bladelab.predict.collocation` (``CollocationSettings``) take their defaults from here,
and the command line shows the same values in ``bladelab predict --help`` and
``bladelab sweep --help`` without loading numba, MuJoCo or CasADi.
"""

from __future__ import annotations

__all__ = [
    "ATHLETE_STARTS",
    "BODY",
    "CHECKPOINT_EVERY",
    "DURATION_S",
    "GENERATIONS",
    "GUESS",
    "INITIAL_STEP",
    "INTEGRATOR",
    "LEAN_WEIGHT_PER_DEG",
    "MAX_ITER",
    "MESH_INTERVALS",
    "METHOD",
    "PEOPLE_WEIGHT_PER_RAD2",
    "POLISH_ITER",
    "POPULATION_SIZE",
    "RECIPE_SEEDS",
    "REFLEX_BLADE",
    "REFLEX_BODY",
    "ROBUST_DIRECTIONS",
    "ROBUST_JITTER",
    "ROBUST_SAMPLES",
    "SEED",
    "SPEED_M_PER_S",
    "STARTS",
    "STRIKE_LIMIT_BW",
    "SWEEP_CATEGORIES",
    "SWEEP_SPEEDS_M_PER_S",
    "SWING_KNEE_MIN_DEG",
    "TIME_STEP_S",
    "TRACK_WEIGHT_PER_RAD2",
    "people_weight_for",
    "swing_knee_for",
]

# -- a predicted gait, either method -------------------------------------------------------
#: Method of ``bladelab predict``: direct collocation of one periodic stride on the human body
#: (the reflex controller, seed 001's method, is ``--method reflex``). ``bladelab sweep`` keeps
#: the reflex grid as its default: its grid and recipe options belong to that method.
METHOD = "collocation"
#: Prescribed mean speed of a predicted gait [m/s] (``ObjectiveSettings.speed``,
#: ``CollocationSettings.speed_m_per_s``).
SPEED_M_PER_S = 3.5

# -- the reflex controller and its objective (predict.reflex) ------------------------------
#: Blade category of the reflex controller's amputee runner (seed 001's reflex gaits).
REFLEX_BLADE = "Cat6"
#: The reflex controller's body: seed 001's, the body its parameters, recipes and reflex
#: starts were found on (``--body human`` runs it on the human body).
REFLEX_BODY = "seed001"
#: Simulated time of one candidate [s] (``ObjectiveSettings.duration``).
DURATION_S = 10.0
#: Time step of the closed-loop simulation [s]: the runner model's own step
#: (``bladelab.runner.model.DEFAULT_DT``; a test checks that they agree).
TIME_STEP_S = 2.5e-4
#: Simulations per candidate: the nominal one only (``ObjectiveSettings.robust_samples``).
ROBUST_SAMPLES = 1
#: Relative parameter jitter of a candidate's robust copies [-].
ROBUST_JITTER = 1e-6
#: How the robust copies' jitter directions are drawn: once per run.
ROBUST_DIRECTIONS = "fixed"
#: Peak force of a swinging foot's strike at which a step loses all its credit [body weights].
STRIKE_LIMIT_BW = 1.0
#: Weight of the pelvis tilt outside its window [1/deg] (seed 001's 0.1 per degree).
LEAN_WEIGHT_PER_DEG = 0.1
#: Integrator of the closed loop: the explicit scheme at :data:`TIME_STEP_S`.
INTEGRATOR = "explicit"
#: Weight of the term that tracks a collocation stride [1/rad²]: 10° of rms error costs 30,
#: as much as running 30 % of the simulation outside the speed window.
TRACK_WEIGHT_PER_RAD2 = 1000.0

# -- CMA-ES (predict.reflex.optimize, predict.reflex.sweep) --------------------------------
#: Generations of one optimisation.
GENERATIONS = 100
#: Candidates per generation.
POPULATION_SIZE = 16
#: Initial step [× each parameter's scale].
INITIAL_STEP = 1.0
#: Seed of CMA-ES's random draws.
SEED = 1
#: Generations between two checkpoints.
CHECKPOINT_EVERY = 5

# -- the reflex sweeps ----------------------------------------------------------------------
#: Blade categories of the category × speed sweep (seed 001 Table 3.1).
SWEEP_CATEGORIES = ("Cat4", "Cat5", "Cat6", "Cat6High", "Cat7")
#: Speeds of the sweep's grid [m/s], rising.
SWEEP_SPEEDS_M_PER_S = (3.5, 4.0, 4.5, 5.0)
#: CMA-ES seeds per category of a recipe sweep.
RECIPE_SEEDS = (1, 2, 3)

# -- collocation (predict.collocation) -----------------------------------------------------
#: Mesh intervals of the stride (``CollocationSettings.mesh_intervals``).
MESH_INTERVALS = 50
#: IPOPT's iteration limit per stage (``CollocationSettings.max_iter``).
MAX_ITER = 3000
#: IPOPT's iteration limit of the exact-Hessian polish of a predictive stage that ran out of
#: iterations near a feasible point (``CollocationSettings.polish_iter``; 0: no polish).
POLISH_ITER = 500
#: The runner's body: ``human`` (published gait-model properties, docs/runner-model.md, "The
#: human body"); ``seed001`` reproduces seed 001's model, ``toes`` is it with a toe segment and
#: compliant Achilles tendons.
BODY = "human"
#: Initial guess of a stride: the stride shipped for the runner's kind on the human body,
#: scaled to the prescribed speed, where there is one; else the measured 3.5 m/s trial's mean
#: stride (``bladelab.predict.collocation.starting_guess``). Measured on the human body: the
#: template's tracking stage stalled (objective 280 after 1,050 iterations); from the trial
#: the able runner at 3.5 m/s reached strides 4.7 and 7.2 of objective on two versions of
#: the body, 50 % apart, where the stored stride re-converges to the cheaper one.
GUESS = "stored"
#: Weight [1/rad²] of people's measured hip, knee and ankle angles in the predictive objective
#: of the human body (``CollocationSettings(reference="people")``, docs/collocation.md,
#: "People's joint angles in the objective"): a tracking term of measured running, reported
#: as such. Measured on the able runner at 3.5 m/s (weights 0, 10, 20): swing knees 75/73°,
#: 89/92°, 92/92° (people ≥ 85°); cost of transport 4.12, 4.28, 4.39 J/(kg·m); knee RMSE
#: against another runner's trial 18.5/15.7°, 12.5/7.3°, 11.1/7.1°. 10 is the smaller weight
#: that gives people's swing, at 4 % more energy. Seed 001's body (and ``toes``) keep none.
PEOPLE_WEIGHT_PER_RAD2 = 10.0
#: People's peak swing knee flexion [deg] that the human body's predicted strides keep at
#: least (``CollocationSettings.swing_knee_min_deg``): the mean of the two reference runners'
#: at 3.5 m/s (``bladelab.predict.collocation.swing_knee.people_swing_knee_deg``, a test keeps
#: them equal); people flex more as they run faster, so above 3.5 m/s it is a floor. Measured
#: on the able runner at 3.5 m/s (docs/collocation.md, "People's swing knee"): without it the
#: knees fold to 91–94° and the stride takes 0.62 s (people 0.64–0.78 s).
SWING_KNEE_MIN_DEG = 108.5
#: Starts per problem of a collocation sweep or stride (the best solve is kept).
STARTS = 1
#: Starts of ``bladelab predict`` for an athlete scaled from the body's own: measured
#: 2026-11-30, the amputee scaled to 68 kg and 1.75 m reached +17 % of the settled objective
#: from the shipped stride's default barrier start and +0.08 % from its barrier start 1e-4.
ATHLETE_STARTS = 2


def people_weight_for(body: str, weight: float | None = None) -> float:
    """The weight [1/rad²] of people's joint angles for a runner ``body``: ``weight`` when
    given, else the default, :data:`PEOPLE_WEIGHT_PER_RAD2` on the human body and 0 on the
    others (seed 001's is reproduced as the seed solved it)."""
    if weight is not None:
        return weight
    return PEOPLE_WEIGHT_PER_RAD2 if body == "human" else 0.0


def swing_knee_for(body: str, degrees: float | None = None,
                   kind: str = "able") -> float | None:
    """The minimum peak knee flexion [deg] of the predicted strides of a runner ``kind`` on
    ``body``: ``degrees`` when given (0: none), else :data:`SWING_KNEE_MIN_DEG` for the able
    and transtibial runners on the human body and none (None) on seed 001's body, ``toes``
    and for the transfemoral runner, whose intact leg swings beside a passive prosthetic
    knee (its stride with the intact knee held at 110° did not converge:
    benchmarks/human_body/swing-knee/README.md)."""
    if degrees is not None:
        return float(degrees) or None
    return SWING_KNEE_MIN_DEG if body == "human" and kind != "transfemoral" else None
