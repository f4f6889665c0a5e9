import math

import numpy as np

from bladelab import units


def test_stiffness_round_trip_and_factor():
    k_deg = 18.0
    k_rad = units.stiffness_per_deg_to_per_rad(k_deg)
    # 1 N·m/deg = 180/π N·m/rad ≈ 57.2958 N·m/rad
    assert math.isclose(k_rad, 18.0 * 57.29577951308232, rel_tol=1e-12)
    assert math.isclose(units.stiffness_per_rad_to_per_deg(k_rad), k_deg, rel_tol=1e-12)


def test_angles_arrays_and_scalars():
    assert isinstance(units.deg2rad(90), float)
    assert math.isclose(units.deg2rad(180.0), math.pi)
    arr = units.rad2deg(np.array([0.0, math.pi / 2]))
    np.testing.assert_allclose(arr, [0.0, 90.0])
