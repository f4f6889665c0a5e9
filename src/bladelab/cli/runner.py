"""``bladelab runner ...``: simulate the planar musculoskeletal runner."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from bladelab._io import read_json
from bladelab.errors import InputFileError, SpecError
from bladelab.predict.defaults import TIME_STEP_S
from bladelab.units import damping_per_deg_to_per_rad, stiffness_per_deg_to_per_rad

runner_app = typer.Typer(help="Planar musculoskeletal runner with a running blade: the human "
                                "body of predict and design, or seed 001's.")


def _read_controller(path: Path, muscle_names: tuple[str, ...]) -> list[float]:
    """Constant excitations from a controller JSON file.

    Format: ``{"excitations": {"glut_max_l": 0.3, ...}, "default": 0.05}``; muscles not named
    get ``default``. (Gait controllers are the reflex route's: ``bladelab predict``.)
    """

    data = read_json(path, what="controller file")
    if not isinstance(data, dict):
        raise InputFileError("expected a JSON object", file=path)
    unknown_keys = set(data) - {"excitations", "default"}
    if unknown_keys:
        raise SpecError(
            f"unknown key(s) {', '.join(sorted(unknown_keys))}",
            file=path,
            hint='use {"excitations": {muscle: value}, "default": value}',
        )
    default = data.get("default", 0.05)
    table = data.get("excitations", {})
    if not isinstance(table, dict):
        raise SpecError("must be an object {muscle: value}", file=path, where="excitations")
    unknown = sorted(set(table) - set(muscle_names))
    if unknown:
        raise SpecError(
            f"unknown muscle(s) {', '.join(unknown)}",
            file=path,
            where="excitations",
            hint=f"muscles of this model: {', '.join(muscle_names)}",
        )
    out = []
    for name in muscle_names:
        value = table.get(name, default)
        if not isinstance(value, int | float) or not 0.0 <= float(value) <= 1.0:
            raise SpecError(
                f"excitation must be a number in [0, 1], got {value!r}",
                file=path,
                where=f"excitations.{name}",
            )
        out.append(float(value))
    return out


def _wear(name: str, links: int | None, k_deg: float | None, d_deg: float | None):
    """A BladeModel from the blade module, with optional link count and K*, D*."""
    import numpy as np

    from bladelab.blade import load_blade, multilink_blade  # deferred: keeps bladelab --help fast

    if links is not None:
        return multilink_blade(name, n_links=links, K_Nm_per_deg=k_deg, D_Nms_per_deg=d_deg)
    blade = load_blade(name).build()
    if k_deg is not None or d_deg is not None:
        n = len(blade.joints)
        k = (
            [j.stiffness for j in blade.joints]
            if k_deg is None
            else [stiffness_per_deg_to_per_rad(k_deg)] * n
        )
        d = (
            [j.damping for j in blade.joints]
            if d_deg is None
            else [damping_per_deg_to_per_rad(d_deg)] * n
        )
        blade = blade.with_joint_parameters(np.array(k, float), np.array(d, float))
    return blade


@runner_app.command("simulate")
def simulate_cmd(
    model: str = typer.Option("amputee", "--model", help="able or amputee."),
    body: str = typer.Option(
        "human", "--body",
        help="human (the default body of predict and design), seed001 (seed 001's body, which "
        "the reflex route runs on) or toes (seed 001's with a toe segment). Ignored with "
        "--params (the file says it)."),
    blade: str = typer.Option("Cat6", "--blade", help="Blade category (amputee): Cat4..Cat7."),
    params: Path | None = typer.Option(None, "--params", help="Runner parameter YAML file."),
    wear: str | None = typer.Option(
        None,
        "--wear",
        help="Wear a multi-link blade (built-in name or blade spec YAML) instead of the sphere.",
    ),
    links: int | None = typer.Option(
        None, "--links", help="With --wear: regroup into this many links (seed 002)."
    ),
    k_deg: float | None = typer.Option(
        None, "--K", help="With --wear: joint stiffness K* [N·m/deg] (identified)."
    ),
    d_deg: float | None = typer.Option(
        None, "--D", help="With --wear: joint damping D* [N·m·s/deg] (identified)."
    ),
    controller: Path | None = typer.Option(
        None, "--controller", help="Controller JSON (constant excitations); none: 0.05 for all."
    ),
    duration: float = typer.Option(10.0, "--duration", help="Simulated time [s]."),
    dt: float | None = typer.Option(
        None, "--dt", help=f"Time step [s] (default: {TIME_STEP_S:g} s with the explicit "
                           "integrator, 1e-4 s with --wear; 1e-3 s with newmark or implicit)."),
    integrator: str | None = typer.Option(
        None, "--integrator",
        help="explicit, newmark (contacts, ligaments and socket linearly implicit, "
        "second-order rule: at --dt 1e-3 more accurate than explicit at 0.25 ms, also with "
        "--wear) or implicit (its first-order predecessor, stable at 1 ms; with --wear at "
        "5e-4). Default: the body's (bladelab.runner.integrator_for): explicit where its "
        "0.25 ms step integrates every joint damper (seed 001's and the toes body), else "
        "newmark at 1e-3 s (the human body, whose toe damper would need an explicit step "
        "below 0.1 ms).",
    ),
    initial_state: str = typer.Option("stand", "--initial-state", help="stand or gait."),
    speed: float = typer.Option(0.0, "--speed", help="Initial forward speed [m/s]."),
    out: Path | None = typer.Option(None, "--out", help="Folder for the CSV/JSON outputs."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Simulate a runner forward and print its summary (optionally write states, GRF, events,
    power balance and muscle states as CSV into --out)."""
    # deferred: keeps bladelab --help fast
    from bladelab.runner import analyses, build_runner, load_runner_params, simulate_runner
    from bladelab.runner.export import write_simulation  # deferred: keeps bladelab --help fast
    from bladelab.runner.model import DEFAULT_DT  # deferred: keeps bladelab --help fast
    from bladelab.runner.params import BODIES  # deferred: keeps bladelab --help fast
    from bladelab.runner.simulate import DEFAULT_TIME_STEPS, integrator_for  # deferred: --help

    if model not in ("able", "amputee"):
        raise SpecError(f"unknown model {model!r}", where="--model", hint="use able or amputee")
    if not (duration > 0 and math.isfinite(duration)):
        raise SpecError("must be positive", where="--duration")
    if initial_state not in ("stand", "gait"):
        raise SpecError(f"unknown initial state {initial_state!r}", where="--initial-state")
    if body not in BODIES:
        raise SpecError(f"unknown body {body!r}", where="--body", hint="use " + ", ".join(BODIES))
    blade_model = None
    if wear is not None:
        if model != "amputee":
            raise SpecError("only the amputee model wears a blade", where="--wear")
        blade_model = _wear(wear, links, k_deg, d_deg)
    if params is not None:
        p = load_runner_params(params)
        if p.kind != model:
            raise SpecError(
                f"parameter file is for a {p.kind} model, not {model}",
                file=params,
                where="kind",
                hint=f"use --model {p.kind}",
            )
        runner = build_runner(
            p, blade=blade if model == "amputee" else None, blade_model=blade_model
        )
    else:
        runner = build_runner(
            model, blade=blade if model == "amputee" else None, blade_model=blade_model,
            body=body,
        )
    if integrator is None:  # the library's choice for this body's feet
        integrator, _ = integrator_for(runner)
    if dt is None:  # an unknown integrator is refused by name by simulate_runner
        dt = DEFAULT_TIME_STEPS.get(integrator, DEFAULT_DT)
    if wear is not None and dt == DEFAULT_DT and integrator == "explicit":
        dt = 1e-4  # the blade's sole contact needs a finer step
    excitations = None
    if controller is not None:
        excitations = _read_controller(controller, runner.muscle_names)
    result = simulate_runner(
        runner,
        excitations=excitations,
        duration=duration,
        dt=dt,
        initial_state=initial_state,
        initial_speed=speed,
        integrator=integrator,
    )
    origin = "the parameter file" if params is not None else f"{body} body"
    about = {"body": "parameter file" if params is not None else body,
             "integrator": integrator, "time_step_s": dt}
    if out is not None:
        summary = write_simulation(result, out, about=about)
    else:
        summary = {**analyses.summary(result), **about}
    if as_json:
        typer.echo(json.dumps(summary, indent=2))
    else:
        typer.echo(
            f"{runner.kind} ({summary['blade'] or 'no blade'}; "
            f"{origin}, "
            f"{integrator} at {dt:g} s): "
            f"{'fell' if summary['fell'] else 'ran'} {summary['duration_s']:.3f} s, "
            f"mean speed {summary['mean_speed_mps']:.2f} m/s, "
            f"power balance residual {summary['power_balance_residual_pct']:.2f} %"
        )


@runner_app.command("blades")
def blades_cmd(
    as_json: bool = typer.Option(False, "--json", help="Print as JSON."),
) -> None:
    """List the blade categories (seed 001 Table 2.3)."""
    from bladelab.runner import blade_catalogue  # deferred: keeps bladelab --help fast

    rows = [c.to_dict() for c in blade_catalogue().values()]
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
        return
    for r in rows:
        lo, hi = r["body_mass_kg"]
        typer.echo(f"{r['name']:9s} {r['stiffness_kN_per_m']:6.2f} kN/m   body mass {lo}-{hi} kg")


def register(app: typer.Typer) -> None:
    """Add ``bladelab runner`` to the root app."""
    app.add_typer(runner_app, name="runner")
