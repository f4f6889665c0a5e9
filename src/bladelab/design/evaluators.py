"""Design evaluators: design point -> generated blade -> simulation -> responses.

An evaluator is a picklable callable ``{factor: value in its unit} -> {response: value}`` for
:func:`~bladelab.design.study.run_design`.

:class:`BladeEvaluator` (``--evaluator blade``) simulates one running stance of the generated
blade with :func:`bladelab.sim.synthetic.generate_stance`: a point-mass runner (``body_mass_kg``
at the hip) whose rigid pylon carries the blade lands at ``speed_mps`` with a fixed touch-down
leg angle and vertical speed; the blade and the contact law decide the rest. During stance the
pylon hangs from the hip on a moment-free hinge, so the ground reaction force points at the hip
(up to the small inertia of pylon and blade). Responses (name, unit):

================================  =====  ===================================================
``delta_vx_m_per_s``              m/s    hip speed at toe-off − at touch-down (Δv_x = I_x/m)
``avg_vx_m_per_s``                m/s    hip forward travel / contact time
``impulse_x_Ns``                  N·s    m·Δv_x (from the momentum, see below)
``impulse_z_Ns``                  N·s    ∫F_z dt over contact (gross)
``impulse_z_net_Ns``              N·s    ∫(F_z − m·g) dt over contact
``evaluation_E_m``                m      bouncing-ball parameter I_x·I_z,net/(m²·g)
``peak_grf_z_N``                  N      peak vertical GRF
``contact_time_s``                s      F_z > 1 N
``compression_m``                 m      Δd: largest drop of the clamp–tip distance
``knee_moment_min_Nm``            N·m    minimum knee extension moment over loaded stance
``swing_clearance_m``             m      lowest blade point above ground in the swing pose
``blade_mass_kg``                 kg     generated blade mass
================================  =====  ===================================================

Notes
-----
- Forces come from the runner's momentum, not from the sampled contact force: in the stick
  regime of the friction law the horizontal contact force chatters at the time-step scale and a
  sampled trace aliases (measured: the sampled ∫F_x dt varied from −2.9 to −27.6 N·s with the
  sampling rate while m·Δv stayed within 0.2 %; for a stiff blade the sampled F_x even changed
  sign mid-stance). So I_x = m·Δv_x of the hip point mass, and the force on the body is
  m·(ẍ_hip, z̈_hip + g) from central second differences of the hip path (hip = clamp + pylon);
  ``peak_grf_z_N`` and the vertical impulses use that force. The blade's own mass (≈ 0.5–0.8 kg)
  is left out of m (about 1 %).
- Knee moment (blade-level proxy of the knee-buckling constraint): the knee sits on the pylon
  ``knee_above_clamp_m`` above the clamp; the GRF line passes through the hip (moment-free hinge
  in stance), so the hip serves as the point on the line of action in
  :func:`~bladelab.design.constraints.knee_extension_moment`. Samples with contact F_z above 5 %
  of its peak count as loaded stance.
- Swing clearance (blade-level proxy of the tripping constraint): the undeformed blade with its
  clamp ``swing_clamp_height_m`` above the ground, pitched by ``swing_pitch_deg`` (positive: leg
  swung back, toe down); the lowest of its segment points, tip and sole-ellipse surfaces. The
  transfemoral runner evaluator computes the real swing trajectory instead.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.constants import STANDARD_GRAVITY
from bladelab.design import defaults
from bladelab.design.blade_generator import generate_blade
from bladelab.design.constraints import knee_extension_moment
from bladelab.design.performance import bouncing_ball
from bladelab.design.responses import BLADE_RESPONSE_UNITS
from bladelab.errors import SpecError
from bladelab.sim.synthetic import generate_stance

__all__ = [
    "BladeEvaluator",
    "make_evaluator",
    "swing_clearance",
]



def _ellipse_lowest_z(e, pitch: float) -> float:
    """Lab-frame height of the lowest point of sole ellipse ``e`` relative to the clamp."""
    c, s = math.cos(pitch), math.sin(pitch)
    cz = -s * e.center[0] + c * e.center[1]
    psi = pitch + e.angle
    # extent in z of an ellipse rotated by psi (same convention as the rotation of points)
    half = math.hypot(e.semi_axis_x * math.sin(psi), e.semi_axis_z * math.cos(psi))
    return cz - half


def swing_clearance(
    model: BladeModel, *, clamp_height_m: float = 0.50, pitch_deg: float = 60.0
) -> float:
    """Lowest point of the undeformed blade above the ground in a swing pose [m].

    Parameters
    ----------
    model
        The blade.
    clamp_height_m
        Height of the clamp above the ground [m].
    pitch_deg
        Clamp pitch [deg] about +y (positive turns +z toward +x: the leg swung back, toe down).
    """
    th = math.radians(pitch_deg)
    c, s = math.cos(th), math.sin(th)
    pts = np.vstack([np.asarray(model.points, float), np.asarray(model.tip, float)[None, :]])
    z = -s * pts[:, 0] + c * pts[:, 1]
    low = float(z.min())
    for e in model.soles:
        low = min(low, _ellipse_lowest_z(e, th))
    return float(clamp_height_m + low)


@dataclass(frozen=True)
class BladeEvaluator:
    """Design point -> generated blade -> one simulated stance -> responses.

    Attributes
    ----------
    speed_mps, body_mass_kg
        Touch-down speed [m/s] and runner mass [kg].
    touchdown_angle_deg, touchdown_vertical_speed_mps, pylon_length_m
        As :func:`bladelab.sim.synthetic.generate_stance`.
    knee_above_clamp_m
        Distance of the (virtual) prosthetic knee above the clamp along the pylon [m].
    swing_clamp_height_m, swing_pitch_deg
        Swing pose of :func:`swing_clearance`.
    dt, sample_rate
        Simulation step [s] and sampling rate [Hz] of the stance.
    generator
        Keyword options of :func:`~bladelab.design.blade_generator.generate_blade` (e.g.
        ``base``, ``n_links``, ``roles``).
    """

    speed_mps: float = defaults.BLADE_SPEED_MPS
    body_mass_kg: float = defaults.BODY_MASS_KG
    touchdown_angle_deg: float = -25.0
    touchdown_vertical_speed_mps: float = -0.5
    pylon_length_m: float = 0.45
    knee_above_clamp_m: float = 0.08
    swing_clamp_height_m: float = 0.50
    swing_pitch_deg: float = 60.0
    dt: float = 1e-5
    sample_rate: float = 2000.0
    generator: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("speed_mps", "body_mass_kg", "pylon_length_m", "dt", "sample_rate"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and v > 0 and math.isfinite(v)):
                raise SpecError(f"{name} must be a positive number, got {v!r}",
                                where=f"blade evaluator: {name}")
        if not 0 <= self.knee_above_clamp_m < self.pylon_length_m:
            raise SpecError("knee_above_clamp_m must lie between 0 and the pylon length",
                            where="blade evaluator: knee_above_clamp_m")

    @property
    def units(self) -> dict[str, str]:
        return dict(BLADE_RESPONSE_UNITS)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["generator"] = {k: str(v) if isinstance(v, Path) else v
                          for k, v in dict(self.generator).items()}
        return {"evaluator": "blade", **d}

    def blade(self, point: Mapping[str, float]):
        """The generated blade of a design point."""
        return generate_blade(point, **dict(self.generator))

    def __call__(self, point: Mapping[str, float]) -> dict[str, float]:
        """Responses of one design point (see the module table)."""
        blade = self.blade(point).model
        stance, truth = generate_stance(
            blade, speed_mps=self.speed_mps, body_mass_kg=self.body_mass_kg,
            touchdown_angle_deg=self.touchdown_angle_deg,
            touchdown_vertical_speed_mps=self.touchdown_vertical_speed_mps,
            pylon_length_m=self.pylon_length_m, dt=self.dt, sample_rate=self.sample_rate,
        )
        return self._responses(blade, stance, truth)

    def _responses(self, blade: BladeModel, stance, truth: Mapping[str, Any]) -> dict[str, float]:
        m, g, L = self.body_mass_kg, STANDARD_GRAVITY, self.pylon_length_m
        t = np.asarray(stance.time)
        th = np.asarray(stance.clamp_pitch)
        hip_x = np.asarray(stance.clamp_x) + L * np.sin(th)
        hip_z = np.asarray(stance.clamp_z) + L * np.cos(th)
        # force on the body from the hip point mass's acceleration (central differences)
        h = float(t[1] - t[0])
        fx = np.zeros_like(hip_x)
        fz = np.full_like(hip_z, m * g)
        fx[1:-1] = m * (hip_x[2:] - 2 * hip_x[1:-1] + hip_x[:-2]) / h**2
        fz[1:-1] += m * (hip_z[2:] - 2 * hip_z[1:-1] + hip_z[:-2]) / h**2
        f_contact = np.asarray(truth["grf_z"])
        loaded = np.flatnonzero(f_contact > 1.0)
        i0, i1 = int(loaded[0]), int(loaded[-1])
        t_c = float(t[i1] - t[i0])
        dvx = float(truth["hip_speed_toeoff_mps"] - self.speed_mps)
        i_x = m * dvx
        sl = slice(i0, i1 + 1)
        i_z = float(np.trapezoid(fz[sl], t[sl]))
        i_z_net = i_z - m * g * t_c
        _, _, e = bouncing_ball(i_x, i_z_net, m, g=g)
        # knee extension moment; the GRF line passes through the moment-free hip hinge
        on = np.zeros(t.size, bool)
        on[i0:i1 + 1] = True
        on &= f_contact > 0.05 * f_contact.max()
        on[[0, -1]] = False
        d = L - self.knee_above_clamp_m  # hip -> knee along the pylon
        knee_x = hip_x[on] - d * np.sin(th[on])
        knee_z = hip_z[on] - d * np.cos(th[on])
        moment = knee_extension_moment(hip_x[on], hip_z[on], knee_x, knee_z, fx[on], fz[on])
        return {
            "delta_vx_m_per_s": dvx,
            "avg_vx_m_per_s": float((hip_x[i1] - hip_x[i0]) / max(t_c, 1e-12)),
            "impulse_x_Ns": float(i_x),
            "impulse_z_Ns": i_z,
            "impulse_z_net_Ns": float(i_z_net),
            "evaluation_E_m": float(e),
            "peak_grf_z_N": float(fz[sl].max()),
            "contact_time_s": float(truth["contact_time_s"]),
            "compression_m": float(truth["max_compression_m"]),
            "knee_moment_min_Nm": float(moment.min()),
            "swing_clearance_m": swing_clearance(
                blade, clamp_height_m=self.swing_clamp_height_m, pitch_deg=self.swing_pitch_deg),
            "blade_mass_kg": float(blade.mass),
        }


def make_evaluator(kind: str, **options: Any):
    """An evaluator by name: ``"blade"`` (:class:`BladeEvaluator`), ``"runner"``
    (:class:`bladelab.design.transfemoral.RunnerEvaluator`) or ``"collocation"``
    (:class:`bladelab.design.collocation_evaluator.CollocationEvaluator`), with its options as
    keywords."""
    if kind == "blade":
        return BladeEvaluator(**options)
    if kind == "runner":
        # a design run with another evaluator never needs the runner models:
        # deferred: the transfemoral runner loads them (~0.45 s)
        from bladelab.design.transfemoral import RunnerEvaluator

        return RunnerEvaluator(**options)
    if kind == "collocation":
        # a design run with another evaluator never needs CasADi or the runner models:
        # deferred: the collocation evaluator loads them (~0.4 s on top of the runner's)
        from bladelab.design.collocation_evaluator import CollocationEvaluator

        return CollocationEvaluator(**options)
    raise SpecError(f"unknown evaluator {kind!r}", where="evaluator",
                    hint="use 'blade', 'runner' or 'collocation'")
