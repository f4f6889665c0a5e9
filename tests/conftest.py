"""Fixtures and the paths of the real data files the tests read.

The measured running dataset (Fukuchi et al. 2017) is package data, found through
:mod:`bladelab.datasets`; OpenSim's walking trials and SCONE's H0918 model are test data in
``tests/data/`` (each folder with its licence and a README).

The collocation NLPs map the node function compiled to C, the library's default (about 10 s per
model and objective, once: the cache is shared by the test workers and kept between runs),
which is faster than building every NLP's expanded interpreted graph (measured: the collocation
tests 363 s against 398 s on a cold cache; test_collocation_solution.py 70 s against 135 s on a
warm one). ``BLADELAB_COMPILE=0`` runs them interpreted.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bladelab.datasets import (
    measured_forces_table,
    measured_running_trial,
    measured_static_trial,
    measured_subject_table,
)

PROJECT_ROOT = Path(__file__).resolve().parents[1]
#: Test-only data files (not shipped in the package).
TEST_DATA = Path(__file__).resolve().parent / "data"

#: Subject RBDS001 (62 kg) running on a treadmill at 3.5 m/s, and standing (package data).
FUKUCHI_RUN = measured_running_trial()
FUKUCHI_STATIC = measured_static_trial()
#: The dataset's subject table and subject RBDS004's treadmill forces at 2.5 m/s (package data).
FUKUCHI_INFO = measured_subject_table()
FUKUCHI_FORCES = measured_forces_table()
#: Two overground walking trials from OpenSim's test data (two type-2 force platforms).
WALKING = (TEST_DATA / "opensim-walking" / "walking2.c3d",
           TEST_DATA / "opensim-walking" / "walking5.c3d")
#: SCONE's planar H0918 model (OpenSim 4 and Hyfydy files).
SCONE_H0918 = TEST_DATA / "scone-h0918"


@pytest.fixture(scope="session")
def fukuchi_trials():
    """The Fukuchi 3.5 m/s running trial and its static trial, in the same lab axes."""
    from bladelab.trial import read_c3d

    run = read_c3d(FUKUCHI_RUN)
    ax = run.metadata["axes"]
    return run, read_c3d(FUKUCHI_STATIC, forward=ax["forward"], up=ax["up"])


@pytest.fixture(scope="session")
def ray_instance():
    """One local Ray instance (2 CPUs) for every Ray test of the session (started once: Ray's
    start-up is most of a Ray test's time); bladelab's Ray executor uses a running instance."""
    ray = pytest.importorskip("ray", reason="ray not installed (pip install bladelab[ray])")
    from bladelab.executors import start_local_ray

    started = start_local_ray(2)
    yield ray
    if started:
        ray.shutdown()


@pytest.fixture(scope="session")
def shipped_amputee_report(tmp_path_factory):
    """The predictive report of seed 001's amputee Cat6 3.5 m/s reflex gait (a reflex start) (3 s re-simulated,
    exported for OpenSim), written once: its tables are checked in ``test_predict_report.py``
    and its animated runner played in ``test_report_animation.py`` (a report costs ~15 s,
    mostly drawing its figures)."""
    from bladelab.report.predictive import build_predictive_report

    solution = PROJECT_ROOT / "src" / "bladelab" / "data" / "runner" / "reflex-starts"
    return build_predictive_report(solution / "amputee-Cat6-3.5.json",
                                   tmp_path_factory.mktemp("amputee") / "r", duration=3.0,
                                   progress=False, export=True)


#: Mesh intervals of the fake collocation solutions (``collocation_fake``).
FAKE_MESH = 12


@pytest.fixture(scope="module")
def fakes():
    """Per model kind: (runner, a converged-looking collocation solution on FAKE_MESH
    intervals at 3.5 m/s) (``collocation_fake.fake_models``)."""
    from collocation_fake import fake_models

    return fake_models(FAKE_MESH)


@pytest.fixture
def fake_solve(fakes, monkeypatch):
    """The collocation continuation's solve replaced by a ``collocation_fake.FakeSolve``."""
    from collocation_fake import install_fake_solve

    return install_fake_solve(fakes, monkeypatch)
