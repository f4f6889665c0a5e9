"""Bilateral symmetry of a stride: the mirror of names, the check that the legs are mirror
images, the symmetric stride nearest a stride, and that the rows a symmetric NLP leaves out
follow from those it keeps."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from bladelab.errors import SpecError
from bladelab.predict.collocation.dynamics import stride_dynamics
from bladelab.predict.collocation.model import build_collocation_model
from bladelab.predict.collocation.settings import CollocationSettings
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.starting_guess import stored_stride_path
from bladelab.predict.collocation.symmetry import (
    check_mirror_image,
    mirror_permutation,
    symmetrized,
)
from bladelab.predict.collocation.transcription import StrideNLP
from bladelab.runner import build_runner

N = 12


@pytest.fixture(scope="module")
def able():
    runner = build_runner("able", body="human")
    dyn = stride_dynamics(build_collocation_model(runner))
    return runner, dyn


def test_mirror_permutation_swaps_sides_and_keeps_the_rest():
    names = ["pelvis_tilt", "hip_l", "knee_l", "hip_r", "knee_r", "lumbar"]
    perm = mirror_permutation(names)
    assert [names[i] for i in perm] == ["pelvis_tilt", "hip_r", "knee_r", "hip_l", "knee_l",
                                        "lumbar"]
    with pytest.raises(SpecError, match="'ankle_l' has no mirror twin 'ankle_r'"):
        mirror_permutation(["ankle_l", "hip_l", "hip_r"])


def test_legs_that_differ_are_refused():
    """A node function whose right leg is 10 % stiffer than its left: refused; the same
    with equal legs passes."""
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 2)
    perm = np.array([1, 0])
    for right, ok in ((1.0, True), (1.1, False)):
        k = ca.DM([1.0, right])
        node = ca.Function("node", [x, u], [-k * x + u, k * x, ca.sum1(u**2), ca.sum1(x),
                                            ca.vertcat(x[0], x[1])])
        points = [np.array([0.3, -0.2]), np.array([1.0, 0.5])]
        if ok:
            check_mirror_image(node, perm, perm, perm, points)
        else:
            with pytest.raises(SpecError, match="not mirror images"):
                check_mirror_image(node, perm, perm, perm, points)


def test_an_amputee_or_an_odd_mesh_is_refused(able):
    _, dyn = able
    amputee = build_runner("amputee", blade="Cat6", body="human")
    with pytest.raises(SpecError, match="no mirror twin"):
        StrideNLP(stride_dynamics(build_collocation_model(amputee)), n=N, symmetric=True)
    with pytest.raises(SpecError, match="even number of mesh intervals"):
        StrideNLP(dyn, n=N + 1, symmetric=True)
    with pytest.raises(SpecError, match="even number of mesh intervals") as err:
        CollocationSettings(mesh_intervals=51, symmetric=True)
    assert err.value.where == "mesh_intervals"
    assert not CollocationSettings(symmetric=True).same_problem(CollocationSettings())


def test_the_rows_left_out_follow_from_those_kept(able):
    """On the shipped able stride made symmetric, the whole stride's defects, path residuals
    and inequalities of the second half are the mirror of the first half's (so leaving them
    out loses nothing), and the symmetric NLP's own symmetry rows vanish."""
    runner, dyn = able
    guess = CollocationSolution.read(stored_stride_path(runner)).to_guess("shipped")
    sym = StrideNLP(dyn, n=N, symmetric=True)
    free = StrideNLP(dyn, n=N)
    w = sym.initial_vector(guess)
    w_free = free.initial_vector(guess)
    assert not np.allclose(w, w_free)  # the shipped stride is not symmetric itself
    evaluate = {nlp: ca.Function("g", [nlp.nlp["x"], nlp.nlp["p"]], [nlp.nlp["g"]])
                for nlp in (sym, free)}
    g_sym = np.asarray(evaluate[sym](w, 3.5)).ravel()
    rows = [i for i, name in enumerate(sym._g_names) if name.startswith("symmetry")]
    assert len(rows) == (N // 2) * (sym.nx + sym.nu)
    assert np.max(np.abs(g_sym[rows])) < 1e-12
    g = np.asarray(evaluate[free](w, 3.5)).ravel()
    names = free._g_names
    perm_x, perm_u = sym._mirror
    nq, nm = dyn.nq, dyn.nm
    perm_path = np.concatenate([perm_x[:nq], nq + perm_x[2 * nq:2 * nq + nm] - 2 * nq])

    def block(kind, k):
        return np.array([g[i] for i, name in enumerate(names)
                         if name.startswith(kind) and name.endswith(f"@{k}")])

    scale = max(1.0, np.max(np.abs(g)))
    for k in range(N // 2):
        first, second = block("defect", k), block("defect", k + N // 2)
        assert np.max(np.abs(second - first[perm_x])) < 1e-9 * scale
        first, second = block("path", k), block("path", k + N // 2)
        assert np.max(np.abs(second - first[perm_path])) < 1e-9 * scale
        first, second = block("inequality", k), block("inequality", k + N // 2)
        assert np.allclose(np.sort(second), np.sort(first), rtol=0, atol=1e-9 * scale)
    # and the defects do not vanish (the guess is no solution): the comparison has teeth
    assert np.max(np.abs(block("defect", 0))) > 1e-3


def test_symmetrized_is_a_projection():
    """Symmetrizing twice changes nothing; a symmetric stride is kept as it is; the stride
    length is kept."""
    rng = np.random.default_rng(1)
    perm = np.array([0, 2, 1, 3])  # pelvis_tx, left, right, trunk
    X, U = rng.standard_normal((4, 9)), rng.standard_normal((2, 9))
    X[0] = np.linspace(0.0, 2.0, 9)
    Xs, Us = symmetrized(X, U, perm, np.array([1, 0]), 0)
    again = symmetrized(Xs, Us, perm, np.array([1, 0]), 0)
    np.testing.assert_allclose(again[0], Xs, atol=1e-15)
    np.testing.assert_allclose(again[1], Us, atol=1e-15)
    assert Xs[0, -1] - Xs[0, 0] == pytest.approx(2.0)
    np.testing.assert_allclose(Xs[[2, 1], 4:8], Xs[[1, 2], :4])
    np.testing.assert_allclose(Xs[0, 4:8], Xs[0, :4] + 1.0)
