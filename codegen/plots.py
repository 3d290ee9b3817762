"""Pictures accugrid draws, as PNG bytes (matplotlib, Agg backend, imported on first use).
Lengths mm."""

from __future__ import annotations

import io

from accugrid.compensation.comparison import TARGET_SETS, Comparison

__all__ = ["comparison_png"]

_NO_SOFTWARE = {"Software": None}  # no matplotlib version in the file: the same bytes anywhere


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(plt, fig, dpi: float | None = None, metadata: dict | None = _NO_SOFTWARE) -> bytes:
    """The figure as PNG bytes; closes it."""
    buffer = io.BytesIO()
    options = {} if dpi is None else {"dpi": dpi}
    fig.savefig(buffer, format="png", metadata=metadata, **options)
    plt.close(fig)
    return buffer.getvalue()


def comparison_png(result: Comparison) -> bytes:
    """``accugrid compare``: held-out max |P - M| (solid) and std (dashed) per axis, mm, against
    the measured-point budget, one line pair per method; a row per target set."""
    plt = _pyplot()
    methods = [m for m in dict.fromkeys(r.method for r in result.rows) if m != "uncorrected"]
    budgets = sorted({r.budget for r in result.rows if r.budget})
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4), sharex=True, constrained_layout=True)
    colours = plt.get_cmap("tab10").colors
    for i, targets in enumerate(TARGET_SETS):
        before = result.row(0, targets, "uncorrected")
        for k, axis in enumerate("XYZ"):
            ax = axes[i, k]
            for colour, method in zip(colours, methods, strict=False):
                rows = [result.row(b, targets, method) for b in budgets]
                peak = [r.max_mm[k] for r in rows]
                std = [r.std_mm[k] for r in rows]
                ax.plot(budgets, peak, "o-", color=colour, label=f"{method}, max")
                ax.plot(budgets, std, "s--", color=colour, ms=3, lw=0.8, label=f"{method}, std")
            ax.set_title(
                f"{targets}: {axis} (uncorrected max {before.max_mm[k]:.2f} mm)", fontsize=9
            )
            ax.set_ylim(bottom=0.0)
            ax.grid(alpha=0.3)
            if i == 1:
                ax.set_xlabel("measured points (budget)")
            if k == 0:
                ax.set_ylabel("held-out |P - M|, mm")
    axes[0, 0].legend(fontsize=6, ncol=2)
    fig.suptitle(
        f"{result.robot}: {result.n_targets} held-out targets per set, {result.repeats} repeats "
        f"per measured point, KUKA Status {result.status}",
        fontsize=10,
    )
    return _png(plt, fig, dpi=80)
