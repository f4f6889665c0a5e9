"""Write a runner simulation for other tools: CSV tables, OpenSim motion and external loads.

:func:`write_simulation` writes a folder of CSV tables and a JSON summary: ``states.csv``
(coordinates), ``grf.csv`` (per leg), ``events.csv`` (touch-downs and lift-offs),
``power_balance.csv``, ``muscles.csv`` and ``joint_powers.csv``; ``summary.json`` is
:func:`bladelab.runner.analyses.summary`.

:func:`write_opensim` writes what OpenSim and other musculoskeletal tools read
(docs/runner-model.md, "Export"):

- ``coordinates.mot``: the coordinates in OpenSim's names and conventions (rotations in degrees,
  ``inDegrees=yes``; ``pelvis_tx``/``pelvis_ty`` [m] locate the pelvis frame origin of SCONE's
  H0918 OpenSim model, 0.0707 m (×height/1.80 m) in front of the pelvis centre of mass);
- ``grf.mot``: the ground reaction force of each leg as OpenSim external loads, in the ground
  frame of OpenSim (x forward, y up, z to the right): ``ground_force_<side>_v{x,y,z}`` [N], the
  point of application ``ground_force_<side>_p{x,y,z}`` [m] (the centre of pressure on the
  ground) and ``ground_torque_<side>_{x,y,z}`` [N·m] (zero: the point is chosen so that the
  force alone has the contacts' moment); side ``l`` is the intact, ``r`` the prosthetic leg;
- ``external_loads.xml``: the OpenSim ``ExternalLoads`` that applies ``grf.mot`` to each foot
  (``calcn_l``/``calcn_r``) or to the prosthesis;
- ``states.csv``: every recorded state, one column per quantity with its unit in the name.

Any :class:`~bladelab.runner.RunnerResult` can be exported, whichever method produced it (a
forward simulation, a reflex-controlled one, or a trajectory built from a collocation solution
with the same fields). :func:`read_mot` reads a ``.mot``/``.sto`` file back (plain parser).
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np
import pandas as pd

from bladelab._io import atomic_open, write_json
from bladelab.errors import InputFileError
from bladelab.runner import analyses
from bladelab.runner.geometry import REFERENCE_HEIGHT_M
from bladelab.runner.layout import CP_BODY, CP_LEG
from bladelab.runner.simulate import (
    RC_DEPTH,
    RC_FX,
    RC_FZ,
    RC_PX,
    RC_PZ,
    RC_VX,
    RC_VZ,
    RunnerResult,
)

__all__ = [
    "OPENSIM_PELVIS_ORIGIN_M",
    "all_states",
    "leg_ground_force",
    "opensim_coordinates",
    "opensim_ground_forces",
    "read_mot",
    "write_mot",
    "write_opensim",
    "write_simulation",
]

#: Distance [m] of the pelvis frame origin in front of the pelvis centre of mass in SCONE's
#: H0918 OpenSim model (``H0918M_osim4.osim``: pelvis ``mass_center`` −0.0707 m), for the
#: 1.80 m reference athlete (scaled with the height).
OPENSIM_PELVIS_ORIGIN_M = 0.0707

_FLOAT = "%.9g"


def write_simulation(result: RunnerResult, out: str | Path, *, about: dict | None = None) -> dict:
    """Write ``result``'s tables and summary into the folder ``out`` (created; each file written
    atomically); returns the summary, with ``about`` (e.g. how it was simulated) added."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tables = {
        "states.csv": result.states(),
        "grf.csv": result.leg_grf(),
        "events.csv": analyses.gait_events(result),
        "power_balance.csv": analyses.power_balance(result),
        "muscles.csv": result.muscle_states(),
        "joint_powers.csv": analyses.joint_powers(result),
    }
    for name, df in tables.items():
        with atomic_open(out / name, "w", newline="") as fh:
            df.to_csv(fh, index=False)
    summary = {**analyses.summary(result), **(about or {})}
    write_json(out / "summary.json", summary)
    return summary


