"""Every picture accugrid draws, as PNG bytes (matplotlib, Agg backend, imported on first use):
seed Fig. 3 (``simulate --plot``), Fig. 12 and the Table 5 histograms (``study``), the robot-frame
fit (``fit-frame --plot``), the method comparison (``compare``: one figure for the max, one for
the std). Lengths mm. Where a plot shows remaining errors it draws the tolerance (default
+-0.3 mm) as a line, and its legend stands outside the data, at the figure's right."""

from __future__ import annotations

import io
from collections.abc import Mapping

import numpy as np

from accugrid.compensation.comparison import TARGET_SETS, Comparison
from accugrid.compensation.settings import DEFAULT_TOLERANCE_MM
from accugrid.compensation.study import AXES, DEFAULT_STD_FRACTION, StudyResult, Validation
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.base_frame import RobotFrameFit
from accugrid.kinematics.fitting import CircleFit
from accugrid.kinematics.frames import invert, transform_points

__all__ = [
    "COMPARISON_STATS",
    "comparison_png",
    "correction_map_png",
    "fig3_png",
    "fig12_png",
    "frame_fit_png",
    "hist_png",
    "rows_png",
    "validation_hist_png",
]

_NO_SOFTWARE = {"Software": None}  # no matplotlib version in the file: the same bytes anywhere


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _legend_outside(fig, ax) -> None:
    """One legend for the figure, at its right, outside every panel (``ax``'s handles; the
    figure must use the constrained layout)."""
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right center", fontsize=8, frameon=False)


def _tolerance_lines(ax, tol: float, label: str, *, vertical: bool = False) -> None:
    """Dashed lines at +-``tol`` mm (across a histogram's x axis with ``vertical``)."""
    line = ax.axvline if vertical else ax.axhline
    line(tol, color="tab:green", ls="--", lw=1.0, label=label)
    line(-tol, color="tab:green", ls="--", lw=1.0)


def _png(plt, fig, dpi: float | None = None, metadata: dict | None = _NO_SOFTWARE) -> bytes:
    """The figure as PNG bytes; closes it."""
    buffer = io.BytesIO()
    options = {} if dpi is None else {"dpi": dpi}
    fig.savefig(buffer, format="png", metadata=metadata, **options)
    plt.close(fig)
    return buffer.getvalue()


