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
from bladelab.runner.blade_categories import BLADE_FRICTION, BLADE_RADIUS_M
from bladelab.runner.feet import TOETIP_RADIUS_M, add_foot
from bladelab.runner.frames import difference, lab_inertia, lab_vector
from bladelab.runner.joints import joint_params
from bladelab.runner.layout import (
    CP_AZ,
    CP_BLADE,
    CP_RADIUS,
    CP_SITE,
    LAW_HUNT_CROSSLEY,
)
from bladelab.runner.multilink import add_multilink_blade, multilink_contact_rows
from bladelab.runner.muscle import MP_COLUMNS, MP_LOPT, MP_LTS
from bladelab.runner.params import (
    PROSTHETIC_KINDS,
    RunnerParams,
    default_runner_params,
    muscle_names,
    runner_params_from_dict,
)
from bladelab.runner.prosthesis import (
    PROSTHETIC_PYLON_COM_M,
    PROSTHETIC_SHANK_COM,
    add_prosthesis,
    blade_contact_modulus,
    prosthetic_bottom,
)
from bladelab.runner.scaling import (
    active_strength,
    muscle_max_force,
    residual_tibia_factors,
    scale_ratios,
    segment_mass_ratio,
)

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
        body.inertia = lab_inertia(ixx, iyy, izz, mr * sb(name) * sb(name) * ki)

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
        pos = lab_vector(difference(ppos, parent_origin), sb(parent))
        offset = np.subtract(ppos, parent_origin)
        neutral[name] = (neutral[parent][0] + offset * sb(parent),
                         neutral[parent][1] + offset * s)
        body = bodies[parent].add_body(name=name, pos=pos)
        body.add_joint(name=dof, type=mujoco.mjtJoint.mjJNT_HINGE, axis=axis)
        inertial(body, seg,
                 lab_vector(difference((0, 0, 0), cpos), sb(name)) if com is None else com)
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
            knee = {"parent": "femur_r",
                    "pos": lab_vector(difference(pp, joint_child["femur_r"]), sb("femur_r")),
                    "joint": "knee_angle_r"}
            depth = prosthetic_bottom(s, params.shank_length_factor, 0.0,
                                      params.prosthesis_extra_length_m)
            if blade_model is None:
                add_prosthesis(bodies, joint_child, params, s, mr, axis, depth=depth,
                               com_fraction=PROSTHETIC_SHANK_COM, **knee)
            else:
                add_multilink_blade(bodies, joint_child, params, s, mr, axis, blade_model,
                                    depth, com_z=-PROSTHETIC_PYLON_COM_M, **knee)
        elif side == "r" and amputee:
            table_len = params.residual_tibia_fraction * geo.TIBIA_LENGTH_M  # at 1.80 m
            res_len = table_len * sb("tibia_res_r")
            com = [0.0, 0.0, -0.5 * res_len]
            add("tibia_res_r", "tibia_res_r", "knee_r", "knee_angle_r", "femur_r", pp, pc, com=com)
            depth = prosthetic_bottom(s, params.shank_length_factor, table_len,
                                      params.prosthesis_extra_length_m)
            if blade_model is None:
                add_prosthesis(bodies, joint_child, params, s, mr, axis, parent="tibia_res_r",
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
            add_foot(body, side, pc, s, axis, params)
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
            bodies[body_name].add_site(name=site,
                                       pos=lab_vector(difference(p, origin), sb(body_name)))
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

    jp = joint_params(params, dof_names, blade_model)

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


def _myodesis_point(p: tuple[float, float, float]) -> tuple[float, float, float]:
    """A tibial path point (tibia COM-relative) as a point of the femur (femur COM-relative)
    where it lies with the knee straight: a myodesis anchors the muscle there."""
    _, knee_in_femur, knee_in_tibia = geo.JOINTS["knee_r"]
    return difference(knee_in_femur, difference(knee_in_tibia, p))


def _segment_factor(params: RunnerParams, body: str) -> float:
    """The length factor [-] of a body's segment: the thighs' and the shanks' (the residual
    tibia's too) of the parameter set, 1 for every other body."""
    if body.startswith("femur_"):
        return params.thigh_length_factor
    if body in ("tibia_l", "tibia_r", "tibia_res_r"):
        return params.shank_length_factor
    return 1.0


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
