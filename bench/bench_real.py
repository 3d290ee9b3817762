"""Identification on a real robot: the UR10 laser-tracker series of ``../shared/realdata/ipa-ur10``.

Series C (2,773 random poses with logged joints) and Series A (a grid at up to 24 orientations,
11,910 rows, another session and another tracker frame), read as they come and calibrated as the
command line does (``bench.real_ur10``: the built-in ``ur10``, the T-Mac's TCP, the tracker frame
identified with the arm).

Table 1 (``in_distribution_table``): N random poses of C (the same seed each run) against the rest
of C: the 3D error |measured - model| mean, p95, max mm of the nominal arm in its best-fit tracker
frame, the DH-only fit (``--structure dh``), the default (``--structure auto``) and the default
where the poses support the target and the DH-only fit where not (``kinematics.support``); the
default's nested estimate (3D RMS) against the held-out 3D RMS, the groups chosen and the
identification's wall time and CPU time (nested estimate included; the CPU time is what
an otherwise idle machine would take, the wall time depends on its load).

Table 2 (``shifted_table``): calibrated on one part of joint space, scored on another: C split at
the median of A1, A2 or A3 (300 random poses of one half, scored on the whole other half), A by
elbow (sign of A3) and by wrist (sign of A5) configuration, and C -> A (300 random C poses, scored
on the A grid; A's tracker frame fitted for each model by the rigid fit of its predictions to 30
random A rows, the rest scored). Mean 3D error of the DH-only fit, the default, the default with
the DH-only fit where no support, each ratio to the DH-only fit, the share without support, and
how many of the poses the default misses by more than twice its own estimate
(``bench.real_ur10.own_estimate``) carry a flag for where they lie (no support, or outside the
calibration poses' region: ``flagged_anywhere``).

Table 3 (``reach_table``): how far the method reaches on this arm. The default's structure chosen
from ``REACH_POSES`` random poses of C, scored on the rest; then ``DRAWS`` draws of N poses from the
C poses that choice never saw, each scored on the rest of them: the default (structure chosen from
the N poses) against the same N poses fitted with the terms the larger set chose (told the
structure: a reference, not evidence for the selection). Mean 3D error per draw, mm.

Not a timed test: ``make bench ARGS=real`` (or ``.venv/bin/python bench/bench_real.py``);
``--tables 1`` (2, 3) prints one table, ``--poses 100,300`` the sizes of tables 1 and 3.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from accugrid.kinematics.identification import identify, rigid_fit  # noqa: E402
from bench.real_ur10 import (  # noqa: E402
    REAL,
    ROBOT,
    Fit,
    calibrate,
    flagged_anywhere,
    in_frame,
    model_points,
    own_estimate,
    read_series,
)

SEED = 0
SHIFT_POSES = 300
REACH_POSES = 1000  # table 3: the poses the reference structure is chosen from
DRAWS = 5  # table 3: random draws of the calibration poses per size
A_FRAME_ROWS = 30  # Series A rows a model's tracker frame for A is fitted on (C -> A)


def errors(fit: Fit, q: np.ndarray, m: np.ndarray, frame_rows: np.ndarray | None = None):
    """3D errors (N,) mm of the DH-only fit, the default and the default with the DH-only fit
    where no support, and the share without support, at joints q (N, 6) rad measured m (N, 3)
    mm: in each model's identified tracker frame, or (``frame_rows``: another session) in the
    rigid fit of its predictions at those rows to their measurements (those rows not scored)."""
    out = []
    for result in (fit.dh, fit.default):
        if frame_rows is None:
            predicted = in_frame(result, q)
        else:
            points = model_points(result, q)
            frame = rigid_fit(points[frame_rows], m[frame_rows])
            predicted = points @ frame[:3, :3].T + frame[:3, 3]
        out.append(np.linalg.norm(m - predicted, axis=1))
    flagged = fit.support.ratio(q) > 1.0
    out.append(np.where(flagged, out[0], out[1]))
    scored = np.ones(len(q), bool)
    if frame_rows is not None:
        scored[frame_rows] = False
    return [e[scored] for e in out], float(flagged[scored].mean())


def nominal_errors(q: np.ndarray, m: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """3D errors (N,) mm of the nominal arm in the tracker frame best fitted on ``rows``."""
    points = ROBOT.fk(q)[:, :3, 3]
    frame = rigid_fit(points[rows], m[rows])
    return np.linalg.norm(m - (points @ frame[:3, :3].T + frame[:3, 3]), axis=1)


def _cells(e: np.ndarray) -> str:
    return f"{e.mean():.3f} | {np.quantile(e, 0.95):.3f} | {e.max():.3f}"


def in_distribution_table(sizes: tuple[int, ...]) -> None:
    """Table 1 (printed)."""
    c = read_series("C")
    q, m = c.q, c.m
    order = np.random.default_rng(SEED).permutation(len(q))
    print("\nN random Series C poses -> the rest of C; 3D error mean | p95 | max mm\n")
    print(
        "| poses | model | mean | p95 | max | nested est. RMS | held-out RMS | groups "
        + "| time s (CPU s) |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        train, test = order[:n], order[n:]
        fit = calibrate(c, train)
        (dh, default, guarded), flagged = errors(fit, q[test], m[test])
        nominal = nominal_errors(q, m, train)[test]
        nested = fit.selection.nested
        estimate = float(np.linalg.norm(nested.rms_mm)) if nested is not None else float("nan")
        rms = float(np.sqrt(np.mean(default**2)))
        print(f"| {n} | nominal, best-fit tracker frame | {_cells(nominal)} | | | | |")
        print(f"| {n} | DH only | {_cells(dh)} | | {np.sqrt(np.mean(dh**2)):.3f} | | |")
        print(
            f"| {n} | default | {_cells(default)} | {estimate:.3f} | {rms:.3f} | "
            f"{len(fit.selection.chosen)} | {fit.seconds[0]:.1f} ({fit.seconds[1]:.1f}) |"
        )
        print(
            f"| {n} | default, DH-only where no support ({flagged:.0%}) | {_cells(guarded)} "
            "| | | | |"
        )


def shifted_splits() -> list[tuple[str, str, np.ndarray, np.ndarray]]:
    """(name, series "C", "A" or "C->A", training rows, scored rows) of table 2."""
    rng = np.random.default_rng(SEED)
    q_c, q_a = read_series("C").q, read_series("A").q

    def pick(rows: np.ndarray) -> np.ndarray:
        return np.sort(rng.choice(rows, min(SHIFT_POSES, len(rows)), replace=False))

    out = []
    rows_c = np.arange(len(q_c))
    for axis in (0, 1, 2):
        low = q_c[:, axis] < np.median(q_c[:, axis])
        out.append((f"C, A{axis + 1} low -> high", "C", pick(rows_c[low]), rows_c[~low]))
        out.append((f"C, A{axis + 1} high -> low", "C", pick(rows_c[~low]), rows_c[low]))
    rows_a = np.arange(len(q_a))
    for name, side in (("elbow (A3 > 0)", q_a[:, 2] > 0), ("wrist (A5 > 0)", q_a[:, 4] > 0)):
        out.append((f"A, {name} -> other", "A", pick(rows_a[side]), rows_a[~side]))
        out.append((f"A, other -> {name}", "A", pick(rows_a[~side]), rows_a[side]))
    out.append(("C -> A", "C->A", pick(rows_c), rows_a))
    return out


def shifted_table() -> None:
    """Table 2 (printed)."""
    data = {"C": read_series("C"), "A": read_series("A")}
    print(
        f"\ncalibrated on {SHIFT_POSES} poses of one part of joint space, scored on another; "
        "mean 3D error mm (ratio to the DH-only fit)\n"
    )
    print(
        "| split | scored | DH only | default | default, DH-only where no support | no support "
        "| misses of their own estimate flagged |"
    )
    print("|---|---|---|---|---|---|---|")
    frame_rows = np.random.default_rng(SEED + 1).choice(len(data["A"]), A_FRAME_ROWS, replace=False)
    for name, where, train, test in shifted_splits():
        series = data["A" if where == "A" else "C"]
        q, m = series.q, series.m
        fit = calibrate(series, train)
        if where == "C->A":
            (dh, default, guarded), flagged = errors(fit, data["A"].q, data["A"].m, frame_rows)
            target = data["A"].rows(np.setdiff1d(np.arange(len(data["A"])), frame_rows))
        else:
            (dh, default, guarded), flagged = errors(fit, q[test], m[test])
            target = series.rows(test)
        ratio = [e.mean() / dh.mean() for e in (default, guarded)]
        miss = default > 2.0 * own_estimate(fit, target.q)
        caught = int((flagged_anywhere(fit, target) & miss).sum())
        print(
            f"| {name} | {len(dh)} | {dh.mean():.3f} | {default.mean():.3f} ({ratio[0]:.2f}) | "
            f"{guarded.mean():.3f} ({ratio[1]:.2f}) | {flagged:.0%} | {caught} of {miss.sum()} |",
            flush=True,
        )


def reach_table(sizes: tuple[int, ...]) -> None:
    """Table 3 (printed)."""
    c = read_series("C")
    order = np.random.default_rng(SEED).permutation(len(c))
    large, rest = order[:REACH_POSES], order[REACH_POSES:]
    reference = calibrate(c, large)
    scored = np.linalg.norm(in_frame(reference.default, c.q[rest]) - c.m[rest], axis=1)
    told = reference.selection
    print(
        f"\nthe default from {REACH_POSES} poses of C: {scored.mean():.3f} mean, "
        f"{np.quantile(scored, 0.95):.3f} p95 mm on the other {len(rest)} "
        f"({len(told.harmonics)} harmonics, {len(told.gravity)} gravity groups)\n"
    )
    print(f"{DRAWS} draws of N poses from those {len(rest)}, scored on the rest of them: mean mm\n")
    print("| poses | model | each draw | median |")
    print("|---|---|---|---|")
    for n in sizes:
        rows = {"default": [], f"told the terms {REACH_POSES} poses chose": []}
        for draw in range(DRAWS):
            pick = rest[np.random.default_rng(SEED + 1 + draw).permutation(len(rest))]
            train, test = pick[:n], pick[n:]
            data = c.rows(train).measurements.pose_set(ROBOT, None)
            fitted = (
                calibrate(c, train).default,
                identify(
                    ROBOT,
                    data,
                    base_frame=True,
                    harmonics=told.harmonics,
                    gravity=told.gravity,
                    selected=True,
                ),
            )
            for errors_of, result in zip(rows.values(), fitted, strict=True):
                errors_of.append(np.linalg.norm(in_frame(result, c.q[test]) - c.m[test], axis=1))
        for name, errors_of in rows.items():
            means = [e.mean() for e in errors_of]
            each = " ".join(f"{m:.3f}" for m in means)
            print(f"| {n} | {name} | {each} | {np.median(means):.3f} |", flush=True)


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", default="1,2,3")
    parser.add_argument("--poses", default="100,300")
    args, _ = parser.parse_known_args(argv)
    if not REAL.is_dir():
        print(f"{REAL} is missing: the real data sit beside the checkout (../shared/realdata)")
        return
    tables = args.tables.split(",")
    if "1" in tables:
        in_distribution_table(tuple(int(n) for n in args.poses.split(",")))
    if "2" in tables:
        shifted_table()
    if "3" in tables:
        reach_table(tuple(int(n) for n in args.poses.split(",")))


if __name__ == "__main__":
    main(sys.argv[1:])
