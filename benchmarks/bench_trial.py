"""Trial pipeline speed: read a real ~2.5 MB C3D, find its stances, extract one stance; and the
command line's start-up (`bladelab --help`, `bladelab trial info FILE`, warm install)."""

from __future__ import annotations

import statistics
import subprocess
import sys
import time

from bladelab.datasets import measured_running_trial

FILE = measured_running_trial()  # package data (bladelab.datasets): Fukuchi et al. 2017, 3.5 m/s
REPEATS = 7


def _median_time(fn, repeats: int = REPEATS) -> tuple[float, object]:
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def _command_seconds(args: list[str], repeats: int = 5) -> float:
    """Median wall time [s] of ``python -m bladelab ARGS`` in a fresh interpreter (warm disk)."""
    command = [sys.executable, "-m", "bladelab", *args]
    subprocess.run(command, capture_output=True, check=True)  # warm-up: .pyc files, disk cache
    return _median_time(
        lambda: subprocess.run(command, capture_output=True, check=True), repeats
    )[0]


def run() -> str:
    from bladelab.trial import MarkerMap, detect_stances, extract_stance, read_c3d

    size_mb = FILE.stat().st_size / 1e6
    read_c3d(FILE)  # warm-up (imports, ezc3d)
    t_read, trial = _median_time(lambda: read_c3d(FILE))
    t_detect, stances = _median_time(lambda: detect_stances(trial))
    t_both, _ = _median_time(lambda: detect_stances(read_c3d(FILE)))
    markers = MarkerMap(clamp_anterior="R.MT1", clamp_posterior="R.Heel.Bottom", tip="R.Shank.Top.Lateral")
    t_extract, stance = _median_time(lambda: extract_stance(trial, 0, markers=markers, stances=stances))
    t_help = _command_seconds(["--help"])
    t_info = _command_seconds(["trial", "info", str(FILE)])
    return "\n".join(
        [
            "## trial: C3D reading and stance detection",
            "",
            f"File: `{FILE.name}` ({size_mb:.1f} MB; 32 markers × 4500 frames at 150 Hz, one type-4 "
            f"platform, 6 channels × 9000 samples at 300 Hz). Median of {REPEATS} runs.",
            "",
            "| step | median time |",
            "|---|---|",
            f"| `read_c3d` (ezc3d + calibration, COP, lab frame) | {t_read * 1e3:.0f} ms |",
            f"| `detect_stances` ({len(stances)} stances, 75 Hz filter) | {t_detect * 1e3:.0f} ms |",
            f"| read + detect | {t_both * 1e3:.0f} ms |",
            f"| `extract_stance` (one stance, {len(stance.time)} samples at 1 kHz, filtered) | "
            f"{t_extract * 1e3:.0f} ms |",
            "",
            "Command-line start-up (a fresh interpreter each, median of 5; target ≤ 1 s each):",
            "",
            "| command | median wall time |",
            "|---|---|",
            f"| `bladelab --help` | {t_help:.2f} s |",
            f"| `bladelab trial info {FILE.name}` | {t_info:.2f} s |",
        ]
    )
