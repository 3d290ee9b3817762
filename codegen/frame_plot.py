"""A PNG picture of a robot-frame fit: plane, A1 circle, flange-hole circle and residuals."""

from __future__ import annotations

import io
from collections.abc import Mapping

import numpy as np

from accugrid.codegen.textsafe import fixed
from accugrid.kinematics.base_frame import RobotFrameFit
from accugrid.kinematics.fitting import CircleFit
from accugrid.kinematics.frames import invert, transform_points

__all__ = ["plot_frame_fit"]


def _circle_points(fit: CircleFit, n: int = 361) -> np.ndarray:
    """(n, 3) mm points on a fitted circle, in the frame of the fit."""
    e1 = np.cross(fit.normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 0.5:
        e1 = np.cross(fit.normal, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(fit.normal, e1)
    t = np.linspace(0.0, 2.0 * np.pi, n)
    return fit.center + fit.radius_mm * (np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2))


def plot_frame_fit(fit: RobotFrameFit, points: Mapping[str, np.ndarray]) -> bytes:
    """PNG bytes: the measured points and fits drawn in the fitted robot frame (mm).

    ``points`` holds the tracker-frame (N, 3) arrays under base_plane, a1_circle, flange_holes.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    robot_T_tracker = invert(fit.tracker_T_robot)

    def robot(pts: np.ndarray) -> np.ndarray:
        return transform_points(robot_T_tracker, pts)

    base, arc, holes = (robot(points[k]) for k in ("base_plane", "a1_circle", "flange_holes"))
    arc_fit, holes_fit = (
        robot(_circle_points(fit.a1_circle)),
        robot(_circle_points(fit.flange_holes)),
    )

    fig = plt.figure(figsize=(15, 5.6), dpi=100)
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    reach = float(np.max(np.linalg.norm(base[:, :2], axis=1)))
    grid = np.linspace(-reach, reach, 2)
    gx, gy = np.meshgrid(grid, grid)
    ax.plot_surface(gx, gy, np.zeros_like(gx), color="tab:gray", alpha=0.25)
    ax.scatter(*base.T, s=8, color="tab:gray", label="base-plane SMR points")
    ax.plot(*arc_fit.T, color="tab:blue", lw=0.8, ls="--")
    ax.scatter(*arc.T, s=10, color="tab:blue", label="A1-arc points, fitted circle")
    ax.plot(*holes_fit.T, color="tab:red", lw=0.8)
    ax.scatter(*holes.T, s=10, color="tab:red", label="flange holes, fitted circle")
    axis_len = 500.0
    for i, color in enumerate(("r", "g", "b")):
        tip = np.zeros(3)
        tip[i] = axis_len
        ax.plot([0, tip[0]], [0, tip[1]], [0, tip[2]], color=color, lw=2)
    ax.plot([0, 0], [0, 0], [0, float(np.max(arc[:, 2]))], color="b", lw=0.6, ls=":")
    everything = np.vstack([base, arc, holes])
    span = float(np.max(np.abs(everything[:, :2])))
    top = float(np.max(everything[:, 2])) * 1.1
    ax.set(xlim=(-span, span), ylim=(-span, span), zlim=(0.0, top))
    ax.set_box_aspect((2 * span, 2 * span, top))
    ax.set_xlabel("X mm")
    ax.set_ylabel("Y mm")
    ax.set_zlabel("Z mm", labelpad=8)
    ax.set_title("Fitted robot frame (A1 axis dotted)")
    ax.legend(loc="upper left", fontsize=7)

    ax2 = fig.add_subplot(1, 3, 2)
    ax2.plot(holes_fit[:, 1], holes_fit[:, 2], color="tab:red", lw=0.8)
    ax2.scatter(holes[:, 1], holes[:, 2], color="tab:red", s=25, zorder=3)
    centre = robot(fit.flange_holes.center[None])[0]
    ax2.scatter([centre[1]], [centre[2]], marker="+", s=80, color="k")
    ax2.set_aspect("equal")
    ax2.set_xlabel("Y mm")
    ax2.set_ylabel("Z mm")
    ax2.set_title(
        f"Flange holes at mechanical zero (robot frame)\ncentre X {fixed(centre[0], 2)}, "
        f"Y {fixed(centre[1], 3)}, Z {fixed(centre[2], 2)} mm",
        fontsize=10,
    )

    ax3 = fig.add_subplot(1, 3, 3)
    sets = (
        ("base plane", fit.plane.distances(points["base_plane"]), "tab:gray"),
        ("A1 circle", fit.a1_circle.distances(points["a1_circle"]), "tab:blue"),
        ("flange holes", fit.flange_holes.distances(points["flange_holes"]), "tab:red"),
    )
    start = 0
    for label, dist, color in sets:
        idx = np.arange(start, start + len(dist))
        ax3.vlines(idx, 0, 1000.0 * dist, color=color)
        ax3.scatter(
            idx,
            1000.0 * dist,
            s=10,
            color=color,
            label=f"{label}, RMS {1000.0 * np.sqrt(np.mean(dist**2)):.1f} µm",
        )
        start += len(dist)
    ax3.axhline(0.0, color="k", lw=0.5)
    ax3.set_xlabel("point")
    ax3.set_ylabel("residual µm (signed for the plane)")
    ax3.set_title("Fit residuals")
    ax3.legend(fontsize=7)

    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.97))
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    plt.close(fig)
    return buffer.getvalue()
