"""The result of one stride NLP solve (:class:`NLPSolution`) and what it reads of IPOPT's.

The node values are unscaled (q [m, rad], q̇, q̈, activations and excitations [-], tendon
forces normalised by F_max [-] and their rates [1/s]), n + 1 rows at the mesh's nodes.
:func:`solve_timings` turns IPOPT's statistics into the solution's timings [s] and call counts;
:func:`constraint_violations` finds the largest violations of the constraint bounds (scaled
NLP). :meth:`~bladelab.predict.collocation.transcription.StrideNLP.unpack` builds the solution
with both.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field

import numpy as np

from bladelab.predict.collocation.stride_guess import COLLOCATION_SOURCE, StrideGuess

__all__ = ["NLPSolution", "constraint_violations", "solve_timings"]


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


def _peak_memory_mb() -> float | None:
    """The process's peak resident memory so far [MB] (``getrusage``), None where the
    platform does not tell; after a solve, an upper bound of that solve's peak."""
    try:
        import resource
    except ImportError:  # Windows
        return None
    peak = float(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
    return peak / 2**20 if sys.platform == "darwin" else peak / 2**10  # bytes / KiB


def solve_timings(stats: dict, wall: float, t_build: float,
                  compile_s: float) -> dict[str, float]:
    """:attr:`NLPSolution.timings` from IPOPT's statistics ``stats`` (CasADi's
    ``solver.stats()``; {} gives the build times alone), the solve's wall time ``wall``, the
    time of building its solver ``t_build`` and of compiling the node ``compile_s`` [s]."""
    timings = {"build_s": t_build, "compile_s": compile_s}
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
    return timings


def constraint_violations(lbg: np.ndarray, ubg: np.ndarray, gval: np.ndarray,
                          names) -> tuple[float, tuple[tuple[str, float], ...]]:
    """The largest violation of the constraint bounds ``lbg <= g <= ubg`` by the values
    ``gval`` (0 without constraints) and the worst five violated rows, (name, violation),
    largest first (:attr:`NLPSolution.max_violation`, :attr:`NLPSolution.worst_constraints`)."""
    viol = np.maximum(lbg - gval, gval - ubg)
    order = np.argsort(viol)[::-1][:5]
    return (float(viol.max()) if viol.size else 0.0,
            tuple((names[i], float(viol[i])) for i in order if viol[i] > 0))
