"""Blade spec: building a BladeModel (units, indices, mass properties, soles) and clear errors
for bad spec files."""

from __future__ import annotations

import copy
import math
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml

from bladelab.blade import (
    Profile,
    ProfileElement,
    load_blade,
    profile_from_elements,
    read_blade_spec,
    segment_mass_properties,
    segment_profile,
)
from bladelab.errors import InputFileError, SpecError

DEG = math.pi / 180.0


def _builtin(name: str) -> dict:
    path = Path(str(resources.files("bladelab") / "data" / "blades" / f"{name}.yaml"))
    return yaml.safe_load(path.read_text(encoding="utf-8"))


def _write(tmp_path: Path, data: dict, name: str = "blade.yaml") -> Path:
    f = tmp_path / name
    f.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return f


# ---------------------------------------------------------------- built-ins


@pytest.mark.parametrize("name", ["xceed", "xtreme"])
def test_builtin_dimensions_are_plausible(name):
    spec = load_blade(name)
    prof = spec.profile_geometry()
    model = spec.build()
    assert 0.40 <= prof.height <= 0.45  # clamp to ground, brief: 0.40–0.45 m
    assert 0.15 <= prof.toe_length <= 0.30  # toe ~0.2 m
    assert 0.5 <= model.mass <= 0.7
    assert model.mass == pytest.approx(spec.mass_kg, rel=1e-12)
    # Clamp origin first, profile hangs below it, tip is the last point.
    np.testing.assert_allclose(model.points[0], [0.0, 0.0], atol=1e-12)
    assert np.all(model.points[1:, 1] < 0.0)
    np.testing.assert_allclose(model.tip, model.points[-1])
    assert model.tip_segment == model.n_segments - 1
    # Segmentation: the automatic N is the smallest meeting 1 mm²/mm (near seed 000's 16).
    seg = spec.segmentation_result()
    assert seg.n == model.n_segments
    assert 14 <= seg.n <= 18
    assert seg.error <= 1.0 < segment_profile(prof, n_segments=seg.n - 1).error
    # The segmented blade does not fold: every segment goes on along the profile.
    assert np.all(np.diff(seg.breaks) > 0)


@pytest.mark.parametrize("name", ["xceed", "xtreme"])
def test_builtin_soles_touch_the_ground_first(name):
    model = load_blade(name).build()
    lows = [_ellipse_lowest(e) for e in model.soles]
    # The soles are the lowest part of the blade: below every segment end point.
    assert min(lows) < model.points[:, 1].min()
    # Each ellipse's x axis lies along its segment's chord.
    for e in model.soles:
        a, b = model.points[e.segment], model.points[e.segment + 1]
        u = (b - a) / np.hypot(*(b - a))
        axis = np.array([math.cos(e.angle), -math.sin(e.angle)])  # rotation about +y
        assert abs(u @ axis) == pytest.approx(1.0, abs=1e-12)
    assert [e.segment for e in model.soles] == list(range(model.n_segments - 3, model.n_segments))


def _ellipse_lowest(e) -> float:
    # Sample the ellipse boundary: independent of the module's closed form.
    t = np.linspace(0.0, 2 * np.pi, 20001)
    ex = np.array([math.cos(e.angle), -math.sin(e.angle)])
    ez = np.array([math.sin(e.angle), math.cos(e.angle)])
    pts = (np.asarray(e.center)[:, None] + e.semi_axis_x * np.cos(t) * ex[:, None]
           + e.semi_axis_z * np.sin(t) * ez[:, None])
    return float(pts[1].min())


def test_categories_differ_only_in_nominal_stiffness():
    models = {c: load_blade(f"xtreme-{c}").build() for c in ("cat4", "cat5", "cat6")}
    ks = [models[c].joints[0].stiffness for c in ("cat4", "cat5", "cat6")]
    assert ks[0] < ks[1] < ks[2]
    for c in ("cat4", "cat6"):
        np.testing.assert_array_equal(models[c].points, models["cat5"].points)
        np.testing.assert_array_equal(models[c].segment_mass, models["cat5"].segment_mass)
        assert models[c].joints[0].damping == models["cat5"].joints[0].damping
        assert models[c].soles == models["cat5"].soles
    # Seed 000's identified K* range is 13–22 N·m/deg.
    for k in ks:
        assert 13.0 <= k * DEG <= 22.0
    assert models["cat4"].name == "xtreme-cat4"


