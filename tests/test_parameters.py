"""The blade-joint parameter vocabulary: keys, units and conversions in one place."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from bladelab.errors import SpecError
from bladelab.parameters import JOINT_PARAMETERS, joint_parameter


def test_conversions_use_the_degree_power():
    k, d, k2 = (JOINT_PARAMETERS[n] for n in ("K", "D", "K2"))
    # 1 N·m/deg = 180/π N·m/rad; K2 per degree squared: (180/π)²
    assert k.from_edge(1.0) == pytest.approx(180.0 / math.pi, rel=1e-15)
    assert d.to_edge(180.0 / math.pi) == pytest.approx(1.0, rel=1e-15)
    assert k2.from_edge(1.0) == pytest.approx((180.0 / math.pi) ** 2, rel=1e-15)
    values = np.array([3.0, 18.75, 60.0])
    np.testing.assert_allclose(k2.to_edge(k2.from_edge(values)), values, rtol=1e-15)
    assert isinstance(k.to_edge(2.0), float) and k.to_edge([1.0, 2.0]).shape == (2,)


def test_keys_match_what_identification_writes():
    assert [p.edge_key for p in JOINT_PARAMETERS.values()] == [
        "K_Nm_per_deg", "D_Nms_per_deg", "K2_Nm_per_deg2"]
    assert JOINT_PARAMETERS["K"].ci_key == "K_ci_Nm_per_deg"
    assert JOINT_PARAMETERS["K2"].edge_unit == "N·m/deg²"
    with pytest.raises(SpecError, match="unknown joint parameter 'K3'"):
        joint_parameter("K3")


def test_bounds_and_identification_speak_the_vocabulary():
    from bladelab.identify.bounds import make_bounds

    b = make_bounds(k_nm_per_deg=(10.0, 30.0), k2_nm_per_deg2=(0.0, 2.0))
    edge = b.to_dict()
    assert edge["K_Nm_per_deg"] == pytest.approx([10.0, 30.0])
    assert edge["K2_Nm_per_deg2"] == pytest.approx([0.0, 2.0])
    assert b.upper[2] == pytest.approx(2.0 * (180.0 / math.pi) ** 2)


def test_blade_specs_and_reports_read_and_write_the_vocabulary():
    from bladelab.blade import load_blade
    from bladelab.report.tables import parameter_summary_display

    spec = load_blade("xceed-cat2")
    joint = spec.build().joints[0]
    # the spec's K is in N·m/deg: the model holds it per radian (× 180/π), the summary per degree
    assert joint.stiffness == pytest.approx(spec.joint_stiffness_Nm_per_deg()[0] * 180.0 / math.pi)
    shown = spec.summary()["joints"][0]
    assert set(shown) >= {"K_Nm_per_deg", "D_Nms_per_deg", "K2_Nm_per_deg2"}
    assert shown["K_Nm_per_deg"] == pytest.approx(spec.joint_stiffness_Nm_per_deg()[0], rel=1e-14)

    summary = pd.DataFrame({"group": ["a"], "speed_band": ["fast"], "n": [3],
                            **{f"{c}{s}": [v] for c in ("K_Nm_per_deg", "D_Nms_per_deg")
                               for s, v in (("", 1.5), ("_ci_low", 1.0), ("_ci_high", 2.0))}})
    headers = list(parameter_summary_display(summary).columns)
    assert "K* [N·m/deg] mean (95 % CI)" in headers and "D* [N·m·s/deg] mean (95 % CI)" in headers
