"""The command line: trial commands, and the generic error path (exit 2, no traceback)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import trial_synth as synth
from bladelab.cli import main
from bladelab.trial.stance import read_stance_csv
from conftest import FUKUCHI_RUN as FUKUCHI
from conftest import FUKUCHI_STATIC


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "s.c3d"
    synth.write_single_plate(path)
    return path


def test_info(capsys):
    assert main(["trial", "info", str(FUKUCHI)]) == 0
    out = capsys.readouterr().out
    assert "platform 1: type 4, 300 Hz" in out and "R.Heel.Bottom" in out and "units mm" in out
    assert main(["trial", "info", str(FUKUCHI), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["marker_rate_Hz"] == 150.0 and info["platforms"][0]["type"] == 4
    assert info["platforms"][0]["channels"] == ["F1X", "F1Y", "F1Z", "M1X", "M1Y", "M1Z"]


def test_segments_of_a_static_trial(capsys):
    """``bladelab trial segments``: the static trial's thighs and shanks in metres (what
    ``predict --static`` uses); a trial without the knee markers says so, and its JSON holds
    null, not NaN."""
    from bladelab.trial import read_c3d, segment_lengths

    assert main(["trial", "segments", str(FUKUCHI_STATIC), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    want = segment_lengths(read_c3d(FUKUCHI_STATIC))
    assert data["thigh_m"] == pytest.approx(want.thigh_m) and data["shank_m"]["left"] > 0.4
    assert main(["trial", "segments", str(FUKUCHI_STATIC)]) == 0
    assert f"left leg:     thigh {want.thigh_m['left']:.3f} m" in capsys.readouterr().out
    assert main(["trial", "segments", str(FUKUCHI)]) == 0
    assert "thigh none (no epicondyle markers)" in capsys.readouterr().out
    assert main(["trial", "segments", str(FUKUCHI), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["thigh_m"] == {"left": None, "right": None}


def test_stances_json(synthetic, capsys):
    assert main(["trial", "stances", str(synthetic), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == 1
    row = rows[0]
    for key in ("index", "plates", "start_s", "end_s", "contact_time_s", "peak_fz_N", "impulse_z_Ns"):
        assert key in row
    assert row["plates"] == [1]
    assert row["index"] == 1  # stance numbers count from 1 at the command line
    assert row["start_s"] == pytest.approx(synth.TD, abs=2e-3)
    assert row["peak_fz_N"] == pytest.approx(synth.PEAK, rel=5e-3)


def test_stances_table_and_threshold(synthetic, capsys):
    assert main(["trial", "stances", str(synthetic), "--tip", "BLADE_TIP"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split()[:3] == ["index", "plates", "start_s"] and out[1].split()[-1] == "yes"
    assert main(["trial", "stances", str(synthetic), "--threshold", "5000"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and "no stance found" in err and "Traceback" not in err


def test_extract(synthetic, tmp_path, capsys):
    out = tmp_path / "stance.csv"
    assert main(["trial", "extract", str(synthetic), "--stance", "1", "--out", str(out)]) == 0
    st = read_stance_csv(out)
    assert st.sample_rate == pytest.approx(1000.0)
    assert st.grf_z.max() == pytest.approx(synth.PEAK, rel=0.02)
    assert st.metadata["stance"] == 1  # the header numbers the stance as --stance does
    t = st.time + st.metadata["window_start_s"]
    np.testing.assert_allclose(st.clamp_pitch, synth.clamp_pitch(t), atol=np.deg2rad(0.3))


def test_extract_with_marker_map_and_errors_leave_no_file(synthetic, tmp_path, capsys):
    mapping = tmp_path / "map.yaml"
    mapping.write_text("clamp_anterior: CLAMP_ANT\nclamp_posterior: CLAMP_POST\ntip: TOE\n")
    out = tmp_path / "stance.csv"
    code = main(["trial", "extract", str(synthetic), "--stance", "1", "--out", str(out),
                 "--markers", str(mapping)])
    assert code == 2
    err = capsys.readouterr().err
    assert "no marker named 'TOE'" in err and "BLADE_TIP" in err
    assert list(tmp_path.iterdir()) == [mapping]  # no output, no temporary file
    code = main(["trial", "extract", str(synthetic), "--stance", "7", "--out", str(out)])
    assert code == 2 and not out.exists()
    # numbered from 1 in the message too, as `--stance 7` and `bladelab trial stances` count
    assert "no stance 7: the trial has 1 stance (stance 1)" in capsys.readouterr().err
    code = main(["trial", "extract", str(synthetic), "--stance", "0", "--out", str(out)])
    assert code == 2 and not out.exists()  # stance numbers start at 1


def test_bad_file_exit_2(tmp_path, capsys):
    bad = tmp_path / "x.c3d"
    bad.write_text("hello" * 200)
    for cmd in ("info", "stances"):
        assert main(["trial", cmd, str(bad)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: {bad}: not a C3D file")


def _run(*args):
    return subprocess.run([sys.executable, "-m", "bladelab", *args], capture_output=True, text=True,
                          timeout=120)


def test_error_path_in_a_real_process(tmp_path):
    """Exit status 2, one line on stderr, no traceback; --debug shows the traceback."""
    bad = tmp_path / "x.c3d"
    bad.write_text("hello" * 200)
    proc = _run("trial", "info", str(bad))
    assert proc.returncode == 2
    assert proc.stderr.startswith("error:") and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    for args in (("--debug", "trial", "info", str(bad)), ("trial", "info", str(bad), "--debug")):
        proc = _run(*args)  # --debug before or after the sub-command
        assert proc.returncode != 0
        assert "Traceback" in proc.stderr and "InputFileError" in proc.stderr


def test_units_in_brackets_stay_visible_in_help(capsys):
    assert main(["blade", "segment", "--help"]) == 0
    assert "[mm²/mm]" in capsys.readouterr().out


def test_usage_error_exit_2(capsys):
    assert main(["trial", "extract"]) == 2
