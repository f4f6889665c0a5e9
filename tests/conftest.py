"""Shared fixtures: paths to the real data in ../shared/data."""

from __future__ import annotations

from pathlib import Path

import pytest

PROJECT_ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = PROJECT_ROOT.parent / "shared" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The folder ``../shared/data`` (real C3D files and reference models)."""
    if not SHARED_DATA.is_dir():
        pytest.fail(f"{SHARED_DATA} not found: clone bladelab beside the shared/ folder")
    return SHARED_DATA


FUKUCHI_RUN = "real/fukuchi2017/RBDS001runT35.c3d"
FUKUCHI_STATIC = "real/fukuchi2017/RBDS001static.c3d"


@pytest.fixture(scope="session")
def fukuchi_trials(shared_data):
    """The Fukuchi 3.5 m/s running trial and its static trial, in the same lab axes."""
    from bladelab.trial import read_c3d

    run = read_c3d(shared_data / FUKUCHI_RUN)
    ax = run.metadata["axes"]
    return run, read_c3d(shared_data / FUKUCHI_STATIC, forward=ax["forward"], up=ax["up"])


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
    """The predictive report of the shipped amputee Cat6 3.5 m/s solution (3 s re-simulated,
    exported for OpenSim), written once: its tables are checked in ``test_predict_report.py``
    and its animated runner played in ``test_report_animation.py`` (a report costs ~15 s,
    mostly drawing its figures)."""
    from bladelab.report.predictive import build_predictive_report

    solution = PROJECT_ROOT / "src" / "bladelab" / "data" / "runner" / "solutions"
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