def fig3_png(
    robot_name: str, xs: np.ndarray, ys: np.ndarray, error: np.ndarray, z_mm: float, abc: tuple
) -> bytes:
    """Seed Fig. 3: the error e = P - M (s, s, 3) mm over the plane X (s,) by Y (s,) mm at Z
    ``z_mm`` and KUKA A B C ``abc`` deg, one panel per axis."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6), constrained_layout=True)
    for k, (ax, axis) in enumerate(zip(axes, "XYZ", strict=True)):
        field = error[:, :, k].T  # rows = Y, columns = X
        mesh = ax.contourf(xs, ys, field, levels=20, cmap="viridis")
        ax.contour(xs, ys, field, levels=10, colors="k", linewidths=0.4)
        fig.colorbar(mesh, ax=ax, label=f"D_{axis} (mm)")
        ax.set_title(f"({'abc'[k]}) D_{axis}: {field.min():.2f} .. {field.max():.2f} mm")
        ax.set_xlabel("X (mm)")
        ax.set_ylabel("Y (mm)")
        ax.set_aspect("equal")
    fig.suptitle(
        f"{robot_name}: TCP error e = P - M at Z {z_mm:g} mm, A B C "
        f"{' '.join(f'{v:g}' for v in abc)} deg (seed Fig. 3)"
    )
    return _png(plt, fig, dpi=110, metadata=None)


def fig12_png(result: StudyResult) -> bytes:
    """Seed Fig. 12: max/min error against step per axis, cubic curves, tolerance lines."""
    plt = _pyplot()

    tol = result.tolerance_mm
    steps = result.steps
    dense = np.linspace(steps.min(), steps.max(), 300)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), sharey=True, layout="constrained")
    for a, ax in enumerate(axes):
        ax.axhspan(-tol, tol, color="tab:green", alpha=0.08)
        _tolerance_lines(ax, tol, f"tolerance ±{tol:g} mm")
        ax.plot(steps, [r.max[a] for r in result.table], "o", color="tab:red", label="max")
        ax.plot(steps, [r.min[a] for r in result.table], "s", color="tab:blue", label="min")
        ax.plot(dense, result.max_curves[a](dense), "-", color="tab:red", lw=1, label="max, cubic")
        ax.plot(dense, result.min_curves[a](dense), "-", color="tab:blue", lw=1, label="min, cubic")
        th = result.decision.thresholds[a]
        if np.isfinite(th):
            ax.axvline(th, color="gray", ls=":", label="threshold step")
        if result.decision.step is not None:
            ax.axvline(result.decision.step, color="black", ls="-.", label="chosen step")
        ax.set_title(f"{AXES[a]} after compensation")
        ax.set_xlabel("grid step (mm)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("remaining error (mm)")
    _legend_outside(fig, max(axes, key=lambda ax: len(ax.get_legend_handles_labels()[1])))
    return _png(plt, fig, dpi=110)


def hist_png(validation: Validation, tolerance_mm: float = DEFAULT_TOLERANCE_MM) -> bytes:
    """Table 5 before/after histograms per axis (all samples), the tolerance +-``tolerance_mm``
    as lines."""
    plt = _pyplot()

    before = validation.before.reshape(-1, 3)
    after = validation.after.reshape(-1, 3)
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8), layout="constrained")
    for a, ax in enumerate(axes):
        lo = min(before[:, a].min(), after[:, a].min(), -tolerance_mm)
        hi = max(before[:, a].max(), after[:, a].max(), tolerance_mm)
        bins = np.linspace(lo, hi, 40)
        ax.hist(before[:, a], bins=bins, alpha=0.6, label="before", color="tab:orange")
        ax.hist(after[:, a], bins=bins, alpha=0.6, label="after", color="tab:blue")
        _tolerance_lines(ax, tolerance_mm, f"tolerance ±{tolerance_mm:g} mm", vertical=True)
        ax.set_title(f"{AXES[a]} error at validation points")
        ax.set_xlabel("error (mm)")
    axes[0].set_ylabel("samples")
    _legend_outside(fig, axes[0])
    return _png(plt, fig, dpi=110)


def _circle_points(fit: CircleFit, n: int = 361) -> np.ndarray:
    """(n, 3) mm points on a fitted circle, in the frame of the fit."""
    e1 = np.cross(fit.normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 0.5:
        e1 = np.cross(fit.normal, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(fit.normal, e1)
    t = np.linspace(0.0, 2.0 * np.pi, n)
    return fit.center + fit.radius_mm * (np.outer(np.cos(t), e1) + np.outer(np.sin(t), e2))


def frame_fit_png(fit: RobotFrameFit, points: Mapping[str, np.ndarray]) -> bytes:
    """PNG bytes: the measured points and fits drawn in the fitted robot frame (mm).

    ``points`` holds the tracker-frame (N, 3) arrays under base_plane, a1_circle, flange_holes.
    """
    plt = _pyplot()

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
    return _png(plt, fig)


COMPARISON_STATS = ("max", "std")  # one figure each


def comparison_png(
    result: Comparison, stat: str, tolerance_mm: float = DEFAULT_TOLERANCE_MM
) -> bytes:
    """``accugrid compare``: the held-out ``stat`` ("max": max |P - M|, with the tolerance
    ``tolerance_mm`` as a line; "std": the std, with the study's std limit, a fraction of the
    tolerance) per axis, mm, against the measured-point budget: one line per method, a row of
    panels per target set, the legend outside at the right."""
    plt = _pyplot()
    methods = [m for m in dict.fromkeys(r.method for r in result.rows) if m != "uncorrected"]
    fig, axes = plt.subplots(2, 3, figsize=(13, 6.4), sharex=True, layout="constrained")
    colours = plt.get_cmap("tab10").colors
    limit = tolerance_mm if stat == "max" else DEFAULT_STD_FRACTION * tolerance_mm
    limit_label = (
        f"tolerance {tolerance_mm:g} mm"
        if stat == "max"
        else f"std limit {limit:g} mm ({DEFAULT_STD_FRACTION:g} x tolerance)"
    )
    for i, targets in enumerate(TARGET_SETS):
        before = result.row(0, targets, "uncorrected")
        for k, axis in enumerate("XYZ"):
            ax = axes[i, k]
            for colour, method in zip(colours, methods, strict=False):
                rows = [r for r in result.rows if (r.targets, r.method) == (targets, method)]
                at = [r.budget for r in rows]  # a budget too small for a model has no row
                values = [(r.max_mm if stat == "max" else r.std_mm)[k] for r in rows]
                ax.plot(at, values, "o-", color=colour, label=method)
            ax.axhline(limit, color="tab:green", ls="--", lw=1.0, label=limit_label)
            uncorrected = (before.max_mm if stat == "max" else before.std_mm)[k]
            ax.set_title(f"{targets}: {axis} (uncorrected {stat} {uncorrected:.2f} mm)", fontsize=9)
            ax.set_ylim(bottom=0.0)
            ax.grid(alpha=0.3)
            if i == 1:
                ax.set_xlabel("measured points (budget)")
            if k == 0:
                ax.set_ylabel(
                    f"held-out {stat} |P - M|, mm" if stat == "max" else "held-out std, mm"
                )
    _legend_outside(fig, axes[0, 0])
    fig.suptitle(
        f"{result.robot}: {stat} of the remaining error, {result.n_targets} held-out targets per "
        f"set, {result.repeats} repeats per measured point, KUKA Status {result.status}",
        fontsize=10,
    )
    return _png(plt, fig, dpi=80)


def validation_hist_png(deviation: np.ndarray, tolerance_mm: float) -> bytes:
    """``accugrid validate``: histograms of the deviation d = M - P (N, 3) mm per axis after
    correction, the tolerance +-``tolerance_mm`` as lines."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(10, 2.9), layout="constrained")
    reach = max(float(np.abs(deviation).max()), tolerance_mm) * 1.1
    bins = np.linspace(-reach, reach, 41)
    for k, ax in enumerate(axes):
        ax.hist(deviation[:, k], bins=bins, color="tab:blue", alpha=0.8, label="measured rows")
        _tolerance_lines(ax, tolerance_mm, f"tolerance ±{tolerance_mm:g} mm", vertical=True)
        ax.set_title(f"{'XYZ'[k]}: measured - target", fontsize=9)
        ax.set_xlabel("deviation (mm)")
    axes[0].set_ylabel("rows")
    _legend_outside(fig, axes[0])
    return _png(plt, fig, dpi=90)


