"""Trial data: motion-capture trials, force platforms, stance windows and blade kinematics.

``read_c3d`` -> :class:`Trial` (lab frame, SI) -> ``detect_stances`` -> :class:`StanceEvent` ->
``extract_stance`` -> :class:`Stance` (written/read as a stance CSV); ``segment_lengths`` of
the legs from a static trial.
"""

from bladelab.trial.c3d import C3DWarning, plate_corners, read_c3d, write_c3d
from bladelab.trial.events import StanceEvent, classify_stances, combined_grf, detect_stances
from bladelab.trial.filters import fill_gaps, lowpass
from bladelab.trial.kinematics import (
    BladeKinematics,
    MarkerMap,
    blade_kinematics,
    compression,
    extract_stance,
    load_marker_map,
    stance_window,
)
from bladelab.trial.segments import SegmentLengths, SegmentMarkerMap, segment_lengths
from bladelab.trial.stance import STANCE_COLUMNS, Stance, read_stance_csv, write_stance_csv
from bladelab.trial.trial import ForcePlatform, Trial

__all__ = [
    "STANCE_COLUMNS",
    "BladeKinematics",
    "C3DWarning",
    "ForcePlatform",
    "MarkerMap",
    "SegmentLengths",
    "SegmentMarkerMap",
    "Stance",
    "StanceEvent",
    "Trial",
    "blade_kinematics",
    "classify_stances",
    "combined_grf",
    "compression",
    "detect_stances",
    "extract_stance",
    "fill_gaps",
    "load_marker_map",
    "lowpass",
    "plate_corners",
    "read_c3d",
    "read_stance_csv",
    "segment_lengths",
    "stance_window",
    "write_c3d",
    "write_stance_csv",
]
