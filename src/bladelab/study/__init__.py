"""Whole studies: ``study.yaml``, the ``results.sqlite`` store and the batch runner (its tasks run
on :mod:`bladelab.executors`).

See ``docs/study-yaml.md``.
"""

from bladelab.study.runner import StudyRun, run_study, trial_seed, variant_name
from bladelab.study.spec import (
    Athlete,
    BladeEntry,
    Configuration,
    Study,
    Trial,
    load_study,
    parse_study,
)
from bladelab.study.store import ResultsStore, open_results

__all__ = [
    "Athlete",
    "BladeEntry",
    "Configuration",
    "ResultsStore",
    "Study",
    "StudyRun",
    "Trial",
    "load_study",
    "open_results",
    "parse_study",
    "run_study",
    "trial_seed",
    "variant_name",
]