# ---------------------------------------------------------------- units and indices


def test_units_and_one_based_segment_numbers(tmp_path):
    data = _builtin("xtreme")
    data.pop("categories")
    data.pop("category")
    data["segmentation"] = {"n_segments": 16}
    data["joints"] = [{"between_segments": [7, 8], "K_Nm_per_deg": 18.0, "D_Nms_per_deg": 0.3,
                       "K2_Nm_per_deg2": 0.5}]
    data["soles"] = [{"segment": s, "semi_axes_mm": [20.0, 5.0]} for s in (14, 15, 16)]
    model = read_blade_spec(_write(tmp_path, data)).build()
    assert model.n_segments == 16
    j = model.joints[0]
    # "Between segments 7 and 8" (1-based) is the hinge at points[7], between 0-based 6 and 7.
    assert j.point == 7
    assert j.stiffness == pytest.approx(18.0 * 180.0 / math.pi)
    assert j.damping == pytest.approx(0.3 * 180.0 / math.pi)
    # τ = K2·q|q|: 0.5 N·m per deg² is 0.5·(180/π)² N·m per rad².
    assert j.stiffness_quadratic == pytest.approx(0.5 * (180.0 / math.pi) ** 2)
    assert [e.segment for e in model.soles] == [13, 14, 15]
    # Sole centre at mid-chord of its segment (position 0.5, offset 0).
    e = model.soles[0]
    np.testing.assert_allclose(e.center, 0.5 * (model.points[13] + model.points[14]), atol=1e-12)


def test_contact_keys_map_to_contact_model(tmp_path):
    data = _builtin("xceed")
    data["contact"] = {"law": "hunt_crossley", "stiffness_N_per_m_pow_n": 2.0e9, "exponent": 1.5,
                       "dissipation_s_per_m": 0.4, "friction_static": 0.8,
                       "friction_kinetic": 0.6, "critical_velocity_m_per_s": 0.02,
                       "track": {"stiffness_N_per_m": 5.0e5, "damping_Ns_per_m": 300.0}}
    c = read_blade_spec(_write(tmp_path, data)).build().contact
    assert (c.law, c.stiffness, c.exponent, c.dissipation) == ("hunt_crossley", 2.0e9, 1.5, 0.4)
    assert (c.friction_static, c.friction_kinetic, c.critical_velocity) == (0.8, 0.6, 0.02)
    assert (c.track_stiffness, c.track_damping) == (5.0e5, 300.0)
    rigid = load_blade("xceed").build().contact
    assert rigid.track_stiffness is None and rigid.law == "spring_damper"


def test_yaml_round_trip(tmp_path):
    spec = load_blade("xtreme-cat6")
    again = read_blade_spec(_write(tmp_path, yaml.safe_load(spec.to_yaml())))
    assert again == spec
    a, b = spec.build(), again.build()
    np.testing.assert_array_equal(a.points, b.points)
    assert a.joints == b.joints


def test_edited_joint_K_conflicting_with_the_category_is_an_error(tmp_path):
    # `bladelab blade show xtreme --yaml`, joint K edited: the category used to win silently
    data = yaml.safe_load(load_blade("xtreme").to_yaml())
    assert data["category"] == "cat5" and data["joints"][0]["K_Nm_per_deg"] == 18.0
    data["joints"][0]["K_Nm_per_deg"] = 25.0
    data["joints"][0]["D_Nms_per_deg"] = 0.5
    f = _write(tmp_path, data)
    with pytest.raises(SpecError) as info:
        read_blade_spec(f)
    msg = str(info.value)
    assert "joint K = 25 N·m/deg conflicts with category 'cat5', whose K = 18 N·m/deg" in msg
    assert str(f) in msg and "joints.0.K_Nm_per_deg" in msg and "delete the line 'category" in msg
    with pytest.raises(SpecError, match="conflicts with category 'cat5'"):
        load_blade(f)
    # without the category, the edited values are the blade's
    del data["category"]
    model = read_blade_spec(_write(tmp_path, data)).build()
    assert model.joints[0].stiffness == pytest.approx(25.0 / DEG)
    assert model.joints[0].damping == pytest.approx(0.5 / DEG)


