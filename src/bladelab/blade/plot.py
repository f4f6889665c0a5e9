"""Figure helper: draw a segmented blade in its clamp frame (side view)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bladelab._io import atomic_path, figure_format
from bladelab.blade.model import BladeModel
from bladelab.blade.profile import Profile

__all__ = ["plot_blade", "save_blade_figure"]


def plot_blade(
    model: BladeModel,
    ax=None,
    *,
    profile: Profile | None = None,
    show_ground: bool = True,
    annotate: bool = True,
):
    """Draw a blade: segments, compliant joints, sole ellipses, tip marker and clamp origin.

    Parameters
    ----------
    model
        The built blade (clamp frame, undeformed posture).
    ax
        Matplotlib axes; a new figure is created when ``None``.
    profile
        Optional original profile, drawn thin behind the segments.
    show_ground
        Draw a horizontal line at the lowest point of the soles (the ground at touch-down).
    annotate
        Number the segments (1-based, as in the blade spec) and label the joints with K.

    Returns
    -------
    matplotlib.axes.Axes
        Axes with x [mm] horizontal (forward to the right) and z [mm] vertical, equal aspect.
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Ellipse

    if ax is None:
        _, ax = plt.subplots(figsize=(4.5, 5.5))
    mm = 1e3
    pts = np.asarray(model.points) * mm
    if profile is not None:
        ax.plot(profile.points[:, 0] * mm, profile.points[:, 1] * mm, color="0.7", lw=3,
                zorder=1, label="profile")
    ax.plot(pts[:, 0], pts[:, 1], "-", color="C0", lw=1.8, zorder=2, label="segments")
    ax.plot(pts[:, 0], pts[:, 1], "o", color="C0", ms=2.5, zorder=3)
    if annotate:
        mid = 0.5 * (pts[:-1] + pts[1:])
        for i, (x, z) in enumerate(mid):
            ax.annotate(str(i + 1), (x, z), xytext=(-7, 2), textcoords="offset points",
                        fontsize=6, color="C0")
    lowest = np.inf
    for k, sole in enumerate(model.soles):
        cx, cz = sole.center[0] * mm, sole.center[1] * mm
        # SoleEllipse.angle turns +x toward -z (rotation about +y): -angle in the x-z plot.
        e = Ellipse((cx, cz), 2 * sole.semi_axis_x * mm, 2 * sole.semi_axis_z * mm,
                    angle=-np.degrees(sole.angle), facecolor="C2", alpha=0.5, edgecolor="C2",
                    zorder=2, label="sole" if k == 0 else None)
        ax.add_patch(e)
        lowest = min(lowest, _ellipse_lowest_z(sole) * mm)
    for j in model.joints:
        x, z = pts[j.point]
        ax.plot(x, z, "s", color="C3", ms=7, mfc="none", mew=1.5, zorder=4)
        if annotate:
            k_deg = j.stiffness * np.pi / 180.0  # N·m/rad -> N·m/deg, label only
            ax.annotate(f"K={k_deg:.1f} N·m/deg", (x, z), xytext=(6, -3), textcoords="offset points",
                        fontsize=7, color="C3")
    ax.plot([], [], "s", color="C3", mfc="none", label="compliant joint")
    tx, tz = model.tip[0] * mm, model.tip[1] * mm
    ax.plot(tx, tz, "*", color="C1", ms=10, zorder=5, label="tip marker")
    ax.plot(0.0, 0.0, "k+", ms=12, mew=2, zorder=5, label="clamp origin")
    ax.plot([0.0, tx], [0.0, tz], ":", color="C1", lw=1)
    if show_ground and np.isfinite(lowest):
        ax.axhline(lowest, color="0.4", lw=1, ls="--")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm] (forward)")
    ax.set_ylabel("z [mm] (up)")
    ax.set_title(f"{model.name}: {model.n_segments} segments, {model.mass:.2f} kg", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    return ax


def _ellipse_lowest_z(sole) -> float:
    """Lowest z [m] of a sole ellipse."""
    # Ellipse axes in the clamp frame: e_x = (cos a, -sin a), e_z = (sin a, cos a).
    a = sole.angle
    return float(sole.center[1] - np.hypot(sole.semi_axis_x * np.sin(a), sole.semi_axis_z * np.cos(a)))


def save_blade_figure(model: BladeModel, path: str | Path, *,
                      profile: Profile | None = None) -> Path:
    """Draw a blade (:func:`plot_blade`) into an image file, atomically; the format follows the
    file's extension (png, svg, pdf...; an unknown one is refused before any drawing)."""
    fmt = figure_format(path)
    import matplotlib  # deferred: matplotlib takes about 0.5 s to import

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4.5, 5.5))
    plot_blade(model, ax, profile=profile)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=150)
    plt.close(fig)
    return Path(path)
