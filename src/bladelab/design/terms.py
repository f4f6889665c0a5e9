"""Polynomial model terms of response surfaces.

A term is a sorted tuple of factor indices: ``()`` is the intercept, ``(0,)`` the linear term of
factor 0, ``(0, 1)`` the interaction of factors 0 and 1, ``(0, 0)`` the square of factor 0. By
name: ``"1"``, ``"A"``, ``"A*B"``, ``"A^2"`` with the factors' names.

Named models: ``"linear"`` (1 + k terms), ``"interaction"`` (linear + two-factor interactions),
``"pure_quadratic"`` (linear + squares), ``"quadratic"`` (the full second-order model,
1 + 2k + k(k-1)/2 terms: 15 for four factors), ``"reduced"`` (the full quadratic's terms, which
the design must estimate; each response's surface keeps a subset of them,
:mod:`bladelab.design.reduction`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from bladelab.errors import SpecError

__all__ = ["Term", "MODELS", "model_terms", "parse_terms", "term_name", "model_matrix"]

Term = tuple[int, ...]

MODELS = ("linear", "interaction", "pure_quadratic", "quadratic", "reduced")


def model_terms(n_factors: int, model: str = "quadratic") -> tuple[Term, ...]:
    """Terms of a named model in ``n_factors`` factors, in hierarchical order.

    Order: intercept, linear terms, two-factor interactions, squares.
    """
    if model not in MODELS:
        raise SpecError(
            f"unknown model {model!r}", where="model", hint=f"use one of {', '.join(MODELS)}"
        )
    k = int(n_factors)
    terms: list[Term] = [()]
    terms += [(i,) for i in range(k)]
    if model in ("interaction", "quadratic", "reduced"):
        terms += list(itertools.combinations(range(k), 2))
    if model in ("pure_quadratic", "quadratic", "reduced"):
        terms += [(i, i) for i in range(k)]
    return tuple(terms)


def term_name(term: Term, names: Sequence[str]) -> str:
    """``()`` -> ``"1"``, ``(0,)`` -> ``"A"``, ``(0, 1)`` -> ``"A*B"``, ``(0, 0)`` -> ``"A^2"``."""
    if not term:
        return "1"
    counts: dict[int, int] = {}
    for i in term:
        counts[i] = counts.get(i, 0) + 1
    parts = [names[i] if c == 1 else f"{names[i]}^{c}" for i, c in sorted(counts.items())]
    return "*".join(parts)


def _parse_one(text: str, names: Sequence[str]) -> Term:
    text = text.strip().replace(" ", "")
    if text in ("1", "intercept", ""):
        return ()
    idx: list[int] = []
    for part in text.split("*"):
        base, _, power = part.partition("^")
        if base not in names:
            raise SpecError(
                f"unknown factor {base!r} in term {text!r}",
                where="model terms",
                hint=f"factors are {', '.join(names)}",
            )
        try:
            p = int(power) if power else 1
        except ValueError:
            raise SpecError(f"bad power in term {text!r}", where="model terms") from None
        if p < 1:
            raise SpecError(f"bad power in term {text!r}", where="model terms")
        idx += [list(names).index(base)] * p
    if len(idx) > 2:
        raise SpecError(
            f"term {text!r} is of order {len(idx)}; response surfaces here are second order",
            where="model terms",
        )
    return tuple(sorted(idx))


def parse_terms(spec: str | Sequence[str] | Sequence[Term], names: Sequence[str]) -> tuple[Term, ...]:
    """Terms from a named model, a comma-separated string of term names or a list of terms.

    The intercept is always included (R² and the ANOVA need it); duplicates are removed.
    """
    names = list(names)
    if isinstance(spec, str):
        if spec in MODELS:
            return model_terms(len(names), spec)
        items: list = [s for s in spec.split(",") if s.strip()]
    else:
        items = list(spec)
    terms: list[Term] = [()]
    for item in items:
        if isinstance(item, str):
            term = _parse_one(item, names)
        else:
            term = tuple(sorted(int(i) for i in item))
            if any(i < 0 or i >= len(names) for i in term) or len(term) > 2:
                raise SpecError(f"invalid term {item!r}", where="model terms")
        if term not in terms:
            terms.append(term)
    return tuple(terms)


def model_matrix(coded: np.ndarray, terms: Sequence[Term]) -> np.ndarray:
    """The model matrix ``X`` (n_runs × n_terms) of coded points for ``terms``."""
    coded = np.atleast_2d(np.asarray(coded, dtype=float))
    X = np.ones((coded.shape[0], len(terms)))
    for j, term in enumerate(terms):
        for i in term:
            X[:, j] *= coded[:, i]
    return X
