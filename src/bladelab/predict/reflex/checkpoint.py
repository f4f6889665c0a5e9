"""The checkpoint of a reflex-controller optimisation: its files, how they are written and read.

:func:`write_checkpoint` writes a run folder's ``checkpoint.pkl`` (the whole optimiser state,
pickled: ``cma.CMAEvolutionStrategy`` with its random generator, generation, history, best),
``best.json`` (the best parameters so far) and ``history.csv`` (one row per generation), each
atomically; :func:`load_checkpoint` reads the checkpoint back and refuses a file of another
format with a hint. :mod:`bladelab.predict.reflex.optimize` writes them as it runs.
"""

from __future__ import annotations

import csv
import math
import pickle
from pathlib import Path

from bladelab._io import atomic_open, atomic_path
from bladelab.errors import InputFileError
from bladelab.predict import defaults
from bladelab.predict.reflex.controller import write_parameters

__all__ = ["CHECKPOINT_FORMAT", "CHECKPOINT_NAME", "RUN_FILES", "load_checkpoint",
           "write_checkpoint"]

#: Version of the checkpoint's contents.
CHECKPOINT_FORMAT = 1
#: The optimiser's state in a run folder.
CHECKPOINT_NAME = "checkpoint.pkl"
#: Files of a run folder (an ``out`` holding any of them holds a run).
RUN_FILES = (CHECKPOINT_NAME, "best.json", "history.csv")


def write_checkpoint(
    out_dir,
    es,
    gen,
    evals,
    history,
    best_x,
    best_f,
    best_ev,
    layout,
    model,
    blade,
    speed,
    seed,
    settings,
    elapsed,
    wall_time_s,
    subspace,
    *,
    body: str = defaults.REFLEX_BODY,
) -> None:
    """Write the optimiser's state to ``out_dir``: ``checkpoint.pkl`` (atomically),
    ``best.json`` and ``history.csv`` (the module's docstring says what each holds)."""
    import cma  # deferred: cma takes ~2 s to import (see optimize_controller)

    out_dir.mkdir(parents=True, exist_ok=True)
    state = {
        "format": CHECKPOINT_FORMAT,
        "cma_version": cma.__version__,
        "model": model,
        "blade": blade,
        "body": body,
        "speed": speed,
        "seed": seed,
        "settings": settings.to_dict(),
        "parameter_names": list(layout.names),
        "es": es,
        "generation": gen,
        "evaluations": evals,
        "history": history,
        "best_x": best_x,
        "best_f": best_f,
        "best_eval": best_ev,
        "elapsed": list(elapsed),
        "elapsed_s": wall_time_s,
        "subspace": subspace,
    }
    with atomic_path(out_dir / CHECKPOINT_NAME) as tmp:
        tmp.write_bytes(pickle.dumps(state, protocol=4))
    write_parameters(
        out_dir / "best.json",
        layout,
        best_x,
        blade=blade,
        body=body,
        speed_m_per_s=speed,
        generation=gen,
        evaluations=evals,
        seed=seed,
        settings=settings.to_dict(),
        evaluation=best_ev,
        wall_time_s=wall_time_s if math.isfinite(wall_time_s) else None,
    )
    with atomic_open(out_dir / "history.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["generation", "evaluations", "best", "median", "sigma", "elapsed_s"])
        w.writerows((*row, t) for row, t in zip(history, elapsed, strict=True))



def load_checkpoint(path: str | Path) -> dict:
    """Read a checkpoint written by :func:`optimize_controller`."""
    path = Path(path)
    try:
        state = pickle.loads(path.read_bytes())
    except FileNotFoundError:
        raise InputFileError("file not found", file=path) from None
    except Exception as err:  # noqa: BLE001 - corrupt or incompatible pickle
        raise InputFileError(
            f"cannot read checkpoint ({type(err).__name__}: {err})",
            file=path,
            hint="warm-start a new run from best.json with --init instead",
        ) from None
    if not isinstance(state, dict) or state.get("format") != CHECKPOINT_FORMAT:
        raise InputFileError(
            "not a bladelab checkpoint of this format",
            file=path,
            hint="warm-start a new run from best.json with --init instead",
        )
    return state
