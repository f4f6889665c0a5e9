"""Blade mechanics of one stance: compression, stiffness, angular deformation and hysteresis.

The quantities of seed 000 §2.3–2.4 and seed 001 eq. (1.2), for a measured stance or a
simulated one. A simulated result is passed as a :class:`~bladelab.trial.Stance` holding the
simulated GRF and distance on the same clamp motion, e.g.
``dataclasses.replace(measured, grf_x=sim_fx, grf_z=sim_fz, distance=sim_d)``, with the
simulated tip path (``tip_x``, ``tip_z``) or blade angle (``theta``).

Definitions (SI inside; see ``docs/mechanics.md``)
---------------------------------------------------
- **Force** F(t) [N]: the vertical GRF ``grf_z`` (``force="vertical"``, default, as in seed 000)
  or the magnitude of the sagittal GRF ``hypot(grf_x, grf_z)`` (``force="resultant"``).
- **Pre-loading distance** d0 [m]: the median clamp–tip distance over the unloaded samples
  before touch-down (F below ``contact_threshold``); when the window starts loaded, the distance
  at the first sample. ``d0=`` overrides it.
- **Compression** Δd(t) = d0 − d(t) [m] (positive when the blade is compressed).
- **Equivalent compressive stiffness** K_c(t) = F(t)/Δd(t) [N/m]; NaN where Δd is below the
  **compression threshold** max(``min_compression`` (5 mm), ``noise_factor`` (10) × σ_d), σ_d the
  robust SD (1.4826 × median absolute deviation) of the distance over the unloaded samples before
  touch-down (its measurement noise, which also makes d0 uncertain): K_c's relative error from the distance noise is then ≤ 1/noise_factor
  (10 %). Near touch-down Δd → 0 and F/Δd is not defined. Its peak over the valid samples and its
  value at peak compression (where seed 000 reports it) are both given.
- **Blade angle** θ(t) [rad]: the direction of the clamp→tip line in the clamp frame, measured
  from the clamp's −z axis (pointing down the pylon) toward its +x axis (forward):
  θ = atan2(v_x, −v_z) with v the clamp→tip vector expressed in the clamp frame (rotated by
  −pitch). Compression of a C- or J-shaped blade raises the toe toward the clamp and turns this
  line forward, so θ grows.
- **Angular deformation** Δθ(t) = θ0 − θ(t) [rad], θ0 = the unloaded blade angle, taken like
  d0 (median before touch-down, else the first sample): negative under compression, as in seed 000 §3.4 (−20° to −25° at peak).
- **Instantaneous torsional stiffness** K(t) = M_y(t)/(θ(t) − θ0) = b(t)·|F(t)|/(θ(t) − θ0)
  [N·m/rad] (seed 000 §2.3), with M_y the moment of the sagittal GRF about the hinge point and
  b(t) its moment arm; NaN where |θ − θ0| is below ``min_deflection``.
- **Loops** F–Δd and F–Δθ, split at peak compression (the sample of maximum Δd; of maximum
  |Δθ| for the angle loop) into a loading and an unloading branch.
- **Energy** stored = ∫ F dΔd over loading, returned = −∫ F dΔd over unloading, dissipated =
  stored − returned (the loop area, the hysteresis) [J]; efficiency η = returned/stored·100 [%]
  (seed 001 eq. 1.2). Trapezoidal rule on the samples. These are loop areas of the vertical GRF
  against the clamp–tip distance, which are not work-conjugate (the GRF acts at a contact point
  that rolls along the sole, and the clamp rotates): indices of the loop's shape, not the blade's
  strain energy. :data:`PLAUSIBLE_EFFICIENCY_PCT` is the range accepted as an energy return
  (``efficiency_plausible``); carbon-fibre blades return most of the stored energy.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np
import pandas as pd

from bladelab import units
from bladelab.errors import DataError
from bladelab.trial.stance import Stance

__all__ = ["PLAUSIBLE_EFFICIENCY_PCT", "Loop", "StanceMechanics", "stance_mechanics",
           "mechanics_table", "blade_angle"]

PLAUSIBLE_EFFICIENCY_PCT: tuple[float, float] = (50.0, 100.0)
"""Efficiencies [%] plausible as a carbon-fibre blade's energy return; outside: an artefact of the
F–Δd loop (not work-conjugate), marked ``efficiency_plausible = False``."""

ForceComponent = Literal["vertical", "resultant"]


@dataclasses.dataclass(frozen=True, eq=False)
class Loop:
    """A force–deformation loop split at peak compression.

    Attributes
    ----------
    deformation
        Deformation samples (Δd [m] or Δθ [rad]), shape (n,).
    force
        Force samples F [N], shape (n,).
    peak_index
        Index of peak compression: ``[:peak_index + 1]`` is loading, ``[peak_index:]`` unloading.
    """

    deformation: np.ndarray
    force: np.ndarray
    peak_index: int

    @property
    def loading(self) -> tuple[np.ndarray, np.ndarray]:
        """(deformation, force) of the loading branch, touch-down to peak compression."""
        i = self.peak_index + 1
        return self.deformation[:i], self.force[:i]

    @property
    def unloading(self) -> tuple[np.ndarray, np.ndarray]:
        """(deformation, force) of the unloading branch, peak compression to toe-off."""
        i = self.peak_index
        return self.deformation[i:], self.force[i:]


@dataclasses.dataclass(frozen=True, eq=False)
class StanceMechanics:
    """Mechanical quantities of one stance (SI inside; edge units in :meth:`to_dict`).

    Time series have the shape of ``time``; angular ones are None when no blade angle was
    available (neither tip positions nor ``theta`` given).

    Attributes
    ----------
    time
        Sample times [s].
    force
        F(t) [N] (see ``force_component``).
    compression
        Δd(t) = d0 − d(t) [m].
    compressive_stiffness
        K_c(t) [N/m], NaN where Δd is below ``compression_threshold``.
    angular_deformation
        Δθ(t) = θ0 − θ(t) [rad] or None.
    torsional_stiffness
        K(t) [N·m/rad] or None; NaN where the deflection is too small.
    d0
        Pre-loading distance [m].
    theta0
        Unloaded blade angle [rad] (like d0) or NaN.
    contact_index
        Index of touch-down (first loaded sample).
    force_component
        ``"vertical"`` or ``"resultant"``.
    peak_force, peak_compression, peak_compressive_stiffness
        Peaks of F [N], Δd [m], K_c [N/m].
    peak_angular_deformation
        Δθ of largest magnitude [rad] (signed; negative under compression) or NaN.
    torsional_stiffness_at_peak
        K at peak angular deformation [N·m/rad] or NaN.
    energy_stored, energy_returned, energy_dissipated
        [J], from the F–Δd loop.
    efficiency
        returned/stored [%] (NaN if nothing was stored).
    compression_threshold
        Δd [m] from which K_c is defined (see the module docstring).
    distance_noise
        σ_d [m]: robust SD of the distance before touch-down (0 with fewer than 3 samples).
    compressive_stiffness_at_peak_compression
        K_c at the sample of maximum Δd [N/m].
    """

    time: np.ndarray
    force: np.ndarray
    compression: np.ndarray
    compressive_stiffness: np.ndarray
    angular_deformation: np.ndarray | None
    torsional_stiffness: np.ndarray | None
    d0: float
    theta0: float
    contact_index: int
    force_component: str
    peak_force: float
    peak_compression: float
    peak_compressive_stiffness: float
    peak_angular_deformation: float
    torsional_stiffness_at_peak: float
    energy_stored: float
    energy_returned: float
    energy_dissipated: float
    efficiency: float
    metadata: dict[str, Any] = dataclasses.field(default_factory=dict)
    compression_threshold: float = 5e-3
    distance_noise: float = 0.0
    compressive_stiffness_at_peak_compression: float = float("nan")

    @property
    def compression_loop(self) -> Loop:
        """The F–Δd loop [m, N], split at maximum Δd."""
        return Loop(self.compression, self.force, int(np.nanargmax(self.compression)))

    @property
    def angle_loop(self) -> Loop | None:
        """The F–Δθ loop [rad, N], split at maximum |Δθ|; None without a blade angle."""
        if self.angular_deformation is None:
            return None
        return Loop(
            self.angular_deformation,
            self.force,
            int(np.nanargmax(np.abs(self.angular_deformation))),
        )

    def to_dict(self) -> dict[str, Any]:
        """Scalar results with the unit in each key (K_c in kN/m, angles in deg, K in N·m/deg).

        Scalar metadata of the stance (group, trial, speed, ...) comes first.
        """
        meta = {k: v for k, v in self.metadata.items() if isinstance(v, str | int | float)}
        return {
            **meta,
            "force_component": self.force_component,
            "d0_m": self.d0,
            "theta0_deg": float(units.rad2deg(self.theta0)),
            "peak_force_N": self.peak_force,
            "peak_compression_m": self.peak_compression,
            "peak_Kc_kN_per_m": self.peak_compressive_stiffness / 1e3,
            "Kc_at_peak_compression_kN_per_m": self.compressive_stiffness_at_peak_compression / 1e3,
            "Kc_threshold_mm": self.compression_threshold * 1e3,
            "distance_noise_mm": self.distance_noise * 1e3,
            "peak_angular_deformation_deg": float(units.rad2deg(self.peak_angular_deformation)),
            "K_at_peak_Nm_per_deg": float(
                units.stiffness_per_rad_to_per_deg(self.torsional_stiffness_at_peak)
            ),
            "energy_stored_J": self.energy_stored,
            "energy_returned_J": self.energy_returned,
            "energy_dissipated_J": self.energy_dissipated,
            "efficiency_pct": self.efficiency,
            "efficiency_plausible": bool(
                PLAUSIBLE_EFFICIENCY_PCT[0] <= self.efficiency <= PLAUSIBLE_EFFICIENCY_PCT[1]),
        }

    def to_frame(self) -> pd.DataFrame:
        """The time series as a tidy DataFrame, edge units in the column names."""
        nan = np.full_like(self.time, np.nan)
        dtheta = nan if self.angular_deformation is None else self.angular_deformation
        k = nan if self.torsional_stiffness is None else self.torsional_stiffness
        return pd.DataFrame(
            {
                "time_s": self.time,
                "force_N": self.force,
                "compression_m": self.compression,
                "Kc_kN_per_m": self.compressive_stiffness / 1e3,
                "angular_deformation_deg": units.rad2deg(dtheta),
                "K_Nm_per_deg": units.stiffness_per_rad_to_per_deg(k),
            }
        )


def blade_angle(
    clamp_x: np.ndarray,
    clamp_z: np.ndarray,
    clamp_pitch: np.ndarray,
    tip_x: np.ndarray,
    tip_z: np.ndarray,
) -> np.ndarray:
    """Direction θ [rad] of the clamp→tip line in the clamp frame (see the module docstring).

    Parameters
    ----------
    clamp_x, clamp_z
        Clamp origin in the lab frame [m].
    clamp_pitch
        Clamp pitch about +y [rad] (positive turns +z toward +x).
    tip_x, tip_z
        Blade tip (distal marker) in the lab frame [m].

    Returns
    -------
    numpy.ndarray
        θ [rad] (a float array of the broadcast shape), 0 when the tip is straight below the
        clamp along the clamp's −z axis, positive when it lies forward (clamp +x side); a 1-D
        series is unwrapped over time.
    """
    vx = np.asarray(tip_x, float) - np.asarray(clamp_x, float)
    vz = np.asarray(tip_z, float) - np.asarray(clamp_z, float)
    p = np.asarray(clamp_pitch, float)
    # Lab -> clamp frame: rotate by -pitch about +y (R_y(φ): x' = x cosφ + z sinφ, z' = -x sinφ + z cosφ).
    cx = vx * np.cos(p) - vz * np.sin(p)
    cz = vx * np.sin(p) + vz * np.cos(p)
    angle = np.arctan2(cx, -cz)
    return np.unwrap(angle) if angle.ndim == 1 else angle


def _force(stance: Stance, component: str) -> np.ndarray:
    if component == "vertical":
        return stance.grf_z.copy()
    if component == "resultant":
        return np.hypot(stance.grf_x, stance.grf_z)
    raise DataError(
        f"unknown force component {component!r}",
        where="force",
        hint="use 'vertical' or 'resultant'",
    )


def _work(force: np.ndarray, deformation: np.ndarray) -> float:
    """∫ F d(deformation) by the trapezoidal rule [J or N·rad]."""
    if len(force) < 2:
        return 0.0
    return float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(deformation)))


def stance_mechanics(
    stance: Stance,
    *,
    tip_x: np.ndarray | None = None,
    tip_z: np.ndarray | None = None,
    theta: np.ndarray | None = None,
    hinge: tuple[float, float] | None = None,
    force: ForceComponent = "vertical",
    d0: float | None = None,
    contact_threshold: float = 20.0,
    min_compression: float = 5e-3,
    noise_factor: float = 10.0,
    min_deflection: float = np.deg2rad(1.0),
) -> StanceMechanics:
    """Compute Δd, K_c, Δθ, K(t), peaks, loops and energies of one stance.

    Parameters
    ----------
    stance
        Measured or simulated stance (time [s], clamp pose, GRF [N], distance [m]).
    tip_x, tip_z
        Blade tip in the lab frame [m], shape like ``time``; give them (or ``theta``) for the
        angular quantities.
    theta
        Blade angle θ(t) [rad] directly (e.g. from a simulation), instead of tip positions.
    hinge
        Hinge point (compliant joint or clamp) in the clamp frame, (x, z) [m]; needed with the
        tip positions for the torsional stiffness K(t). The GRF is taken to act at the tip.
    force
        ``"vertical"`` (grf_z) or ``"resultant"`` (|(grf_x, grf_z)|).
    d0
        Pre-loading distance [m]; default from the unloaded samples before touch-down.
    contact_threshold
        Force [N] above which the blade is loaded (touch-down detection).
    min_compression
        Smallest Δd [m] at which K_c is defined.
    noise_factor
        K_c is also NaN where Δd < noise_factor × σ_d (σ_d: robust SD of the distance before
        touch-down);
        0 uses ``min_compression`` alone (e.g. for a simulated stance, with the threshold of its
        measured one).
    min_deflection
        |θ − θ0| [rad] below which K(t) is NaN.

    Returns
    -------
    StanceMechanics

    Raises
    ------
    DataError
        If the stance is never loaded, the distance has NaN during contact, or the angle
        inputs have the wrong shape.
    """
    n = len(stance.time)
    f = _force(stance, force)
    loaded = np.flatnonzero(f > contact_threshold)
    if len(loaded) == 0 or n < 3:
        raise DataError(
            f"the force never exceeds the contact threshold of {contact_threshold} N",
            where="stance.grf_z" if force == "vertical" else "stance.grf",
            hint="check the force channel and its units (N), or lower contact_threshold",
        )
    i0 = int(loaded[0])
    dist = stance.distance
    if np.any(~np.isfinite(dist[i0:])):
        raise DataError(
            "distance has NaN or inf after touch-down",
            where="stance.distance",
            hint="fill marker gaps of the clamp and tip markers before computing mechanics",
        )
    if d0 is None:
        before = dist[:i0][np.isfinite(dist[:i0])]
        d0 = float(np.median(before)) if len(before) else float(dist[i0])
    dd = d0 - dist
    pre = dist[:i0][np.isfinite(dist[:i0])]
    # robust SD (1.4826 × MAD about d0): the spread of the distance in flight, insensitive to the
    # few samples where the blade already moves just before touch-down
    noise = float(1.4826 * np.median(np.abs(pre - np.median(pre)))) if len(pre) >= 3 else 0.0
    threshold = max(float(min_compression), float(noise_factor) * noise)
    with np.errstate(divide="ignore", invalid="ignore"):
        kc = np.where(dd >= threshold, f / np.where(dd == 0, 1.0, dd), np.nan)
    # Energies from the last unloaded sample on (samples before it carry no force).
    start = max(i0 - 1, 0)
    loop_dd, loop_f = dd[start:], f[start:]
    ip = int(np.argmax(loop_dd))
    stored = _work(loop_f[: ip + 1], loop_dd[: ip + 1])
    returned = -_work(loop_f[ip:], loop_dd[ip:])
    efficiency = 100.0 * returned / stored if stored > 0 else float("nan")

    dtheta = ktors = None
    theta0 = peak_dtheta = k_peak = float("nan")
    if theta is None and (tip_x is not None or tip_z is not None):
        if tip_x is None or tip_z is None:
            raise DataError("give both tip_x and tip_z", where="tip", hint="pass both arrays [m]")
        for name, arr in (("tip_x", tip_x), ("tip_z", tip_z)):
            if np.shape(arr) != (n,):
                raise DataError(
                    f"has shape {np.shape(arr)}, expected ({n},) like stance.time", where=name
                )
        theta = blade_angle(stance.clamp_x, stance.clamp_z, stance.clamp_pitch, tip_x, tip_z)
    if theta is not None:
        theta = np.asarray(theta, float)
        if theta.shape != (n,):
            raise DataError(
                f"has shape {theta.shape}, expected ({n},) like stance.time", where="theta"
            )
        before = theta[:i0][np.isfinite(theta[:i0])]
        theta0 = float(np.median(before)) if len(before) else float(theta[i0])
        dtheta = theta0 - theta
        ipk = i0 + int(np.nanargmax(np.abs(dtheta[i0:])))
        peak_dtheta = float(dtheta[ipk])
        if hinge is not None and tip_x is not None:
            moment = _hinge_moment(
                stance, np.asarray(tip_x, float), np.asarray(tip_z, float), hinge
            )
            defl = theta - theta0
            with np.errstate(divide="ignore", invalid="ignore"):
                ktors = np.where(
                    np.abs(defl) >= min_deflection,
                    moment / np.where(defl == 0, 1.0, defl),
                    np.nan,
                )
            k_peak = float(ktors[ipk])
    return StanceMechanics(
        time=stance.time.copy(),
        force=f,
        compression=dd,
        compressive_stiffness=kc,
        angular_deformation=dtheta,
        torsional_stiffness=ktors,
        d0=float(d0),
        theta0=theta0,
        contact_index=i0,
        force_component=force,
        peak_force=float(np.max(f)),
        peak_compression=float(np.max(dd[i0:])),
        peak_compressive_stiffness=float(np.nanmax(kc)) if np.any(np.isfinite(kc)) else np.nan,
        peak_angular_deformation=peak_dtheta,
        torsional_stiffness_at_peak=k_peak,
        energy_stored=stored,
        energy_returned=returned,
        energy_dissipated=stored - returned,
        efficiency=efficiency,
        metadata=dict(stance.metadata),
        compression_threshold=threshold,
        distance_noise=noise,
        compressive_stiffness_at_peak_compression=float(kc[i0 + int(np.argmax(dd[i0:]))]),
    )


def _hinge_moment(
    stance: Stance, tip_x: np.ndarray, tip_z: np.ndarray, hinge: tuple[float, float]
) -> np.ndarray:
    """Moment of the GRF acting at the tip, about the hinge [N·m].

    Signed so that a force that compresses the blade (turns the clamp→tip line forward, θ up)
    gives a positive moment: M = −(r × F)_y with r = tip − hinge in the lab x–z plane.
    """
    hx, hz = hinge
    p = stance.clamp_pitch
    # Hinge to lab: clamp origin + R_y(pitch)·(hx, hz).
    lab_hx = stance.clamp_x + hx * np.cos(p) + hz * np.sin(p)
    lab_hz = stance.clamp_z - hx * np.sin(p) + hz * np.cos(p)
    rx, rz = tip_x - lab_hx, tip_z - lab_hz
    # (r × F)_y = r_z F_x − r_x F_z; compression moment is its negative (θ grows about −y).
    return -(rz * stance.grf_x - rx * stance.grf_z)


def mechanics_table(results: Sequence[StanceMechanics]) -> pd.DataFrame:
    """One row per stance with :meth:`StanceMechanics.to_dict` columns (a tidy table)."""
    return pd.DataFrame([r.to_dict() for r in results])
