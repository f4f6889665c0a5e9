"""Shared file input and output: atomic writes with the umask's mode, readers naming the file."""

from __future__ import annotations

import os
import stat

import pytest

from bladelab._io import atomic_open, read_json, read_yaml, write_json
from bladelab.errors import InputFileError


def test_finished_files_get_the_umask_mode_not_0600(tmp_path):
    old = os.umask(0o022)
    try:
        write_json(tmp_path / "a.json", {"x": 1})
        with atomic_open(tmp_path / "b.txt") as fh:
            fh.write("hello")
    finally:
        os.umask(old)
    for name in ("a.json", "b.txt"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o644, name
    assert not list(tmp_path.glob("*.part"))


def test_readers_return_content_and_name_the_file_on_errors(tmp_path):
    write_json(tmp_path / "ok.json", {"K_Nm_per_deg": 18.0})
    assert read_json(tmp_path / "ok.json") == {"K_Nm_per_deg": 18.0}
    (tmp_path / "ok.yaml").write_text("a: 1\nb: [2, 3]\n")
    assert read_yaml(tmp_path / "ok.yaml") == {"a": 1, "b": [2, 3]}

    with pytest.raises(InputFileError, match="blade spec not found") as err:
        read_yaml(tmp_path / "missing.yaml", what="blade spec")
    assert "missing.yaml" in str(err.value)
    (tmp_path / "bad.json").write_text('{"a": 1,\n "b": }\n')
    with pytest.raises(InputFileError, match=r"not valid JSON: .* line 2, column 7") as err:
        read_json(tmp_path / "bad.json")
    assert "bad.json" in str(err.value)
    (tmp_path / "bad.yaml").write_text("a: 1\nb: [2, 3\nc: 4\n")
    with pytest.raises(InputFileError, match=r"not valid YAML: .* line \d+, column \d+") as err:
        read_yaml(tmp_path / "bad.yaml", hint="fix the list")
    assert "bad.yaml" in str(err.value) and "fix the list" in str(err.value)
    (tmp_path / "latin1.json").write_bytes(b'{"a": "\xe9"}')
    with pytest.raises(InputFileError, match="cannot read the JSON file"):
        read_json(tmp_path / "latin1.json")


def test_writing_onto_a_folder_is_refused_naming_it(tmp_path):
    (tmp_path / "out").mkdir()
    with pytest.raises(InputFileError, match="is a folder, not a file name") as err:
        write_json(tmp_path / "out", {"x": 1})
    assert "out" in str(err.value) and (tmp_path / "out").is_dir()
