"""An animated runner for the HTML report: a stick figure played in the page, offline.

:func:`runner_frames` turns a :class:`~bladelab.runner.RunnerResult` (any trajectory with the
runner's ``time``, ``qpos`` and ``contacts``: a forward simulation, a reflex-controlled one, or a
collocation solution put into the same form) into frames of points in the sagittal plane:
the joint centres of every segment (read from the MuJoCo model by forward kinematics, so the
able runner, the amputee with the blade sphere and the amputee wearing a multi-link blade are
all drawn), the contact spheres (the blade sphere as its lower arc) and each leg's ground
reaction force as an arrow at its centre of pressure. :func:`animation_html` packs them into a
:class:`~bladelab.report.builder.EmbeddedHTML` block: inline SVG drawn by a small script
(``templates/runner_animation.js``), with play/pause, a time slider and a playback speed; no
file or library is loaded from elsewhere.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import re
from importlib import resources

import mujoco
import numpy as np

from bladelab.report.builder import EmbeddedHTML
from bladelab.runner.export import leg_ground_force
from bladelab.runner.layout import CP_AZ, CP_BLADE, CP_BODY, CP_LEG, CP_RADIUS, CP_SITE
from bladelab.runner.simulate import RunnerResult, leg_names

__all__ = ["RunnerFrames", "animation_html", "runner_frames"]

#: Length [m] of the arrow of a ground reaction force of one body weight.
BW_ARROW_M = 0.5


@dataclasses.dataclass(frozen=True)
class RunnerFrames:
    """Frames of a stick figure in the sagittal plane (lab x forward, z up).

    Attributes
    ----------
    time
        (n_frames,) time of each frame [s].
    points
        (n_frames, n_points, 2) x, z of every point [m]; point 0 is the pelvis.
    edges
        Segments drawn: (point, point, style), style ``l``/``r`` (left/intact or
        right/prosthetic leg), ``trunk`` or ``blade``.
    circles
        (centre point, radius [m], style, arc): contact spheres and the head; ``arc`` draws only
        the lower arc (the blade sphere).
    grf
        (n_frames, 2, 3): per leg, centre of pressure x [m], Fx, Fz [N].
    body_weight
        [N], to scale the force arrows.
    legs
        Leg names, (left/intact, right/prosthetic).
    """

    time: np.ndarray
    points: np.ndarray
    edges: tuple[tuple[int, int, str], ...]
    circles: tuple[tuple[int, float, str, bool], ...]
    grf: np.ndarray
    body_weight: float
    legs: tuple[str, str]


def _style(body_name: str, blade: bool = False) -> str:
    if blade or body_name.startswith(("prosthesis", "blade")):
        return "blade"
    if body_name.endswith("_l"):
        return "l"
    if body_name.endswith("_r"):
        return "r"
    return "trunk"


def _skeleton(result: RunnerResult):
    """Point definitions and the edges and circles between them (frame independent)."""
    m = result.model.mj_model
    points: list[tuple[str, int]] = []  # (kind, id): body anchor, torso top, head, contact site
    index: dict[tuple[str, int], int] = {}

    def add(kind: str, ident: int) -> int:
        index[(kind, ident)] = len(points)
        points.append((kind, ident))
        return index[(kind, ident)]

    edges, circles = [], []
    for b in range(1, m.nbody):
        add("anchor", b)
    for b in range(2, m.nbody):
        parent = int(m.body_parentid[b])
        if parent > 0:
            # the segment from the parent's joint to this body's joint is the parent
            edges.append((index[("anchor", parent)], index[("anchor", b)],
                          _style(m.body(parent).name)))
    if "torso" in result.model.segment_names:
        torso = m.body("torso").id
        top, head = add("top", torso), add("head", torso)
        edges.append((index[("anchor", torso)], top, "trunk"))
        circles.append((head, 0.11, "head", False))
    cp = result.model.contact_params
    last_on_body: dict[int, int] = {}
    for c in range(len(cp)):
        body, blade = int(cp[c, CP_BODY]), bool(cp[c, CP_BLADE])
        site = add("site", int(cp[c, CP_SITE]))
        style = _style(m.body(body).name, blade)
        edges.append((index[("anchor", body)], site, style))
        if body in last_on_body:
            edges.append((last_on_body[body], site, style))
        last_on_body[body] = site
        if cp[c, CP_RADIUS] == cp[c, CP_AZ]:
            circles.append((site, float(cp[c, CP_RADIUS]), style, blade))
    return points, tuple(edges), tuple(circles)


def runner_frames(result: RunnerResult, *, fps: float = 50.0,
                  max_duration: float | None = None) -> RunnerFrames:
    """Frames of ``result`` at ``fps`` frames per second of simulated time (nearest recorded
    sample), at most ``max_duration`` [s] from the start (default: all of it)."""
    t = result.time
    end = t[-1] if max_duration is None else min(t[-1], t[0] + max_duration)
    want = np.arange(t[0], end + 1e-9, 1.0 / fps)
    idx = np.clip(np.searchsorted(t, want), 0, len(t) - 1)
    prev = np.clip(idx - 1, 0, len(t) - 1)
    idx = np.where(np.abs(t[prev] - want) < np.abs(t[idx] - want), prev, idx)
    model = result.model
    m = model.mj_model
    d = mujoco.MjData(m)
    points, edges, circles = _skeleton(result)
    jnt_of_body = {int(m.jnt_bodyid[j]): j for j in range(m.njnt - 1, -1, -1)}
    out = np.zeros((len(idx), len(points), 2))
    for k, i in enumerate(idx):
        d.qpos[:] = result.qpos[i]
        mujoco.mj_kinematics(m, d)
        for p, (kind, ident) in enumerate(points):
            if kind == "anchor":
                j = jnt_of_body.get(ident)
                hinge = j is not None and m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
                xyz = d.xanchor[j] if hinge and ident != 1 else d.xpos[ident]
            elif kind in ("top", "head"):
                j = jnt_of_body[ident]
                axis = d.xipos[ident] - d.xanchor[j]
                xyz = d.xanchor[j] + 2.0 * axis
                if kind == "head":
                    xyz = xyz + axis / np.linalg.norm(axis) * 0.13
            else:
                xyz = d.site_xpos[ident]
            out[k, p] = xyz[0], xyz[2]
    grf = np.zeros((len(idx), 2, 3))
    for leg in (0, 1):
        if np.any(model.contact_params[:, CP_LEG] == leg):
            fx, fz, cop = leg_ground_force(result, leg)
            grf[:, leg] = np.stack([cop[idx], fx[idx], fz[idx]], axis=1)
    return RunnerFrames(t[idx], out, edges, circles, grf, float(model.body_weight),
                        leg_names(model))


@functools.cache
def _player_script() -> str:
    ref = resources.files("bladelab.report") / "templates" / "runner_animation.js"
    return ref.read_text(encoding="utf-8")


def _frames_json(frames: RunnerFrames, label: str, fps: float) -> str:
    data = {
        "label": label,
        "dt": 1.0 / fps,
        "n": len(frames.time),
        "np": frames.points.shape[1],
        "t": [round(float(x), 4) for x in frames.time],
        "P": np.rint(frames.points * 1000).astype(int).ravel().tolist(),  # mm
        "G": np.rint(frames.grf * [1000, 1, 1]).astype(int).ravel().tolist(),  # mm, N, N
        "edges": [list(e) for e in frames.edges],
        "circles": [[c[0], round(c[1] * 1000), c[2], int(c[3])] for c in frames.circles],
        "bw": frames.body_weight,
        "bw_length_m": BW_ARROW_M,
        "legs": list(frames.legs),
        "has_blade": any(e[2] == "blade" for e in frames.edges),
    }
    # "</" cannot end the script element early: JSON allows the escaped solidus
    return json.dumps(data, separators=(",", ":")).replace("</", "<\\/")


def animation_html(result: RunnerResult, *, label: str = "", fps: float = 50.0,
                   max_duration: float | None = None, speed: float = 0.25) -> EmbeddedHTML:
    """The animated runner of ``result`` as a self-contained HTML block for
    :meth:`bladelab.report.Report.add_section` (``html=[...]``).

    Parameters
    ----------
    result
        The trajectory.
    label
        Shown in the drawing (e.g. the solution's name).
    fps
        Frames per second of simulated time.
    max_duration
        Animate at most this much simulated time [s] from the start (default: all).
    speed
        Initial playback speed (simulated seconds per second of wall time: 0.1, 0.25, 0.5
        or 1).
    """
    frames = runner_frames(result, fps=fps, max_duration=max_duration)
    ident = "anim-" + (re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-") or "runner")
    digest = hashlib.sha1(f"{label}|{len(frames.time)}|{frames.time[-1]:.6f}".encode())
    ident += "-" + digest.hexdigest()[:8]
    options = "".join(
        f'<option value="{v}"{" selected" if abs(v - speed) < 1e-9 else ""}>{v:g}×</option>'
        for v in (0.1, 0.25, 0.5, 1.0)
    )
    body = (
        f'<div class="runner-animation" id="{ident}" data-frame="0" data-playing="no">'
        '<div class="anim-stage"></div>'
        '<div class="anim-controls" style="display:flex;gap:12px;align-items:center;'
        'max-width:900px;margin-top:8px;font-size:13px">'
        '<button type="button" class="anim-play" style="min-width:5em">Play</button>'
        '<input type="range" class="anim-slider" min="0" max="0" value="0" step="1" '
        'aria-label="time" style="flex:1 1 auto">'
        '<label>speed <select class="anim-speed" aria-label="playback speed">'
        f"{options}</select></label>"
        '<span class="anim-time" style="min-width:15em;font-variant-numeric:tabular-nums">'
        "</span></div>"
        f'<script type="application/json" class="anim-data">{_frames_json(frames, label, fps)}'
        "</script></div>"
        f"<script>{_player_script()}\n"
        f'window.bladelabRunnerAnimation(document.getElementById("{ident}"));</script>'
    )
    caption = (
        f"Animated runner{': ' + label if label else ''} ({len(frames.time)} frames, "
        f"{fps:g} per simulated second, {frames.time[-1] - frames.time[0]:.2f} s). Segments "
        "join the joint centres; circles are the contact spheres (the blade sphere drawn as its "
        f"lower arc); arrows are each leg's ground reaction force at its centre of pressure "
        f"(1 body weight = {BW_ARROW_M:g} m). Play/pause, drag the slider, pick a speed "
        "(simulated seconds per second)."
    )
    return EmbeddedHTML(body, caption)
