"""IPOPT's iteration callback of a built stride solver (:meth:`~bladelab.predict.collocation.
transcription.StrideNLP.solve` reports each iteration through it)."""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

__all__ = ["ProgressRelay"]


class ProgressRelay(ca.Callback):
    """IPOPT's iteration callback of one built solver: calls ``target(iteration, objective,
    max constraint violation)`` when a target is set (:meth:`StrideNLP.solve` sets it for
    the length of one solve)."""

    def __init__(self, nlp) -> None:
        ca.Callback.__init__(self)
        self.target: Callable[[int, float, float], None] | None = None
        self.calls = 0
        self._n_vars, self._n_cons = nlp.n_vars, nlp.n_cons
        _, _, self._lbg, self._ubg = nlp.bounds()
        self.construct("stride_progress", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self._n_vars)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self._n_cons)
        if name == "lam_p":
            return ca.Sparsity.dense(1)  # the speed parameter
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        if self.target is None:
            return [0]
        g = np.asarray(arg[2]).ravel()
        viol = float(np.max(np.maximum(self._lbg - g, g - self._ubg), initial=0.0))
        self.target(self.calls, float(arg[1]), viol)
        self.calls += 1
        return [0]