def _is_translation(dof: str) -> bool:
    return dof in ("pelvis_tx", "pelvis_tz")


def opensim_coordinates(result: RunnerResult) -> pd.DataFrame:
    """The coordinates as OpenSim names them: time [s], ``pelvis_tilt`` [deg], ``pelvis_tx``,
    ``pelvis_ty`` [m] (pelvis frame origin of the H0918 OpenSim model, see
    :data:`OPENSIM_PELVIS_ORIGIN_M`; bladelab's ``pelvis_tx``/``pelvis_tz`` locate the pelvis
    centre of mass), then every other coordinate in degrees in the model's order (hip flexion,
    knee angle, ankle angle or ``socket_angle_r``, ``lumbar_extension``; signs as OpenSim's).
    """
    model = result.model
    q = result.qpos
    tilt = q[:, model.dof("pelvis_tilt")]
    offset = OPENSIM_PELVIS_ORIGIN_M * model.params.athlete.height_m / REFERENCE_HEIGHT_M
    cols: dict[str, np.ndarray] = {"time": result.time, "pelvis_tilt": np.degrees(tilt)}
    cols["pelvis_tx"] = q[:, model.dof("pelvis_tx")] + offset * np.cos(tilt)
    cols["pelvis_ty"] = q[:, model.dof("pelvis_tz")] + offset * np.sin(tilt)
    for j, name in enumerate(model.dof_names):
        if name not in cols and not _is_translation(name):
            cols[name] = np.degrees(q[:, j])
    return pd.DataFrame(cols)


