"""What a blade simulation returns: :class:`SimResult` (one parameter set) and
:class:`BatchResult` (many), on the stance's time base, in SI units."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from bladelab import units
from bladelab._io import atomic_open
from bladelab.parameters import JOINT_PARAMETERS

__all__ = ["BatchResult", "SimResult", "write_simulation_csv"]


@dataclasses.dataclass(frozen=True, eq=False)
class SimResult:
    """Outputs of one simulation on the stance's time base (SI units).

    Attributes
    ----------
    time
        [s], (n,).
    grf_x, grf_z
        Ground reaction force on the blade [N], (n,).
    grf_elements
        (n, n_soles, 2) force (x, z) on each sole ellipse [N].
    distance
        Characteristic distance |tip − clamp origin| [m], (n,).
    deflection
        (n, n_joints) joint angle q [rad]: rotation of the distal body relative to the proximal
        one about +y, 0 at the undeformed posture.
    torque
        (n, n_joints) spring-damper torque on the distal body [N·m].
    contact_state
        (n, n_soles) 0 no contact, 1 stick (|slip| ≤ critical velocity), 2 slip.
    energy
        ``term -> (n,)`` [J]: clamp_work (cumulative), kinetic, potential_gravity, spring,
        contact_elastic (contact law and track spring), dissipated_joint / dissipated_contact /
        dissipated_friction / dissipated_track (cumulative; the track damper, 0 on rigid ground).
    stiffness, damping, stiffness_quadratic
        Joint parameters used [N·m/rad], [N·m·s/rad], [N·m/rad²].
    engine
        ``"kernel"`` or ``"mujoco"``.
    dt
        Integration step [s].
    """

    time: np.ndarray
    grf_x: np.ndarray
    grf_z: np.ndarray
    grf_elements: np.ndarray
    distance: np.ndarray
    deflection: np.ndarray
    torque: np.ndarray
    contact_state: np.ndarray
    energy: dict[str, np.ndarray]
    stiffness: np.ndarray
    damping: np.ndarray
    stiffness_quadratic: np.ndarray
    engine: str
    dt: float

    @property
    def grf_total(self) -> np.ndarray:
        """|GRF| in the x–z plane [N]."""
        return np.hypot(self.grf_x, self.grf_z)

    def energy_balance_error(self) -> np.ndarray:
        """Clamp work minus (Δ stored energy + dissipated energy) [J] at every sample."""
        e = self.energy
        stored = e["kinetic"] + e["potential_gravity"] + e["spring"] + e["contact_elastic"]
        dissipated = sum(v for k, v in e.items() if k.startswith("dissipated_"))
        return e["clamp_work"] - (stored - stored[0]) - dissipated

    def to_dict(self) -> dict[str, Any]:
        """Plain-Python summary: parameters (literature units too) and the signals as lists."""
        return {
            "engine": self.engine,
            "dt_s": self.dt,
            "K_Nm_per_rad": self.stiffness.tolist(),
            "D_Nms_per_rad": self.damping.tolist(),
            "K2_Nm_per_rad2": self.stiffness_quadratic.tolist(),
            "K_Nm_per_deg": np.atleast_1d(units.stiffness_per_rad_to_per_deg(self.stiffness)).tolist(),
            "D_Nms_per_deg": np.atleast_1d(units.damping_per_rad_to_per_deg(self.damping)).tolist(),
            "signals": self.to_frame().to_dict(orient="list"),
        }

    def to_frame(self) -> pd.DataFrame:
        """One row per sample; units in the column names (deflection in deg, as at the edges)."""
        cols: dict[str, np.ndarray] = {
            "time_s": self.time,
            "grf_x_N": self.grf_x,
            "grf_z_N": self.grf_z,
            "grf_total_N": self.grf_total,
            "distance_m": self.distance,
        }
        for j in range(self.deflection.shape[1]):
            cols[f"deflection_deg_j{j + 1}"] = units.rad2deg(self.deflection[:, j])
            cols[f"torque_Nm_j{j + 1}"] = self.torque[:, j]
        for e in range(self.grf_elements.shape[1]):
            cols[f"grf_x_N_s{e + 1}"] = self.grf_elements[:, e, 0]
            cols[f"grf_z_N_s{e + 1}"] = self.grf_elements[:, e, 1]
            cols[f"contact_state_s{e + 1}"] = self.contact_state[:, e].astype(int)
        for name, values in self.energy.items():
            cols[f"energy_{name}_J"] = values
        return pd.DataFrame(cols)


def write_simulation_csv(result: SimResult, path: str | Path, *, blade: str = "",
                         stance: str | Path = "") -> Path:
    """Write a simulation as CSV (atomically): ``#`` header lines (blade, stance, engine, time
    step [s], the joints' K* [N·m/deg] and D* [N·m·s/deg]) and one row per sample
    (:meth:`SimResult.to_frame`, units in the column names). Read it back with
    ``pandas.read_csv(path, comment="#")``."""
    path = Path(path)
    k_used = np.atleast_1d(JOINT_PARAMETERS["K"].to_edge(result.stiffness))
    d_used = np.atleast_1d(JOINT_PARAMETERS["D"].to_edge(result.damping))
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("# bladelab simulation\n")
        fh.write(f"# blade: {blade}\n# stance: {stance}\n# engine: {result.engine}\n")
        fh.write(f"# dt_s: {result.dt:.6g}\n")
        for key, used in ((JOINT_PARAMETERS["K"].edge_key, k_used),
                          (JOINT_PARAMETERS["D"].edge_key, d_used)):
            fh.write(f"# {key}: " + ",".join(f"{v:.6g}" for v in used) + "\n")
        result.to_frame().to_csv(fh, index=False, float_format="%.9g")
    return path


@dataclasses.dataclass(frozen=True, eq=False)
class BatchResult:
    """Outputs of many parameter sets of one problem (SI units).

    ``grf_x``, ``grf_z``, ``distance``: (n_sets, n_samples); ``deflection``, ``torque``:
    (n_sets, n_samples, n_joints); ``ok``: (n_sets,) False where the simulation diverged even
    with the smaller retry steps (its rows are NaN); ``time`` (n_samples,) [s]; ``refined``:
    (n_sets,) True where the set diverged at the problem's step and was simulated again with a
    smaller one (:data:`RETRY_STEP_FACTORS`).
    """

    time: np.ndarray
    grf_x: np.ndarray
    grf_z: np.ndarray
    distance: np.ndarray
    deflection: np.ndarray
    torque: np.ndarray
    ok: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    stiffness_quadratic: np.ndarray
    refined: np.ndarray | None = None

    @property
    def n_sets(self) -> int:
        """Number of parameter sets."""
        return self.grf_x.shape[0]

    def to_dict(self) -> dict[str, Any]:
        """Parameters and a per-set summary (peak GRF [N], minimum distance [m])."""
        return {
            "K_Nm_per_rad": self.stiffness.tolist(),
            "D_Nms_per_rad": self.damping.tolist(),
            "ok": self.ok.tolist(),
            "peak_grf_z_N": np.nanmax(self.grf_z, axis=1).tolist(),
            "min_distance_m": np.nanmin(self.distance, axis=1).tolist(),
        }

