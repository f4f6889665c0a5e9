"""``bladelab simulate``: drive a blade through a stance's clamp motion and write the outputs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from bladelab.errors import ModelError
from bladelab.parameters import JOINT_PARAMETERS

__all__ = ["register"]


def _per_joint(text: str | None, n_joints: int, name: str) -> np.ndarray | None:
    """'18' or '18,20,22' -> array of n_joints values (literature units), None if not given."""
    if text is None:
        return None
    try:
        values = np.array([float(v) for v in text.split(",")], float)
    except ValueError as err:
        raise ModelError(f"not a number or comma-separated list: {text!r}", where=name) from err
    if values.size == 1:
        values = np.full(n_joints, values[0])
    if values.size != n_joints:
        raise ModelError(f"{values.size} values for {n_joints} joint(s)", where=name,
                         hint="give one value for all joints or one per joint")
    if not np.all(np.isfinite(values)) or np.any(values < 0):
        raise ModelError(f"must be finite and >= 0, got {text}", where=name)
    return values


def _simulate(
    blade: str = typer.Option(..., "--blade", help="Built-in blade name or blade spec file."),
    stance: Path = typer.Option(..., "--stance", help="Stance CSV (docs/stance-csv.md)."),
    out: Path = typer.Option(..., "--out", help="Output CSV (units in the column names)."),
    K: str | None = typer.Option(None, "--K", help="Joint stiffness [N·m/deg]; one value or one "
                                 "per joint (comma-separated). Default: the blade's own."),
    D: str | None = typer.Option(None, "--D", help="Joint damping [N·m·s/deg]; as --K."),
    engine: str = typer.Option("kernel", "--engine", help="kernel (numba, default) or mujoco."),
    dt: float = typer.Option(2e-4, "--dt", help="Largest integration step [s] (kernel default "
                             "2e-4; MuJoCo uses a smaller stable step itself)."),
    belt_speed: float = typer.Option(0.0, "--belt-speed", help="Treadmill belt speed [m/s]."),
) -> None:
    """Simulate a blade driven by the clamp motion of a stance; write GRF, distance, deflection."""
    from bladelab.blade import load_blade  # deferred: keeps bladelab --help fast

    # deferred: keeps bladelab --help fast
    from bladelab.sim import prepare, simulate, write_simulation_csv
    from bladelab.trial.stance import read_stance_csv  # deferred: keeps bladelab --help fast

    if engine not in ("kernel", "mujoco"):
        raise ModelError(f"unknown engine {engine!r}", where="--engine", hint="kernel or mujoco")
    model = load_blade(blade).build()
    st = read_stance_csv(stance)
    n_joints = len(model.joints)
    k_deg = _per_joint(K, n_joints, "--K")
    d_deg = _per_joint(D, n_joints, "--D")
    problem = prepare(model, st, dt=dt, engine=engine, belt_speed=belt_speed)
    result = simulate(
        problem,
        stiffness=None if k_deg is None else JOINT_PARAMETERS["K"].from_edge(k_deg),
        damping=None if d_deg is None else JOINT_PARAMETERS["D"].from_edge(d_deg),
    )
    write_simulation_csv(result, out, blade=model.name, stance=stance)
    typer.echo(
        f"wrote {out}: {len(result.time)} samples, peak GRF z {result.grf_z.max():.1f} N, "
        f"min distance {result.distance.min():.4f} m",
        err=True,
    )


def register(app: typer.Typer) -> None:
    """Add ``bladelab simulate`` to the root command."""
    app.command("simulate")(_simulate)