def leg_ground_force(result: RunnerResult, leg: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Horizontal and vertical ground reaction force Fx, Fz [N] of one leg (0: left/intact,
    1: right/prosthetic) per sample, and its centre of pressure x [m] on the ground (z = 0),
    placed so that the force alone has the moment of the leg's contact forces (no free torque);
    where the leg is unloaded, the mean x of its contact points."""
    cols = result.model.contact_params[:, CP_LEG] == leg
    c = result.contacts[:, cols, :]
    fx = c[:, :, RC_FX].sum(axis=1)
    fz = c[:, :, RC_FZ].sum(axis=1)
    # the moment about the origin of the contact forces, Σ(x·Fz − z·Fx), = cop·Fz on z = 0
    moment = (c[:, :, RC_PX] * c[:, :, RC_FZ] - c[:, :, RC_PZ] * c[:, :, RC_FX]).sum(axis=1)
    loaded = fz > 1e-9
    cop = np.where(loaded, moment / np.where(loaded, fz, 1.0), c[:, :, RC_PX].mean(axis=1))
    return fx, fz, cop


def opensim_ground_forces(result: RunnerResult) -> pd.DataFrame:
    """Ground reaction forces per leg as OpenSim external-load columns (ground frame of OpenSim:
    x forward, y up, z right): time [s]; for side ``r`` then ``l``: ``ground_force_<s>_vx, _vy,
    _vz`` [N], ``ground_force_<s>_px, _py, _pz`` [m] (centre of pressure on the ground; x is
    moment-preserving, so that the free torque is zero), ``ground_torque_<s>_x, _y, _z`` [N·m]."""
    n = len(result.time)
    cols: dict[str, np.ndarray] = {"time": result.time}
    zero = np.zeros(n)
    for leg, side in ((1, "r"), (0, "l")):
        fx, fz, cop = leg_ground_force(result, leg)
        cols |= {
            f"ground_force_{side}_vx": fx,
            f"ground_force_{side}_vy": fz,
            f"ground_force_{side}_vz": zero,
            f"ground_force_{side}_px": cop,
            f"ground_force_{side}_py": zero,
            f"ground_force_{side}_pz": zero,
        }
    for side in ("r", "l"):
        cols |= {f"ground_torque_{side}_{a}": zero for a in "xyz"}
    return pd.DataFrame(cols)


def all_states(result: RunnerResult) -> pd.DataFrame:
    """Every recorded state as one wide table, the unit in each column name: ``time_s``; per
    coordinate ``<dof>_rad`` or ``_m`` and ``<dof>_speed_rad_per_s`` or ``_m_per_s``; per muscle
    ``<muscle>_excitation``, ``_activation`` (dimensionless, 0–1), ``_fiber_length_m``,
    ``_fiber_velocity_m_per_s``, ``_tendon_force_N``, ``_mtu_length_m``,
    ``_mtu_velocity_m_per_s``; per contact ``<contact>_Fx_N``, ``_Fz_N``, ``_point_x_m``,
    ``_point_z_m``, ``_point_vx_m_per_s``, ``_point_vz_m_per_s``, ``_compression_m``; per joint
    ``<dof>_passive_torque_Nm`` (ligament, socket and blade springs)."""
    model = result.model
    cols: dict[str, np.ndarray] = {"time_s": result.time}
    for j, dof in enumerate(model.dof_names):
        unit = "m" if _is_translation(dof) else "rad"
        cols[f"{dof}_{unit}"] = result.qpos[:, j]
    for j, dof in enumerate(model.dof_names):
        unit = "m_per_s" if _is_translation(dof) else "rad_per_s"
        cols[f"{dof}_speed_{unit}"] = result.qvel[:, j]
    fields = (("activation", 0), ("fiber_length_m", 1), ("fiber_velocity_m_per_s", 2),
              ("tendon_force_N", 3))
    for i, m in enumerate(model.muscle_names):
        cols[f"{m}_excitation"] = result.excitation[:, i]
        for name, k in fields:
            cols[f"{m}_{name}"] = result.muscles[:, i, k]
        cols[f"{m}_mtu_length_m"] = result.mtu[:, i, 0]
        cols[f"{m}_mtu_velocity_m_per_s"] = result.mtu[:, i, 1]
    contact_fields = (("Fx_N", RC_FX), ("Fz_N", RC_FZ), ("point_x_m", RC_PX),
                      ("point_z_m", RC_PZ), ("point_vx_m_per_s", RC_VX),
                      ("point_vz_m_per_s", RC_VZ), ("compression_m", RC_DEPTH))
    for c, name in enumerate(model.contact_names):
        for field, k in contact_fields:
            cols[f"{name}_{field}"] = result.contacts[:, c, k]
    for j, dof in enumerate(model.dof_names):
        if not dof.startswith("pelvis"):
            cols[f"{dof}_passive_torque_Nm"] = result.ligament[:, j]
    return pd.DataFrame(cols)


def write_mot(table: pd.DataFrame, path: str | Path, *, name: str | None = None,
              in_degrees: bool = True) -> Path:
    """Write ``table`` (first column ``time`` [s]) as an OpenSim ``.mot`` file (version 1
    header: name, ``version=1``, ``nRows``, ``nColumns``, ``inDegrees``, ``endheader``; then
    tab-separated labels and rows), atomically. ``in_degrees`` declares the rotations' unit."""
    path = Path(path)
    lines = [
        name or path.stem,
        "version=1",
        f"nRows={len(table)}",
        f"nColumns={table.shape[1]}",
        f"inDegrees={'yes' if in_degrees else 'no'}",
        "endheader",
    ]
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")
        table.to_csv(fh, sep="\t", index=False, float_format=_FLOAT, lineterminator="\n")
    return path


def read_mot(path: str | Path) -> tuple[dict[str, str], pd.DataFrame]:
    """Read an OpenSim ``.mot``/``.sto`` file: (header ``key=value`` entries, plus ``name`` for
    the first line if it has no ``=``; the table with its column labels).

    Raises
    ------
    InputFileError
        No ``endheader`` line, or rows that do not match the labels.
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as err:
        raise InputFileError(f"cannot read ({err})", file=path) from None
    header: dict[str, str] = {}
    for k, line in enumerate(lines):
        text = line.strip()
        if text.lower() == "endheader":
            break
        if "=" in text:
            key, _, value = text.partition("=")
            header[key.strip()] = value.strip()
        elif k == 0:
            header["name"] = text
    else:
        raise InputFileError("no 'endheader' line", file=path, hint="is this an OpenSim file?")
    labels = lines[k + 1].split("\t") if "\t" in lines[k + 1] else lines[k + 1].split()
    rows = [r.split() for r in lines[k + 2 :] if r.strip()]
    bad = next((i for i, r in enumerate(rows) if len(r) != len(labels)), None)
    if bad is not None:
        raise InputFileError(f"row has {len(rows[bad])} values for {len(labels)} labels",
                             file=path, where=f"line {k + 3 + bad}")
    data = np.array(rows, dtype=float).reshape(len(rows), len(labels))
    return header, pd.DataFrame(data, columns=[lab.strip() for lab in labels])


def _external_loads_xml(result: RunnerResult, datafile: str) -> str:
    model = result.model
    forces = []
    for leg, side in ((1, "r"), (0, "l")):
        rows = model.contact_params[model.contact_params[:, CP_LEG] == leg]
        body = model.mj_model.body(int(rows[0, CP_BODY])).name
        forces.append(
            f'      <ExternalForce name="grf_{side}">\n'
            f"        <applied_to_body>{escape(body)}</applied_to_body>\n"
            "        <force_expressed_in_body>ground</force_expressed_in_body>\n"
            "        <point_expressed_in_body>ground</point_expressed_in_body>\n"
            f"        <force_identifier>ground_force_{side}_v</force_identifier>\n"
            f"        <point_identifier>ground_force_{side}_p</point_identifier>\n"
            f"        <torque_identifier>ground_torque_{side}_</torque_identifier>\n"
            f"        <data_source_name>{escape(datafile)}</data_source_name>\n"
            "      </ExternalForce>\n"
        )
    return (
        '<?xml version="1.0" encoding="UTF-8" ?>\n'
        '<OpenSimDocument Version="40000">\n'
        '  <ExternalLoads name="externalloads">\n'
        "    <objects>\n" + "".join(forces) + "    </objects>\n"
        "    <groups />\n"
        f"    <datafile>{escape(datafile)}</datafile>\n"
        "  </ExternalLoads>\n"
        "</OpenSimDocument>\n"
    )


def write_opensim(result: RunnerResult, out: str | Path, *, every: int = 1) -> dict[str, Path]:
    """Write ``coordinates.mot``, ``grf.mot``, ``external_loads.xml`` and ``states.csv`` (module
    docstring) into the folder ``out`` (created; each file atomically).

    Parameters
    ----------
    result
        The trajectory to export.
    out
        Output folder.
    every
        Keep every ``every``-th sample (1: all; e.g. 4 turns a 2 kHz record into 500 Hz).

    Returns
    -------
    dict
        ``{"coordinates": path, "grf": path, "external_loads": path, "states": path}``.
    """
    if not float(every).is_integer() or every < 1:
        raise ValueError(f"every must be a positive integer, not {every!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    pick = slice(None, None, int(every))
    paths = {
        "coordinates": write_mot(opensim_coordinates(result).iloc[pick], out / "coordinates.mot"),
        "grf": write_mot(opensim_ground_forces(result).iloc[pick], out / "grf.mot"),
    }
    xml = out / "external_loads.xml"
    with atomic_open(xml, "w", encoding="utf-8") as fh:
        fh.write(_external_loads_xml(result, "grf.mot"))
    paths["external_loads"] = xml
    with atomic_open(out / "states.csv", "w", newline="") as fh:
        all_states(result).iloc[pick].to_csv(fh, index=False, float_format=_FLOAT)
    paths["states"] = out / "states.csv"
    return paths
