"""Bilateral symmetry of a stride: each leg does what the other did half a stride earlier.

People's running is near-symmetric, and a predictive simulation of an able runner commonly
imposes it: PredSim (Falisse et al. 2019, J R Soc Interface 16:20190402) solves half a gait
cycle and mirrors it. Here the whole stride stays in the NLP (every node's variables, so a
solution file, a guess and a report see a whole stride as always) and the second half is tied
to the first by linear equalities,

    x_{k+n/2} = M·x_k,   u_{k+n/2} = M·u_k   (k = 0 … n/2 − 1),

where M swaps every left quantity with its right twin (``*_l`` ↔ ``*_r``) and keeps the rest
(pelvis, trunk); pelvis_tx advances by half the stride length. With node n equal to node 0
(periodicity), the second half's trapezoidal defects, path residuals and path inequalities
then follow from the first half's for a model whose legs are mirror images, and are left out:
kept, they would repeat the first half's rows and make the constraint Jacobian rank-deficient.
Whether the legs are mirror images is checked on the model's own node function
(:func:`check_mirror_image`), so an amputee (or any model with unequal legs) is refused.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from bladelab.errors import SpecError

__all__ = ["check_mirror_image", "mirror_permutation", "stride_mirror", "symmetrized",
           "symmetry_rows"]

_TWIN = {"_l": "_r", "_r": "_l"}

#: Largest relative difference [-] between a node function's outputs at a mirrored point and
#: the mirrored outputs at the point itself for legs that are mirror images (round-off).
MIRROR_TOLERANCE = 1e-9


def mirror_permutation(names) -> np.ndarray:
    """Indices ``p`` with ``names[p[i]]`` the mirror twin of ``names[i]`` (``*_l`` ↔ ``*_r``;
    a name without a side is its own twin).

    Raises
    ------
    SpecError
        A sided name has no twin (e.g. a prosthetic leg's own joint).
    """
    names = list(names)
    index = {name: i for i, name in enumerate(names)}
    perm = []
    for name in names:
        twin = name[:-2] + _TWIN[name[-2:]] if name[-2:] in _TWIN else name
        if twin not in index:
            raise SpecError(f"{name!r} has no mirror twin {twin!r}", where="symmetric",
                            hint="a symmetric stride needs two legs that are mirror images "
                                 "(the able runner)")
        perm.append(index[twin])
    return np.asarray(perm, int)


def check_mirror_image(node: ca.Function, perm_x: np.ndarray, perm_u: np.ndarray,
                       perm_path: np.ndarray, points, *, seed: int = 0) -> None:
    """Refuse a model whose legs are not mirror images: the node function
    ``node(x, u) -> (ẋ, path residuals, effort, metabolic rate, path inequalities, …)`` at
    each state of ``points`` (scaled, e.g. poses with the feet on and off the ground) with
    random controls, and at its mirror, must give mirrored derivatives and residuals, the same
    scalars and the same inequalities (as a set), to :data:`MIRROR_TOLERANCE`.

    Raises
    ------
    SpecError
        The legs differ (e.g. an amputee's prosthetic leg).
    """
    rng = np.random.default_rng(seed)
    worst = 0.0
    for x in points:
        x = np.asarray(x, float)
        u = 0.1 * rng.standard_normal(perm_u.size)
        here = [np.asarray(v, float).ravel() for v in node(x, u)]
        there = [np.asarray(v, float).ravel() for v in node(x[perm_x], u[perm_u])]
        pairs = [(there[0], here[0][perm_x]), (there[1], here[1][perm_path]),
                 *zip(there[2:4], here[2:4], strict=True),
                 (np.sort(there[4]), np.sort(here[4]))]
        for a, b in pairs:
            worst = max(worst, _relative_difference(a, b))
    if not worst <= MIRROR_TOLERANCE:
        raise SpecError(f"the legs are not mirror images (the dynamics of a mirrored state "
                        f"differ by {worst:.2g} relative)", where="symmetric",
                        hint="a symmetric stride is for the able runner; an amputee's legs "
                             "differ")


def stride_mirror(dyn, node: ca.Function, scale_x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(perm_x, perm_u): the mirror of a stride NLP's node states (q, q̇, a, F̃ₜ) and controls
    (q̈, e, dF̃ₜ/dt) of the model ``dyn`` (a
    :class:`~bladelab.predict.collocation.stride_problem.StrideDynamics`), after
    :func:`check_mirror_image` on its node function ``node`` (scaled states: ``scale_x``) at
    four pelvis heights, the feet on and off the ground."""
    nq, nm = dyn.nq, dyn.nm
    pq, pm = mirror_permutation(dyn.dof_names), mirror_permutation(dyn.muscle_names)
    perm_x = np.concatenate([pq, nq + pq, 2 * nq + pm, 2 * nq + nm + pm])
    perm_u = np.concatenate([pq, nq + pm, nq + nm + pm])
    rng = np.random.default_rng(0)
    points = []
    for height in (0.85, 0.9, 0.95, 1.0):  # [m]
        q = 0.3 * rng.uniform(-1.0, 1.0, nq)
        q[list(dyn.dof_names).index("pelvis_tz")] = height
        x = np.concatenate([q, rng.uniform(-1.0, 1.0, nq), rng.uniform(0.05, 0.6, nm),
                            rng.uniform(0.05, 1.0, nm)])
        points.append(x / scale_x)
    check_mirror_image(node, perm_x, perm_u, np.concatenate([pq, nq + pm]), points)
    return perm_x, perm_u


def _relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """Largest |a − b| over max(1, |b|); NaN where both are NaN agrees (a random state can
    lie outside a curve's domain), NaN on one side only is infinitely different."""
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if (nan_a != nan_b).any():
        return np.inf
    a, b = a[~nan_a], b[~nan_b]
    if not a.size:
        return 0.0
    d = float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b)))))
    return d if np.isfinite(d) else np.inf