def test_another_category_shown_as_yaml_reads_back(tmp_path):
    # `bladelab blade show xtreme --category cat6 --yaml` writes the category's K into the joint
    data = yaml.safe_load(load_blade("xtreme", category="cat6").to_yaml())
    assert data["category"] == "cat6" and data["joints"][0]["K_Nm_per_deg"] == 20.0
    spec = read_blade_spec(_write(tmp_path, data))
    assert spec.build().joints[0].stiffness == pytest.approx(20.0 / DEG)
    # a category chosen on reading replaces the file's (consistent) one
    assert read_blade_spec(_write(tmp_path, data), category="cat4").joint_stiffness_Nm_per_deg() \
        == [16.0]


def test_csv_profile_relative_to_spec(tmp_path):
    prof = load_blade("xceed").profile_geometry()
    sub = tmp_path / "cad"
    sub.mkdir()
    pts = prof.points[::10]
    pts = np.vstack([pts, prof.points[-1:]]) if not np.allclose(pts[-1], prof.points[-1]) else pts
    (sub / "xceed.csv").write_text(
        "x_mm,z_mm\n" + "\n".join(f"{x * 1e3:.6f},{z * 1e3:.6f}" for x, z in pts) + "\n")
    data = _builtin("xceed")
    data["profile"] = {"csv": "cad/xceed.csv"}
    spec = read_blade_spec(_write(tmp_path, data))
    model, ref = spec.build(), load_blade("xceed").build()
    assert model.n_segments == ref.n_segments
    np.testing.assert_allclose(model.points, ref.points, atol=2e-4)


# ---------------------------------------------------------------- mass properties


def test_uniform_straight_bar_mass_properties():
    prof = Profile(np.array([[0.0, 0.0], [0.0, -0.4]]))
    seg = segment_profile(prof, n_segments=4)
    m, com, inertia = segment_mass_properties(prof, seg, 0.8)
    np.testing.assert_allclose(m, 0.2)
    np.testing.assert_allclose(com[:, 1], [-0.05, -0.15, -0.25, -0.35], atol=1e-12)
    np.testing.assert_allclose(inertia, 0.2 * 0.1**2 / 12.0, rtol=1e-9)  # rod: m·l²/12
    # A 20 mm thick bar (constant thickness: same masses): rectangle, m·(l² + t²)/12.
    m2, _, inertia2 = segment_mass_properties(prof, seg, 0.8,
                                              thickness=np.array([[0.0, 20.0], [1.0, 20.0]]))
    np.testing.assert_allclose(m2, m)
    np.testing.assert_allclose(inertia2, 0.2 * (0.1**2 + 0.02**2) / 12.0, rtol=1e-9)


def test_tapered_bar_mass_follows_thickness():
    prof = Profile(np.array([[0.0, 0.0], [0.0, -1.0]]))
    seg = segment_profile(prof, n_segments=2)
    # Thickness 2 -> 1 linearly: λ ∝ 2 - s; halves get ∫(2-s) = 0.875 and 0.625 of 1.5.
    m, com, _ = segment_mass_properties(prof, seg, 1.5, thickness=np.array([[0.0, 2.0], [1.0, 1.0]]))
    np.testing.assert_allclose(m, [0.875, 0.625], rtol=1e-6)
    # COM of the first half: ∫ s(2-s) ds / ∫(2-s) ds over [0, 0.5] = (0.25 - 1/24) / 0.875.
    assert -com[0, 1] == pytest.approx((0.25 - 1.0 / 24.0) / 0.875, rel=1e-6)


def test_arc_piece_com_and_inertia_match_circle_formulas():
    r, angle, n = 0.1, math.pi, 3
    prof = profile_from_elements([ProfileElement(r * angle, angle)])
    seg = segment_profile(prof, n_segments=n)
    m, com, inertia = segment_mass_properties(prof, seg, 0.3)
    alpha = angle / n / 2  # half-angle of each piece
    centre = np.array([r, 0.0])
    # COM of a circular arc: r·sin(α)/α from the centre; I about the COM: m r²(1 − (sin α/α)²).
    np.testing.assert_allclose(np.hypot(*(com - centre).T), r * math.sin(alpha) / alpha, rtol=1e-5)
    np.testing.assert_allclose(inertia, 0.1 * r**2 * (1 - (math.sin(alpha) / alpha) ** 2), rtol=1e-3)


# ---------------------------------------------------------------- bad spec files