def rows_png(values: np.ndarray, tolerance_mm: float, ylabel: str, xlabel: str) -> bytes:
    """Per-row errors (N, 3) mm in file order (validation deviations, identification
    residuals), one marker colour per axis, the tolerance as lines; rasterised, small for 1e4
    rows."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 2.6), layout="constrained")
    rows = np.arange(1, len(values) + 1)
    for k, colour in enumerate(("tab:red", "tab:blue", "tab:purple")):
        ax.plot(rows, values[:, k], ".", ms=3, color=colour, label="XYZ"[k])
    _tolerance_lines(ax, tolerance_mm, f"tolerance ±{tolerance_mm:g} mm")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    _legend_outside(fig, ax)
    return _png(plt, fig, dpi=90)


def correction_map_png(
    points: np.ndarray,
    correction: np.ndarray,
    corrected: np.ndarray,
    flagged: np.ndarray,
    plane: str = "robot frame",
) -> bytes:
    """Plan view of the positions (N, 2) mm in a plane's axes u, v (named by ``plane``)
    coloured by the length of the correction (N, 3) mm applied (its u, v, n components), arrows
    along its in-plane part (at most 400, scaled to the plot), the positions not corrected
    (``corrected`` (N,) False) as black crosses and the flagged ones (``flagged`` (N,) bool)
    ringed in orange; rasterised, small for 1e4 holes."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 5.2), layout="constrained")
    length = np.linalg.norm(correction, axis=1)
    done = np.flatnonzero(corrected)
    mesh = ax.scatter(
        points[done, 0], points[done, 1], c=length[done], s=14, cmap="viridis", rasterized=True
    )
    fig.colorbar(mesh, ax=ax, label="|correction| (mm)")
    if done.size:
        arrows = done[:: max(1, done.size // 400)]
        span = np.ptp(points[:, :2], axis=0).max() if len(points) > 1 else 1.0
        scale = max(float(length[arrows].max()), 1e-9) / (0.04 * max(span, 1.0))
        ax.quiver(
            points[arrows, 0],
            points[arrows, 1],
            correction[arrows, 0],
            correction[arrows, 1],
            angles="xy",
            scale_units="xy",
            scale=scale,
            width=0.002,
            color="tab:red",
            label=f"in-plane correction (1 mm drawn as {1.0 / scale:.0f} mm)",
        )
    skipped = np.flatnonzero(~corrected)
    if skipped.size:
        ax.plot(points[skipped, 0], points[skipped, 1], "kx", ms=6, label="not corrected")
    ringed = np.flatnonzero(flagged & corrected)
    if ringed.size:
        ax.plot(
            points[ringed, 0], points[ringed, 1], "o", mfc="none", mec="tab:orange", ms=9,
            label="flagged",
        )  # fmt: skip
    return _plan_view_png(plt, fig, ax, plane)


def _plan_view_png(plt, fig, ax, plane: str) -> bytes:
    """A plan view's axes (u, v mm in ``plane``), equal scale, grid and legend; its PNG."""
    ax.set_xlabel(f"u (mm), {plane}")
    ax.set_ylabel("v (mm)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[1]:
        _legend_outside(fig, ax)
    return _png(plt, fig, dpi=90)


def budget_map_png(
    points: np.ndarray, u95: np.ndarray, tolerance_mm: float, plane: str = "robot frame"
) -> bytes:
    """Plan view of the positions (N, 2) mm in a plane's axes u, v (named by ``plane``)
    coloured by their error budget's 95 % bound ``u95`` (N,) mm (NaN: none, black crosses), those
    beyond ``tolerance_mm`` ringed in red; rasterised, small for 1e4 holes."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 5.2), layout="constrained")
    known = np.flatnonzero(np.isfinite(u95))
    mesh = ax.scatter(
        points[known, 0], points[known, 1], c=u95[known], s=14, cmap="magma_r", rasterized=True
    )
    fig.colorbar(mesh, ax=ax, label="u95: 95 % bound of the error (mm)")
    unknown = np.flatnonzero(~np.isfinite(u95))
    if unknown.size:
        ax.plot(points[unknown, 0], points[unknown, 1], "kx", ms=6, label="no bound")
    over = known[u95[known] > tolerance_mm]
    if over.size:
        ax.plot(
            points[over, 0], points[over, 1], "o", mfc="none", mec="tab:red", ms=9,
            label=f"u95 beyond {tolerance_mm:g} mm",
        )  # fmt: skip
    return _plan_view_png(plt, fig, ax, plane)
