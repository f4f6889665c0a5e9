"""Whole studies: ``study.yaml``, the ``results.sqlite`` store, executors and the batch runner.

See ``docs/study-yaml.md``.
"""

from bladelab.study.executors import LocalExecutor, RayExecutor, SerialExecutor, make_executor
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
    "LocalExecutor",
    "RayExecutor",
    "ResultsStore",
    "SerialExecutor",
    "Study",
    "StudyRun",
    "Trial",
    "load_study",
    "make_executor",
    "open_results",
    "parse_study",
    "run_study",
    "trial_seed",
    "variant_name",
]
