"""Where a calibrated model has support, on the real UR10 (``kinematics.support``).

Models identified (the default structure, tracker frame identified) from 300 poses of Series C
(``../shared/realdata/ipa-ur10``, read as it comes and calibrated as the command line does,
``bench.real_ur10``) and scored on poses they
never saw: the rest of C (each model's own identified tracker frame), Series A (its tracker frame
fitted with each model on all its rows), the shifted distributions of C's joint-space halves (A1
or A4 below their median for calibration, above for scoring) and Series A's elbow configurations
(300 poses with the elbow angle above 0, scored on those below). Per row, 3D errors in mm: the
model's mean and max, the DH-only fit's mean (the fallback, ``--structure dh`` on the same
poses), the mean of the model where it has support and the fallback where not, the share of
poses without support, how many of the poses the model misses by more than twice its nested
estimate are flagged, the same for twice each pose's own estimate (the nested estimate scaled by
the pose's prediction variance, ``own_estimate``) and how many of those carry any of the flags a
corrected position gets for where it lies (no support, or outside the poses' region: box, tool
tilt or a joint's range, ``kinematics.validity``), and on the flagged poses the model's mean
against the fallback's; and the share of errors within their 95 % bound (``compensation.budget``):
the model's at the poses it corrects, the DH-only fallback's own (``ModelBudget.of_fallback``)
at the flagged ones, and there too the model's (what the fallback's errors would be held to without
a bound of their own). Not a timed test: ``make bench ARGS=real`` (or ``.venv/bin/python
bench/bench_real_support.py``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from accugrid.compensation.budget import ModelBudget  # noqa: E402
from accugrid.infra.bounds import length_bound_95  # noqa: E402
from accugrid.kinematics.identification import rigid_fit  # noqa: E402
from bench.real_ur10 import (  # noqa: E402
    REAL,
    Fit,
    Series,
    calibrate,
    flagged_anywhere,
    own_estimate,
    random_pick,
    read_series,
)

POSES = 300


def errors(robot, frame, series: Series, rows: np.ndarray) -> np.ndarray:
    """|measured - model| (N,) mm at ``rows``; ``frame``: tracker_T_robot (None: fitted with
    the model on these rows)."""
    predicted = robot.true_robot().fk(series.q[rows])[:, :3, 3]
    measured = series.m[rows]
    frame = rigid_fit(predicted, measured) if frame is None else frame
    return np.linalg.norm((measured - frame[:3, 3]) @ frame[:3, :3] - predicted, axis=1)


def row(label: str, model: Fit, series: Series, rows: np.ndarray, own_frame: bool) -> str:
    result, selection, support = model.default, model.selection, model.support
    frames = (result.tracker_T_robot, support.fallback_frame) if own_frame else (None, None)
    full = errors(result.robot, frames[0], series, rows)
    dh = errors(support.fallback, frames[1], series, rows)
    flagged = support.ratio(series.q[rows]) > 1.0
    outside = flagged_anywhere(model, series.rows(rows))
    miss = full > 2.0 * float(np.linalg.norm(selection.nested.rms_mm))
    own = full > 2.0 * own_estimate(model, series.q[rows])
    on = f"{full[flagged].mean():.3f} → {dh[flagged].mean():.3f}" if flagged.any() else "-"
    guarded = np.where(flagged, dh, full).mean()
    u95 = length_bound_95(model.budget.covariance(series.q[rows]))
    u95_fallback = length_bound_95(ModelBudget.of_fallback(support).covariance(series.q[rows]))
    within = [
        f"{np.mean(e <= bound):.0%}" if e.size else "-"
        for e, bound in (
            (full[~flagged], u95[~flagged]),
            (dh[flagged], u95_fallback[flagged]),
            (dh[flagged], u95[flagged]),
        )
    ]
    return (
        f"| {label} | {len(rows)} | {full.mean():.3f} / {full.max():.2f} | {dh.mean():.3f} | "
        f"{guarded:.3f} | {flagged.mean():.1%} | {(flagged & miss).sum()} of {miss.sum()} "
        f"| {(flagged & own).sum()} of {own.sum()} | {(outside & own).sum()} of {own.sum()} "
        f"| {on} | {' | '.join(within)} |"
    )


def main() -> None:
    if not REAL.is_dir():
        print(f"{REAL} is missing: the real data sit beside the checkout (../shared/realdata)")
        return
    c = read_series("C")
    a = read_series("A")
    print(
        "| calibrated on → scored on | poses | model mean / max | DH-only mean | with the "
        "fallback: mean | flagged | misses flagged | misses of their own estimate flagged | "
        "those with any flag (support or region) | "
        "on the flagged: model → fallback mean | within u95: model | flagged: within the "
        "fallback's u95 | flagged: within the model's u95 |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    pick = random_pick(len(c), POSES)
    model = calibrate(c, pick)
    rest = np.setdiff1d(np.arange(len(c)), pick)
    print(row(f"{POSES} random C → the rest of C", model, c, rest, True), flush=True)
    print(row(f"{POSES} random C → Series A", model, a, np.arange(len(a)), False), flush=True)
    for axis in (0, 3):
        low = c.q[:, axis] < np.median(c.q[:, axis])
        half = np.flatnonzero(low)
        pick = half[random_pick(len(half), POSES)]
        model = calibrate(c, pick)
        name = f"{POSES} of C, A{axis + 1} below its median"
        inside = np.setdiff1d(half, pick)
        print(row(f"{name} → the rest of that half", model, c, inside, True), flush=True)
        print(row(f"{name} → the other half", model, c, np.flatnonzero(~low), True), flush=True)
    up = np.flatnonzero(a.q[:, 2] > 0)  # Series A, elbow angle above 0: one configuration
    pick = up[random_pick(len(up), POSES)]
    model = calibrate(a, pick)
    name = f"{POSES} of A with the elbow above 0"
    others = np.flatnonzero(a.q[:, 2] <= 0)
    print(row(f"{name} → the rest of them", model, a, np.setdiff1d(up, pick), True), flush=True)
    print(row(f"{name} → A with the elbow below", model, a, others, True), flush=True)


if __name__ == "__main__":
    main()
