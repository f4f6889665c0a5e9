"""Blade generator and virtual compression test: target stiffness, beam theory, Castigliano."""

from __future__ import annotations

import numpy as np
import pytest

from bladelab.blade.spec import spec_from_dict
from bladelab.design.blade_generator import generate_blade, lumped_beam_stiffness
from bladelab.design.compression import compression_test, vertical_stiffness
from bladelab.design.doe import central_composite
from bladelab.design.space import default_design_space
from bladelab.errors import ModelError, SpecError

SPACE = default_design_space()


@pytest.fixture(scope="module")
def corner_blades():
    """Generated blades at 5 points of the default design space (corners and centre)."""
    d = central_composite(SPACE).coded
    pts = [d[0], d[5], d[10], d[15], d[-1]]
    return [(SPACE.point(c), generate_blade(SPACE.point(c))) for c in pts]


def test_hits_target_stiffness_within_1_percent(corner_blades):
    for point, g in corner_blades:
        target = point["stiffness_kN_per_m"] * 1e3
        assert g.model.n_segments == 48 and len(g.model.joints) == 5  # 6 links, 5 springs
        assert vertical_stiffness(g.model) == pytest.approx(target, rel=0.01)
        # independent path: the large-deflection solver at a small displacement
        r = compression_test(g.model, max_displacement=2e-4, n_steps=2)
        assert r.force[1] / r.displacement[1] == pytest.approx(target, rel=0.01)
        # the spec, rebuilt from scratch, is the same blade
        assert vertical_stiffness(g.spec.build()) == pytest.approx(target, rel=1e-6)
        assert g.height == pytest.approx(point["height_m"], abs=1e-6)
        assert g.toe_length == pytest.approx(point["toe_length_m"], abs=1e-6)
        # damping proportional to stiffness
        ratios = [j.damping / j.stiffness for j in g.model.joints]
        assert np.ptp(ratios) < 1e-12


def test_doubling_width_doubles_stiffness_mass_and_contact_in_beam_mode():
    a = generate_blade({"width_m": 0.05}, mode="beam")
    b = generate_blade({"width_m": 0.10}, mode="beam")
    assert b.vertical_stiffness == pytest.approx(2.0 * a.vertical_stiffness, rel=1e-9)
    assert b.model.mass == pytest.approx(2.0 * a.model.mass, rel=1e-9)
    np.testing.assert_allclose(b.model.segment_inertia, 2.0 * a.model.segment_inertia, rtol=1e-9)
    assert b.model.contact.stiffness == pytest.approx(2.0 * a.model.contact.stiffness)
    # in target mode, width leaves the stiffness at the target
    t = generate_blade({"width_m": 0.10, "stiffness_kN_per_m": 20.0})
    assert t.vertical_stiffness == pytest.approx(20e3, rel=1e-9)


@pytest.mark.parametrize("alignment", [0.0, -8.0, 8.0])
def test_six_links_vs_24_links_within_5_percent(alignment):
    k6 = generate_blade({}, n_links=6, mode="beam", alignment_deg=alignment).vertical_stiffness
    k24 = generate_blade({}, n_links=24, mode="beam", alignment_deg=alignment).vertical_stiffness
    assert abs(k6 / k24 - 1.0) < 0.05


def _quarter_circle(radius: float):
    return spec_from_dict({
        "name": "arc",
        "profile": {"start_heading_deg": -90.0,
                    "elements": [{"length_mm": np.pi / 2 * radius * 1e3, "turn_deg": 90.0}]},
        "segmentation": {"n_segments": 48},
        "mass_kg": 0.5,
        "joints": [{"between_segments": [24, 25], "K_Nm_per_deg": 10.0}],
        "soles": [{"segment": 48, "semi_axes_mm": [10.0, 3.0]}],
    })


def test_circular_arc_spring_matches_castigliano():
    """Quarter circle, clamped at the top, loaded at the end: closed forms by hand.

    With r(φ) = R(1 − cos φ, −sin φ), the bending moment of a tip force (F_x, F_z) is
    M = R(sin φ − 1)F_x − R cos φ F_z, and Castigliano gives the tip compliance
    C_xx = (3π/4 − 2)R³/EI, C_zz = (π/4)R³/EI, C_xz = R³/(2EI). Vertical stiffness: free tip
    4EI/(πR³); tip held horizontally 1/(C_zz − C_xz²/C_xx).
    """
    R, E, w, t = 0.2, 70e9, 0.06, 0.012
    EI = E * w * t**3 / 12.0
    k_free = 4.0 * EI / (np.pi * R**3)
    k_held = (EI / R**3) / (np.pi / 4.0 - 0.25 / (3.0 * np.pi / 4.0 - 2.0))
    g = generate_blade({"width_m": w}, base=_quarter_circle(R), n_links=24, mode="beam",
                       thickness_mm=12.0, youngs_modulus_Pa=E)
    assert vertical_stiffness(g.model, support="tip", tip="free") == pytest.approx(k_free, rel=0.01)
    assert vertical_stiffness(g.model, support="tip") == pytest.approx(k_held, rel=0.01)
    # large-deflection solver agrees at small load
    r = compression_test(g.model, support="tip", max_displacement=1e-5, n_steps=1)
    assert r.force[1] / r.displacement[1] == pytest.approx(k_held, rel=0.01)


def test_lumped_beam_stiffness_uniform_cells():
    # uniform beam of 1 m, hinges at cell centres of 4 equal cells: k = EI / 0.25 m
    k = lumped_beam_stiffness(np.array([0.125, 0.375, 0.625, 0.875]), 1.0, youngs_modulus=1e9,
                              width=0.05, thickness=0.01)
    np.testing.assert_allclose(k, 1e9 * 0.05 * 0.01**3 / 12 / 0.25, rtol=1e-9)


def test_compression_curve_and_body_weight_load():
    g = generate_blade({"stiffness_kN_per_m": 25.0})
    r = compression_test(g.model, max_displacement=0.04, n_steps=20, load=70 * 9.81)
    assert np.all(np.diff(r.force) > 0)
    assert 0 < r.displacement_at_load < 0.04
    assert r.stiffness_at_load == pytest.approx(r.load / r.displacement_at_load)
    # the force is dU/dδ: the work ∫F dδ equals the stored spring energy
    work = np.concatenate([[0.0], np.cumsum(0.5 * (r.force[1:] + r.force[:-1])
                                            * np.diff(r.displacement))])
    np.testing.assert_allclose(work[1:], r.energy[1:], rtol=1e-2)  # trapezoid error
    assert work[-1] == pytest.approx(r.energy[-1], rel=1e-3)
    assert r.to_frame().shape == (21, 3)
    with pytest.raises(SpecError, match="not reached"):
        compression_test(g.model, max_displacement=0.001, n_steps=2, load=5000.0)


def test_generator_errors():
    with pytest.raises(SpecError, match="does not know factor"):
        generate_blade({"colour": 1.0})
    with pytest.raises(ModelError, match="cannot reach"):
        generate_blade({"height_m": 0.2, "toe_length_m": 0.22})  # shank would be < 0
    with pytest.raises(ModelError, match="n_links"):
        generate_blade({}, n_links=1)
    with pytest.raises(ModelError, match="cannot compress"):
        generate_blade({}, n_links=2, mode="beam")
    single = generate_blade({}, n_links=2, mode="beam", tip="free")
    with pytest.raises(ModelError, match="cannot compress"):
        vertical_stiffness(single.model)  # one spring cannot move the held support vertically
    assert vertical_stiffness(single.model, tip="free") > 0
