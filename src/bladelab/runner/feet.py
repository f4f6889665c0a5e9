"""The runner's feet in MjSpec: the calcaneus's contact sites, the toes and the arch.

Seed 001's foot is one rigid calcaneus with a heel and a ball contact sphere (radius 0.03 m;
:mod:`bladelab.runner.geometry`). ``RunnerParams.foot = "toes"`` adds a toe segment on a passive
metatarsophalangeal hinge at the ball sphere's centre, with a toe-tip sphere
(docs/runner-model.md, "The toe segment"); ``RunnerParams.arch`` adds a midtarsal hinge between
the calcaneus and a forefoot that carries the ball sphere and the toes (docs/runner-model.md,
"The arch"). The segments' masses are taken from the calcaneus, so that the foot's mass and
centre of mass in the neutral pose are seed 001's. Lengths [m] and inertias [kg·m²] are the
reference athlete's (1.80 m), scaled with the height.
"""

from __future__ import annotations

import mujoco

from bladelab.runner import geometry as geo
from bladelab.runner.frames import difference, lab_vector
from bladelab.runner.params import RunnerParams

# The toe segment of ``RunnerParams.foot = "toes"`` (docs/runner-model.md, "The toe segment").
# Metatarsophalangeal hinge at the ball sphere's centre; its passive spring and damper about
# the neutral pose: ``RunnerParams.toe_hinge``.
# Share of the foot's mass in the toes: gait2392's toes/(calcn + toes) (0.2166/1.4666 kg).
TOES_MASS_FRACTION = 0.148
TOES_INERTIA_KG_M2 = 1.0e-4  # about its COM, every axis (a 0.18 kg, 6 cm segment: ≈ 0.6e-4)
TOES_COM_M = (0.025, -0.01)  # toes COM from the MTP hinge (forward, up) [m], reference athlete
TOETIP_RADIUS_M = 0.02
TOETIP_CENTRE_M = (0.05, -0.01)  # toe-tip sphere centre from the MTP hinge; its bottom is
# level with the ball sphere's (radius 0.03) in the neutral pose; foot length 0.27 m in all

# The arch of ``RunnerParams.arch`` (docs/runner-model.md, "The arch"): a midtarsal hinge
# 4.5 cm ahead of the ankle at its height (the talonavicular joint; calcaneus COM-relative,
# OpenSim axes [m], reference athlete), a forefoot of the cuneiforms and metatarsals carrying
# the ball sphere and the toes.
MIDTARSAL_HINGE_M = (-0.006, 0.012, 0.0)
FOREFOOT_MASS_FRACTION = 0.30  # of the foot (our estimate: the bones' share ahead of the hinge)
FOREFOOT_INERTIA_KG_M2 = 3.0e-4  # about its COM, every axis (0.38 kg over 9 cm: ≈ 2.6e-4)


def add_foot(calcn, side: str, ankle: tuple[float, float, float], s: float,
             axis: list[float], params: RunnerParams) -> None:
    """The foot on the calcaneus body ``calcn`` of side ``side``, whose frame's origin is its
    ankle joint at ``ankle`` (calcaneus COM-relative, OpenSim axes [m], reference athlete): the
    forefoot and toes of ``params.arch`` and ``params.foot`` on their hinges about ``axis``, and
    the heel and ball contact sites (the ball's on the forefoot where there is one); ``s``: the
    height's scale."""
    ball = geo.FOOT_SPHERES["toe"]
    ball_in_calcn = lab_vector(difference(ball, ankle), s)
    fore, fore_origin = calcn, ankle
    if params.arch is not None:
        fore = _add_forefoot(calcn, side, lab_vector(difference(MIDTARSAL_HINGE_M, ankle), s),
                             ball_in_calcn, s, axis)
        fore_origin = MIDTARSAL_HINGE_M
    elif params.foot == "toes":
        _add_toes(calcn, side, ball_in_calcn, s, axis,
                  _take_mass(calcn, TOES_MASS_FRACTION, _toes_com_at(ball_in_calcn, s)))
    for sph, p in geo.FOOT_SPHERES.items():
        on, origin = (fore, fore_origin) if sph == "toe" else (calcn, ankle)
        on.add_site(
            name=f"{sph}_{side}",
            pos=lab_vector(difference(p, origin), s),
            size=[geo.FOOT_SPHERE_RADIUS_M * s, 0, 0],
        )


