"""``prepare`` / ``simulate`` / ``simulate_batch``: a blade driven through one stance.

``prepare`` does everything that does not depend on the joint parameters once (segment merging,
clamp spline, the clamp's pose at every time step); ``simulate`` and ``simulate_batch`` then run
the chosen engine for one or many (K, D[, K2]) sets. Identification calls ``simulate_batch``.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from typing import Literal

import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.errors import DataError, ModelError, SimulationError
from bladelab.sim import kernel as _k
from bladelab.sim.chain import Chain, build_chain
from bladelab.sim.compilation import announce_compilation
from bladelab.sim.motion import ClampMotion
from bladelab.sim.mujoco_engine import default_mujoco_dt, simulate_mujoco
from bladelab.sim.result import BatchResult, SimResult
from bladelab.trial.stance import Stance

Engine = Literal["kernel", "mujoco"]

# The kernel's default (largest) integration step [s]: halving it changes the GRF by < 0.5 %
# nRMSE and the kernel agrees with MuJoCo within 1 % (docs/blade-model.md, tests/test_sim_*.py).
DEFAULT_DT = 2e-4


class Drive(enum.StrEnum):
    """How the model is driven by the stance.

    ``prescribed``: the clamp follows the measured pose; contact with stick-slip friction (seed 000).
    ``utilised-friction``: the clamp follows the measured pose; the friction force of every
    loaded sole element is r(t)·Fn with r = measured Fx/Fz (:func:`utilised_friction_ratio`)
    instead of the stick-slip law, so clamp-path errors no longer become horizontal forces.
    ``grf-driven``: the clamp follows the measured pose and the measured GRF (x, z) is applied
    to the sole, split over the sole elements by the model's normal forces (kernel only); the
    simulated GRF is the measured one, so only the distance carries information.
    """

    PRESCRIBED = "prescribed"
    UTILISED_FRICTION = "utilised-friction"
    GRF_DRIVEN = "grf-driven"


# The utilised ratio r = Fx·Fz/(Fz² + F0²) with F0 this fraction of the peak
UTILISED_FLOOR_FRAC = 0.05
# |r| is limited to this value (a static friction coefficient larger than any measured one)
UTILISED_LIMIT = 1.0


def utilised_friction_ratio(
    stance: Stance, *, floor_frac: float = UTILISED_FLOOR_FRAC, limit: float = UTILISED_LIMIT
) -> np.ndarray:
    """Utilised friction r(t) = Fx/Fz of the measured GRF, regularised where Fz is small.

    r = Fx·Fz / (Fz² + F0²) with F0 = ``floor_frac`` × peak vertical GRF (so r → 0 in flight and
    r ≈ Fx/Fz when loaded), clipped to ±``limit``. Dimensionless, on the stance's time base.

    Raises
    ------
    DataError
        The stance has no finite horizontal or vertical GRF inside contact.
    """
    fx = np.asarray(stance.grf_x, float)
    fz = np.asarray(stance.grf_z, float)
    ok = np.isfinite(fx) & np.isfinite(fz)
    if not np.any(ok & (fz > 0)):
        raise DataError("no finite vertical GRF: the utilised friction needs GRF x and z",
                        where="stance.grf_x / grf_z", hint="use drive='prescribed'")
    peak = float(np.max(np.abs(fz[ok])))
    f0 = max(floor_frac * peak, 1e-9)
    r = np.where(ok, fx * fz / (fz * fz + f0 * f0), 0.0)
    return np.clip(r, -limit, limit)


@dataclasses.dataclass(frozen=True, eq=False)
class SimProblem:
    """One (blade, stance) ready to simulate. Build it with :func:`prepare`.

    Attributes
    ----------
    blade, stance
        The inputs.
    chain
        The blade merged into rigid bodies between compliant joints.
    motion
        The clamp splines (belt speed included).
    time
        Output sample times [s] (the stance's own time base).
    dt
        Integration step [s] actually used (the stance interval divided by ``n_substeps``).
    n_substeps
        Integration steps per stance sample.
    base
        (n_steps + 1, 11) clamp pose, velocity, acceleration, cos and sin of the pitch at every
        step time; a 12th column holds the utilised friction ratio r(t) with
        ``drive="utilised-friction"``, 12th and 13th the measured GRF x, z [N] with
        ``drive="grf-driven"``.
    engine, drive, belt_speed
        As given to :func:`prepare`.
    """

    blade: BladeModel
    stance: Stance
    chain: Chain
    motion: ClampMotion
    time: np.ndarray
    dt: float
    n_substeps: int
    base: np.ndarray
    engine: str
    drive: Drive
    belt_speed: float
    order: int = 2
    iterations: int = 1
    refine: int = 10
    finer: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    @property
    def n_joints(self) -> int:
        """Number of compliant joints."""
        return self.chain.n_joints

    @property
    def n_samples(self) -> int:
        """Number of output samples."""
        return len(self.time)


def prepare(
    blade: BladeModel,
    stance: Stance,
    *,
    dt: float = DEFAULT_DT,
    engine: Engine = "kernel",
    belt_speed: float = 0.0,
    drive: Drive | str = Drive.PRESCRIBED,
    order: int = 2,
    iterations: int = 1,
    refine: int = 10,
) -> SimProblem:
    """Set up the simulation of ``blade`` driven by the clamp motion of ``stance``.

    Parameters
    ----------
    blade
        The built blade (``bladelab.blade.load_blade(name).build()`` or a spec).
    stance
        Uniformly sampled stance; its clamp x, z [m] and pitch [rad] drive the blade.
    dt
        Largest integration step [s]; the step used divides the stance interval exactly.
        :data:`DEFAULT_DT` (2e-4 s) is the kernel's default accuracy (GRF z within about 0.1 %,
        GRF x within about 0.4 % nRMSE of a converged solution; 1e-4 s halves the errors at
        1.7× the cost). The MuJoCo engine applies the contact law explicitly and needs a much
        smaller step: it uses ``min(dt, default_mujoco_dt(...))`` (about 5e-6 s for the
        one-joint blades with friction; multi-link blades with light distal links may need
        ``dt=2e-6`` or less — stick-slip chatter in the MuJoCo GRF is the sign).
    engine
        ``"kernel"`` (numba, default) or ``"mujoco"`` (reference).
    belt_speed
        Treadmill belt speed [m/s], added to the clamp's forward motion.
    drive
        ``"prescribed"`` (clamp follows the stance exactly; stick-slip friction, seed 000) or
        ``"utilised-friction"`` (clamp follows the stance; friction r(t)·Fn with r the measured
        Fx/Fz, see :class:`Drive`; needs the stance's GRF x and z) or ``"grf-driven"`` (the
        measured GRF applied to the sole; kernel only).

    Raises
    ------
    DataError
        Non-uniform time or gaps in the clamp channels.
    ModelError
        Unknown engine/drive, a non-positive step, or a blade the engines cannot simulate.
    """
    try:
        drive = Drive(drive)
    except ValueError as err:
        raise ModelError(f"unknown drive {drive!r}", where="drive",
                         hint="one of " + ", ".join(d.value for d in Drive)) from err
    if engine not in ("kernel", "mujoco"):
        raise ModelError(f"unknown engine {engine!r}", where="engine", hint="use kernel or mujoco")
    if engine == "mujoco" and drive == Drive.GRF_DRIVEN:
        raise ModelError("the grf-driven drive exists in the kernel only", where="drive",
                         hint="use engine='kernel', or drive 'prescribed' / 'utilised-friction'")
    if not (dt > 0 and math.isfinite(dt)):
        raise ModelError(f"dt must be > 0, got {dt}", where="dt")
    chain = build_chain(blade)
    time = np.asarray(stance.time, float)
    if len(time) < 2:
        raise DataError("a stance needs at least two samples", where="stance.time")
    steps = np.diff(time)
    h = float(np.median(steps))
    if np.any(steps <= 0) or np.ptp(steps) > 1e-3 * h + 1e-12:
        raise DataError("time is not uniformly sampled", where="stance.time",
                        hint="resample the stance to one rate")
    motion = ClampMotion.from_stance(stance, belt_speed=belt_speed)
    if engine == "mujoco":
        grf_peak = float(np.nanmax(np.abs(stance.grf_z))) if np.any(np.isfinite(stance.grf_z)) else 0.0
        dt = min(dt, default_mujoco_dt(chain, peak_force=max(3000.0, 1.5 * grf_peak)))
    nsub = max(1, int(math.ceil(h / dt - 1e-9)))
    dt_used = h / nsub
    n_steps = (len(time) - 1) * nsub
    t_steps = time[0] + dt_used * np.arange(n_steps + 1)
    t_steps[-1] = time[-1]
    base = motion.evaluate(t_steps)
    if drive == Drive.UTILISED_FRICTION:
        ratio = np.interp(t_steps, time, utilised_friction_ratio(stance))
        base = np.column_stack([base, ratio])
    elif drive == Drive.GRF_DRIVEN:
        gx = np.asarray(stance.grf_x, float)
        gz = np.asarray(stance.grf_z, float)
        if not (np.all(np.isfinite(gx)) and np.all(np.isfinite(gz))):
            raise DataError("missing or non-finite GRF samples: the grf-driven drive needs GRF x "
                            "and z at every sample", where="stance.grf_x / grf_z",
                            hint="fill the gaps or use drive='prescribed'")
        base = np.column_stack([base, np.interp(t_steps, time, gx), np.interp(t_steps, time, gz)])
    base = np.ascontiguousarray(base)
    return SimProblem(
        blade=blade, stance=stance, chain=chain, motion=motion, time=time, dt=dt_used,
        n_substeps=nsub, base=base, engine=engine, drive=drive, belt_speed=float(belt_speed),
        order=int(order), iterations=int(iterations), refine=int(refine),
    )


RETRY_STEP_FACTORS: tuple[int, ...] = (4, 16)
"""A kernel run that diverges is run again with the step divided by these factors, in turn."""


def finer_problem(problem: SimProblem, factor: int) -> SimProblem:
    """The same problem with the integration step divided by ``factor`` (cached on the problem)."""
    if factor not in problem.finer:
        problem.finer[factor] = prepare(
            problem.blade, problem.stance, dt=problem.dt / factor, engine=problem.engine,
            belt_speed=problem.belt_speed, drive=problem.drive, order=problem.order,
            iterations=problem.iterations, refine=problem.refine)
    return problem.finer[factor]


def _params(problem: SimProblem, value, default: np.ndarray, name: str, n_sets: int | None):
    nj = problem.n_joints
    if value is None:
        arr = default[None, :] if n_sets is None else np.broadcast_to(default, (n_sets, nj))
        return np.ascontiguousarray(arr, dtype=float)
    arr = np.asarray(value, dtype=float)
    if n_sets is None:
        arr = np.broadcast_to(np.atleast_1d(arr), (nj,))[None, :]
    else:
        if arr.ndim == 1 and nj == 1 and arr.shape[0] == n_sets:
            arr = arr[:, None]
        try:
            arr = np.broadcast_to(arr, (n_sets, nj))
        except ValueError as err:
            raise ModelError(f"shape {np.shape(value)} does not fit ({n_sets}, {nj})",
                             where=name) from err
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ModelError(f"must be finite and >= 0, got {np.asarray(value).tolist()}", where=name)
    return np.ascontiguousarray(arr, dtype=float)


def run_kernel(problem: SimProblem, K, D, K2, *, parallel: bool = False,
                with_energy: bool = True):
    """Run the kernel for the (n_sets, nj) parameter arrays; the buffers and (n_sets, 2) status."""
    # writable C arrays whatever the caller passes: numba compiles (and caches) one kernel per
    # argument type, and a read-only array (a broadcast view) is another type than a writable
    # one, so K, D, K2 given or left out would each cost a full compilation of the kernel
    K, D, K2 = (np.require(a, np.float64, ["C", "W"]) for a in (K, D, K2))
    nj = K.shape[1]
    q0 = np.zeros(nj)
    model = _k.ChainModel.from_chain(problem.chain)
    stance_drive = _k.StanceDrive(problem.base, problem.dt, problem.n_substeps, 0.0, q0, q0)
    params = _k.JointParams(K, D, K2)
    solver = _k.SolverSettings(problem.order, problem.iterations, problem.refine, with_energy)
    out = _k.KernelOutputs.zeros(K.shape[0], problem.n_samples, problem.chain.n_soles, nj)
    status = np.zeros((K.shape[0], 2), np.int64)
    kernel = _k.simulate_batch_parallel if parallel else _k.simulate_batch_serial
    announce_compilation(kernel, "the blade simulation kernel")
    if parallel:
        _k.simulate_batch_parallel(model, stance_drive, params, solver, out, status)
    else:
        # all sets in one compiled call (a Python loop costs ~10 µs of dispatch per set)
        _k.simulate_batch_serial(model, stance_drive, params, solver, out, status)
    return (*out, status)


def simulate(
    problem: SimProblem,
    *,
    stiffness: np.ndarray | float | None = None,
    damping: np.ndarray | float | None = None,
    stiffness_quadratic: np.ndarray | float | None = None,
) -> SimResult:
    """Simulate one parameter set.

    Parameters
    ----------
    problem
        From :func:`prepare`.
    stiffness, damping, stiffness_quadratic
        Per joint K [N·m/rad], D [N·m·s/rad], K2 [N·m/rad²] (scalars broadcast); None = the
        blade's own values.

    Raises
    ------
    SimulationError
        The integration diverged.
    """
    c = problem.chain
    K = _params(problem, stiffness, c.stiffness, "stiffness", None)
    D = _params(problem, damping, c.damping, "damping", None)
    K2 = _params(problem, stiffness_quadratic, c.stiffness_quadratic, "stiffness_quadratic", None)
    if problem.engine == "mujoco":
        return simulate_mujoco(problem, K[0], D[0], K2[0])
    grf, dist, qout, tau, state, energy, status = run_kernel(problem, K, D, K2)
    used = problem
    tried = []
    for factor in RETRY_STEP_FACTORS:  # diverged: again with a smaller step
        if status[0, 0] == _k.STATUS_OK:
            break
        tried.append(f"{used.dt:.3g} s at t = {used.time[0] + status[0, 1] * used.dt:.4g} s")
        used = finer_problem(problem, factor)
        grf, dist, qout, tau, state, energy, status = run_kernel(used, K, D, K2)
    if status[0, 0] != _k.STATUS_OK:
        tried.append(f"{used.dt:.3g} s at t = {used.time[0] + status[0, 1] * used.dt:.4g} s")
        raise SimulationError(
            "the kernel diverged with every step tried (" + "; ".join(tried) + ")",
            where="simulate",
            hint="check the stance (clamp far below ground?) and K, D, or use engine='mujoco'",
        )
    return SimResult(
        time=problem.time.copy(), grf_x=grf[0, :, :, 0].sum(axis=1),
        grf_z=grf[0, :, :, 1].sum(axis=1), grf_elements=grf[0], distance=dist[0],
        deflection=qout[0], torque=tau[0], contact_state=state[0],
        energy={name: energy[0, :, i] for i, name in enumerate(_k.ENERGY_TERMS)},
        stiffness=K[0].copy(), damping=D[0].copy(), stiffness_quadratic=K2[0].copy(),
        engine="kernel", dt=used.dt,
    )


def simulate_batch(
    problem: SimProblem,
    stiffness: np.ndarray,
    damping: np.ndarray,
    stiffness_quadratic: np.ndarray | None = None,
    *,
    parallel: bool = False,
) -> BatchResult:
    """Simulate many parameter sets of one problem in one call.

    Parameters
    ----------
    problem
        From :func:`prepare`.
    stiffness, damping
        (n_sets, n_joints) K [N·m/rad] and D [N·m·s/rad]; (n_sets,) is accepted for one joint.
    stiffness_quadratic
        (n_sets, n_joints) K2 [N·m/rad²]; None = the blade's own values.
    parallel
        Spread the sets over numba threads (``prange``). Default False: single thread and
        deterministic; results are identical either way.

    Returns
    -------
    BatchResult
        Diverged sets are flagged in ``ok`` with NaN outputs (no exception).
    """
    stiffness = np.asarray(stiffness, dtype=float)
    n_sets = stiffness.shape[0] if stiffness.ndim else 1
    c = problem.chain
    K = _params(problem, stiffness, c.stiffness, "stiffness", n_sets)
    D = _params(problem, damping, c.damping, "damping", n_sets)
    K2 = _params(problem, stiffness_quadratic, c.stiffness_quadratic, "stiffness_quadratic", n_sets)
    if problem.engine == "mujoco":
        results = []
        for s in range(n_sets):
            try:
                results.append(simulate_mujoco(problem, K[s], D[s], K2[s]))
            except SimulationError:
                results.append(None)
        ok = np.array([r is not None for r in results])
        nan = np.full(problem.n_samples, np.nan)
        nanj = np.full((problem.n_samples, problem.n_joints), np.nan)
        return BatchResult(
            time=problem.time.copy(),
            grf_x=np.array([nan if r is None else r.grf_x for r in results]),
            grf_z=np.array([nan if r is None else r.grf_z for r in results]),
            distance=np.array([nan if r is None else r.distance for r in results]),
            deflection=np.array([nanj if r is None else r.deflection for r in results]),
            torque=np.array([nanj if r is None else r.torque for r in results]),
            ok=ok, stiffness=K, damping=D, stiffness_quadratic=K2,
        )
    grf, dist, qout, tau, _state, _energy, status = run_kernel(problem, K, D, K2,
                                                                parallel=parallel,
                                                                with_energy=False)
    ok = status[:, 0] == _k.STATUS_OK
    refined = np.zeros(n_sets, dtype=bool)
    for factor in RETRY_STEP_FACTORS:  # diverged sets: again with a smaller step
        idx = np.flatnonzero(~ok)
        if idx.size == 0:
            break
        fine = finer_problem(problem, factor)
        g2, d2, q2, t2, _s2, _e2, st2 = run_kernel(fine, K[idx], D[idx], K2[idx],
                                                   parallel=parallel, with_energy=False)
        good = st2[:, 0] == _k.STATUS_OK
        sel = idx[good]
        grf[sel], dist[sel], qout[sel], tau[sel] = g2[good], d2[good], q2[good], t2[good]
        ok[sel] = True
        refined[sel] = True
    grf_x = grf[:, :, :, 0].sum(axis=2)
    grf_z = grf[:, :, :, 1].sum(axis=2)
    for arr in (grf_x, grf_z, dist, qout, tau):
        arr[~ok] = np.nan
    return BatchResult(
        time=problem.time.copy(), grf_x=grf_x, grf_z=grf_z, distance=dist, deflection=qout,
        torque=tau, ok=ok, stiffness=K, damping=D, stiffness_quadratic=K2, refined=refined,
    )
