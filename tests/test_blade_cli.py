"""``bladelab blade list/show/segment``: output, exit status 2 on bad input, atomic outputs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml

from bladelab.blade import load_blade
from bladelab.cli import main


def _run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["blade", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_list(capsys):
    code, out, _ = _run(capsys, "list")
    assert code == 0
    for name in ("xceed-cat2", "xtreme-cat4", "xtreme-cat5", "xtreme-cat6"):
        assert name in out
    assert "K_Nm_per_deg" in out
    code, out, _ = _run(capsys, "list", "--json")
    rows = json.loads(out)
    assert {r["name"] for r in rows} >= {"xceed-cat2", "xtreme-cat5"}


def test_show_reports_K_in_literature_units(capsys):
    code, out, _ = _run(capsys, "show", "xtreme-cat4")
    assert code == 0
    assert "K = 16.00 N·m/deg" in out
    assert "between segments 7 and 8" in out
    code, out, _ = _run(capsys, "show", "xtreme", "--json")
    data = json.loads(out)
    assert data["joints"][0]["K_Nm_per_deg"] == pytest.approx(18.0)
    assert data["n_segments"] == load_blade("xtreme").build().n_segments


def test_show_yaml_is_a_valid_spec(capsys, tmp_path):
    code, out, _ = _run(capsys, "show", "xceed", "--yaml")
    assert code == 0
    f = tmp_path / "copy.yaml"
    f.write_text(out, encoding="utf-8")
    assert yaml.safe_load(out)["name"] == "xceed"
    code, out2, _ = _run(capsys, "show", str(f))
    assert code == 0 and "xceed-cat2" in out2


def test_show_plot_writes_an_image(capsys, tmp_path):
    png = tmp_path / "fig" / "xceed.png"
    code, _, _ = _run(capsys, "show", "xceed", "--plot", str(png))
    assert code == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(png.parent.glob("*.part"))


def test_segment_csv(capsys, tmp_path):
    # Half circle of radius 100 mm: the circle formula gives the smallest N at 1 mm²/mm.
    r, n_pts = 100.0, 721
    ang = np.linspace(0.0, math.pi, n_pts)
    f = tmp_path / "arc.csv"
    f.write_text("x_mm,z_mm\n" + "\n".join(f"{r * math.sin(a):.6f},{-r + r * math.cos(a):.6f}"
                                           for a in ang) + "\n")
    n_ref = next(n for n in range(1, 100)
                 if 0.5 * r**2 * (math.pi / n - math.sin(math.pi / n)) / (r * math.pi / n) <= 1.0)
    out_json = tmp_path / "seg.json"
    code, out, _ = _run(capsys, "segment", str(f), "--max-error", "1.0", "--out", str(out_json))
    assert code == 0
    assert f"segments: {n_ref} " in out
    data = json.loads(out_json.read_text())
    assert data["n_segments"] == n_ref and data["error_mm2_per_mm"] <= 1.0
    code, out, _ = _run(capsys, "segment", str(f), "--n", "3")
    assert code == 0 and "segments: 3 (N given)" in out


def test_bad_inputs_exit_2_without_traceback(capsys, tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\n")
    for args in (["show", "nonexistent-blade"], ["show", str(bad)],
                 ["segment", str(tmp_path / "missing.csv")]):
        code, out, err = _run(capsys, *args)
        assert code == 2, args
        assert err.startswith("error: ")
        assert "Traceback" not in err
    _, _, err = _run(capsys, "show", str(bad))
    assert "bad.yaml" in err and "missing field" in err
    one = tmp_path / "one.csv"
    one.write_text("x_m,z_m\n0,0\n")
    code, _, err = _run(capsys, "segment", str(one), "--out", str(tmp_path / "o.json"))
    assert code == 2 and "at least two points" in err
    assert not (tmp_path / "o.json").exists()


def test_an_unknown_image_format_is_refused_before_any_work(capsys, tmp_path):
    for args in (["blade", "show", "xtreme-cat5", "--plot", str(tmp_path / "x.txt")],
                 ["blade", "test", "xtreme-cat5", "--plot", str(tmp_path / "y.docx")]):
        capsys.readouterr()
        assert main(args) == 2
        captured = capsys.readouterr()
        assert captured.out == ""  # nothing computed or printed
        err = captured.err.strip().splitlines()
        assert len(err) == 1 and "--plot" in err[0] and ".png" in err[0]
    assert not list(tmp_path.iterdir())
