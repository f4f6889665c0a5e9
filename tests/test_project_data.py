"""The project carries its data: nothing reads a folder beside the project, the measured trials
are package data found through importlib.resources, and commands write under the current folder,
never inside the installation."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pandas as pd
import pytest

import bladelab
from bladelab import datasets
from bladelab.errors import InputFileError

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "bladelab"

# A path into the data folder that once stood beside the project: its name after "../", before
# "/data", or quoted in a Path join (the name is spelled in two halves so that this file does not
# match itself; the English word alone is not a path and does not match).
_SHARED = "shar" + "ed"
OUTSIDE = re.compile(rb"\.\./" + _SHARED.encode() + rb"\b|\b" + _SHARED.encode()
                     + rb"/data\b|[\"']" + _SHARED.encode() + rb"[\"']\s*/")
SKIPPED = {"__pycache__", ".pytest_cache", ".ruff_cache"}
NEWLINE = b"\n"


def _files(folder: Path):
    for path in sorted(folder.rglob("*")):
        if path.is_file() and not SKIPPED & set(path.relative_to(ROOT).parts) \
                and not path.parent.name.endswith(".egg-info"):
            yield path


def test_no_file_reads_a_folder_beside_the_project():
    hits = []
    for folder in ("src", "tests", "benchmarks"):
        for path in _files(ROOT / folder):
            data = path.read_bytes()
            hits += [f"{path.relative_to(ROOT)}:{data.count(NEWLINE, 0, m.start()) + 1}"
                     for m in OUTSIDE.finditer(data)]
    assert not hits, "paths into a folder beside the project (copy the data into it): " \
        + ", ".join(hits)


def test_no_module_climbs_out_of_the_package_from_its_own_file():
    """``Path(__file__).parents[k]`` may reach ``bladelab/`` but never above it (an installed
    package has no project around it)."""
    climbing = []
    for path in PACKAGE.rglob("*.py"):
        depth = len(path.relative_to(PACKAGE).parts) - 1  # folders between bladelab/ and the file
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"__file__\)(?:\.resolve\(\))?\.parents\[(\d+)\]", text):
            if int(m.group(1)) > depth:
                climbing.append(f"{path.relative_to(ROOT)}: parents[{m.group(1)}]")
        for m in re.finditer(r"__file__\)(?:\.resolve\(\))?((?:\.parent)+)", text):
            if m.group(1).count(".parent") > depth + 1:
                climbing.append(f"{path.relative_to(ROOT)}: {m.group(0)}")
    assert not climbing, climbing


@pytest.mark.parametrize(("function", "name"), [
    (datasets.measured_running_trial, "RBDS001runT35.c3d"),
    (datasets.measured_static_trial, "RBDS001static.c3d"),
    (datasets.measured_forces_table, "RBDS0041runT252forces.txt"),
    (datasets.measured_subject_table, "RBDSinfo.txt"),
])
def test_measured_files_are_package_data(function, name):
    path = function()
    assert isinstance(path, Path) and path.is_file() and path.name == name
    # found through importlib.resources, inside the package, licence and README beside it
    resource = resources.files("bladelab").joinpath("data", "measured", "fukuchi2017", name)
    assert path == Path(str(resource))
    assert path.resolve().is_relative_to(Path(bladelab.__file__).resolve().parent)
    assert (path.parent / "LICENSE.txt").is_file() and (path.parent / "README.md").is_file()


def test_subject_constants_match_the_subject_table():
    info = pd.read_csv(datasets.measured_subject_table(), sep="\t")
    row = info.loc[info["FileName"] == datasets.measured_running_trial().name].iloc[0]
    assert row["Mass"] == datasets.MEASURED_SUBJECT_MASS_KG  # kg
    assert row["Height"] / 100.0 == pytest.approx(datasets.MEASURED_SUBJECT_HEIGHT_M)  # cm -> m


def test_a_missing_package_file_names_it_and_says_how_to_fix_it():
    with pytest.raises(InputFileError, match=r"fukuchi2017/absent\.c3d.*reinstall bladelab"):
        datasets.measured_file("absent.c3d")


def test_outputs_go_under_the_current_folder(tmp_path, monkeypatch):
    """The demo and ``bladelab example make`` write ``examples/...`` where they are run from
    (``make demo`` runs from the project root), read when called, not at import."""
    from bladelab.demo import examples_dir
    from bladelab.example.study import default_example_dir

    monkeypatch.chdir(tmp_path)
    assert examples_dir() == tmp_path / "examples"
    assert default_example_dir() == tmp_path / "examples" / "sprint-study"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert examples_dir() == elsewhere / "examples"
