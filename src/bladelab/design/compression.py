"""Virtual compression test of a multi-link blade (seed 002's bench test, quasi-static).

The bench test of seed 002 loads the blade at its mount (the clamp) while a fixture limits the
horizontal motion of the part that rests on the plate. Here, in the lab frame (x forward, z up),
with the blade turned by an alignment angle about the clamp (pitch about +y):

- the clamp moves only vertically (no horizontal motion, no rotation): it is pressed down by δ;
- the support point (default: the lowest point of the sole ellipses; or the lowest segment end,
  or the tip) rests on the plate: its
  vertical position is fixed and, with ``tip="held"`` (default), also its horizontal position;
  with ``tip="free"`` it slides without friction;
- the rigid links between compliant joints carry the load; joint j resists with
  τ = −(K_j·q + K2_j·q·|q|).

Small loads (linear): with J the 2×n Jacobian of the support point with respect to the joint
angles (column j = (r_z, −r_x) with r = support − hinge_j, for hinges proximal to the support),
the compliance of the support relative to the clamp is C = J K⁻¹ Jᵀ, and the vertical stiffness
is 1/(C_zz − C_xz²/C_xx) (held) or 1/C_zz (free). Large loads: the joint angles minimise the
spring energy subject to the support constraint at each δ (continuation), and the force is the
constraint's Lagrange multiplier, so F = dU/dδ exactly. The support point is fixed on the blade
(no rolling of the sole along the plate).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import optimize

from bladelab.blade.model import BladeModel
from bladelab.errors import ModelError, SimulationError, SpecError
from bladelab.units import deg2rad

__all__ = ["CompressionTestResult", "vertical_stiffness", "compression_test"]


def _rot(theta: float | np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate (x, z) vectors by ``theta`` about +y (positive turns +z toward +x)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.stack([c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1]], axis=-1)


@dataclass(frozen=True)
class _Setup:
    hinges: np.ndarray  # (n, 2) lab frame, proximal to the support
    support: np.ndarray  # (2,)
    k: np.ndarray  # (n,) N·m/rad
    k2: np.ndarray  # (n,) N·m/rad²
    support_index: int


def _sole_lowest(e, beta: float) -> np.ndarray:
    """Lowest point (x, z) of a sole ellipse after turning the blade by ``beta`` about +y."""
    centre = _rot(beta, np.asarray(e.center, dtype=float))
    alpha = e.angle + beta
    u = np.array([-e.semi_axis_x * np.sin(alpha), e.semi_axis_z * np.cos(alpha)])
    cos_t, sin_t = -u / np.hypot(*u)
    x = centre[0] + e.semi_axis_x * cos_t * np.cos(alpha) + e.semi_axis_z * sin_t * np.sin(alpha)
    z = centre[1] + u @ np.array([cos_t, sin_t])
    return np.array([x, z])


def _setup(model: BladeModel, alignment_deg: float, support: str) -> _Setup:
    if support not in ("sole", "lowest", "tip"):
        raise SpecError(f"support must be 'sole', 'lowest' or 'tip', got {support!r}",
                        where="support")
    beta = deg2rad(alignment_deg)
    pts = _rot(beta, np.asarray(model.points, dtype=float))
    if support == "sole" and model.soles:
        lows = [_sole_lowest(e, beta) for e in model.soles]
        i = int(np.argmin([p[1] for p in lows]))
        sup, seg = lows[i], model.soles[i].segment
    elif support == "tip" or (support == "sole" and not model.soles):
        sup, seg = _rot(beta, np.asarray(model.tip, dtype=float)), model.tip_segment
    else:
        idx = int(np.argmin(pts[:, 1]))
        sup, seg = pts[idx], idx - 1
    # the joint at point p joins segments p-1 and p: it carries the load if p <= seg
    joints = [j for j in model.joints if j.point <= seg]
    if not joints:
        raise ModelError(
            "no compliant joint lies between the clamp and the support point",
            where=f"{model.name}: joints",
            hint="the blade would be rigid in this test; check the joints and alignment",
        )
    joints.sort(key=lambda j: j.point)
    hinges = np.array([pts[j.point] for j in joints])
    k = np.array([j.stiffness for j in joints], dtype=float)
    k2 = np.array([j.stiffness_quadratic for j in joints], dtype=float)
    if np.any(k <= 0):
        raise ModelError("joint stiffness must be positive", where=f"{model.name}: joints")
    return _Setup(hinges, np.asarray(sup, dtype=float), k, k2, int(seg))


def _jacobian(hinges: np.ndarray, point: np.ndarray) -> np.ndarray:
    r = point[None, :] - hinges
    return np.stack([r[:, 1], -r[:, 0]], axis=0)  # (2, n)


def _stiffness_from(setup: _Setup, tip: str) -> float:
    J = _jacobian(setup.hinges, setup.support)
    C = (J / setup.k[None, :]) @ J.T
    if tip == "free":
        return 1.0 / C[1, 1]
    det = C[0, 0] * C[1, 1] - C[0, 1] ** 2
    if C[0, 0] <= 0 or det <= 1e-12 * C[0, 0] * C[1, 1]:
        raise ModelError(
            "with the support held horizontally this blade cannot compress (fewer than two "
            "independent compliant joints between clamp and support)",
            hint="use tip='free', or a multi-link blade",
        )
    return C[0, 0] / det


def vertical_stiffness(
    model: BladeModel,
    *,
    alignment_deg: float = 0.0,
    tip: str = "held",
    support: str = "sole",
) -> float:
    """Small-load vertical stiffness [N/m] of the virtual compression test.

    Parameters
    ----------
    model
        The blade (its compliant joints carry the load).
    alignment_deg
        Pitch of the blade about the clamp [deg] (positive turns the toe down).
    tip
        ``"held"`` (the fixture blocks the support's horizontal motion, seed 002) or ``"free"``.
    support
        Where the blade rests on the plate: ``"sole"`` (the lowest point of its sole ellipses at
        this alignment; default), ``"lowest"`` (lowest segment end point) or ``"tip"``.
    """
    if tip not in ("held", "free"):
        raise SpecError(f"tip must be 'held' or 'free', got {tip!r}", where="tip")
    return float(_stiffness_from(_setup(model, alignment_deg, support), tip))


def _support_position(setup: _Setup, q: np.ndarray) -> np.ndarray:
    theta = np.cumsum(q)
    h = setup.hinges
    links = np.vstack([np.diff(h, axis=0), (setup.support - h[-1])[None, :]])
    return h[0] + np.sum(_rot(theta, links), axis=0)


def _support_jacobian(setup: _Setup, q: np.ndarray) -> np.ndarray:
    theta = np.cumsum(q)
    h = setup.hinges
    links = _rot(theta, np.vstack([np.diff(h, axis=0), (setup.support - h[-1])[None, :]]))
    # hinge positions after rotation, then the point's lever arm about each
    pos = h[0] + np.vstack([[0.0, 0.0], np.cumsum(links, axis=0)])
    return _jacobian(pos[:-1], pos[-1])


@dataclass(frozen=True, eq=False)
class CompressionTestResult:
    """Force–displacement curve of the virtual compression test.

    Attributes
    ----------
    displacement
        Clamp displacement δ [m] (downward positive), starting at 0.
    force
        Vertical force at the clamp [N] (compressive positive).
    energy
        Spring energy stored in the joints [J] (equals ∫F dδ).
    stiffness_linear
        Small-load vertical stiffness [N/m].
    load, displacement_at_load, stiffness_at_load
        The requested load [N] (e.g. body weight), δ there [m] and the secant stiffness
        load/δ [N/m]; NaN if no load was requested.
    alignment_deg, tip, support
        Test set-up.
    """

    displacement: np.ndarray
    force: np.ndarray
    energy: np.ndarray
    stiffness_linear: float
    load: float
    displacement_at_load: float
    stiffness_at_load: float
    alignment_deg: float
    tip: str
    support: str

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame(
            {"displacement_m": self.displacement, "force_N": self.force, "energy_J": self.energy}
        )

    def to_dict(self) -> dict:
        return {
            "displacement_m": self.displacement.tolist(),
            "force_N": self.force.tolist(),
            "energy_J": self.energy.tolist(),
            "stiffness_linear_N_per_m": self.stiffness_linear,
            "load_N": self.load,
            "displacement_at_load_m": self.displacement_at_load,
            "stiffness_at_load_N_per_m": self.stiffness_at_load,
            "alignment_deg": self.alignment_deg,
            "tip": self.tip,
            "support": self.support,
        }


def compression_test(
    model: BladeModel,
    *,
    max_displacement: float = 0.06,
    n_steps: int = 30,
    load: float | None = None,
    alignment_deg: float = 0.0,
    tip: str = "held",
    support: str = "sole",
) -> CompressionTestResult:
    """Large-deflection quasi-static compression test.

    Parameters
    ----------
    model
        The blade.
    max_displacement
        Largest clamp displacement [m].
    n_steps
        Displacement steps (continuation).
    load
        A force [N] (e.g. body weight m·g) at which the secant stiffness is reported; it must be
        reached within ``max_displacement``.
    alignment_deg, tip, support
        As :func:`vertical_stiffness`.
    """
    if tip not in ("held", "free"):
        raise SpecError(f"tip must be 'held' or 'free', got {tip!r}", where="tip")
    if not (max_displacement > 0 and n_steps >= 1):
        raise SpecError("max_displacement must be > 0 and n_steps >= 1", where="compression test")
    setup = _setup(model, alignment_deg, support)
    k_lin = _stiffness_from(setup, tip)
    n = len(setup.k)
    rows = slice(None) if tip == "held" else slice(1, 2)
    s0 = setup.support

    def energy(q):
        return float(0.5 * np.sum(setup.k * q**2) + np.sum(setup.k2 * np.abs(q) ** 3) / 3.0)

    def grad(q):
        return setup.k * q + setup.k2 * q * np.abs(q)

    deltas = np.linspace(0.0, float(max_displacement), int(n_steps) + 1)
    forces = [0.0]
    energies = [0.0]
    q = np.zeros(n)
    for d in deltas[1:]:
        target = s0 + np.array([0.0, d])

        def cons(qq, target=target):
            return (_support_position(setup, qq) - target)[rows]

        def cons_jac(qq):
            return _support_jacobian(setup, qq)[rows]

        res = optimize.minimize(
            energy, q, jac=grad, method="SLSQP",
            constraints=[{"type": "eq", "fun": cons, "jac": cons_jac}],
            options={"ftol": 1e-14, "maxiter": 500},
        )
        viol = float(np.max(np.abs(cons(res.x))))
        if not np.all(np.isfinite(res.x)) or viol > 1e-8:
            raise SimulationError(
                f"the compression test did not converge at δ = {d * 1e3:.1f} mm "
                f"(constraint error {viol:.2e} m)",
                where=f"{model.name}: compression test",
                hint="lower max_displacement or raise n_steps",
            )
        q = res.x
        Jq = _support_jacobian(setup, q)[rows]
        lam = np.linalg.lstsq(Jq.T, grad(q), rcond=None)[0]
        forces.append(float(lam[-1]))  # multiplier of the vertical constraint = dU/dδ
        energies.append(energy(q))
    force = np.asarray(forces)
    if load is None:
        d_at, k_at, load_v = float("nan"), float("nan"), float("nan")
    else:
        load_v = float(load)
        if not 0 < load_v <= force.max():
            raise SpecError(
                f"load {load_v:.0f} N is not reached (max {force.max():.0f} N at "
                f"{max_displacement * 1e3:.0f} mm)",
                where="load", hint="raise max_displacement",
            )
        i = int(np.argmax(force >= load_v))
        d_at = float(np.interp(load_v, force[i - 1:i + 1], deltas[i - 1:i + 1]))
        k_at = load_v / d_at
    return CompressionTestResult(
        displacement=deltas, force=force, energy=np.asarray(energies), stiffness_linear=float(k_lin), load=load_v,
        displacement_at_load=d_at, stiffness_at_load=k_at, alignment_deg=float(alignment_deg),
        tip=tip, support=support,
    )
