"""Stance CSV: round trip, documented format, and the wrong-input errors."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.errors import DataError, InputFileError
from bladelab.trial.stance import STANCE_COLUMNS, Stance, read_stance_csv, write_stance_csv


def _stance(n=200):
    t = np.arange(n) / 1000.0
    tau = t / t[-1]
    return Stance(
        time=t, clamp_x=0.3 + 2.0 * t, clamp_y=np.full(n, 0.1), clamp_z=0.45 - 0.03 * np.sin(np.pi * tau),
        clamp_pitch=np.deg2rad(-30 + 70 * tau), grf_x=-200 * np.sin(2 * np.pi * tau),
        grf_y=np.zeros(n), grf_z=2000 * np.sin(np.pi * tau), distance=0.40 - 0.05 * np.sin(np.pi * tau),
        metadata={"athlete": "TT1", "category": 5, "speed_pct_pb": 95.5},
    )


def test_round_trip_and_format(tmp_path):
    st = _stance()
    path = write_stance_csv(st, tmp_path / "s.csv")
    lines = path.read_text().splitlines()
    assert lines[0].startswith("# bladelab stance CSV")
    assert "# athlete: TT1" in lines
    header = next(line for line in lines if not line.startswith("#"))
    assert header == ",".join(STANCE_COLUMNS)
    # pitch is in degrees in the file
    first = lines[lines.index(header) + 1].split(",")
    assert float(first[STANCE_COLUMNS.index("clamp_pitch")]) == pytest.approx(-30.0)
    back = read_stance_csv(path)
    for name in STANCE_COLUMNS:
        np.testing.assert_allclose(getattr(back, name), getattr(st, name), rtol=1e-8, atol=1e-9)
    assert back.metadata["category"] == 5 and back.metadata["speed_pct_pb"] == 95.5


def _write(tmp_path, header, rows):
    path = tmp_path / "user.csv"
    path.write_text(header + "\n" + "\n".join(",".join(f"{v:.6g}" for v in r) for r in rows) + "\n")
    return path


def _rows(st, scale=None):
    cols = [st.column(c) * (scale.get(c, 1.0) if scale else 1.0) for c in STANCE_COLUMNS]
    return np.column_stack(cols)


def test_missing_column(tmp_path):
    st = _stance()
    rows = np.delete(_rows(st), STANCE_COLUMNS.index("distance"), axis=1)
    path = _write(tmp_path, ",".join(c for c in STANCE_COLUMNS if c != "distance"), rows)
    with pytest.raises(DataError, match="missing column.*distance") as err:
        read_stance_csv(path)
    assert str(path) in str(err.value)


@pytest.mark.parametrize(
    ("scale", "column", "unit"),
    [
        ({"clamp_x": 1000.0, "clamp_y": 1000.0, "clamp_z": 1000.0},
         "columns clamp_x, clamp_y, clamp_z", "millimetres"),
        ({"distance": 1000.0}, "column distance", "millimetres"),
        ({"time": 1000.0}, "column time", "ms"),
        ({"grf_x": 1e-3, "grf_y": 1e-3, "grf_z": 1e-3}, "column grf_z", "kN"),
        ({"clamp_pitch": np.pi / 180.0}, "column clamp_pitch", "rad"),
    ],
)
def test_wrong_units(tmp_path, scale, column, unit):
    path = _write(tmp_path, ",".join(STANCE_COLUMNS), _rows(_stance(), scale))
    with pytest.raises(DataError, match=unit) as err:
        read_stance_csv(path)
    assert column in str(err.value)


@pytest.mark.parametrize(("scale", "unit", "divide"), [(100.0, "centimetres", 100),
                                                        (1000.0, "millimetres", 1000)])
def test_clamp_positions_in_cm_or_mm_are_refused_with_the_likely_unit(tmp_path, scale, unit,
                                                                       divide):
    # 45 cm reads as a clamp 45 m above the ground: under the old ">100 is mm" rule it passed
    # as metres and identification ran to K* at its upper bound with exit status 0
    st = _stance()
    path = _write(tmp_path, ",".join(STANCE_COLUMNS),
                  _rows(st, {"clamp_x": scale, "clamp_y": scale, "clamp_z": scale}))
    with pytest.raises(DataError) as err:
        read_stance_csv(path)
    message = str(err.value)
    assert f"clamp positions look like {unit}, not metres" in message
    assert f"clamp_z up to {0.45 * scale:.4g}" in message
    assert f"divide by {divide}" in message and str(path) in message


def test_clamp_positions_in_cm_with_a_distance_in_metres(tmp_path):
    path = _write(tmp_path, ",".join(STANCE_COLUMNS),
                  _rows(_stance(), {"clamp_z": 100.0}))  # z alone in cm: 45 "m" high
    with pytest.raises(DataError, match="look like centimetres"):
        read_stance_csv(path)
    fast = _stance()  # a clamp crossing 40 m in 0.2 s is not a runner's
    path = _write(tmp_path, ",".join(STANCE_COLUMNS), _rows(fast, {"clamp_x": 100.0}))
    with pytest.raises(DataError, match=r"look like centimetres.*\(200 m/s\)"):
        read_stance_csv(path)


def test_non_finite_and_missing_file(tmp_path):
    rows = _rows(_stance())
    rows[10, STANCE_COLUMNS.index("grf_z")] = np.nan
    path = _write(tmp_path, ",".join(STANCE_COLUMNS), rows)
    with pytest.raises(DataError, match="row 11"):
        read_stance_csv(path)
    with pytest.raises(InputFileError):
        read_stance_csv(tmp_path / "nope.csv")
