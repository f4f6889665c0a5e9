"""Realistic measurement conditions: what a motion-capture lab records of a clean stance.

From a clean, physically consistent stance (clamp pose, GRF and, ideally, the blade tip on a fine
time base, e.g. from :func:`bladelab.sim.synthetic.generate_stance`) this module makes

(a) the raw recording, :func:`measure_stance` -> :class:`MeasuredTrial`: marker trajectories of
    a clamp cluster and the tip marker at ``marker_rate_hz`` (100–250 Hz) with white noise, and
    force platforms at ``analog_rate_hz`` (1000 Hz) with noise, ready for
    :func:`bladelab.trial.write_c3d` (type-2 platforms: forces, and moments about the plate
    origin consistent with the centre of pressure) or as an in-memory
    :class:`bladelab.trial.Trial`;
(b) :func:`degrade_stance`: the :class:`~bladelab.trial.Stance` the trial pipeline recovers from
    that recording (``bladelab.trial.extract_stance``: clamp pose from the cluster, low-pass
    filter, resampling to the force rate), i.e. what identification sees with real data.

Clamp cluster (clamp frame: origin at the clamp, x forward along the clamp, y lateral, z up;
metres), :data:`CLAMP_CLUSTER`:

==============  ====================  ====================================================
marker          position (x, y, z)    role
==============  ====================  ====================================================
``CLAMP_ANT``   (+0.06, 0, 0)         front of the clamp (used by the trial pipeline)
``CLAMP_POST``  (−0.06, 0, 0)         back of the clamp (used by the trial pipeline)
``CLAMP_SUP``   (0, 0, +0.06)         on the pylon above the clamp (redundant, for checks)
``CLAMP_LAT``   (0, +0.04, +0.02)     lateral face (redundant, for checks)
``BLADE_TIP``   the blade tip         distal end of the blade
==============  ====================  ====================================================

The trial pipeline takes the clamp origin as the midpoint of ``CLAMP_ANT``/``CLAMP_POST`` and the
pitch from their direction (see ``docs/trial.md``), so with 1 mm noise per coordinate the
recovered pitch has a noise of about √2·1 mm / 0.12 m ≈ 0.68°, as a 3-marker cluster in the
design notes.

Noise model (all seeded; the same seed gives the same recording):

- markers: independent Gaussian noise of ``marker_noise_m`` [m] on every coordinate of every
  marker and frame;
- forces: Gaussian noise on each force channel of each plate with standard deviation
  ``force_noise_frac`` × (peak vertical GRF of the stance) while the plate is loaded, and
  ``force_floor_n`` [N] (the unloaded plate's electronic noise) otherwise;
- touch-down timing: the sampling grids start at a random phase in [0, 1 / marker_rate), so
  touch-down falls anywhere between two marker frames (it does in a lab).

The centre of pressure is not part of a stance; it is modelled as moving forward along the
sole by ``cop_roll_m`` (default 0.10 m) in proportion to the vertical impulse, ending near the
tip's touch-down position. Only the plate moments and, with ``plate_boundary_x``, the split of
the force between two plates depend on it; the stance pipeline uses the summed forces.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from scipy import interpolate

from bladelab.constants import STANDARD_GRAVITY
from bladelab.errors import DataError
from bladelab.trial.c3d import plate_corners, write_c3d
from bladelab.trial.kinematics import extract_stance
from bladelab.trial.stance import Stance
from bladelab.trial.trial import ForcePlatform, Trial

__all__ = [
    "CLAMP_CLUSTER",
    "TIP_MARKER",
    "MeasuredTrial",
    "clamp_cluster_positions",
    "default_tip",
    "degrade_stance",
    "extend_flight",
    "measure_stance",
]

#: Clamp-cluster marker positions in the clamp frame [m] (x forward, y lateral, z up).
CLAMP_CLUSTER: dict[str, tuple[float, float, float]] = {
    "CLAMP_ANT": (0.06, 0.0, 0.0),
    "CLAMP_POST": (-0.06, 0.0, 0.0),
    "CLAMP_SUP": (0.0, 0.0, 0.06),
    "CLAMP_LAT": (0.0, 0.04, 0.02),
}
#: Name of the tip marker.
TIP_MARKER = "BLADE_TIP"

_PLATE_LENGTH_M = 0.6
_PLATE_WIDTH_M = 0.4


@dataclasses.dataclass(frozen=True, eq=False)
class MeasuredTrial:
    """A synthetic recording: markers and force platforms, lab frame, SI.

    Attributes
    ----------
    markers
        ``label -> (n, 3)`` marker positions [m].
    marker_rate
        [Hz].
    platforms
        One mapping per plate: ``force`` (m, 3) [N] (GRF on the subject), ``cop`` (m, 3) [m],
        ``free_moment`` (m,) [N·m], ``corners`` (4, 3) [m] (C3D order, z down), ``origin`` (3,).
        ``m = n × analog_rate / marker_rate``.
    analog_rate
        [Hz].
    time_offset_s
        Time of the first recorded frame on the clean stance's time axis [s]: clean time =
        recording time + ``time_offset_s``.
    settings
        The measurement settings (noise levels, rates, seed, phase).
    """

    markers: dict[str, np.ndarray]
    marker_rate: float
    platforms: tuple[dict[str, np.ndarray], ...]
    analog_rate: float
    time_offset_s: float
    settings: dict[str, Any]

    def to_dict(self) -> dict[str, Any]:
        """Summary (no samples): rates, marker names, plates, offset, settings."""
        n = next(iter(self.markers.values())).shape[0]
        return {
            "marker_rate_Hz": self.marker_rate, "analog_rate_Hz": self.analog_rate,
            "n_frames": n, "markers": list(self.markers), "n_platforms": len(self.platforms),
            "time_offset_s": self.time_offset_s, **self.settings,
        }

    def write_c3d(self, path: str | Path, *, metadata: Mapping[str, Any] | None = None) -> Path:
        """Write the recording as a C3D file (atomically) with :func:`bladelab.trial.write_c3d`."""
        return write_c3d(path, markers=self.markers, marker_rate=self.marker_rate,
                         platforms=self.platforms, analog_rate=self.analog_rate,
                         metadata=metadata)

    def to_trial(self, *, metadata: Mapping[str, Any] | None = None):
        """The recording as an in-memory :class:`bladelab.trial.Trial` (no file)."""
        plates = tuple(
            ForcePlatform(index=k + 1, type=2, rate=self.analog_rate, force=p["force"],
                          cop=np.where(p["force"][:, 2:3] >= 20.0, p["cop"], np.nan),
                          free_moment=np.where(p["force"][:, 2] >= 20.0, p["free_moment"], np.nan),
                          corners=p["corners"],
                          channels=tuple(f"{c}{k + 1}{a}" for c in "FM" for a in "XYZ"))
            for k, p in enumerate(self.platforms)
        )
        meta = {"source": "", "point_units": "m",
                "axes": {"forward": "+x", "lateral": "+y", "up": "+z"}, **dict(metadata or {})}
        return Trial(markers=dict(self.markers), marker_rate=self.marker_rate,
                     analog_rate=self.analog_rate, platforms=plates, metadata=meta)


def _rng(seed: int | np.random.Generator | None) -> np.random.Generator:
    return seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)


def clamp_cluster_positions(
    clamp_x: np.ndarray,
    clamp_y: np.ndarray,
    clamp_z: np.ndarray,
    clamp_pitch: np.ndarray,
    *,
    cluster: Mapping[str, tuple[float, float, float]] = CLAMP_CLUSTER,
) -> dict[str, np.ndarray]:
    """Lab positions [m] of the cluster markers for a clamp pose (position [m], pitch [rad]).

    A clamp-frame point (a, b, c) is at ``x = cx + cos θ·a + sin θ·c``, ``y = cy + b``,
    ``z = cz − sin θ·a + cos θ·c`` (pitch θ about +y, positive turns +z toward +x).
    """
    c, s = np.cos(clamp_pitch), np.sin(clamp_pitch)
    out = {}
    for name, (a, b, h) in cluster.items():
        y = np.broadcast_to(np.asarray(clamp_y, float) + b, np.shape(c))
        out[name] = np.column_stack([clamp_x + c * a + s * h, y, clamp_z - s * a + c * h])
    return out


def default_tip(stance: Stance) -> np.ndarray:
    """A tip trajectory [m] (n, 3) consistent with the stance's distance when none is known.

    The tip is placed ``distance`` below the clamp along the clamp's −z axis. Only its distance
    from the clamp matters to the stance pipeline; the blade angle derived from it is not the
    real one.
    """
    p = np.asarray(stance.clamp_pitch, float)
    d = np.asarray(stance.distance, float)
    return np.column_stack([stance.clamp_x - d * np.sin(p), stance.clamp_y,
                            stance.clamp_z - d * np.cos(p)])


def extend_flight(
    stance: Stance,
    *,
    tip: np.ndarray | None = None,
    before_s: float = 0.25,
    after_s: float = 0.25,
    pitch_decay_s: float = 0.05,
) -> tuple[Stance, np.ndarray]:
    """Add flight before and after a stance so that a recording has room for filters and margins.

    In flight the clamp follows a ballistic path (velocity estimated from the first/last three
    samples, standard gravity), its pitch rate decays exponentially with time constant
    ``pitch_decay_s`` [s], the tip moves rigidly with the clamp and the GRF is zero.

    Parameters
    ----------
    stance
        Uniformly sampled clean stance that starts and ends in flight (GRF ≈ 0 at both ends).
    tip
        Tip trajectory (n, 3) [m] (default :func:`default_tip`).
    before_s, after_s
        Flight added [s].
    pitch_decay_s
        Time constant [s] of the pitch rate in flight.

    Returns
    -------
    (Stance, numpy.ndarray)
        The longer stance (time still starts at the original ``time[0] − before_s``) and its tip.
    """
    t = np.asarray(stance.time, float)
    if t.size < 4:
        raise DataError("a stance needs at least 4 samples", where="stance.time")
    h = float(np.median(np.diff(t)))
    tip = default_tip(stance) if tip is None else np.asarray(tip, float).reshape(t.size, 3)
    nb, na = int(round(before_s / h)), int(round(after_s / h))
    cols = {k: np.asarray(getattr(stance, k), float) for k in
            ("clamp_x", "clamp_y", "clamp_z", "clamp_pitch", "grf_x", "grf_y", "grf_z", "distance")}

    def side(idx0: int, idx1: int, n: int, sign: int) -> dict[str, np.ndarray]:
        s = h * np.arange(1, n + 1)  # time away from the stance end
        v = {k: (cols[k][idx1] - cols[k][idx0]) / ((idx1 - idx0) * h) for k in
             ("clamp_x", "clamp_y", "clamp_z", "clamp_pitch")}
        base = {k: cols[k][idx0 if sign < 0 else idx1] for k in cols}
        out = {
            "clamp_x": base["clamp_x"] + sign * v["clamp_x"] * s,
            "clamp_y": base["clamp_y"] + sign * v["clamp_y"] * s,
            "clamp_z": base["clamp_z"] + sign * v["clamp_z"] * s - 0.5 * STANDARD_GRAVITY * s**2,
            "clamp_pitch": base["clamp_pitch"]
            + sign * v["clamp_pitch"] * pitch_decay_s * (1.0 - np.exp(-s / pitch_decay_s)),
            "distance": np.full(n, base["distance"]),
        }
        for k in ("grf_x", "grf_y", "grf_z"):
            out[k] = np.zeros(n)
        return out

    pre = side(0, 2, nb, -1)
    post = side(t.size - 3, t.size - 1, na, +1)
    pre = {k: v[::-1] for k, v in pre.items()}
    new = {k: np.concatenate([pre[k], cols[k], post[k]]) for k in cols}
    time = t[0] + h * np.arange(-nb, t.size + na)

    # tip rigid with the clamp in flight: keep its clamp-frame offset at the boundary
    def rel(i):
        p = cols["clamp_pitch"][i]
        dx, dz = tip[i, 0] - cols["clamp_x"][i], tip[i, 2] - cols["clamp_z"][i]
        return (math.cos(p) * dx - math.sin(p) * dz, tip[i, 1] - cols["clamp_y"][i],
                math.sin(p) * dx + math.cos(p) * dz)

    def tip_of(sl_cols, offset):
        return clamp_cluster_positions(sl_cols["clamp_x"], sl_cols["clamp_y"], sl_cols["clamp_z"],
                                       sl_cols["clamp_pitch"], cluster={"t": offset})["t"]

    tip_new = np.concatenate([tip_of(pre, rel(0)), tip, tip_of(post, rel(t.size - 1))])
    out = Stance(time=time, **new, metadata=dict(stance.metadata))
    return out, tip_new


def _cop_path(t: np.ndarray, grf_z: np.ndarray, tip: np.ndarray, roll: float,
              threshold: float) -> np.ndarray:
    """COP (n, 3) [m] along x: from (tip x at touch-down − roll) forward by ``roll`` with impulse."""
    loaded = np.flatnonzero(grf_z > threshold)
    if loaded.size == 0:
        raise DataError("the stance never loads the ground", where="grf_z",
                        hint="give a stance with a contact phase")
    imp = np.cumsum(np.clip(grf_z, 0.0, None))
    frac = imp / imp[-1]
    x0 = float(tip[loaded[0], 0]) - roll
    cop = np.zeros((t.size, 3))
    cop[:, 0] = x0 + roll * frac
    cop[:, 1] = float(np.mean(tip[loaded, 1]))
    return cop


def measure_stance(
    stance: Stance,
    *,
    tip: np.ndarray | None = None,
    marker_rate_hz: float = 100.0,
    analog_rate_hz: float = 1000.0,
    marker_noise_m: float = 1e-3,
    force_noise_frac: float = 0.01,
    force_floor_n: float = 1.0,
    plate_boundary_x: float | None = None,
    cop_roll_m: float = 0.10,
    random_phase: bool = True,
    cluster: Mapping[str, tuple[float, float, float]] = CLAMP_CLUSTER,
    seed: int | np.random.Generator | None = None,
) -> MeasuredTrial:
    """Record a clean stance as a lab would: noisy cluster + tip markers, two noisy force plates.

    Parameters
    ----------
    stance
        Clean, uniformly sampled stance on a fine time base (≥ ``analog_rate_hz`` preferred),
        with flight at both ends (see :func:`extend_flight`).
    tip
        Blade tip (n, 3) [m] in the lab frame (default :func:`default_tip`).
    marker_rate_hz, analog_rate_hz
        Sampling rates [Hz]; the analog rate must be an integer multiple of the marker rate.
    marker_noise_m
        Standard deviation [m] of the noise on each marker coordinate.
    force_noise_frac
        Standard deviation of the force noise while loaded, as a fraction of the peak vertical
        GRF.
    force_floor_n
        Standard deviation [N] of the force noise of an unloaded plate.
    plate_boundary_x
        x [m] of the edge between plate 1 (behind) and plate 2 (ahead); None puts the whole
        stance on plate 1 (the boundary 0.15 m past the last COP). The force is shared between
        the plates over ±20 mm around the edge (the contact patch straddles it).
    cop_roll_m
        Forward travel of the centre of pressure during stance [m].
    random_phase
        Start the sampling grids at a random phase in [0, 1/marker_rate) (touch-down jitter).
    cluster
        Clamp-cluster layout (clamp frame) [m].
    seed
        Seed or Generator.

    Raises
    ------
    DataError
        Rates that do not divide, a stance without contact or too short for one frame.
    """
    rng = _rng(seed)
    if marker_rate_hz <= 0 or analog_rate_hz <= 0:
        raise DataError("rates must be positive", where="marker_rate_hz / analog_rate_hz")
    ratio = analog_rate_hz / marker_rate_hz
    if ratio < 1 or abs(ratio - round(ratio)) > 1e-9:
        raise DataError(
            f"analog rate {analog_rate_hz:g} Hz is not an integer multiple of the marker rate "
            f"{marker_rate_hz:g} Hz", where="marker_rate_hz", hint="use 100, 200 or 250 Hz with 1000 Hz")
    if marker_noise_m < 0 or force_noise_frac < 0 or force_floor_n < 0:
        raise DataError("noise levels must be >= 0", where="marker_noise_m / force_noise_frac")
    ratio = int(round(ratio))
    t = np.asarray(stance.time, float)
    tip = default_tip(stance) if tip is None else np.asarray(tip, float).reshape(t.size, 3)
    phase = float(rng.uniform(0.0, 1.0 / marker_rate_hz)) if random_phase else 0.0
    span = t[-1] - t[0] - phase - (ratio - 1) / analog_rate_hz
    n = int(math.floor(span * marker_rate_hz + 1e-9)) + 1
    if n < 2:
        raise DataError("the stance is shorter than two marker frames", where="stance.time")
    t0 = t[0] + phase
    tm = t0 + np.arange(n) / marker_rate_hz
    ta = t0 + np.arange(n * ratio) / analog_rate_hz

    # markers: cubic interpolation of the clean pose, then the cluster, then noise
    def spline(v):
        return interpolate.CubicSpline(t, v, axis=0)(tm)

    pitch = spline(np.asarray(stance.clamp_pitch, float))
    pos = clamp_cluster_positions(spline(stance.clamp_x), spline(stance.clamp_y),
                                  spline(stance.clamp_z), pitch, cluster=cluster)
    pos[TIP_MARKER] = spline(tip)
    markers = {k: v + rng.normal(0.0, marker_noise_m, v.shape) if marker_noise_m > 0 else v
               for k, v in pos.items()}

    # forces: linear interpolation, COP model, plate split, noise
    grf = np.column_stack([np.interp(ta, t, np.asarray(getattr(stance, f"grf_{a}"), float))
                           for a in "xyz"])
    cop = _cop_path(t, np.asarray(stance.grf_z, float), tip, cop_roll_m, 20.0)
    cop_a = np.column_stack([np.interp(ta, t, cop[:, i]) for i in range(3)])
    peak = float(np.max(grf[:, 2]))
    if plate_boundary_x is None:
        boundary = float(cop[:, 0].max()) + 0.15
    else:
        boundary = float(plate_boundary_x)
    half = 0.02
    share2 = np.clip((cop_a[:, 0] - (boundary - half)) / (2 * half), 0.0, 1.0)
    loaded = grf[:, 2] > 20.0
    plates = []
    for k, share in enumerate((1.0 - share2, share2)):
        cx = boundary + (k - 0.5) * _PLATE_LENGTH_M
        lo, hi = cx - _PLATE_LENGTH_M / 2, cx + _PLATE_LENGTH_M / 2
        f = grf * share[:, None]
        on = loaded & (share > 0)
        sd = np.where(on, force_noise_frac * peak, force_floor_n)
        noise = rng.normal(0.0, 1.0, f.shape) * sd[:, None]
        pc = cop_a.copy()
        pc[:, 0] = np.clip(pc[:, 0], lo + 1e-3, hi - 1e-3)
        plates.append({
            "force": f + noise, "cop": pc, "free_moment": np.zeros(len(ta)),
            "corners": plate_corners((cx, float(cop[:, 1].mean()), 0.0), _PLATE_LENGTH_M,
                                     _PLATE_WIDTH_M),
            "origin": np.array([0.0, 0.0, -0.04]),
        })
    settings = {
        "marker_noise_m": marker_noise_m, "force_noise_frac": force_noise_frac,
        "force_floor_N": force_floor_n, "phase_s": phase,
        "plate_boundary_x_m": boundary, "cop_roll_m": cop_roll_m,
        "seed": seed if isinstance(seed, int) else None,
    }
    return MeasuredTrial(markers=markers, marker_rate=float(marker_rate_hz),
                         platforms=tuple(plates), analog_rate=float(analog_rate_hz),
                         time_offset_s=float(t0), settings=settings)


def degrade_stance(
    stance: Stance,
    *,
    tip: np.ndarray | None = None,
    marker_rate_hz: float = 100.0,
    marker_noise_m: float = 1e-3,
    force_noise_frac: float = 0.01,
    cutoff_hz: float | None = 20.0,
    force_cutoff_hz: float | None = None,
    rate_hz: float = 1000.0,
    flight_s: float = 0.25,
    seed: int | np.random.Generator | None = None,
) -> Stance:
    """The stance as the trial pipeline would recover it from a realistic recording.

    The clean stance gets flight before and after (:func:`extend_flight`), is recorded with
    :func:`measure_stance` (cluster and tip markers at ``marker_rate_hz`` with noise, forces at
    ``rate_hz`` with noise, random touch-down phase) and is cut out again by
    :func:`bladelab.trial.extract_stance` (clamp pose from the cluster, zero-lag Butterworth
    low-pass, cubic resampling of the kinematics to ``rate_hz``).

    Parameters
    ----------
    stance
        Clean, uniformly sampled stance (time [s], clamp pose [m, rad], GRF [N], distance [m]).
    tip
        Blade tip (n, 3) [m] (default :func:`default_tip`).
    marker_rate_hz
        Marker rate [Hz] (a divisor of ``rate_hz``: 100, 200, 250 with 1000).
    marker_noise_m
        Marker noise per coordinate [m].
    force_noise_frac
        Force noise as a fraction of the peak vertical GRF.
    cutoff_hz
        Marker low-pass cut-off [Hz] (None: unfiltered).
    force_cutoff_hz
        Force low-pass cut-off [Hz] (None: unfiltered).
    rate_hz
        Force rate and rate of the returned stance [Hz].
    flight_s
        Flight added on each side before recording [s].
    seed
        Seed or Generator (same seed, same result).

    Returns
    -------
    Stance
        Time starts at 0 at the window start (as ``extract_stance`` returns it); the metadata
        holds the pipeline's keys plus ``clean_time_offset_s`` (clean time = time + offset) and
        the measurement settings.
    """
    long, tip_long = extend_flight(stance, tip=tip, before_s=flight_s, after_s=flight_s)
    rec = measure_stance(long, tip=tip_long, marker_rate_hz=marker_rate_hz,
                         analog_rate_hz=rate_hz, marker_noise_m=marker_noise_m,
                         force_noise_frac=force_noise_frac, seed=seed)
    trial = rec.to_trial()
    out = extract_stance(trial, 0, rate=rate_hz, marker_cutoff=cutoff_hz,
                         force_cutoff=force_cutoff_hz)
    meta = dict(stance.metadata)
    meta.update(out.metadata)
    meta["source"] = "bladelab.example.degrade_stance"
    meta["clean_time_offset_s"] = round(float(out.metadata["window_start_s"]) + rec.time_offset_s, 9)
    meta.update({f"measurement_{k}": v for k, v in rec.settings.items() if v is not None})
    meta["measurement_marker_rate_Hz"] = marker_rate_hz
    return dataclasses.replace(out, metadata=meta)
