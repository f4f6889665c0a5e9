"""Measured data shipped inside bladelab, found through :mod:`importlib.resources`.

The package carries one public running dataset, so that the demo, ``bladelab predict --method
collocation --guess trial`` and the tests work from a clone or an installed wheel with nothing
beside them: Fukuchi, Fukuchi & Duarte (2017), "A public dataset of running biomechanics and the
effects of running speed on lower extremity kinematics and kinetics", PeerJ 5:e3298 (CC BY 4.0),
in ``bladelab/data/measured/fukuchi2017/`` with its licence and a README saying what each file is.

Every function returns a :class:`pathlib.Path` to a real file (read-only: write results elsewhere)
and raises :class:`~bladelab.errors.InputFileError` naming the file when the installation lacks it.
"""

from __future__ import annotations

import atexit
import contextlib
from importlib import resources
from pathlib import Path

from bladelab.errors import InputFileError

__all__ = [
    "MEASURED_SUBJECT_HEIGHT_M",
    "MEASURED_SUBJECT_MASS_KG",
    "MEASURED_TRIAL_SPEED_M_PER_S",
    "measured_file",
    "measured_forces_table",
    "measured_running_trial",
    "measured_static_trial",
    "measured_subject_table",
    "people_joint_angles_table",
]

#: Mass [kg] of subject RBDS001, the runner of :func:`measured_running_trial` (``RBDSinfo.txt``).
MEASURED_SUBJECT_MASS_KG = 62.0
#: Height [m] of subject RBDS001 (``RBDSinfo.txt``: 181 cm).
MEASURED_SUBJECT_HEIGHT_M = 1.81
#: Treadmill speed [m/s] of :func:`measured_running_trial`.
MEASURED_TRIAL_SPEED_M_PER_S = 3.5

_PACKAGE = "bladelab"
_FOLDER = ("data", "measured", "fukuchi2017")
# Files extracted from a zipped installation stay until the interpreter exits.
_EXTRACTED = contextlib.ExitStack()
atexit.register(_EXTRACTED.close)


def measured_file(name: str) -> Path:
    """The file ``name`` of ``bladelab/data/measured/fukuchi2017/`` as a filesystem path.

    Raises
    ------
    InputFileError
        The installation of bladelab lacks the file.
    """
    resource = resources.files(_PACKAGE).joinpath(*_FOLDER, name)
    if not resource.is_file():
        raise InputFileError(
            "bladelab's packaged data file is missing", file="/".join((_PACKAGE, *_FOLDER, name)),
            hint="the installation is incomplete: reinstall bladelab "
                 "(pip install --force-reinstall bladelab, or pip install -e . in a clone)")
    if isinstance(resource, Path):
        return resource
    return _EXTRACTED.enter_context(resources.as_file(resource))


def measured_running_trial() -> Path:
    """``RBDS001runT35.c3d``: subject RBDS001 (:data:`MEASURED_SUBJECT_MASS_KG` kg) running on an
    instrumented treadmill at :data:`MEASURED_TRIAL_SPEED_M_PER_S` m/s for 30 s: 32 markers at
    150 Hz, one type-4 force platform (6 channels at 300 Hz)."""
    return measured_file("RBDS001runT35.c3d")


def measured_static_trial() -> Path:
    """``RBDS001static.c3d``: the same subject standing (markers only, no force platform data);
    the zero posture of joint angles computed from :func:`measured_running_trial`."""
    return measured_file("RBDS001static.c3d")


def measured_forces_table() -> Path:
    """``RBDS0041runT252forces.txt``: another subject's (RBDS004) treadmill forces at 2.5 m/s, the
    dataset's tab-separated text export: ``Time Fx Fy Fz COPx COPy COPz Ty``, 9000 samples at
    300 Hz; forces [N] (vertical = ``Fy``), COP [mm], free moment ``Ty`` [N·mm]."""
    return measured_file("RBDS0041runT252forces.txt")


def measured_subject_table() -> Path:
    """``RBDSinfo.txt``: the dataset's tab-separated subject table (columns include ``Subject``,
    ``FileName``, ``Age`` [years], ``Height`` [cm], ``Mass`` [kg])."""
    return measured_file("RBDSinfo.txt")


def people_joint_angles_table() -> Path:
    """``people-3.5mps-joint-angles.csv``: two other subjects of the dataset (RBDS002, 80 kg,
    183 cm; RBDS003, 65.4 kg, 177 cm) running at 3.5 m/s, each one leg's mean pattern over 30 s
    (as processed by BioMAC-Sim-Toolbox, Apache-2.0): hip flexion, knee flexion and ankle
    dorsiflexion [deg] and vertical ground force [BW] over 100 samples of the stride from its
    heel strike; comma-separated with a header row (``stride_pct``, ``RBDS002_hip_flexion_deg``,
    ...)."""
    return measured_file("people-3.5mps-joint-angles.csv")
