"""``bladelab blade ...``: list, show and segment blades."""

from __future__ import annotations

import json
from pathlib import Path

import typer

from bladelab._io import figure_format
from bladelab.parameters import JOINT_PARAMETERS

__all__ = ["register"]

blade_app = typer.Typer(help="Blades: built-in catalogue, blade specs, profile segmentation.",
                        no_args_is_help=True)


@blade_app.command("list")
def _list(
    as_json: bool = typer.Option(False, "--json", help="Print JSON instead of a table."),
) -> None:
    """List the built-in blades (family-category names usable wherever a blade is asked for)."""
    from bladelab.blade import blade_catalogue  # deferred: keeps bladelab --help fast

    table = blade_catalogue()
    if as_json:
        typer.echo(table.to_json(orient="records", indent=2, force_ascii=False))
        return
    cols = ["name", "K_Nm_per_deg", "D_Nms_per_deg", "mass_kg", "height_m", "toe_length_m",
            "n_segments"]
    typer.echo(table[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))


@blade_app.command("show")
def _show(
    blade: str = typer.Argument(..., help="Built-in name (see 'bladelab blade list') or spec file."),
    category: str | None = typer.Option(None, "--category", help="Stiffness category, e.g. cat5."),
    as_yaml: bool = typer.Option(False, "--yaml", help="Print the full blade spec as YAML."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    plot: Path | None = typer.Option(None, "--plot", help="Also draw the blade to this image file."),
) -> None:
    """Show a blade: dimensions, segmentation, joints (K in N·m/deg), soles, contact."""
    # deferred: keeps bladelab --help fast
    from bladelab.blade import load_blade, save_blade_figure

    if plot is not None:
        figure_format(plot)  # refuse an unknown image format before any work
    spec = load_blade(blade, category=category)
    if as_yaml:
        typer.echo(spec.to_yaml(), nl=False)
    else:
        summary = spec.summary()
        if as_json:
            typer.echo(json.dumps(summary, indent=2, ensure_ascii=False))
        else:
            typer.echo(_format_summary(summary))
    if plot is not None:
        save_blade_figure(spec.build(), plot, profile=spec.profile_geometry())
        typer.echo(f"wrote {plot}", err=True)


@blade_app.command("segment")
def _segment(
    profile: Path = typer.Argument(..., help="Profile CSV (columns x_m,z_m or x_mm,z_mm)."),
    max_error: float = typer.Option(1.0, "--max-error", help="Error threshold [mm²/mm]."),
    n_segments: int | None = typer.Option(None, "--n", help="Use exactly N segments instead."),
    out: Path | None = typer.Option(None, "--out", help="Write the result as JSON to this file."),
) -> None:
    """Segment a profile polyline: smallest N whose error is below --max-error."""
    # deferred: keeps bladelab --help fast
    from bladelab.blade import read_profile_csv, segment_profile, write_segmentation_json

    prof = read_profile_csv(profile)
    seg = segment_profile(prof, max_error_mm2_per_mm=max_error, n_segments=n_segments)
    typer.echo(f"profile: {profile.name}: {len(prof.points)} points, length {prof.length * 1e3:.1f} mm, "
               f"height {prof.height * 1e3:.1f} mm, toe length {prof.toe_length * 1e3:.1f} mm")
    how = f"threshold {max_error:g} mm²/mm" if n_segments is None else "N given"
    typer.echo(f"segments: {seg.n} ({how}); error (worst segment) {seg.error:.3f} mm²/mm, "
               f"mean {seg.mean_error:.3f} mm²/mm")
    typer.echo(" seg  x0_mm    z0_mm    x1_mm    z1_mm  length_mm  error_mm2_per_mm")
    for i in range(seg.n):
        (x0, z0), (x1, z1) = seg.points[i] * 1e3, seg.points[i + 1] * 1e3
        typer.echo(f"{i + 1:4d} {x0:7.1f} {z0:8.1f} {x1:8.1f} {z1:8.1f} "
                   f"{seg.chord_lengths[i] * 1e3:9.1f} {seg.segment_errors[i]:12.3f}")
    if out is not None:
        write_segmentation_json(seg, out, profile=profile)
        typer.echo(f"wrote {out}", err=True)


def _format_summary(s: dict) -> str:
    lines = [
        f"{s['name']}: {s['description']}",
        f"  mass {s['mass_kg']:.3f} kg; profile length {s['profile_length_m'] * 1e3:.1f} mm, "
        f"height {s['height_m'] * 1e3:.1f} mm, toe length {s['toe_length_m'] * 1e3:.1f} mm",
        f"  segments: {s['n_segments']} (error {s['segmentation_error_mm2_per_mm']:.3f} mm²/mm"
        + (f", threshold {s['segmentation_threshold_mm2_per_mm']:g})"
           if s["segmentation_threshold_mm2_per_mm"] is not None else ", N fixed)"),
        f"  rest distance clamp–tip d0 = {s['rest_distance_m'] * 1e3:.1f} mm",
    ]
    for j in s["joints"]:
        a, b = j["between_segments"]
        values = ", ".join(f"{p.name} = {j[p.edge_key]:{fmt}} {p.edge_unit}" for p, fmt in (
            (JOINT_PARAMETERS["K"], ".2f"), (JOINT_PARAMETERS["D"], ".3f"),
            (JOINT_PARAMETERS["K2"], ".3g")))
        lines.append(f"  joint between segments {a} and {b}: {values}")
    for e in s["soles"]:
        lines.append(f"  sole ellipse on segment {e['segment']}: centre ({e['center_x_m'] * 1e3:.1f}, "
                     f"{e['center_z_m'] * 1e3:.1f}) mm, semi-axes {e['semi_axis_x_m'] * 1e3:.1f} × "
                     f"{e['semi_axis_z_m'] * 1e3:.1f} mm, angle {e['angle_deg']:.1f} deg")
    lines.append(f"  contact law: {s['contact_law']}")
    if s["categories"]:
        cats = ", ".join(f"{k}: K = {v}" for k, v in s["categories"].items())
        lines.append(f"  categories (K in N·m/deg): {cats}; selected: {s['category']}")
    return "\n".join(lines)


def register(app: typer.Typer) -> None:
    """Add the ``blade`` sub-command group to the root app."""
    app.add_typer(blade_app, name="blade")
