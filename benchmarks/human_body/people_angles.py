"""Write bladelab's packaged joint angles of people running at 3.5 m/s from BioMAC-Sim-Toolbox's
processed Fukuchi et al. (2017) trials (a one-off conversion; its output is committed).

Usage (repository root)::

    .venv/bin/python benchmarks/human_body/people_angles.py BIOMAC_DATA_FOLDER

``BIOMAC_DATA_FOLDER`` is ``data/IntroductionExamples/`` of a checkout of
mad-lab-fau/BioMAC-Sim-Toolbox (Apache-2.0), which holds ``RBDS00<k>runT35.mat``: each
subject's mean pattern of 30 s of treadmill running at 3.5 m/s (Fukuchi et al. 2017, CC BY 4.0),
a MATLAB table of hip, knee and ankle angles [rad] and ground forces [BW] over half a gait
cycle from the right heel strike (50 samples; the two legs' halves make the whole cycle, the
dataset's patterns being symmetric). Writes
``src/bladelab/data/measured/fukuchi2017/people-3.5mps-joint-angles.csv``: per subject
RBDS002 and RBDS003 (not RBDS001, the trial the predicted strides are checked against), one
leg's hip flexion, knee flexion and ankle dorsiflexion [deg] and vertical ground force [BW]
over 100 samples of the stride from its heel strike.
"""

from __future__ import annotations

import io
import sys
from pathlib import Path

import numpy as np
import scipy.io as sio
from scipy.io.matlab._mio5 import MatFile5Reader

SUBJECTS = ("RBDS002", "RBDS003")
OUT = Path("src/bladelab/data/measured/fukuchi2017/people-3.5mps-joint-angles.csv")


def read_table(path: Path) -> dict[str, np.ndarray]:
    """The ``variables`` table of a BioMAC data file: name -> mean over the samples. MATLAB
    stores a table as an opaque object in the file's function workspace, a MAT stream of its
    own that scipy reads once told its byte order."""
    workspace = sio.loadmat(path)["__function_workspace__"].tobytes()
    reader = MatFile5Reader(io.BytesIO(workspace), byte_order="<", squeeze_me=True,
                            struct_as_record=False)
    reader.mat_stream.seek(8)
    reader.initialize_read()
    header, _ = reader.read_var_header()
    names, _types, means, _vars, _units = reader.read_var_array(header).MCOS[0][3][10]
    return {str(n): np.asarray(m, float) for n, m in zip(names, means, strict=True)}


def whole_cycle(table: dict[str, np.ndarray], name: str) -> np.ndarray:
    """The right leg's values over the whole cycle from its heel strike: its own half, then
    the left leg's half (symmetric patterns)."""
    return np.concatenate([table[f"{name}_r"], table[f"{name}_l"]])


def main() -> None:
    folder = Path(sys.argv[1])
    columns = {"stride_pct": np.arange(100.0)}
    for subject in SUBJECTS:
        t = read_table(folder / f"{subject}runT35.mat")
        columns[f"{subject}_hip_flexion_deg"] = np.degrees(whole_cycle(t, "hip_flexion"))
        columns[f"{subject}_knee_flexion_deg"] = -np.degrees(whole_cycle(t, "knee_angle"))
        columns[f"{subject}_ankle_dorsiflexion_deg"] = np.degrees(whole_cycle(t, "ankle_angle"))
        columns[f"{subject}_vertical_grf_bw"] = whole_cycle(t, "GRF_y")
    header = ",".join(columns)
    rows = np.column_stack(list(columns.values()))
    np.savetxt(OUT, rows, delimiter=",", header=header, comments="", fmt="%.4f")
    print(f"wrote {OUT} ({rows.shape[0]} samples, {len(columns) - 1} columns)")


if __name__ == "__main__":
    main()
