"""Seed 001's Tables 3.2, 3.3 and D.1 (and K_leg, Fig. 3.12a) from a collocation sweep folder.

    python benchmarks/collocation/tables.py benchmarks/collocation/study-4mps/

Reads every model subfolder of a ``bladelab sweep --method collocation`` output (``able``,
``amputee-<blade>``: ``speed-<v>.json`` and ``max-speed.json``; best iterates are left out),
computes :func:`bladelab.predict.collocation.analyses.stride_analyses` of each solution and
prints one markdown table per model: a row per quantity (with its unit), a column per solve,
and seed 001's value where the seed gives the same quantity for that blade. Seed 001's
tables are of its simulations at maximum speed (§3.2 B–E: 4.27–4.675 m/s), so they stand
beside our maximum-speed column (§ "The category study" of docs/collocation.md: ours is
7.5–7.8 m/s). Table 3.2 lists P− as magnitudes; here both are negative (absorbed power).
"""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

# Seed 001 (/work/shared/seeds/001_*.txt), per blade category.
# Table 3.2: P+ and P− [W/kg] of the intact hip, knee, ankle, the prosthetic hip, knee, RSP,
# and the TOTAL (both legs), P− as printed (magnitudes).
_T32 = {
    "Cat4": (5.07, 0.29, 0.54, 3.19, 0.58, 0.22, 2.41, 0.56, 0.03, 1.11, 1.00, 1.01, 9.65, 4.37),
    "Cat5": (5.11, 0.33, 0.57, 3.38, 0.60, 0.21, 2.48, 0.51, 0.03, 1.13, 0.99, 1.00, 9.78, 4.58),
    "Cat6": (5.34, 0.35, 0.57, 3.80, 0.76, 0.27, 2.71, 0.61, 0.04, 1.15, 0.95, 0.95, 10.37,
             5.23),
    "Cat6High": (5.20, 0.36, 0.66, 3.80, 0.77, 0.22, 2.91, 0.73, 0.03, 1.20, 0.97, 0.97, 10.54,
                 5.34),
    "Cat7": (5.40, 0.45, 0.46, 3.87, 0.92, 0.16, 2.63, 0.70, 0.02, 1.13, 0.87, 0.87, 10.29,
             5.45),
}
_T32_KEYS = [f"{s}_power_{j}_{leg}_W_per_kg"
             for j, leg in (("hip", "intact"), ("knee", "intact"), ("ankle", "intact"),
                            ("hip", "prosthetic"), ("knee", "prosthetic"),
                            ("rsp", "prosthetic"), ("total", None))
             for s in ("positive", "negative")]
_T32_KEYS = [k.replace("_None", "") for k in _T32_KEYS]
# Table 3.3: intact E stored, E generated, hysteresis [J], recoil [%]; the same of the
# prosthetic leg; total E generated [J].
_T33 = {
    "Cat4": (1.08, 60.48, 59.39, 2, 60.74, 11.48, 49.26, 18.9, 71.95),
    "Cat5": (1.87, 55.86, 53.99, 3, 58.00, 16.36, 41.63, 28.22, 72.23),
    "Cat6": (1.21, 68.21, 67.00, 2, 64.78, 13.46, 51.32, 20.78, 81.67),
    "Cat6High": (0.16, 70.32, 70.16, 2, 67.34, 16.55, 50.78, 24.58, 86.87),
    "Cat7": (2.28, 54.08, 51.80, 4, 59.76, 20.79, 38.97, 34.78, 74.87),
}
_T33_KEYS = [f"{q}_{leg}_{u}" for leg in ("intact", "prosthetic")
             for q, u in (("leg_energy_stored", "J"), ("leg_energy_generated", "J"),
                          ("leg_hysteresis", "J"), ("leg_recoil", "pct"))]
_T33_KEYS.append("leg_energy_generated_total_J")
# Table D.1: the RSP's E stored, E returned, hysteresis [J], recoil [%] per cycle.
_TD1 = {
    "Cat4": (41.09, 41, 0.092, 99.78),
    "Cat5": (39.67, 39.55, 0.125, 99.68),
    "Cat6": (37.55, 37.44, 0.118, 99.69),
    "Cat6High": (38.45, 38.34, 0.116, 99.7),
    "Cat7": (33.84, 33.73, 0.113, 99.67),
}
_TD1_KEYS = ["blade_energy_stored_J", "blade_energy_returned_J", "blade_hysteresis_J",
             "blade_recoil_pct"]
# §3.2 E text (Fig. 3.12a): the intact leg's K_leg relative to the prosthetic leg's [%].
_KLEG_REL = {"Cat4": -5.8, "Cat5": 2.3, "Cat6": -10.4, "Cat6High": -14.3, "Cat7": -2.9}
KLEG_REL_KEY = "leg_stiffness_intact_vs_prosthetic_pct"

SOURCES = {**dict.fromkeys(_T32_KEYS, "Table 3.2"), **dict.fromkeys(_T33_KEYS, "Table 3.3"),
           **dict.fromkeys(_TD1_KEYS, "Table D.1"), KLEG_REL_KEY: "§3.2 E (Fig. 3.12a)"}