def symmetry_rows(X: ca.MX, U: ca.MX, perm_x: np.ndarray, perm_u: np.ndarray, itx: int):
    """The equality rows (= 0) x_{k+n/2} − M·x_k and u_{k+n/2} − M·u_k for k = 0 … n/2 − 1,
    states first, node by node, of the scaled node matrices ``X`` (n_x, n + 1) and ``U``
    (n_u, n + 1); ``itx`` is pelvis_tx's row, which advances by half of
    X[itx, n] − X[itx, 0] (the stride length)."""
    n = X.shape[1] - 1
    half = n // 2
    shift = ca.DM.zeros(X.shape[0], 1)
    shift[itx] = 1.0
    advance = ca.mtimes(shift, (X[itx, n] - X[itx, 0]) / 2)
    rows_x = X[:, half:n] - X[perm_x.tolist(), :half] - ca.repmat(advance, 1, half)
    rows_u = U[:, half:n] - U[perm_u.tolist(), :half]
    return ca.vertcat(ca.vec(rows_x), ca.vec(rows_u))


def symmetrized(X: np.ndarray, U: np.ndarray, perm_x: np.ndarray, perm_u: np.ndarray,
                itx: int) -> tuple[np.ndarray, np.ndarray]:
    """A symmetric stride made of a stride's node values ``X`` (n_x, n + 1) and ``U``
    (n_u, n + 1) (scaled or not; n even): of each mirrored pair of rows the first (the left
    leg's) as it is and the second that row half a stride later; each row without a side
    (pelvis, trunk) the mean of itself and itself half a stride later (pelvis_tx, row ``itx``,
    half the stride length ahead); node n is node 0 (pelvis_tx a stride ahead). A leg's
    motion, continuous over the stride, is kept whole: a mean of the two legs would blur
    their stances where the steps are not exactly half a stride apart."""
    X, U = np.array(X, float), np.array(U, float)
    n = X.shape[1] - 1
    half = n // 2
    length = X[itx, n] - X[itx, 0]
    X[itx] -= np.arange(n + 1) * length / n  # pelvis_tx about its steady advance
    for values, perm in ((X, perm_x), (U, perm_u)):
        body = values[:, :n]  # one period (a view)
        for i, j in enumerate(perm):
            if j > i:
                body[j] = np.roll(body[i], half)
            elif j == i:
                body[i] = np.tile(0.5 * (body[i, :half] + body[i, half:]), 2)
        values[:, n] = values[:, 0]
    X[itx] += np.arange(n + 1) * length / n
    return X, U
