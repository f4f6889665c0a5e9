"""Catalogue: names, loading by name or file, the multi-link blade, the figure helper."""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pytest

from bladelab.blade import (
    BladeSpec,
    blade_catalogue,
    list_blades,
    load_blade,
    multilink_blade,
    plot_blade,
)
from bladelab.errors import ModelError, SpecError

matplotlib.use("Agg")


def test_list_and_load_every_builtin():
    names = list_blades()
    assert {"xceed-cat2", "xtreme-cat4", "xtreme-cat5", "xtreme-cat6"} <= set(names)
    for name in names:
        spec = load_blade(name)
        assert isinstance(spec, BladeSpec)
        assert spec.build().name == name


def test_family_name_gives_default_category_and_aliases():
    assert load_blade("xtreme").category == "cat5"
    assert load_blade("XTREME_cat4").category == "cat4"
    assert load_blade("xtreme", category="cat6").category == "cat6"


def test_load_from_file(tmp_path):
    f = tmp_path / "mine.yaml"
    f.write_text(load_blade("xceed").to_yaml(), encoding="utf-8")
    spec = load_blade(f)
    assert spec.name == "xceed"
    assert load_blade(str(f)).build().n_segments == spec.build().n_segments


def test_unknown_names():
    with pytest.raises(SpecError, match="unknown blade") as info:
        load_blade("cheetah")
    assert "xtreme-cat5" in str(info.value)  # the hint lists what exists
    with pytest.raises(SpecError, match="unknown category"):
        load_blade("xtreme-cat9")


def test_catalogue_table():
    table = blade_catalogue()
    assert list(table["name"]) == list_blades()
    assert {"K_Nm_per_deg", "D_Nms_per_deg", "mass_kg", "height_m", "n_segments"} <= set(table.columns)
    xt = table[table["family"] == "xtreme"].sort_values("K_Nm_per_deg")
    assert list(xt["category"]) == ["cat4", "cat5", "cat6"]


def test_multilink_blade_six_links_five_joints():
    spec = load_blade("xtreme")
    base = spec.build()
    m = multilink_blade(spec)
    assert len(m.joints) == 5
    points = [j.point for j in m.joints]
    assert points == sorted(set(points)) and 1 <= points[0] and points[-1] <= m.n_segments - 1
    # Joints split the blade into six links of roughly equal arc length.
    seg_len = np.hypot(*np.diff(m.points, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg_len)])
    links = np.diff(np.concatenate([[0.0], s[points], [s[-1]]]))
    assert len(links) == 6
    assert links.max() < 2.0 * links.min()
    # Same geometry, masses and soles as the single-joint blade.
    np.testing.assert_array_equal(m.points, base.points)
    np.testing.assert_array_equal(m.segment_mass, base.segment_mass)
    assert m.soles == base.soles
    # Default K: five equal springs in series are as compliant as the spec's single joint.
    assert sum(1.0 / j.stiffness for j in m.joints) == pytest.approx(1.0 / base.joints[0].stiffness)
    assert m.name == "xtreme-cat5-6link"


def test_multilink_explicit_parameters_and_errors():
    k = np.array([60.0, 70.0, 80.0, 90.0, 100.0])
    m = multilink_blade("xceed", K_Nm_per_deg=k, D_Nms_per_deg=0.5)
    np.testing.assert_allclose([j.stiffness for j in m.joints], k * 180.0 / math.pi)
    np.testing.assert_allclose([j.damping for j in m.joints], 0.5 * 180.0 / math.pi)
    assert len(multilink_blade("xceed", n_links=3).joints) == 2
    with pytest.raises(ModelError, match="n_links"):
        multilink_blade("xceed", n_links=1)
    with pytest.raises(ModelError, match="positive"):
        multilink_blade("xceed", K_Nm_per_deg=-1.0)
    with pytest.raises(ModelError, match="one per joint"):
        multilink_blade("xceed", K_Nm_per_deg=[1.0, 2.0])


def test_plot_blade_draws_every_part():
    import matplotlib.pyplot as plt

    spec = load_blade("xceed")
    model = spec.build()
    ax = plot_blade(model, profile=spec.profile_geometry())
    try:
        assert len(ax.patches) == len(model.soles)
        seg_line = next(line for line in ax.lines if line.get_label() == "segments")
        np.testing.assert_allclose(seg_line.get_xydata(), model.points * 1e3)
        # The ground line sits at the lowest sole point, below every segment point.
        ground = [line for line in ax.lines if len(line.get_ydata()) == 2
                  and line.get_ydata()[0] == line.get_ydata()[1]]
        assert ground and ground[0].get_ydata()[0] < model.points[:, 1].min() * 1e3
        assert "17 segments" in ax.get_title() or f"{model.n_segments} segments" in ax.get_title()
    finally:
        plt.close(ax.figure)
