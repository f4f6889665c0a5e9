"""``python -m bladelab.demo`` (``make demo``): the trial pipeline on a real running trial.

Until the example study exists, the demo reads ``../shared/data/real/fukuchi2017/RBDS001runT35.c3d``
(relative to the project root: a recreational runner, 62 kg, treadmill at 3.5 m/s), finds its
stances and prints them with peak forces in body weights.
"""

from __future__ import annotations

import sys
from pathlib import Path

from bladelab.errors import BladelabError, InputFileError

PROJECT_ROOT = Path(__file__).resolve().parents[2]
DEMO_TRIAL = PROJECT_ROOT.parent / "shared" / "data" / "real" / "fukuchi2017" / "RBDS001runT35.c3d"
DEMO_MASS_KG = 62.0  # RBDSinfo.txt, subject RBDS001


def run(path: Path = DEMO_TRIAL) -> str:
    """Run the trial pipeline on ``path`` and return the printed report."""
    from bladelab.trial import detect_stances, read_c3d
    from bladelab.units import body_weight

    if not path.is_file():
        raise InputFileError(
            "demo trial not found", file=path,
            hint="the demo needs the shared data folder beside the project (../shared/data)",
        )
    trial = read_c3d(path)
    stances = detect_stances(trial)
    bw = body_weight(DEMO_MASS_KG)
    axes = trial.metadata["axes"]
    lines = [
        f"bladelab demo: {path.name} ({trial.duration:.1f} s, {len(trial.markers)} markers at "
        f"{trial.marker_rate:g} Hz, {len(trial.platforms)} force platform(s) at "
        f"{trial.platforms[0].rate:g} Hz; file axes forward {axes['forward']}, up {axes['up']})",
        f"{len(stances)} complete stances (threshold 20 N), runner {DEMO_MASS_KG:g} kg:",
        f"{'index':>5} {'start_s':>8} {'end_s':>8} {'contact_s':>9} {'peak_fz_N':>9} {'peak_BW':>7} "
        f"{'impulse_z_Ns':>12}",
    ]
    for s in stances:
        lines.append(
            f"{s.index:>5} {s.start_s:>8.3f} {s.end_s:>8.3f} {s.contact_time_s:>9.3f} "
            f"{s.peak_fz_N:>9.1f} {s.peak_fz_N / bw:>7.2f} {s.impulse_z_Ns:>12.2f}"
        )
    ct = [s.contact_time_s for s in stances]
    pk = [s.peak_fz_N / bw for s in stances]
    lines.append(
        f"contact time {min(ct):.3f}–{max(ct):.3f} s, peak vertical force {min(pk):.2f}–{max(pk):.2f} BW"
    )
    return "\n".join(lines)


def main() -> int:
    """Print the demo report; a :class:`BladelabError` prints one line and returns 2."""
    try:
        print(run())
    except BladelabError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