def seed_values(blade: str | None) -> dict[str, float]:
    """Seed 001's values of a blade category, under :func:`stride_analyses`' key names (P−
    negative)."""
    if blade not in _T32:
        return {}
    out = {}
    for key, v in zip(_T32_KEYS, _T32[blade], strict=True):
        out[key] = -v if key.startswith("negative_") else v
    out.update(zip(_T33_KEYS, _T33[blade], strict=True))
    out.update(zip(_TD1_KEYS, _TD1[blade], strict=True))
    out[KLEG_REL_KEY] = _KLEG_REL[blade]
    return out


_UNITS = (("_kN_per_m", "kN/m"), ("_W_per_kg", "W/kg"), ("_pct", "%"), ("_J", "J"))


def _label(key: str) -> tuple[str, str]:
    """(quantity, unit) of a key."""
    name, unit = key, ""
    for suffix, u in _UNITS:
        if key.endswith(suffix):
            name, unit = key[: -len(suffix)], u
            break
    m = re.fullmatch(r"(positive|negative)_power_(?:(\w+)_)?(intact|prosthetic|left|right|total)",
                     name)
    if m:
        sign, joint, leg = m.groups()
        p = "P+" if sign == "positive" else "P−"
        joint = {"rsp": "RSP", None: "leg"}.get(joint, joint)
        return (f"TOTAL {p}" if leg == "total" else f"{leg} {joint} {p}"), unit
    if key == KLEG_REL_KEY:
        return "K_leg intact vs prosthetic", unit
    m = re.fullmatch(r"leg_stiffness_(\w+)", name)
    if m:
        return f"{m.group(1)} K_leg", unit
    m = re.fullmatch(r"leg_(energy_stored|energy_generated|hysteresis|recoil)_(\w+)", name)
    if m:
        q = {"energy_stored": "E stored", "energy_generated": "E generated"}.get(
            m.group(1), m.group(1))
        return f"{m.group(2)} leg {q}", unit
    m = re.fullmatch(r"blade_(energy_stored|energy_returned|hysteresis|recoil)", name)
    if m:
        q = {"energy_stored": "E stored", "energy_returned": "E returned"}.get(
            m.group(1), m.group(1))
        return f"RSP {q}", unit
    return name, unit


def _fmt(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    return f"{v:.3g}" if abs(v) >= 100 else f"{v:.2f}"


def _solves(folder: Path) -> list[tuple[str, Path]]:
    """(column title, file) of a model folder's converged solves: speeds in order, then the
    maximum speed."""
    speeds = []
    for p in folder.glob("speed-*.json"):
        m = re.fullmatch(r"speed-([0-9.]+)\.json", p.name)
        if m:
            speeds.append((float(m.group(1)), p))
    out = [(f"{v:g} m/s", p) for v, p in sorted(speeds)]
    if (folder / "max-speed.json").is_file():
        out.append(("maximum speed", folder / "max-speed.json"))
    return out


def model_table(folder: Path, *, refine: int | None = None) -> str:
    """The markdown table of one model folder."""
    from bladelab.predict.collocation import build_collocation_model
    from bladelab.predict.collocation.analyses import REFINE, stride_analyses
    from bladelab.predict.collocation.solution import CollocationSolution
    from bladelab.predict.collocation.stored import model_label, runner_from_spec

    solves = _solves(folder)
    if not solves:
        return ""
    sols = [(title, CollocationSolution.read(path)) for title, path in solves]
    spec = sols[0][1].model_spec
    runner = runner_from_spec(spec)
    cm = build_collocation_model(runner)
    cols, results = [], []
    for title, sol in sols:
        res = stride_analyses(sol, runner, refine=refine or REFINE, cm=cm)
        legs = sol.leg_names
        if legs == ("intact", "prosthetic"):
            k_i, k_p = (res[f"leg_stiffness_{leg}_kN_per_m"] for leg in legs)
            res[KLEG_REL_KEY] = 100 * (k_i - k_p) / k_p
        cols.append(f"{title} ({sol.mean_speed_mps:.2f} m/s)" if title == "maximum speed"
                    else title)
        results.append(res)
    seed = seed_values(spec["blade"])
    keys = list(results[0])
    lines = [f"### {model_label(spec)}", ""]
    head = ["quantity", "unit", *cols] + (["seed 001 (max speed)", "source"] if seed else [])
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key in keys:
        name, unit = _label(key)
        row = [name, unit, *(_fmt(r.get(key)) for r in results)]
        if seed:
            row += [_fmt(seed.get(key)), SOURCES.get(key, "") if key in seed else ""]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="a collocation sweep's output folder")
    ap.add_argument("--refine", type=int, default=None,
                    help="samples per mesh interval (default: analyses.REFINE)")
    args = ap.parse_args(argv)
    if not args.folder.is_dir():
        ap.error(f"{args.folder} is not a folder")
    tables = [model_table(sub, refine=args.refine)
              for sub in sorted(p for p in args.folder.iterdir() if p.is_dir())]
    tables = [t for t in tables if t]
    if not tables:
        ap.error(f"no solution in the model subfolders of {args.folder}")
    print("\n\n".join(tables))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
