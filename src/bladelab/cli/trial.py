"""``bladelab trial ...``: inspect C3D trials, list their stances, extract a stance CSV,
measure the legs' segments of a static trial."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

__all__ = ["register"]

trial_app = typer.Typer(
    help="Trials: C3D files, force platforms, stance detection, stance CSV export.",
    no_args_is_help=True,
)

_FORWARD = typer.Option("auto", "--forward", help="File axis that is forward (+x, -y, ...) or auto.")
_UP = typer.Option("auto", "--up", help="File axis that is up (+z, +y, ...) or auto.")
_ZERO = typer.Option(True, "--zero-offset/--no-zero-offset",
                     help="Remove each plate's offset measured in its unloaded periods "
                          "(docs/trial.md).")


def _read(path: Path, forward: str, up: str, zero_offset: bool = True):
    import warnings

    from bladelab.trial import C3DWarning  # deferred: keeps bladelab --help fast
    from bladelab.trial.c3d import read_c3d  # deferred: keeps bladelab --help fast

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", C3DWarning)
        trial = read_c3d(path, forward=forward, up=up, zero_offset=zero_offset)
    for w in caught:  # one plain line each, like the CLI's errors
        typer.echo(f"warning: {w.message}", err=True)
    return trial


@trial_app.command("info")
def _info(
    file: Path = typer.Argument(..., help="C3D file."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of text."),
    forward: str = _FORWARD,
    up: str = _UP,
    zero_offset: bool = _ZERO,
) -> None:
    """Markers, rates, units and force platforms (type, channels) of a C3D file."""
    info = _read(file, forward, up, zero_offset).info()
    if as_json:
        typer.echo(json.dumps(info, indent=2))
        return
    typer.echo(f"file:      {info['source']}")
    typer.echo(f"duration:  {info['duration_s']:.3f} s")
    axes = info["axes"] or {}
    typer.echo(
        f"lab frame: x forward = file {axes.get('forward')}, y lateral = file {axes.get('lateral')}, "
        f"z up = file {axes.get('up')}"
    )
    typer.echo(
        f"markers:   {len(info['markers'])} at {info['marker_rate_Hz']:g} Hz, "
        f"{info['n_frames']} frames, file units {info['point_units']}"
    )
    if info["markers"]:
        typer.echo("           " + ", ".join(info["markers"]))
    typer.echo(f"analogs:   {len(info['analogs'])} at {info['analog_rate_Hz']:g} Hz")
    if not info["platforms"]:
        typer.echo("platforms: none")
    for p in info["platforms"]:
        typer.echo(
            f"platform {p['index']}: type {p['type']}, {p['rate_Hz']:g} Hz, channels "
            f"{', '.join(p['channels'])}"
        )
    for key, value in info["metadata"].items():
        typer.echo(f"{key}: {value}")


@trial_app.command("stances")
def _stances(
    file: Path = typer.Argument(..., help="C3D file."),
    threshold: float = typer.Option(20.0, "--threshold", help="Vertical force threshold [N]."),
    min_duration: float = typer.Option(0.05, "--min-duration", help="Shortest contact [s]."),
    tip: str | None = typer.Option(
        None, "--tip", help="Blade tip marker: mark stances where it is over the COP as prosthetic."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print a JSON list instead of a table."),
    forward: str = _FORWARD,
    up: str = _UP,
    zero_offset: bool = _ZERO,
) -> None:
    """List the stances: start, end, contact time, peak vertical force, vertical impulse."""
    # deferred: keeps bladelab --help fast
    from bladelab.trial.events import classify_stances, detect_stances

    trial = _read(file, forward, up, zero_offset)
    events = detect_stances(trial, threshold=threshold, min_duration=min_duration)
    if tip:
        events = classify_stances(trial, events, tip=tip)
    # Stances are numbered from 1 at the command line and in study.yaml (``stance:``); the
    # Python API (``StanceEvent.index``, ``extract_stance``) counts from 0.
    rows = [{**e.to_dict(), "index": e.index + 1} for e in events]
    if as_json:
        typer.echo(json.dumps(rows, indent=2))
        return
    header = f"{'index':>5} {'plates':>6} {'start_s':>8} {'end_s':>8} {'contact_s':>9} {'peak_fz_N':>9} {'impulse_z_Ns':>12}"
    if tip:
        header += f" {'prosthetic':>10}"
    typer.echo(header)
    for r in rows:
        line = (
            f"{r['index']:>5} {','.join(map(str, r['plates'])):>6} {r['start_s']:>8.3f} "
            f"{r['end_s']:>8.3f} {r['contact_time_s']:>9.3f} {r['peak_fz_N']:>9.1f} "
            f"{r['impulse_z_Ns']:>12.2f}"
        )
        if tip:
            line += f" {'yes' if r['prosthetic'] else 'no':>10}"
        typer.echo(line)


@trial_app.command("extract")
def _extract(
    file: Path = typer.Argument(..., help="C3D file."),
    stance: int = typer.Option(
        ..., "--stance", min=1, help="Stance number, from 1 (see `bladelab trial stances`)."
    ),
    out: Path = typer.Option(..., "--out", help="Output stance CSV."),
    markers: Path | None = typer.Option(
        None, "--markers", help="YAML map of roles (clamp_anterior, clamp_posterior, tip) to markers."
    ),
    rate: float = typer.Option(1000.0, "--rate", help="Output sampling rate [Hz]."),
    margin: float = typer.Option(0.02, "--margin", help="Margin before touch-down / after toe-off [s]."),
    threshold: float = typer.Option(20.0, "--threshold", help="Vertical force threshold [N]."),
    forward: str = _FORWARD,
    up: str = _UP,
    zero_offset: bool = _ZERO,
) -> None:
    """Write one stance as a stance CSV (clamp pose, GRF, distance; docs/stance-csv.md)."""
    # deferred: keeps bladelab --help fast
    from bladelab.trial.kinematics import MarkerMap, extract_stance, load_marker_map
    from bladelab.trial.stance import write_stance_csv  # deferred: keeps bladelab --help fast

    marker_map = load_marker_map(markers) if markers else MarkerMap()
    trial = _read(file, forward, up, zero_offset)
    result = extract_stance(
        trial, stance - 1, markers=marker_map, rate=rate, margin=margin, threshold=threshold
    )
    write_stance_csv(result, out)
    typer.echo(
        f"wrote {out}: stance {stance}, {len(result.time)} samples at {rate:g} Hz, "
        f"peak GRF {result.grf_z.max():.0f} N"
    )


@trial_app.command("segments")
def _segments(
    file: Path = typer.Argument(..., help="Static (standing) C3D trial."),
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of text."),
) -> None:
    """Thigh and shank lengths [m] of each leg from a static trial's anatomical markers
    (Harrington's hip joint centres, epicondyles, malleoli; docs/trial.md): what
    `bladelab predict --static` scales the runner's legs to."""
    from bladelab.trial.segments import segment_lengths  # deferred: keeps bladelab --help fast

    lengths = segment_lengths(_read(file, "auto", "auto"))
    if as_json:  # a side without the markers: null
        data = lengths.to_dict()
        for key in ("thigh_m", "shank_m"):
            data[key] = {k: (v if math.isfinite(v) else None) for k, v in data[key].items()}
        typer.echo(json.dumps(data, indent=2))
        return

    def text(value: float, missing: str) -> str:
        return f"{value:.3f} m" if math.isfinite(value) else f"none ({missing})"

    typer.echo(f"file:         {lengths.source}")
    for side in lengths.thigh_m:
        typer.echo(f"{side + ' leg:':<13} thigh "
                   f"{text(lengths.thigh_m[side], 'no epicondyle markers')}, shank "
                   f"{text(lengths.shank_m[side], 'no epicondyle or malleolus markers')}")
    typer.echo(f"pelvis:       width {lengths.pelvic_width_m:.3f} m (between the ASIS), "
               f"depth {lengths.pelvic_depth_m:.3f} m (to the PSIS)")


def register(app: typer.Typer) -> None:
    """Add ``bladelab trial`` to the root app."""
    app.add_typer(trial_app, name="trial")