def _mutate(data, path: str, value):
    keys = path.split(".")
    d = data
    for k in keys[:-1]:
        d = d[int(k)] if isinstance(d, list) else d[k]
    if value is _DELETE:
        del d[keys[-1]]
    elif isinstance(d, list):
        d[int(keys[-1])] = value
    else:
        d[keys[-1]] = value
    return data


_DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "where", "match"),
    [
        ("mass_kg", _DELETE, "mass_kg", "missing field"),
        ("joints.0.K_Nm_per_deg", -5.0, "joints.0.K_Nm_per_deg", "greater than 0"),
        ("joints.0.D_Nms_per_deg", -0.1, "joints.0.D_Nms_per_deg", "greater than or equal to 0"),
        ("joints.0.between_segments", [7, 9], "joints.0.between_segments", "consecutive"),
        ("joints.0.stiffness", 3.0, "joints.0.stiffness", "unknown field"),
        ("mass_kg", -0.6, "mass_kg", "greater than 0"),
        ("profile.elements", [], "profile", "empty"),
        ("soles.0.semi_axes_mm", [0.0, 5.0], "soles.0.semi_axes_mm.0", "greater than 0"),
        ("categories.cat5.K_Nm_per_deg", -1.0, "categories.cat5.K_Nm_per_deg", "greater than 0"),
        ("category", "cat9", "(top level)", "cat9"),
    ],
)
def test_invalid_fields_are_named(tmp_path, path, value, where, match):
    data = _mutate(copy.deepcopy(_builtin("xtreme")), path, value)
    f = _write(tmp_path, data)
    with pytest.raises(SpecError, match=match) as info:
        read_blade_spec(f)
    msg = str(info.value)
    assert str(f) in msg
    assert where in msg


def test_profile_with_fewer_than_two_points(tmp_path):
    data = _builtin("xceed")
    data["profile"] = {"points_mm": [[0.0, 0.0]]}
    with pytest.raises(SpecError, match="at least two points") as info:
        read_blade_spec(_write(tmp_path, data))
    assert "profile" in str(info.value)


def test_sole_not_under_the_blade(tmp_path):
    data = _builtin("xceed")
    data["soles"][0]["segment"] = 3  # near the clamp
    with pytest.raises(SpecError, match="not under the blade") as info:
        read_blade_spec(_write(tmp_path, data))
    assert "soles[0]" in str(info.value)
    data = _builtin("xceed")
    data["soles"][1]["offset_mm"] = 80.0  # floats far from its segment
    with pytest.raises(SpecError, match="from segment") as info:
        read_blade_spec(_write(tmp_path, data))
    assert "soles[1]" in str(info.value)


def test_segment_numbers_beyond_the_blade(tmp_path):
    data = _builtin("xceed")
    data["soles"][2]["segment"] = 40
    with pytest.raises(SpecError, match="does not exist") as info:
        read_blade_spec(_write(tmp_path, data))
    assert "soles[2]" in str(info.value)
    data = _builtin("xceed")
    data["joints"][0]["between_segments"] = [17, 18]
    with pytest.raises(SpecError, match="do not exist"):
        read_blade_spec(_write(tmp_path, data))


def test_self_intersecting_segmentation(tmp_path):
    t = np.linspace(0.0, 1.0, 800)
    rad, ang = 100.0 * (1.0 - 0.5 * t), 4.0 * math.pi * t
    data = _builtin("xceed")
    data["profile"] = {"points_mm": np.stack([rad * np.cos(ang), rad * np.sin(ang)], 1).tolist()}
    data["segmentation"] = {"n_segments": 4}
    with pytest.raises(SpecError, match="intersects itself") as info:
        read_blade_spec(_write(tmp_path, data))
    assert "segmentation" in str(info.value)


def test_contact_law_and_stiffness_key_must_agree(tmp_path):
    data = _builtin("xceed")
    data["contact"]["law"] = "hunt_crossley"
    with pytest.raises(SpecError, match="stiffness_N_per_m_pow_n"):
        read_blade_spec(_write(tmp_path, data))


def test_unreadable_files(tmp_path):
    with pytest.raises(InputFileError, match="not found"):
        read_blade_spec(tmp_path / "none.yaml")
    f = tmp_path / "broken.yaml"
    f.write_text("name: [unclosed\n")
    with pytest.raises(InputFileError, match=r"not valid YAML: .* line 2"):
        read_blade_spec(f)
    f.write_text("- just a list\n")
    with pytest.raises(SpecError, match="mapping"):
        read_blade_spec(f)
