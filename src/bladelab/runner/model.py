"""Build the planar runner (able-bodied, transtibial or transfemoral amputee) in MuJoCo with MjSpec.

MuJoCo supplies the multibody dynamics, the tendon (muscle path) lengths, velocities and moment
arms; muscles, ligaments and ground contact are computed by bladelab's own numba code
(:mod:`bladelab.runner.simulate`) and applied as forces. MuJoCo's native contact is disabled.

Coordinates (``RunnerModel.dof_names``, OpenSim names and signs): ``pelvis_tx``, ``pelvis_tz`` [m]
(pelvis centre of mass), ``pelvis_tilt`` (positive tilts the pelvis backward), ``hip_flexion_*``
(positive flexes), ``knee_angle_*`` (0 straight, negative flexes), ``ankle_angle_*`` (positive
dorsiflexes) / ``socket_angle_r`` (amputee), ``lumbar_extension`` (positive extends). All hinges
turn about the lab's −y axis, so that these signs hold with x forward and z up.
Side ``l`` is the intact leg of the amputee, ``r`` the prosthetic one. The transfemoral runner's
``knee_angle_r`` is its passive prosthetic knee (:mod:`bladelab.runner.prosthetic_knee`); it has
no ``ankle_angle_r``.

Geometry: SCONE H0918 (Apache-2.0), see :mod:`bladelab.runner.geometry`; masses, inertias and
muscles: seed 001 Tables 2.1–2.2 via :mod:`bladelab.runner.params`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from bladelab.blade.model import BladeModel
from bladelab.contact import hertz_sphere_stiffness
from bladelab.errors import ModelError
from bladelab.runner import geometry as geo
from bladelab.runner.layout import (
    CP_AZ,
    CP_BLADE,
    CP_RADIUS,
    CP_SITE,
    JP_COLUMNS,
    JP_EA,
    JP_EB,
    JP_HI,
    JP_LO,
    JP_SK,
    LAW_HUNT_CROSSLEY,
)
from bladelab.runner.multilink import add_multilink_blade, multilink_contact_rows
from bladelab.runner.muscle import MP_COLUMNS, MP_LOPT, MP_LTS
from bladelab.runner.params import (
    BLADE_ALIGNMENT_DEG,
    BLADE_EXTRA_LENGTH_M,
    BLADE_FRICTION,
    BLADE_OFFSET_A_M,
    BLADE_OFFSET_B_M,
    BLADE_RADIUS_M,
    PROSTHETIC_KINDS,
    RunnerParams,
    active_strength,
    blade_contact_modulus,
    default_runner_params,
    muscle_max_force,
    muscle_names,
    residual_tibia_factors,
    runner_params_from_dict,
    scale_ratios,
    segment_mass_ratio,
)

# Ligaments (joint-limit springs–dampers): (lower, upper) [deg], stiffness [N·m/rad],
# damping [N·m·s/rad]. Hip and ankle ranges and the knee's stiffness/damping from H0918; the knee
# range (−90°, 0°) and the soft lumbar limit at 0° from seed 001 §2.1 (the knee's flexion limit
# is the parameter set's ``knee_flexion_limit_deg``).
LIGAMENTS: dict[str, tuple[float, float, float, float]] = {
    "hip_flexion": (-40.0, 120.0, 500.0, 5.0),
    "knee_angle": (-90.0, 0.0, 114.592, 2.86479),
    "ankle_angle": (-60.0, 60.0, 500.0, 5.0),
    "lumbar_extension": (0.0, 0.0, 500.0, 5.0),
    "mtp_angle": (-30.0, 60.0, 100.0, 1.0),
    "midtarsal_angle": (-15.0, 30.0, 500.0, 5.0),
}
# Socket: stiff nonlinear torsional spring τ = −(K·q + K2·q·|q|) − D·q̇ (seed 001 §2.1).
SOCKET_STIFFNESS = 1000.0  # N·m/rad
SOCKET_STIFFNESS_QUADRATIC = 2.0e4  # N·m/rad²
SOCKET_DAMPING = 10.0  # N·m·s/rad
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

# The transfemoral prosthesis's COM below the knee axis, as a fraction of the knee-to-ground
# depth: a 1.2 kg knee unit at the top and about as much pylon and blade below (our estimate).
PROSTHETIC_SHANK_COM = 0.4
# With a multi-link blade, the knee unit and pylon (the prosthesis mass minus the blade's) have
# their COM this far below the knee axis [m, reference athlete]: mostly the knee unit.
PROSTHETIC_PYLON_COM_M = 0.08

# Tangential (friction) bristle spring and damper of every contact [N/m, N·s/m].
FRICTION_STIFFNESS = 5.0e4
FRICTION_DAMPING = 200.0


# Default time step [s]. Under running loads 0.5 ms leaves a 2 ms stance oscillation and a 4.8 %
# power-balance residual; 0.25 ms gives 0.4 % (docs/predictive.md), so 0.25 ms is the default.
DEFAULT_DT = 2.5e-4


@dataclass(frozen=True, eq=False)
class RunnerModel:
    """A compiled runner: MuJoCo model plus the parameter arrays of bladelab's force kernels.

    Attributes
    ----------
    params
        The parameter set it was built from.
    mj_model
        The MuJoCo model used for simulation: no native contact, no tendons (muscle forces are
        applied by bladelab as point forces along each path).
    mj_analysis_model
        The same model plus one spatial tendon and one tendon actuator per muscle (ctrl =
        −tendon force): MuJoCo's own MTU lengths, velocities and moment arms, for analyses and
        as an independent check of bladelab's path kinematics.
    dof_names, muscle_names, segment_names, contact_names
        Names in array order.
    muscle_params
        (n_muscles, 8): Fmax [N], l_opt [m], l_ts [m], pennation [rad], tendon strain at Fmax
        [-], active strength [-], passive strain at Fmax [-], maximum shortening velocity
        [l_opt/s] (:mod:`bladelab.runner.muscle`'s ``MP_*`` columns).
    path_points, path_start
        Muscle path points as (site id, body id) rows; muscle i uses rows
        ``path_start[i]:path_start[i+1]`` (origin to insertion).
    contact_params
        (n_contacts, 13): site id, body id, radius or x semi-axis [m], stiffness k [N/m^n],
        dissipation [s/m], friction [-], leg (0 = left/intact, 1 = right/prosthetic), is_blade
        (0/1), z semi-axis [m], law (0 Hunt–Crossley, 1 smooth spring–damper), exponent n,
        damping [N·s/m] and transition width [m] (spring–damper). Spheres have equal semi-axes;
        the multi-link blade's soles are ellipses in the site's x–z plane.
    joint_params
        (n_dof, 8): ligament lower, upper [rad], stiffness [N·m/rad], damping [N·m·s/rad], spring
        K [N·m/rad], K2 [N·m/rad²], damping D while q̇ < 0 and while q̇ > 0 [N·m·s/rad] (the
        socket's, a blade joint's, the toes', a prosthetic knee's).
    blade_modulus
        Plane-strain modulus E [N/m²] of the blade sphere (nan for the able model).
    stand_qpos
        A standing pose with every contact just touching the ground.
    blade_model
        The multi-link blade worn, if any.
    mj_dynamics_model
        ``mj_model`` without sites (same bodies, joints and dofs), for the implicit scheme
        (:mod:`bladelab.runner.implicit`), which places the sites itself.
    """

    params: RunnerParams
    mj_model: mujoco.MjModel
    dof_names: tuple[str, ...]
    muscle_names: tuple[str, ...]
    segment_names: tuple[str, ...]
    contact_names: tuple[str, ...]
    muscle_params: np.ndarray
    path_points: np.ndarray
    path_start: np.ndarray
    mj_analysis_model: mujoco.MjModel
    contact_params: np.ndarray
    joint_params: np.ndarray
    blade_modulus: float
    stand_qpos: np.ndarray = field(repr=False)
    blade_model: BladeModel | None = None
    mj_dynamics_model: mujoco.MjModel | None = field(default=None, repr=False)

    @property
    def kind(self) -> str:
        return self.params.kind

    @property
    def total_mass(self) -> float:
        """Total mass [kg]."""
        return float(np.sum(self.mj_model.body_mass))

    @property
    def gravity(self) -> float:
        """Gravity of the model [m/s²] (its parameter set's)."""
        return self.params.gravity_m_per_s2

    @property
    def body_weight(self) -> float:
        """Body weight [N]."""
        return self.total_mass * self.gravity

    def segment_mass(self, name: str) -> float:
        """Mass [kg] of one segment."""
        return float(self.mj_model.body_mass[self.mj_model.body(name).id])

    def dof(self, name: str) -> int:
        """Index of a coordinate in qpos/qvel."""
        try:
            return self.dof_names.index(name)
        except ValueError:
            raise ModelError(
                f"no coordinate {name!r}", hint=f"use one of {self.dof_names}"
            ) from None

    def to_dict(self) -> dict:
        return {
            "kind": self.kind,
            "blade": None
            if self.kind not in PROSTHETIC_KINDS
            else (self.blade_model.name if self.blade_model is not None else self.params.blade),
            "total_mass_kg": self.total_mass,
            "dof": list(self.dof_names),
            "muscles": {
                n: {"Fmax_N": float(p[0]), "l_opt_m": float(p[1]), "l_ts_m": float(p[2])}
                for n, p in zip(self.muscle_names, self.muscle_params, strict=True)
            },
            "blade_modulus_N_per_m2": None
            if math.isnan(self.blade_modulus)
            else self.blade_modulus,
        }


def _v(p: tuple[float, float, float], s: float) -> list[float]:
    return list(geo.to_lab(p, s))


def _lab_inertia(ixx: float, iyy: float, izz: float, factor: float) -> list[float]:
    """Principal inertias in lab axes; the sagittal one (lab y = OpenSim z) is kept exact, the
    out-of-plane x one is raised if needed to satisfy the triangle inequality (it has no effect
    in the planar model; the prosthesis of Table 2.1 violates it)."""
    ix, iy, iz = ixx * factor, izz * factor, iyy * factor
    if ix + iz < iy:
        ix = iy - iz + 1e-6
    return [ix, iy, iz]


def _sub(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> tuple[float, float, float]:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def build_runner(
    params: RunnerParams | str = "amputee",
    *,
    blade: str | None = None,
    blade_model: BladeModel | None = None,
    body: str = "seed001",
) -> RunnerModel:
    """Build a runner model from a parameter set (or the name ``"able"`` / ``"amputee"`` /
    ``"transfemoral"``).

    Parameters
    ----------
    params
        A :class:`RunnerParams` or the name of a built-in parameter set.
    blade
        Override the blade category of an amputee parameter set (e.g. ``"Cat5"``).
    blade_model
        Wear this multi-link blade (:class:`bladelab.blade.BladeModel`, e.g. with identified K*
        and D*) instead of the category's contact sphere (amputee only; see
        :mod:`bladelab.runner.multilink`; needs a step of about 1e-4 s).
    body
        The body of a built-in parameter set named by ``params``: ``"seed001"``, ``"toes"``
        or ``"human"`` (:data:`bladelab.runner.params.BODIES`).
    """
    if isinstance(params, str):
        params = default_runner_params(params, blade=blade, body=body)
    elif body != "seed001":
        raise ModelError("body= applies to the built-in parameter sets only", where="body",
                         hint="set foot and tendon_strain_at_fmax in the parameter file")
    elif blade is not None:
        params = runner_params_from_dict({**params.model_dump(), "blade": blade})
    amputee = params.kind == "amputee"
    transfemoral = params.kind == "transfemoral"
    prosthetic = params.kind in PROSTHETIC_KINDS
    if blade_model is not None and not prosthetic:
        raise ModelError("only an amputee model wears a blade", where="blade_model")
    s = scale_ratios(params)[1]
    mr = segment_mass_ratio(params)  # the muscles' forces scale with scale_ratios's

    spec = mujoco.MjSpec()
    spec.modelname = f"bladelab_runner_{params.kind}"
    spec.option.timestep = DEFAULT_DT
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    spec.option.gravity = [0.0, 0.0, -params.gravity_m_per_s2]
    spec.worldbody.add_geom(
        name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[50, 1, 0.1], contype=0, conaffinity=0
    )

    axis = [0.0, -1.0, 0.0]
    bodies: dict[str, object] = {}
    joint_child: dict[str, tuple[float, float, float]] = {}  # COM-relative joint point per body

    def sb(name: str) -> float:
        """The length scale of body ``name`` [-]: the height's, times its segment's factor."""
        return s * _segment_factor(params, name)

    def inertial(body, name: str, com: list[float]) -> None:
        seg = params.segments[name]
        ixx, iyy, izz = seg.inertia_kg_m2
        km, ki = residual_tibia_factors(params) if name == "tibia_res_r" else (1.0, 1.0)
        body.explicitinertial = True
        body.mass = seg.mass_kg * mr * km
        body.ipos = com
        body.inertia = _lab_inertia(ixx, iyy, izz, mr * sb(name) * sb(name) * ki)

    pelvis = spec.worldbody.add_body(name="pelvis", pos=[0, 0, 0])
    pelvis.add_joint(name="pelvis_tx", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
    pelvis.add_joint(name="pelvis_tz", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    pelvis.add_joint(name="pelvis_tilt", type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    inertial(pelvis, "pelvis", [0, 0, 0])
    bodies["pelvis"] = pelvis
    joint_child["pelvis"] = (0.0, 0.0, 0.0)
    # each body's joint point standing straight (OpenSim axes [m]), with the segments' length
    # factors and without them: the muscles' neutral lengths, which scale their fibres and
    # tendons (OpenSim's rule)
    neutral = {"pelvis": (np.zeros(3), np.zeros(3))}

    def add(name: str, seg: str, joint: str, dof: str, parent: str, ppos, cpos, com=None):
        parent_origin = joint_child[parent]
        pos = _v(_sub(ppos, parent_origin), sb(parent))
        offset = np.subtract(ppos, parent_origin)
        neutral[name] = (neutral[parent][0] + offset * sb(parent),
                         neutral[parent][1] + offset * s)
        body = bodies[parent].add_body(name=name, pos=pos)
        body.add_joint(name=dof, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
        inertial(body, seg, _v(_sub((0, 0, 0), cpos), sb(name)) if com is None else com)
        bodies[name] = body
        joint_child[name] = cpos
        return body

    for side in ("l", "r"):
        par, pp, pc = geo.JOINTS[f"hip_{side}"]
        add(
            f"femur_{side}", f"femur_{side}", f"hip_{side}", f"hip_flexion_{side}", "pelvis", pp, pc
        )
        par, pp, pc = geo.JOINTS[f"knee_{side}"]
        if side == "r" and transfemoral:
            knee = {"parent": "femur_r", "pos": _v(_sub(pp, joint_child["femur_r"]),
                                                   sb("femur_r")),
                    "joint": "knee_angle_r"}
            depth = _prosthetic_bottom(s, params.shank_length_factor, 0.0)
            if blade_model is None:
                _add_prosthesis(bodies, joint_child, params, s, mr, axis, depth=depth,
                                com_fraction=PROSTHETIC_SHANK_COM, **knee)
            else:
                add_multilink_blade(bodies, joint_child, params, s, mr, axis, blade_model,
                                    depth, com_z=-PROSTHETIC_PYLON_COM_M, **knee)
        elif side == "r" and amputee:
            table_len = params.residual_tibia_fraction * geo.TIBIA_LENGTH_M  # at 1.80 m
            res_len = table_len * sb("tibia_res_r")
            com = [0.0, 0.0, -0.5 * res_len]
            add("tibia_res_r", "tibia_res_r", "knee_r", "knee_angle_r", "femur_r", pp, pc, com=com)
            depth = _prosthetic_bottom(s, params.shank_length_factor, table_len)
            if blade_model is None:
                _add_prosthesis(bodies, joint_child, params, s, mr, axis, parent="tibia_res_r",
                                pos=[0.0, 0.0, -res_len], joint="socket_angle_r",
                                depth=depth)
            else:
                add_multilink_blade(bodies, joint_child, params, s, mr, axis, blade_model,
                                    depth, pos=[0.0, 0.0, -res_len])
        else:
            add(
                f"tibia_{side}",
                f"tibia_{side}",
                f"knee_{side}",
                f"knee_angle_{side}",
                f"femur_{side}",
                pp,
                pc,
            )
            par, pp, pc = geo.JOINTS[f"ankle_{side}"]
            body = add(
                f"calcn_{side}",
                f"calcn_{side}",
                f"ankle_{side}",
                f"ankle_angle_{side}",
                f"tibia_{side}",
                pp,
                pc,
            )
            ball = geo.FOOT_SPHERES["toe"]
            ball_in_calcn = _v(_sub(ball, pc), s)
            fore, fore_origin = body, pc
            if params.arch is not None:
                fore = _add_forefoot(body, side, _v(_sub(MIDTARSAL_HINGE_M, pc), s),
                                     ball_in_calcn, s, axis)
                fore_origin = MIDTARSAL_HINGE_M
            elif params.foot == "toes":
                _add_toes(body, side, ball_in_calcn, s, axis,
                          _take_mass(body, TOES_MASS_FRACTION, _toes_com_at(ball_in_calcn, s)))
            for sph, p in geo.FOOT_SPHERES.items():
                on, origin = (fore, fore_origin) if sph == "toe" else (body, pc)
                on.add_site(
                    name=f"{sph}_{side}",
                    pos=_v(_sub(p, origin), s),
                    size=[geo.FOOT_SPHERE_RADIUS_M * s, 0, 0],
                )
    par, pp, pc = geo.JOINTS["lumbar"]
    add("torso", "torso", "lumbar", "lumbar_extension", "pelvis", pp, pc)

    # muscles: sites on bodies, spatial tendons, tendon actuators (ctrl = −tendon force)
    names = muscle_names(params.kind, params.myodesis)
    mp = np.zeros((len(names), MP_COLUMNS))
    strength = active_strength(params)
    path_sites: list[str] = []
    path_start = [0]
    tendons, actuators = [], []
    neutral_length = np.zeros((len(names), 2))  # standing straight: scaled, uniform [m]
    for i, mname in enumerate(names):
        mtype, side = mname.rsplit("_", 1)
        tendon = spec.add_tendon(name=mname)
        previous = None
        for k, (body_name, p) in enumerate(geo.muscle_path(mtype, side)):
            if body_name == "tibia_r" and amputee:
                body_name, origin = "tibia_res_r", joint_child["tibia_res_r"]
            elif body_name == "tibia_r" and transfemoral:
                # a myodesis: the tibial point, with the knee straight, fixed on the femur
                body_name, p = "femur_r", _myodesis_point(p)
                origin = joint_child["femur_r"]
            else:
                origin = joint_child[body_name]
            site = f"{mname}_p{k}"
            bodies[body_name].add_site(name=site, pos=_v(_sub(p, origin), sb(body_name)))
            local = np.subtract(p, origin)
            point = (neutral[body_name][0] + local * sb(body_name),
                     neutral[body_name][1] + local * s)
            if previous is not None:
                neutral_length[i] += [np.linalg.norm(point[j] - previous[j]) for j in (0, 1)]
            previous = point
            tendon.wrap_site(site)
            path_sites.append(site)
        path_start.append(len(path_sites))
        act = spec.add_actuator(name=mname, trntype=mujoco.mjtTrn.mjTRN_TENDON, target=mname)
        act.ctrllimited = False
        tendons.append(tendon)
        actuators.append(act)
        mt = params.muscle_types[mtype]
        residual = params.residual_muscle_strength.get(mtype, 1.0) if (
            transfemoral and side == "r") else 1.0
        mp[i] = (
            muscle_max_force(params, mtype) * residual,
            mt.optimal_fiber_length_m * s,
            mt.tendon_slack_length_m * s,
            mt.pennation_rad,
            mt.tendon_strain_at_fmax,
            strength,
            mt.passive_strain_at_fmax,
            params.max_shortening_velocity_lopt_per_s,
        )
    if params.thigh_length_factor != 1.0 or params.shank_length_factor != 1.0:
        ratio = neutral_length[:, 0] / neutral_length[:, 1]
        mp[:, MP_LOPT] *= ratio
        mp[:, MP_LTS] *= ratio

    analysis_model = spec.compile()
    # the simulation model has no tendons: bladelab computes the (straight-line, via-point) path
    # lengths and applies the muscle forces itself; MuJoCo's tendon stage cost ~1/3 of a step
    for element in actuators + tendons:
        spec.delete(element)
    model = spec.compile()
    path = np.array(
        [(model.site(n).id, model.site_bodyid[model.site(n).id]) for n in path_sites],
        dtype=np.int64,
    )
    dof_names = tuple(model.joint(j).name for j in range(model.njnt))
    segment_names = tuple(model.body(b).name for b in range(1, model.nbody))

    # contacts
    contacts, rows = [], []

    def sphere(name: str, radius: float, modulus: float, dissipation: float, friction: float,
               leg: int, blade: int) -> None:
        """A Hunt–Crossley sphere (Hertz stiffness of ``radius`` and ``modulus``) at site
        ``name``."""
        site = model.site(name)
        contacts.append(name)
        rows.append((site.id, model.site_bodyid[site.id], radius,
                     hertz_sphere_stiffness(radius, modulus), dissipation, friction, leg, blade,
                     radius, LAW_HUNT_CROSSLEY, 1.5, 0.0, 0.0))

    law = params.foot_contact
    foot_law = (law.plane_strain_modulus_N_per_m2, law.dissipation_s_per_m, law.friction)
    for side, leg in (("l", 0), ("r", 1)):
        if side == "r" and prosthetic:
            continue
        for sph in geo.FOOT_SPHERES:
            sphere(f"{sph}_{side}", geo.FOOT_SPHERE_RADIUS_M * s, *foot_law, leg, 0)
        if params.foot == "toes":
            sphere(f"toetip_{side}", TOETIP_RADIUS_M * s, *foot_law, leg, 0)
    e_blade = math.nan
    if prosthetic and blade_model is not None:
        for i, row in enumerate(multilink_contact_rows(model, blade_model)):
            contacts.append(f"blade_sole{i}")
            rows.append(row)
    elif prosthetic:
        e_blade = blade_contact_modulus(params)
        sphere("blade_r", BLADE_RADIUS_M, e_blade, params.blade_dissipation_s_per_m,
               BLADE_FRICTION, 1, 1)
    cp = np.array(rows, dtype=np.float64)

    jp = np.zeros((len(dof_names), JP_COLUMNS))
    jp[:, JP_LO], jp[:, JP_HI] = -np.inf, np.inf
    for i, dn in enumerate(dof_names):
        base = dn[:-2] if dn.endswith(("_l", "_r")) else dn
        if base in LIGAMENTS:
            lo, hi, k, d = LIGAMENTS[base]
            if base == "knee_angle":
                lo = -params.knee_flexion_limit_deg
            if base == "lumbar_extension" and params.lumbar_passive == "spring":
                jp[i, JP_SK:JP_EA] = (k, 0.0, d, d)  # the limit's K and D about 0°, no limit
            else:
                jp[i, :4] = (math.radians(lo), math.radians(hi), k, d)
        capsule = params.capsule_moments.get(base)
        if capsule is not None:
            jp[i, JP_EA] = capsule.moment_at_zero_Nm
            jp[i, JP_EB] = math.degrees(capsule.rate_per_deg)  # 1/deg → 1/rad
        if base == "mtp_angle":
            toe = params.toe_hinge
            jp[i, JP_SK:JP_EA] = (toe.stiffness_Nm_per_rad, 0.0, toe.damping_Nms_per_rad,
                                  toe.damping_Nms_per_rad)
        if base == "midtarsal_angle":
            arch = params.arch
            jp[i, JP_SK:JP_EA] = (arch.stiffness_Nm_per_rad, 0.0, arch.damping_Nms_per_rad,
                                  arch.damping_Nms_per_rad)
        if dn == "socket_angle_r":
            jp[i, JP_SK:JP_EA] = (SOCKET_STIFFNESS, SOCKET_STIFFNESS_QUADRATIC,
                                  SOCKET_DAMPING, SOCKET_DAMPING)
        if dn == "knee_angle_r" and transfemoral:
            jp[i] = params.prosthetic_knee.joint_row()
        if dn.startswith("blade_joint") and blade_model is not None:
            j = blade_model.joints[int(dn.removeprefix("blade_joint"))]
            jp[i, JP_SK:JP_EA] = (j.stiffness, j.stiffness_quadratic, j.damping, j.damping)

    # the implicit scheme's model: no sites either (MuJoCo's site kinematics was ~1/6 of its
    # step); bladelab places the sites from mj_model's site_bodyid, site_pos and site_quat
    for site in list(spec.sites):
        spec.delete(site)
    dynamics_model = spec.compile()
    if dynamics_model.nbody != model.nbody or dynamics_model.nv != model.nv:
        raise RuntimeError("the site-free dynamics model differs from the simulation model")
    runner = RunnerModel(
        params=params,
        mj_model=model,
        dof_names=dof_names,
        muscle_names=names,
        segment_names=segment_names,
        contact_names=tuple(contacts),
        muscle_params=mp,
        path_points=path,
        path_start=np.array(path_start, dtype=np.int64),
        mj_analysis_model=analysis_model,
        contact_params=cp,
        joint_params=jp,
        blade_modulus=e_blade,
        stand_qpos=np.zeros(model.nq),
        blade_model=blade_model,
        mj_dynamics_model=dynamics_model,
    )
    runner.stand_qpos[:] = _standing_pose(runner)
    return runner


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


def _myodesis_point(p: tuple[float, float, float]) -> tuple[float, float, float]:
    """A tibial path point (tibia COM-relative) as a point of the femur (femur COM-relative)
    where it lies with the knee straight: a myodesis anchors the muscle there."""
    _, knee_in_femur, knee_in_tibia = geo.JOINTS["knee_r"]
    return _sub(knee_in_femur, _sub(knee_in_tibia, p))


def _prosthetic_bottom(s: float, k_shank: float, res_len: float) -> float:
    """Depth [m] below the socket of the prosthetic leg's lowest point, for a socket
    ``res_len`` [m at 1.80 m, before ``k_shank``] below the knee: the straight prosthetic leg
    is 3 cm longer (knee to ground) than the intact one, whose shank is ``k_shank`` times the
    model's; ``s``: the height's scale."""
    intact = geo.TIBIA_LENGTH_M * k_shank + geo.ANKLE_TO_SOLE_M
    return (intact + BLADE_EXTRA_LENGTH_M) * s - res_len * k_shank * s


def _segment_factor(params: RunnerParams, body: str) -> float:
    """The length factor [-] of a body's segment: the thighs' and the shanks' (the residual
    tibia's too) of the parameter set, 1 for every other body."""
    if body.startswith("femur_"):
        return params.thigh_length_factor
    if body in ("tibia_l", "tibia_r", "tibia_res_r"):
        return params.shank_length_factor
    return 1.0


def _add_prosthesis(bodies, joint_child, params, s, mr, axis, *, parent: str, pos,
                    joint: str, depth: float, com_fraction: float | None = None) -> None:
    """The prosthesis below a hinge ``joint`` on ``parent`` at ``pos`` (parent frame [m]), with
    the blade contact sphere: the socket, pylon and blade of the transtibial runner (on the
    residual tibia, hinge ``socket_angle_r``) or the knee unit, pylon and blade of the
    transfemoral runner (on the residual femur, hinge ``knee_angle_r``).

    The sphere's bottom lies ``depth`` [m] below the hinge (the straight prosthetic leg 3 cm
    longer than the intact one, knee to ground). The transtibial prosthesis's COM lies
    a = 0.069 m behind and b = 0.0693 m above the sphere centre, that offset turned by the 9°
    alignment (seed 001 Fig. 2.3, our reading); with ``com_fraction`` the COM lies that
    fraction of ``depth`` straight below the hinge instead.
    """
    centre = (0.0, -(depth - BLADE_RADIUS_M))  # (x, z) in the hinge frame
    if com_fraction is None:
        ox, oz = geo.rotate_pitch(
            BLADE_OFFSET_A_M * s, -BLADE_OFFSET_B_M * s, math.radians(BLADE_ALIGNMENT_DEG)
        )
        com = [centre[0] - ox, 0.0, centre[1] - oz]
    else:
        com = [0.0, 0.0, -com_fraction * depth]
    body = bodies[parent].add_body(name="prosthesis_r", pos=list(pos))
    body.add_joint(name=joint, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
    seg = params.segments["prosthesis_r"]
    ixx, iyy, izz = seg.inertia_kg_m2
    body.explicitinertial = True
    body.mass = seg.mass_kg * mr
    body.ipos = com
    body.inertia = _lab_inertia(ixx, iyy, izz, mr * s * s)
    body.add_site(name="blade_r", pos=[centre[0], 0.0, centre[1]], size=[BLADE_RADIUS_M, 0, 0])
    bodies["prosthesis_r"] = body
    joint_child["prosthesis_r"] = (0.0, 0.0, 0.0)


def contact_heights(runner: RunnerModel, qpos: np.ndarray,
                    data: mujoco.MjData | None = None) -> np.ndarray:
    """Lowest point height [m] of every contact sphere at a pose (negative = penetrating);
    ``data``: a ``MjData`` of ``runner.mj_model`` to reuse (poses in a loop)."""
    if data is None:
        data = mujoco.MjData(runner.mj_model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(runner.mj_model, data)
    out = []
    for r in runner.contact_params:
        site = int(r[CP_SITE])
        xm = data.site_xmat[site]
        h = math.hypot(r[CP_RADIUS] * xm[6], r[CP_AZ] * xm[8])
        out.append(data.site_xpos[site, 2] - h)
    return np.array(out)


def _standing_pose(runner: RunnerModel) -> np.ndarray:
    """Upright pose with all contacts touching: the longer prosthetic leg's knee is flexed."""
    q = np.zeros(runner.mj_model.nq)
    if runner.kind in PROSTHETIC_KINDS:
        iknee = runner.dof("knee_angle_r")
        ihip = runner.dof("hip_flexion_r")
        lo, hi = -1.5, 0.0
        for _ in range(50):  # bisection: blade bottom level with the intact foot
            mid = 0.5 * (lo + hi)
            q[iknee], q[ihip] = mid, -0.5 * mid
            h = contact_heights(runner, q)
            blade = runner.contact_params[:, CP_BLADE] == 1
            if h[blade].min() < h[~blade].min():
                hi = mid
            else:
                lo = mid
            q[iknee], q[ihip] = 0.5 * (lo + hi), -0.25 * (lo + hi)
    h = contact_heights(runner, q)
    q[runner.dof("pelvis_tz")] -= h.min()
    return q