def _toes_com_at(hinge: list[float], s: float) -> list[float]:
    """The toes' centre of mass in the frame of the MTP ``hinge`` given [m] (in the sagittal
    plane: its lateral coordinate is 0, which no sagittal quantity sees)."""
    return [hinge[0] + TOES_COM_M[0] * s, 0.0, hinge[2] + TOES_COM_M[1] * s]


def _take_mass(body, fraction: float, com: list[float]) -> float:
    """Take ``fraction`` of ``body``'s mass away at ``com`` (its frame [m]) and return it
    [kg]: the body keeps its inertia, and its centre of mass moves so that the mass taken and
    the body together have the centre of mass the body had."""
    m = body.mass
    taken = fraction * m
    body.mass = m - taken
    body.ipos = [(m * c - taken * t) / (m - taken) for c, t in zip(body.ipos, com, strict=True)]
    return taken


def _add_toes(parent, side: str, hinge: list[float], s: float, axis: list[float],
              mass: float) -> None:
    """A toe segment of ``mass`` [kg] on a metatarsophalangeal hinge at ``hinge`` (the parent
    body's frame [m]: the calcaneus, or the forefoot of a foot with an arch).

    The caller takes that mass, :data:`TOES_MASS_FRACTION` of the foot's, from the calcaneus
    (:func:`_take_mass`), so that the foot's centre of mass in the neutral pose stays where
    seed 001's is; the calcaneus keeps its inertia (the toes' share of it is < 2 %).
    """
    toes = parent.add_body(name=f"toes_{side}", pos=hinge)
    toes.add_joint(name=f"mtp_angle_{side}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    toes.explicitinertial = True
    toes.mass = mass
    toes.ipos = [TOES_COM_M[0] * s, 0.0, TOES_COM_M[1] * s]
    toes.inertia = [TOES_INERTIA_KG_M2 * s * s] * 3
    toes.add_site(name=f"toetip_{side}",
                  pos=[TOETIP_CENTRE_M[0] * s, 0.0, TOETIP_CENTRE_M[1] * s],
                  size=[TOETIP_RADIUS_M * s, 0, 0])


def _add_forefoot(calcn, side: str, hinge: list[float], ball: list[float], s: float,
                  axis: list[float]):
    """The forefoot on a midtarsal hinge at ``hinge`` and the toes on its MTP hinge at
    ``ball`` (both in the calcaneus frame [m]); returns the forefoot body.

    The forefoot (:data:`FOREFOOT_MASS_FRACTION` of the foot, its centre of mass halfway
    from the hinge to the ball) and the toes take their mass from the calcaneus
    (:func:`_take_mass`): the foot's mass and centre of mass in the neutral pose are seed
    001's.
    """
    to_ball = [b - h for b, h in zip(ball, hinge, strict=True)]
    fore_com = [0.5 * d for d in to_ball]
    m_foot = calcn.mass
    m_fore = _take_mass(calcn, FOREFOOT_MASS_FRACTION,
                        [float(h + c) for h, c in zip(hinge, fore_com, strict=True)])
    m_toes = _take_mass(calcn, TOES_MASS_FRACTION * m_foot / calcn.mass,
                        _toes_com_at(ball, s))
    fore = calcn.add_body(name=f"forefoot_{side}", pos=hinge)
    fore.add_joint(name=f"midtarsal_angle_{side}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    fore.explicitinertial = True
    fore.mass = m_fore
    fore.ipos = fore_com
    fore.inertia = [FOREFOOT_INERTIA_KG_M2 * s * s] * 3
    _add_toes(fore, side, to_ball, s, axis, m_toes)
    return fore


__all__ = [
    "FOREFOOT_INERTIA_KG_M2",
    "FOREFOOT_MASS_FRACTION",
    "MIDTARSAL_HINGE_M",
    "TOES_COM_M",
    "TOES_INERTIA_KG_M2",
    "TOES_MASS_FRACTION",
    "TOETIP_CENTRE_M",
    "TOETIP_RADIUS_M",
    "add_foot",
]
