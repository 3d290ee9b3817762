"""The grid model on 1,000,000 points: predict and correct on a 6 x 7 x 6 grid (the demo grid's
shape, step 200 mm), against scipy's RegularGridInterpolator(method="linear") on the same grid
and points in the same run (the peer: trilinear interpolation of the same vertex errors).
Target: ratio <= 1.0 and well under 1 s.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.interpolate import RegularGridInterpolator

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from accugrid.compensation import GridModel  # noqa: E402
from bench.timing import measure, table  # noqa: E402

N = 1_000_000
REPEATS = 7  # best of 7: the machine is shared


def main_bench() -> None:
    rng = np.random.default_rng(0)
    model = GridModel(
        origin=[1200.0, -600.0, 1100.0],
        step=[200.0, 200.0, 200.0],
        errors=rng.normal(1.0, 0.8, size=(6, 7, 6, 3)),
    )
    points = rng.uniform(model.origin, model.upper, size=(N, 3))
    axes = [model.origin[a] + model.step[a] * np.arange(model.counts[a]) for a in range(3)]
    scipy_linear = RegularGridInterpolator(axes, model.errors, method="linear")
    agree = np.abs(scipy_linear(points[:10_000]) - model.predict(points[:10_000], "trilinear"))
    print(f"trilinear vs scipy linear, largest difference on 10,000 points: {agree.max():.2e} mm")

    peer, peer_mem = measure(lambda: scipy_linear(points), repeats=REPEATS)
    cases = [
        ("scipy RegularGridInterpolator linear", None),
        ("predict idw (power 1, seed Eq. 12-13)", lambda: model.predict(points)),
        ("predict idw power 2", lambda: model.predict(points, power=2.0)),
        ("predict trilinear", lambda: model.predict(points, method="trilinear")),
        ("correct idw, 1 iteration (Eq. 14)", lambda: model.correct(points)),
        ("correct idw, 3 iterations", lambda: model.correct(points, iterations=3)),
    ]
    rows = []
    for name, func in cases:
        seconds, mem = (peer, peer_mem) if func is None else measure(func, repeats=REPEATS)
        rows.append((name, f"{seconds:.3f}", f"{mem:.0f}", f"{seconds / peer:.2f}"))
    print(f"{N:,} points, grid 6x7x6, best of {REPEATS}")
    print(table(rows, ("operation", "time s", "peak MiB", "ratio to scipy")))


if __name__ == "__main__":
    main_bench()
