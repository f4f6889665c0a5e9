"""Reflex controller with a gait-state machine per leg (Geyer & Herr 2010, as in SCONE).

Each leg is in one of five states (SCONE's ``GaitStateController``): ``EarlyStance``,
``LateStance``, ``Liftoff``, ``Swing``, ``Landing``. Transitions, evaluated every step:

- contact = leg load (vertical GRF of the leg / body weight) above ``stance_load_threshold_<side>``;
- EarlyStance → LateStance when the leg's contact points are behind the pelvis (sagittal position
  ``(x_contact − x_pelvis) / leg length`` below ``late_stance_threshold``);
- LateStance → Liftoff when the other leg is in contact (double support, walking) or, our
  addition for running, when the leg's load falls below its stance threshold plus
  ``liftoff_load_margin_<side>`` (the push-off unloads it; 0, the default, never: SCONE's
  machine);
- any stance state → Swing when contact is lost;
- Swing → Landing when the sagittal position exceeds ``landing_threshold``; Swing/Landing →
  EarlyStance on contact. SCONE (since 2019) moves a leg from Swing to EarlyStance only if
  it is also in front of the other leg, so that a trailing foot touching the ground stays in
  Swing; we do not, and gaits found here use it: two Cat6 gaits that let the trailing blade
  touch above their stance threshold fall within 4 s with SCONE's condition (measured
  2026-11-27, docs/predictive.md).

In each state a set of reflexes adds to a muscle's excitation (the sum is clipped to [0, 1]),
SCONE's ``MuscleReflex`` and ``DofReflex`` with delayed sensors:

- length ``KL·(L(t−d) − L0)`` (L = fibre length / optimal length; negative part dropped where SCONE
  sets ``allow_neg_L = 0``), force ``KF·F(t−d)`` (F = tendon force / Fmax), constant ``C0``;
- DOF (pelvis tilt, lumbar extension) ``KP·(P0 − q(t−d)) + KV·(V0 − q̇(t−d))`` [rad, rad/s],
  V0 = 0 but for the swing-leg placement below.

The reflex structure is SCONE's ``H0918RS2v3`` controller (Apache-2.0, T. Geijtenbeek) with separate
parameters per leg (``symmetric = 0``, as ``ControllerGH2010v12Asym``), plus constant offsets
``C0`` per muscle in stance and in swing (Geyer & Herr's S0 / ΔS terms), a Swing-only ``C0`` of
the short head of biceps femoris (early-swing knee flexion so the trailing foot clears the
ground in running; docs/predictive.md), a swing-leg placement reflex (hip flexor and extensor
of the swinging leg on the pelvis's forward velocity, ``KV·(V0 − v)`` [m/s]; our addition, 0
by default) and DOF reflexes for the torso muscles about the lumbar
joint (the seed's model has torso muscles; H0918 has none). The prosthetic leg has no shank muscles: reflexes to or from them are left out on that side.

Parameters form a named flat vector (:class:`ControllerLayout`, names like SCONE's ``.par``:
``S00011.vasti_l.KF`` = vasti of the left leg, states EarlyStance+LateStance, force gain; the state
mask reads right to left: EarlyStance, LateStance, Liftoff, Swing, Landing). The initial guess is
ported from SCONE's ``H0918GaitRS2Hfd4.par`` (column ``best``) where the structure matches.
Everything in the simulation loop is compiled with numba (:func:`control_step`).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from bladelab._io import read_json, write_json
from bladelab.errors import InputFileError, SpecError
from bladelab.numba_cache import refresh_stale_caches
from bladelab.runner.params import REFLEX_STARTS_DIR

EARLY_STANCE, LATE_STANCE, LIFTOFF, SWING, LANDING = range(5)
STATE_NAMES = ("EarlyStance", "LateStance", "Liftoff", "Swing", "Landing")
# Sensor delays [s] of SCONE's H0918RS2v3.
HIP_DELAY, HAM_DELAY, KNEE_DELAY, ANKLE_DELAY, VES_DELAY = 0.01, 0.015, 0.02, 0.035, 0.05
PELVIS_TILT_REF = -0.105  # rad, theta_ref of Geyer & Herr (not optimised)
LATE_STANCE_THRESHOLD = 0.0
LANDING_THRESHOLD = 0.0

# Term kinds of the reflex table.
T_CONST, T_LENGTH, T_LENGTH_POS, T_FORCE, T_DOF_POS, T_DOF_VEL, T_DOF_MEAN_VEL = range(7)
# Columns of the reflex table (float64): kind, target muscle, leg (−1 = always on), state mask,
# source (muscle or dof index), delay [steps], gain parameter index, offset parameter index (−1:
# use the constant), offset constant, averaging window (T_DOF_MEAN_VEL: [s] in ``table``, steps
# in ``table_for``), time step [s] (set by ``table_for``).
(R_KIND, R_TARGET, R_LEG, R_MASK, R_SOURCE, R_DELAY, R_GAIN, R_OFFSET, R_OFFSET_CONST,
 R_WINDOW, R_DT) = range(11)
#: Length of the controller state ``cs`` of the compiled part (below).
CONTROLLER_STATE_SIZE = 5
#: Window [s] of the swing-leg placement's mean forward speed: about one stride at 3–4 m/s, so
#: the mean is steady over a steady gait (the pelvis's velocity swings by ±0.3 m/s within a
#: stride) and moves only when the runner speeds up or slows down.
SPEED_WINDOW = 0.7

_ALL = "S11111"
_STANCE = "S00011"
_SWING = "S11100"
_EARLY_SWING = "S01000"

# (mask, target, source, gain name, offset name or None, kind, delay, SCONE default value(s)).
# Leg reflexes of H0918RS2v3 (source None = the target itself).
_LEG_REFLEXES: list[tuple] = [
    (_ALL, "tib_ant", None, "KL", "L0", T_LENGTH, ANKLE_DELAY, (0.63, 0.55)),
    (_ALL, "tib_ant", None, "KF", None, T_FORCE, ANKLE_DELAY, (0.5,)),
    (_ALL, "soleus", None, "KL", "L0", T_LENGTH, ANKLE_DELAY, (0.66, 0.87)),
    (_ALL, "soleus", None, "KF", None, T_FORCE, ANKLE_DELAY, (1.0,)),
    (_ALL, "gastroc", None, "KL", "L0", T_LENGTH, ANKLE_DELAY, (0.5, 0.68)),
    (_ALL, "gastroc", None, "KF", None, T_FORCE, ANKLE_DELAY, (0.76,)),
    (_ALL, "tib_ant", "soleus", "KL", None, T_LENGTH, ANKLE_DELAY, (-0.08,)),
    (_ALL, "tib_ant", "soleus", "KF", None, T_FORCE, ANKLE_DELAY, (-1.0,)),
    (_ALL, "tib_ant", "gastroc", "KL", None, T_LENGTH, ANKLE_DELAY, (-0.05,)),
    (_ALL, "tib_ant", "gastroc", "KF", None, T_FORCE, ANKLE_DELAY, (-0.7,)),
    (_ALL, "soleus", "tib_ant", "KF", None, T_FORCE, ANKLE_DELAY, (-0.64,)),
    (_ALL, "gastroc", "tib_ant", "KF", None, T_FORCE, ANKLE_DELAY, (-0.77,)),
    (_STANCE, "vasti", None, "KL", "L0", T_LENGTH, KNEE_DELAY, (2.0, 0.6)),
    (_STANCE, "vasti", None, "KF", None, T_FORCE, KNEE_DELAY, (0.8,)),
    (_STANCE, "iliopsoas", None, "KL", "L0", T_LENGTH, HIP_DELAY, (2.0, 0.9)),
    (_STANCE, "rect_fem", None, "KL", "L0", T_LENGTH, HAM_DELAY, (0.2, 0.5)),
    (_STANCE, "hamstrings", None, "KL", "L0", T_LENGTH, HAM_DELAY, (0.8, 0.7)),
    (_STANCE, "bifemsh", None, "KF", None, T_FORCE, KNEE_DELAY, (0.2,)),
    (_STANCE, "glut_max", None, "KL", "L0", T_LENGTH, HIP_DELAY, (0.5, 1.1)),
    (_STANCE, "hamstrings", "pelvis_tilt", "KP", None, T_DOF_POS, VES_DELAY, (1.3,)),
    (_STANCE, "hamstrings", "pelvis_tilt", "KV", None, T_DOF_VEL, VES_DELAY, (0.2,)),
    (_STANCE, "glut_max", "pelvis_tilt", "KP", None, T_DOF_POS, VES_DELAY, (1.0,)),
    (_STANCE, "rect_fem", "pelvis_tilt", "KP", None, T_DOF_POS, VES_DELAY, (-1.1,)),
    (_STANCE, "rect_fem", "pelvis_tilt", "KV", None, T_DOF_VEL, VES_DELAY, (-0.02,)),
    (_SWING, "iliopsoas", None, "KL", "L0", T_LENGTH, HIP_DELAY, (1.0, 0.7)),
    (_SWING, "rect_fem", None, "KL", "L0", T_LENGTH, HAM_DELAY, (0.5, 1.2)),
    (_SWING, "iliopsoas", "pelvis_tilt", "KP", None, T_DOF_POS, VES_DELAY, (1.7,)),
    (_SWING, "iliopsoas", "pelvis_tilt", "KV", None, T_DOF_VEL, VES_DELAY, (0.3,)),
    (_SWING, "iliopsoas", "hamstrings", "KL", "L0", T_LENGTH, HAM_DELAY, (-3.0, 0.7)),
    (_SWING, "hamstrings", None, "KL", "L0", T_LENGTH, HAM_DELAY, (0.2, 1.2)),
    (_SWING, "bifemsh", None, "KF", None, T_FORCE, KNEE_DELAY, (0.2,)),
    (_SWING, "glut_max", None, "KL", "L0", T_LENGTH, HIP_DELAY, (1.0, 0.85)),
    # swing-leg placement on the forward speed (our addition, docs/predictive.md): the hip
    # flexor and extensor of the swinging leg see the pelvis's delayed forward velocity,
    # KV·(V0 − v), so a faster body can reach further forward (a foot-placement feedback,
    # as Song & Geyer 2015's swing-leg target angle or Raibert's hopper). Gains 0 by default:
    # older parameter files run exactly as before.
    (_SWING, "iliopsoas", "pelvis_tx", "KV", "V0", T_DOF_VEL, VES_DELAY, (0.0, 3.5)),
    (_SWING, "glut_max", "pelvis_tx", "KV", "V0", T_DOF_VEL, VES_DELAY, (0.0, 3.5)),
    # the same on the mean forward speed over the last SPEED_WINDOW (the
    # instantaneous velocity swings within every stride, and a gain on it that CMA-ES can
    # take up fells a tuned gait; after a push the tuned gaits speed up stride by stride and
    # lean further forward until they fall, a runaway a placement on the mean speed can stop)
    (_SWING, "iliopsoas", "pelvis_tx", "KS", "S0", T_DOF_MEAN_VEL, VES_DELAY, (0.0, 3.5)),
    (_SWING, "glut_max", "pelvis_tx", "KS", "S0", T_DOF_MEAN_VEL, VES_DELAY, (0.0, 3.5)),
    # and for the stance leg's hip muscles, which pitch the trunk: a runner who is
    # too fast can straighten up and brake, as people do (gains 0 by default)
    (_STANCE, "iliopsoas", "pelvis_tx", "KS", "S0", T_DOF_MEAN_VEL, VES_DELAY, (0.0, 3.5)),
    (_STANCE, "glut_max", "pelvis_tx", "KS", "S0", T_DOF_MEAN_VEL, VES_DELAY, (0.0, 3.5)),
]
# Search scale of the gains on the forward velocity [1/(m/s)], times CMA-ES's sigma: small,
# because an earlier stable gait falls at 2.7 s when one such gain alone is set to 0.01.
_GAIN_SCALE = {("pelvis_tx", "KV"): 0.05, ("pelvis_tx", "KS"): 0.5}
# Bounds of the reflexes' offset parameters: L0 [optimal fibre lengths], V0, S0 [m/s].
_OFFSET_BOUNDS = {"L0": (0.0, 2.0), "V0": (0.0, 10.0), "S0": (0.0, 10.0)}
_LEG_MUSCLES = (
    "hamstrings",
    "bifemsh",
    "glut_max",
    "iliopsoas",
    "rect_fem",
    "vasti",
    "gastroc",
    "soleus",
    "tib_ant",
)
# Constant offsets C0: (state mask, muscles, search scale), per leg in this order.
_CONSTANT_OFFSETS = (
    (_STANCE, _LEG_MUSCLES, 0.02),
    (_SWING, _LEG_MUSCLES, 0.02),
    (_EARLY_SWING, ("bifemsh",), 0.05),
)
# Torso: (muscle, gain name, kind, default); source lumbar_extension, always on, both sides.
_TORSO_REFLEXES: list[tuple] = [
    ("erect_sp", "C0", T_CONST, 0.05),
    ("erect_sp", "KP", T_DOF_POS, 1.0),
    ("erect_sp", "KV", T_DOF_VEL, 0.1),
    ("rect_abd", "C0", T_CONST, 0.02),
    ("rect_abd", "KP", T_DOF_POS, -1.0),
    ("rect_abd", "KV", T_DOF_VEL, -0.1),
    ("int_obl", "C0", T_CONST, 0.02),
]
INITIAL_DOFS = ("pelvis_tilt", "hip_flexion", "knee_angle", "ankle_angle")
_SCONE_PAR = "H0918GaitRS2Hfd4.par"


@dataclass(frozen=True)
class ControllerLayout:
    """Names, initial values, search scales and the compiled reflex table of one runner model.

    Attributes
    ----------
    kind
        ``"able"`` or ``"amputee"`` (the prosthetic right leg has no shank muscles).
    names
        Parameter names in vector order.
    x0
        Initial guess (SCONE's values where the structure matches).
    std
        Initial search scale per parameter (CMA-ES ``CMA_stds``).
    lower, upper
        Bounds of each parameter.
    table
        (n_terms, 9) reflex table (columns ``R_*``), before delays are converted to steps.
    delays_s
        Delay [s] of each table row.
    """

    kind: str
    names: tuple[str, ...]
    x0: np.ndarray = field(repr=False)
    std: np.ndarray = field(repr=False)
    lower: np.ndarray = field(repr=False)
    upper: np.ndarray = field(repr=False)
    table: np.ndarray = field(repr=False)
    delays_s: np.ndarray = field(repr=False)

    @property
    def size(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise SpecError(f"no controller parameter {name!r}", where="parameters") from None

    def vector(self, values: dict[str, float], *, source: str | None = None) -> np.ndarray:
        """A parameter vector from a ``{name: value}`` mapping (missing names: initial guess)."""
        unknown = sorted(set(values) - set(self.names))
        if unknown:
            raise SpecError(
                f"unknown controller parameter(s) {', '.join(unknown[:5])}",
                file=source,
                where="parameters",
                hint=f"this is a {self.kind} controller; parameters look like {self.names[0]!r}",
            )
        x = self.x0.copy()
        for k, v in values.items():
            if not math.isfinite(float(v)):
                raise SpecError(f"parameter {k} is not finite", file=source, where=k)
            x[self.names.index(k)] = float(v)
        return x

    def to_dict(self, x: np.ndarray) -> dict[str, float]:
        return {n: float(v) for n, v in zip(self.names, x, strict=True)}

    def table_for(self, dt: float) -> np.ndarray:
        """The reflex table with delays and averaging windows in steps of ``dt`` [s]."""
        t = self.table.copy()
        t[:, R_DELAY] = np.round(self.delays_s / dt)
        t[:, R_WINDOW] = np.round(t[:, R_WINDOW] / dt)
        t[:, R_DT] = dt
        return t


def _scone_par() -> dict[str, float]:
    """SCONE's RS2 parameters (column ``best``) by name (shipped with bladelab)."""
    path = REFLEX_STARTS_DIR / _SCONE_PAR
    if not path.exists():
        raise InputFileError("SCONE's reflex parameter file is missing from the installation",
                             file=path, hint="reinstall bladelab (pip install --force-reinstall)")
    out = {}
    for line in path.read_text().splitlines():
        parts = line.split()
        if len(parts) >= 2:
            out[parts[0]] = float(parts[1])
    return out


def controller_layout(model) -> ControllerLayout:
    """The controller layout of a :class:`~bladelab.runner.RunnerModel`."""
    muscles = list(model.muscle_names)
    dofs = list(model.dof_names)
    par = _scone_par()
    names, x0, std, lo, hi, rows, delays = [], [], [], [], [], [], []

    def param(name: str, value: float, low: float, high: float, scale: float | None = None) -> int:
        names.append(name)
        x0.append(value)
        std.append(scale if scale is not None else max(0.05 * abs(value), 0.02))
        lo.append(low)
        hi.append(high)
        return len(names) - 1

    for side in ("l", "r"):
        param(f"stance_load_threshold_{side}", par.get("stance_load_threshold", 0.28), 0.01, 1.0)
    # swing initiation before the foot leaves the ground in running: a running
    # leg never sees double support, so SCONE's Liftoff state never comes and the swing
    # reflexes start only after lift-off; 0 keeps SCONE's machine (docs/predictive.md)
    for side in ("l", "r"):
        param(f"liftoff_load_margin_{side}", 0.0, 0.0, 3.0, 0.5)
    for dof in INITIAL_DOFS:
        for side in ("l", "r") if dof != "pelvis_tilt" else ("",):
            dn = f"{dof}_{side}" if side else dof
            if dn not in dofs:
                continue
            param(f"{dn}.offset", par.get(f"{dn}.offset", 0.0), -0.5, 0.5, 0.02)
    for side, leg in (("l", 0), ("r", 1)):
        have = {m[: -len(side) - 1] for m in muscles if m.endswith("_" + side)}
        for mask, target, source, gname, oname, kind, delay, vals in _LEG_REFLEXES:
            if target not in have or (source in _LEG_MUSCLES and source not in have):
                continue
            key = target if source is None else f"{target}-{source}"
            scone_key = f"{mask}.{key}"
            tname = f"{target}_{side}"
            src = muscles.index(tname)
            if source is not None:
                src = dofs.index(source) if source in dofs else muscles.index(f"{source}_{side}")
            gain = param(
                f"{mask}.{tname if source is None else tname + '-' + source}.{gname}",
                par.get(f"{scone_key}.{gname}", vals[0]),
                -10.0,
                10.0,
                _GAIN_SCALE.get((source, gname)),
            )
            off, off_const = -1, 0.0
            if oname is not None:
                off = param(
                    f"{mask}.{tname if source is None else tname + '-' + source}.{oname}",
                    par.get(f"{scone_key}.{oname}", vals[1]),
                    *_OFFSET_BOUNDS[oname],
                )
            elif kind == T_DOF_POS:
                off_const = PELVIS_TILT_REF
            window = SPEED_WINDOW if kind == T_DOF_MEAN_VEL else 0.0
            rows.append((kind, muscles.index(tname), leg, _mask_bits(mask), src, 0, gain, off,
                         off_const, window, 0.0))
            delays.append(delay)
        # constant offsets per muscle in stance and swing, then (our addition,
        # docs/predictive.md) bifemsh in Swing only: early-swing knee flexion so the trailing
        # foot clears the ground
        for mask, offset_muscles, scale in _CONSTANT_OFFSETS:
            for mname in offset_muscles:
                if mname not in have:
                    continue
                tname = f"{mname}_{side}"
                gain = param(f"{mask}.{tname}.C0", 0.0, -1.0, 1.0, scale)
                rows.append((T_CONST, muscles.index(tname), leg, _mask_bits(mask), -1, 0, gain,
                             -1, 0.0, 0.0, 0.0))
                delays.append(0.0)
    if "lumbar_extension" in dofs:
        src = dofs.index("lumbar_extension")
        for mname, gname, kind, val in _TORSO_REFLEXES:
            gain = param(f"torso.{mname}-lumbar_extension.{gname}", val, -10.0, 10.0)
            for side in ("r", "l"):
                tname = f"{mname}_{side}"
                if tname in muscles:
                    rows.append((kind, muscles.index(tname), -1, 31, src, 0, gain, -1, 0.0,
                                 0.0, 0.0))
                    delays.append(HIP_DELAY if kind != T_CONST else 0.0)
    return ControllerLayout(
        kind=model.kind,
        names=tuple(names),
        x0=np.array(x0),
        std=np.array(std),
        lower=np.array(lo),
        upper=np.array(hi),
        table=np.array(rows, dtype=np.float64),
        delays_s=np.array(delays),
    )


def _mask_bits(mask: str) -> int:
    """SCONE's state mask string ("S00011": EarlyStance, LateStance) as bits (bit 0 = EarlyStance)."""
    bits = mask[1:]
    return sum(1 << i for i, ch in enumerate(reversed(bits)) if ch == "1")


def read_parameters(
    path: str | Path, layout: ControllerLayout, *, transfer: bool = False,
    body: str = "seed001",
) -> np.ndarray:
    """Read a parameter JSON file (``{"parameters": {name: value}, ...}``) of a runner on
    ``body`` (the file's ``"body"``, seed 001's where it names none) into a vector.

    With ``transfer=True`` a file of the other model kind or body is accepted (warm start of
    the amputee from an able-bodied solution, as seed 001 does): parameters the layout lacks
    (the prosthetic side's shank reflexes) are dropped, those it has and the file lacks keep
    the initial guess.
    """
    path = Path(path)
    data = read_json(path, what="parameter file")
    params = data.get("parameters") if isinstance(data, dict) else None
    if not isinstance(params, dict):
        raise InputFileError(
            "expected an object with a 'parameters' mapping {name: value}", file=path
        )
    own_body = data.get("body", "seed001")
    if own_body != body and not transfer:
        raise InputFileError(
            f"parameters are for the runner on the {own_body} body, not the {body} body",
            file=path, where="body",
            hint="use --body matching the file (a controller is tuned to its body), or "
                 "another --init file")
    if transfer and data.get("model") not in (None, layout.kind):
        params = {k: v for k, v in params.items() if k in layout.names}
    elif data.get("model") not in (None, layout.kind):
        raise InputFileError(
            f"parameters are for the {data.get('model')} model, not {layout.kind}",
            file=path,
            hint="use --model matching the file, or another --init file",
        )
    return layout.vector(params, source=str(path))


#: Parameters added after task folders (recipes, sweep cells) first stored the digests of their
#: warm starts (:func:`parameter_digest`): left out of a digest while at their defaults, so
#: those folders continue in the grown layout (name prefixes). A parameter added to the layout
#: later belongs here too, or every task folder written before it refuses to continue.
_ADDED_AFTER_DIGESTS = ("liftoff_load_margin_",)


def parameter_digest(x: np.ndarray, layout: ControllerLayout | None = None) -> str:
    """SHA-256 of a parameter vector's little-endian float64 bytes (identifies a warm start);
    with its ``layout``, parameters added since digests were first stored are left out while
    they hold their defaults (the same digest as before the layout grew)."""
    x = np.asarray(x, dtype=float)
    if layout is not None:
        later = np.array([n.startswith(_ADDED_AFTER_DIGESTS) for n in layout.names])
        x = x[~(later & (x == layout.x0))]
    return hashlib.sha256(np.ascontiguousarray(x, dtype="<f8").tobytes()).hexdigest()


def write_parameters(
    path: str | Path, layout: ControllerLayout, x: np.ndarray, **meta: object
) -> Path:
    """Write a parameter vector as JSON (atomically) with optional metadata."""
    data = {"model": layout.kind, **meta, "parameters": layout.to_dict(np.asarray(x, float))}
    write_json(path, data)
    return Path(path)


# ----------------------------------------------------------------------------- compiled part
# Sensor channels in the history buffer: per muscle L, V, F (3 per muscle), then per dof q, qd.
# Controller state ``cs`` (float64 array): per leg the gait state (cs[0], cs[1]); cs[2] = write
# position in the history; cs[3] = number of samples written; cs[4] = 1: a run-up (the mean
# velocity reflexes act from the start, the runner having moved at its initial velocity before).


@njit(cache=True)
def push_sensors(hist, cs, ms, mp, qpos, qvel):
    """Append the current sensor values to the ring buffer ``hist`` (n_hist, n_channels)."""
    nm = ms.shape[0]
    nh = hist.shape[0]
    pos = int(cs[2])
    for i in range(nm):
        lopt = mp[i, 1]
        hist[pos, 3 * i] = ms[i, 1] / lopt
        hist[pos, 3 * i + 1] = ms[i, 2] / lopt
        hist[pos, 3 * i + 2] = ms[i, 3] / mp[i, 0]
    nq = qpos.shape[0]
    for j in range(nq):
        hist[pos, 3 * nm + j] = qpos[j]
        hist[pos, 3 * nm + nq + j] = qvel[j]
    if cs[3] == 0.0:  # first sample: fill the history with it
        for k in range(nh):
            if k != pos:
                hist[k, :] = hist[pos, :]
    cs[3] += 1.0
    cs[2] = (pos + 1) % nh


@njit(cache=True)
def delayed(hist, cs, channel, steps):
    """Sensor channel value ``steps`` samples ago (0 = the newest)."""
    nh = hist.shape[0]
    if steps > nh - 1:
        steps = nh - 1
    pos = (int(cs[2]) - 1 - steps) % nh
    return hist[pos, channel]


@njit(cache=True)
def update_gait_states(cs, crec, cp, qpos, ix_pelvis, body_weight, thresholds, leg_length):
    """Advance each leg's gait state from the contact forces (see module docstring);
    ``thresholds``: the stance load thresholds of both legs, then their liftoff load margins
    [body weights]."""
    contact = np.zeros(2)
    sag = np.zeros(2)
    npts = np.zeros(2)
    for c in range(cp.shape[0]):
        leg = int(cp[c, 6])
        contact[leg] += crec[c, 1]
        sag[leg] += crec[c, 2]
        npts[leg] += 1.0
    for leg in range(2):
        load = contact[leg] / body_weight
        on = load > thresholds[leg]
        other = contact[1 - leg] / body_weight > thresholds[1 - leg]
        s = (sag[leg] / max(npts[leg], 1.0) - qpos[ix_pelvis]) / leg_length
        st = int(cs[leg])
        if st == EARLY_STANCE:
            if not on:
                st = SWING
            elif s < LATE_STANCE_THRESHOLD:
                st = LATE_STANCE
        elif st == LATE_STANCE:
            if not on:
                st = SWING
            elif other or load < thresholds[leg] + thresholds[2 + leg]:
                st = LIFTOFF
        elif st == LIFTOFF:
            if not on:
                st = SWING
        elif st == SWING:
            if on:
                st = EARLY_STANCE
            elif s > LANDING_THRESHOLD:
                st = LANDING
        else:  # LANDING
            if on:
                st = EARLY_STANCE
        cs[leg] = st


@njit(cache=True)
def _position_with_run_up(hist, cs, nm, nq, dof, age, n, dt):
    """Position of ``dof`` ``age`` samples (of ``dt`` [s]) ago when ``n`` samples are written;
    before the first sample, the first sample's position moved back at its velocity (a
    run-up)."""
    if age <= n - 1:
        return delayed(hist, cs, 3 * nm + dof, age)
    first_q = delayed(hist, cs, 3 * nm + dof, n - 1)
    first_v = delayed(hist, cs, 3 * nm + nq + dof, n - 1)
    return first_q - first_v * (age - (n - 1)) * dt


@njit(cache=True)
def compute_excitations(u, table, p, hist, cs, nm, nq):
    """Excitations ``u`` from the reflex table, parameters ``p`` and the delayed sensors."""
    u[:] = 0.0
    for r in range(table.shape[0]):
        leg = int(table[r, R_LEG])
        if leg >= 0:
            st = int(cs[leg])
            if (int(table[r, R_MASK]) >> st) & 1 == 0:
                continue
        kind = int(table[r, R_KIND])
        tgt = int(table[r, R_TARGET])
        src = int(table[r, R_SOURCE])
        d = int(table[r, R_DELAY])
        g = p[int(table[r, R_GAIN])]
        oi = int(table[r, R_OFFSET])
        off = p[oi] if oi >= 0 else table[r, R_OFFSET_CONST]
        if kind == T_CONST:
            u[tgt] += g
        elif kind == T_LENGTH:
            u[tgt] += g * (delayed(hist, cs, 3 * src, d) - off)
        elif kind == T_LENGTH_POS:
            u[tgt] += g * max(delayed(hist, cs, 3 * src, d) - off, 0.0)
        elif kind == T_FORCE:
            u[tgt] += g * (delayed(hist, cs, 3 * src + 2, d) - off)
        elif kind == T_DOF_POS:
            u[tgt] += g * (off - delayed(hist, cs, 3 * nm + src, d))
        elif kind == T_DOF_VEL:
            u[tgt] += g * (off - delayed(hist, cs, 3 * nm + nq + src, d))
        elif kind == T_DOF_MEAN_VEL:
            # mean velocity over the window ending d steps ago, from the position's change;
            # until the history holds the whole window: off, or with a run-up (cs[4] = 1)
            # the position before the start extrapolated at the first sample's velocity
            w = int(table[r, R_WINDOW])
            n = int(cs[3])
            if n - 1 - d >= w:
                v = (delayed(hist, cs, 3 * nm + src, d)
                     - delayed(hist, cs, 3 * nm + src, d + w)) / (w * table[r, R_DT])
                u[tgt] += g * (off - v)
            elif cs[4] > 0.0 and n > 0:
                h = table[r, R_DT]
                v = (_position_with_run_up(hist, cs, nm, nq, src, d, n, h)
                     - _position_with_run_up(hist, cs, nm, nq, src, d + w, n, h)) / (w * h)
                u[tgt] += g * (off - v)
    for i in range(nm):
        if u[i] < 0.0:
            u[i] = 0.0
        elif u[i] > 1.0:
            u[i] = 1.0


def history_length(layout: ControllerLayout, dt: float) -> int:
    """Rows of the sensor ring buffer for the longest delay (plus averaging window) at step
    ``dt`` [s]."""
    reach = layout.delays_s + layout.table[:, R_WINDOW] if len(layout.delays_s) else [0.0]
    return int(round(float(np.max(reach)) / dt)) + 2


__all__ = [
    "ControllerLayout",
    "CONTROLLER_STATE_SIZE",
    "STATE_NAMES",
    "compute_excitations",
    "controller_layout",
    "delayed",
    "history_length",
    "parameter_digest",
    "push_sensors",
    "read_parameters",
    "update_gait_states",
    "write_parameters",
]


refresh_stale_caches(globals())
