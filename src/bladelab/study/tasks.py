"""Top-level task functions run by the executors (importable in worker processes and Ray)."""

from __future__ import annotations

from pathlib import Path

from bladelab.errors import DataError
from bladelab.identify.formulations import DEFAULT_FORMULATION
from bladelab.identify.identify import identify_stance
from bladelab.trial import extract_stance, read_c3d, read_stance_csv


def read_trial_stance(file: str, stance: int = 1):
    """The stance of a study trial file: a stance CSV (holds one stance) or a C3D trial.

    A C3D trial goes through :func:`bladelab.trial.extract_stance` with its defaults (stance
    ``stance`` counted from 1 among the detected stances, markers 20 Hz, forces 75 Hz, 1000 Hz).
    """
    if Path(file).suffix.lower() == ".c3d":
        stance_obj = extract_stance(read_c3d(file), int(stance) - 1)
        return stance_obj
    if stance != 1:
        raise DataError(f"stance {stance} requested, a stance CSV holds one stance",
                        file=file, where="stance",
                        hint="export each stance to its own CSV, or use stance: 1")
    return read_stance_csv(file)


def identify_trial(payload: dict) -> dict:
    """Identify K and D of one trial; returns the result columns of ``results.sqlite``.

    ``payload`` (built by :func:`bladelab.study.runner.plan`): ``file`` (stance CSV or C3D trial),
    ``stance`` (1-based stance number; a stance CSV holds one), ``blade`` (name or spec path),
    ``settings`` (identification settings), ``seed``.
    """
    stance = read_trial_stance(payload["file"], payload.get("stance", 1))
    s = payload["settings"]
    ident = identify_stance(
        stance, payload["blade"], optimizer=s["optimizer"], seed=int(payload["seed"]),
        weights=tuple(s["weights"]), grf_components=tuple(s["grf_components"]),
        joint=s.get("joint"), nonlinear=bool(s["nonlinear"]), polish=s.get("polish"),
        max_evals=int(s["max_evals"]), identifiability=bool(s.get("identifiability", True)),
        formulation=s.get("formulation", DEFAULT_FORMULATION),
    )
    return ident.to_row()
