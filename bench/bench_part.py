"""The part frame from datums (``accugrid fit-part``) over random parts: the error at the holes,
the 95 % bound's coverage and width, and the moved-datum test.

A 1000 x 600 mm part stands up to 3 mm and 0.2 deg from its nominal frame (uniform per
coordinate); its tooling balls stand at the corners, 20-60 mm above the skin, then on a post in
the centre and at the middle of the long edges; 40 holes lie on the skin (z = 0). The tracker
measures each ball once or 3 times (averaged) with the noise of the simulated sessions
(``NOISE_TRACKER_MM`` per axis). Columns: datums, repeats, scale (rigid / fitted), the error at
the holes of the nominal frame (median of the per-part max), of the fitted frame (median, 95th
percentile and max of the per-part max), the share of parts whose holes all land within
0.03 mm, the share of hole errors inside their 95 % bound, the mean bound over the actual 95th
percentile of the hole errors, and the share of parts refused for a moved datum without (false
alarm) and with one ball moved by 0.5 or 1 mm.

``python bench/bench_part.py [--trials N]`` (default 500 parts per row).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc, transform_points
from accugrid.kinematics.part_frame import fit_part_frame
from accugrid.kinematics.robot_family import NOISE_TRACKER_MM

NOMINAL_XYZABC = np.array([1700.0, 300.0, 1000.0, -90.0, 0.0, 90.0])
OFFSET = np.array([3.0, 3.0, 3.0, 0.2, 0.2, 0.2])  # mm, deg: the part's largest offset
BALLS = np.array(
    [
        [-500, -300, 20],
        [500, -300, 40],
        [500, 300, 60],
        [-500, 300, 30],
        [0, 0, 150],
        [0, -300, 25],
        [0, 300, 45],
    ],
    dtype=float,
)
MOVES_MM = (0.5, 1.0)
TOLERANCE_MM = 0.03


def _trial(rng, n: int, scale: float | None, repeats: int, move_mm: float):
    """(hole errors (H,) of the nominal and fitted frames, their bounds) or None if refused."""
    nominal_pose = pose_from_xyzabc(NOMINAL_XYZABC)
    true = pose_from_xyzabc(NOMINAL_XYZABC + rng.uniform(-OFFSET, OFFSET))
    holes = np.column_stack([rng.uniform(-480, 480, 40), rng.uniform(-280, 280, 40), np.zeros(40)])
    balls = BALLS[:n]
    noise = rng.normal(0.0, NOISE_TRACKER_MM, (repeats, *balls.shape)).mean(axis=0)
    measured = transform_points(true, balls) + noise  # the mean of the repeats, as fit-part
    if move_mm:
        direction = rng.normal(size=3)
        measured[rng.integers(n)] += move_mm * direction / np.linalg.norm(direction)
    actual = transform_points(true, holes)
    before = np.linalg.norm(transform_points(nominal_pose, holes) - actual, axis=1)
    try:
        fit = fit_part_frame(balls, measured, [str(i) for i in range(n)], scale=scale)
    except InputError:
        return None
    after = np.linalg.norm(transform_points(fit.robot_T_base, holes) - actual, axis=1)
    return before, after, fit.sigma_at(holes)[1]


def row(n: int, scale: float | None, repeats: int, trials: int, seed: int) -> list[str]:
    rng = np.random.default_rng(seed)
    before, worst, inside, errors, bounds, alarms = [], [], 0, [], [], 0
    for _ in range(trials):
        result = _trial(rng, n, scale, repeats, 0.0)
        if result is None:
            alarms += 1
            continue
        b, a, u95 = result
        before.append(b.max())
        worst.append(a.max())
        inside += int((a <= u95).sum())
        errors.append(a)
        bounds.append(u95)
    caught = [
        sum(_trial(rng, n, scale, repeats, move) is None for _ in range(trials)) if n > 3 else 0
        for move in MOVES_MM
    ]
    worst, errors, bounds = np.array(worst), np.concatenate(errors), np.concatenate(bounds)
    width = bounds.mean() / np.percentile(errors, 95)
    return [
        str(n),
        str(repeats),
        "rigid" if scale is not None else "fit",
        f"{np.median(before):.3f}",
        f"{np.median(worst):.4f}",
        f"{np.percentile(worst, 95):.4f}",
        f"{worst.max():.4f}",
        f"{np.mean(worst <= TOLERANCE_MM):.1%}",
        f"{inside / errors.size:.1%}",
        f"{width:.2f}",
        f"{alarms / trials:.1%}",
        *(f"{c / trials:.1%}" if n > 3 else "-" for c in caught),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=500)
    args, _ = parser.parse_known_args()
    header = [
        "datums",
        "repeats",
        "scale",
        "nominal max",
        "fit max med",
        "p95",
        "max",
        "<= 0.03",
        "in u95",
        "u95/p95",
        "refused",
        *(f"moved {m:g} caught" for m in MOVES_MM),
    ]
    rows = [header]
    start = time.perf_counter()
    cases = [(3, 1.0, 1), (4, 1.0, 1), (5, 1.0, 1), (6, 1.0, 1), (5, None, 1), (6, None, 1)]
    cases += [(4, 1.0, 3), (5, 1.0, 3), (6, 1.0, 3)]
    for seed, (n, scale, repeats) in enumerate(cases):
        rows.append(row(n, scale, repeats, args.trials, seed))
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]
    print(
        f"part frame from datums: {args.trials} random parts per row, offsets <= 3 mm and "
        f"0.2 deg, tracker noise {NOISE_TRACKER_MM} mm per axis, 40 holes on a 1000 x 600 mm "
        "skin; errors in mm; the last columns: one ball moved by that many mm"
    )
    for r in rows:
        print("  ".join(cell.rjust(w) for cell, w in zip(r, widths, strict=True)))
    print(f"({time.perf_counter() - start:.1f} s)")


if __name__ == "__main__":
    main()
