"""Top-level task functions run by the executors (importable in worker processes and Ray)."""

from __future__ import annotations

from bladelab.errors import DataError


def identify_trial(payload: dict) -> dict:
    """Identify K and D of one trial; returns the result columns of ``results.sqlite``.

    ``payload`` (built by :func:`bladelab.study.runner.plan`): ``file`` (stance CSV), ``stance``
    (1-based stance number; a stance CSV holds one), ``blade`` (name or spec path), ``settings``
    (identification settings), ``seed``.
    """
    from bladelab.identify.identify import identify_stance
    from bladelab.trial import read_stance_csv

    if payload.get("stance", 1) != 1:
        raise DataError(f"stance {payload['stance']} requested, a stance CSV holds one stance",
                        file=payload["file"], where="stance",
                        hint="export each stance to its own CSV, or use stance: 1")
    stance = read_stance_csv(payload["file"])
    s = payload["settings"]
    ident = identify_stance(
        stance, payload["blade"], optimizer=s["optimizer"], seed=int(payload["seed"]),
        weights=tuple(s["weights"]), grf_components=tuple(s["grf_components"]),
        joint=s.get("joint"), nonlinear=bool(s["nonlinear"]), polish=bool(s["polish"]),
        max_evals=int(s["max_evals"]), identifiability=bool(s.get("identifiability", True)),
    )
    return ident.to_row()
