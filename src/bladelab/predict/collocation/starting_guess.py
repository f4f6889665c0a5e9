"""The initial guess of a stride named by a word or a file.

``template`` (:func:`~bladelab.predict.collocation.guess.template_guess` at the prescribed
speed), ``trial`` (the measured running trial shipped with bladelab,
:func:`~bladelab.predict.collocation.guess.guess_from_trial`), ``stored`` (the stride that
bladelab ships for the runner's kind on the human body, :data:`STORED_STRIDES`, the cheapest
found; the trial where there is none: another kind, body or parameter set), or the path of a
file: a collocation solution or best iterate (``solution.json``, ``best_iterate.json``; a stride of the
other amputee kind is mapped onto the runner) or a reflex controller's parameter file
(``bladelab predict`` writes ``best.json``). ``bladelab predict --guess`` and
``bladelab sweep --guess`` name their guess this way.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from bladelab._io import read_json
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.collocation.guess import (
    guess_from_reflex,
    measured_trial_guess,
    prosthetic_stride_on,
    template_guess,
)
from bladelab.predict.collocation.solution import CollocationSolution
from bladelab.predict.collocation.stored import runner_from_spec
from bladelab.predict.collocation.stride_guess import StrideGuess
from bladelab.runner.params import PROSTHETIC_KINDS, RUNNER_DATA_DIR, default_runner_params
from bladelab.runner.scaling import ATHLETE_PARAM_FIELDS, leg_length_factor

__all__ = ["GUESS_WORDS", "MAX_SPEED_TEMPLATE_M_PER_S", "STORED_STRIDES", "first_origin",
           "guess_file_kind", "make_guess", "resolve_guess", "scaled_to_athlete",
           "stored_stride_path"]

#: The guesses named by a word; anything else is the path of a file.
GUESS_WORDS = ("template", "trial", "stored")
#: The shipped strides of the human body by runner kind (``data/runner/collocation/``; their
#: provenance in that folder's README): the ``stored`` guess. Any blade category starts from
#: the amputee's Cat6 stride.
STORED_STRIDES = {"able": "able-3.5-human.json", "amputee": "amputee-Cat6-4-human.json"}
#: Speed [m/s] of the template guess of a maximum-speed problem (no prescribed speed).
MAX_SPEED_TEMPLATE_M_PER_S = 4.0

_NEITHER_HINT = ("template, trial, stored, or the path of a solution.json, best_iterate.json or "
                 "reflex parameter JSON file")


def stored_stride_path(runner) -> Path | None:
    """The shipped stride (:data:`STORED_STRIDES`) of ``runner``'s kind if ``runner`` is the
    built-in human body of that kind (any blade category, any athlete:
    :func:`~bladelab.runner.scaling.athlete_params`), else None."""
    name = STORED_STRIDES.get(runner.kind)
    path = RUNNER_DATA_DIR / "collocation" / name if name else None
    if path is None or not path.is_file():
        return None
    athlete_free = {"blade"} | ATHLETE_PARAM_FIELDS
    body = default_runner_params(runner.kind, body="human").model_dump(exclude=athlete_free)
    return path if runner.params.model_dump(exclude=athlete_free) == body else None


def scaled_to_athlete(stride: StrideGuess, runner) -> StrideGuess:
    """A stride of the human body as the start of another athlete of that body
    (:func:`~bladelab.runner.scaling.athlete_params`): the pelvis's translations scaled by the
    heights' ratio (its height also by the legs' length, :func:`leg_length_factor`) and the
    multipliers dropped, which belong to the stored athlete's problem
    (measured: with them, a 68 kg, 1.75 m amputee's solve still stood at twice the stored
    stride's objective after 881 iterations); the stride itself for the body's own athlete."""
    body = default_runner_params(runner.kind, body="human")
    if runner.params.model_dump(exclude={"blade"}) == body.model_dump(exclude={"blade"}):
        return stride
    ratio = runner.params.athlete.height_m / body.athlete.height_m
    leg = leg_length_factor(runner.params) / leg_length_factor(body)
    names = list(stride.dof_names or runner.dof_names)
    q, qd = stride.q.copy(), stride.qd.copy()
    qdd = None if stride.qdd is None else stride.qdd.copy()
    for j, factor in ((names.index("pelvis_tx"), ratio), (names.index("pelvis_tz"), ratio * leg)):
        for a in (q, qd) if qdd is None else (q, qd, qdd):
            a[:, j] *= factor
    return dataclasses.replace(stride, q=q, qd=qd, qdd=qdd, multipliers=None,
                               source=f"{stride.source}, scaled to the athlete")


def first_origin(source: str) -> str:
    """The origin at the bottom of a guess's provenance: a solution started from a solution
    started from ... a trial names the trial (``"collocation solution a.json (collocation
    solution b.json (the trial), stride ≥ 0.4 s)"`` -> ``"the trial"``), so that a stride
    carried through many solves does not carry a growing chain."""
    text = source.strip()
    while text.startswith("collocation solution") and "(" in text:
        start, depth = text.index("("), 0
        for end in range(start, len(text)):
            depth += {"(": 1, ")": -1}.get(text[end], 0)
            if depth == 0:
                break
        else:  # unclosed: to the end
            end = len(text)
        text = text[start + 1:end].strip()
        if text.startswith("first started from "):
            text = text[len("first started from "):]
    return text


def make_guess(runner, guess: str, *, n: int, speed: float | None, where: str = "guess"):
    """The initial guess named by ``guess`` on ``n`` mesh intervals (module docstring).

    Parameters
    ----------
    runner
        The runner model (:class:`bladelab.runner.RunnerModel`).
    guess
        ``"template"``, ``"trial"``, ``"stored"`` or the path of a file.
    n
        Mesh intervals of the stride.
    speed
        Prescribed speed [m/s] of the template; None (a maximum-speed problem):
        :data:`MAX_SPEED_TEMPLATE_M_PER_S`.
    where
        What errors name as the source of ``guess`` (the command line: ``--guess``).

    Raises
    ------
    InputFileError
        ``trial`` in an installation that lacks its packaged trial
        (:mod:`bladelab.datasets` names the file); a file that is neither kind of guess.
    SpecError
        A name that is neither a word nor a file; a solution of an unrelated model.
    """
    if guess == "template":
        return template_guess(runner, speed=speed or MAX_SPEED_TEMPLATE_M_PER_S, n=n)
    if guess == "trial":
        return measured_trial_guess(runner, n=n)
    if guess == "stored":
        stored = stored_stride_path(runner)
        if stored is None:
            trial = measured_trial_guess(runner, n=n)
            return dataclasses.replace(trial, source=f"measured trial {trial.source} (no "
                                                     "stored stride of this runner)")
        return scaled_to_athlete(make_guess(runner, str(stored), n=n, speed=speed, where=where),
                            runner)
    path = Path(guess)
    if guess_file_kind(path, where=where) == "collocation":
        sol = CollocationSolution.read(path)
        stride = sol.to_guess(f"collocation solution {path.name} (first started from "
                              f"{first_origin(sol.guess_source)})")
        if sol.model_spec["model"] == runner.kind:  # another body of the same kind is mapped
            return stride
        if {sol.model_spec["model"], runner.kind} <= set(PROSTHETIC_KINDS):
            grf = sol.leg_vertical_force().sum(axis=1) / sol.body_weight_N
            return prosthetic_stride_on(runner, stride, source=runner_from_spec(sol.model_spec),
                                        source_grf_bw=grf)
        raise SpecError("the guess is a solution of another model", file=path,
                        where=where, hint=f"it is of {sol.model_spec}; an amputee runner's "
                                          "stride starts the other amputee kind")
    return guess_from_reflex(path, n=n)


def guess_file_kind(path: str | Path, *, where: str = "guess") -> str:
    """``"collocation"`` (a solution or best iterate) or ``"reflex"`` (a reflex controller's
    parameter file) for a guess file; errors name ``where``."""
    path = Path(path)
    if not path.is_file():
        raise SpecError(f"{str(path)!r} is neither template, trial, stored nor a file",
                        where=where, hint=_NEITHER_HINT)
    data = read_json(path, what=f"{where} file")
    if isinstance(data, dict) and str(data.get("kind", "")).startswith("collocation-"):
        return "collocation"
    if isinstance(data, dict) and isinstance(data.get("parameters"), dict):
        return "reflex"
    raise InputFileError("not a collocation solution nor a reflex parameter file", file=path,
                         where=where, hint="a solution.json, best_iterate.json or a "
                                           "'bladelab predict' parameter JSON file")


def resolve_guess(guess: str, *, where: str = "guess") -> str:
    """``guess`` checked before any solve: a word as it is, a file as its absolute path (worker
    processes may start in another folder)."""
    if guess in GUESS_WORDS:
        return guess
    path = Path(guess)
    if not path.is_file():
        raise SpecError(f"{guess!r} is neither template, trial, stored nor a file",
                        where=where, hint=_NEITHER_HINT)
    return str(path.resolve())
