"""The seed's grid method on a real grid: Series A of the UR10 laser-tracker data.

Series A (``../shared/realdata/ipa-ur10/Series_A``, read as it comes, ``bench.real_ur10``) is a
grid of TCP positions, x 650..1000 step 50, y -600..600 step 100,
z 400..900 step 100 mm, each at up to 22 tool orientations. The tracker frame is the rigid fit of
the commanded to the measured positions of the grid's own orientation (the orientation with the
most grid positions): the best a grid user can have without a model. The error is e = P - M.

Table 1, the real counterpart of the seed's Table 4: the grid at that orientation subsampled at
100, 200 and 300 mm steps (``GridModel``, IDW power 1, the seed's), the error predicted at every
measured grid position in between (not a vertex of the subsampled grid) and the remaining error
e - e_pred per axis: max, min, standard deviation, and the 3D mean and max. Row "none": the error
itself (no correction). As the seed's ``--measured`` study: one session, r = e - e_pred, the
correction's effect to first order.

Table 2: the 100 mm grid at A's other orientations (the grid's own rows left out), grouped by
their angle from the grid's, against the calibrated model: ``identify`` (the default structure,
tracker frame identified) from 300 random poses of Series C (another session), its tracker frame
for Series A fitted with the model on the grid orientation's rows (the measurements the grid
has). Remaining 3D error, mean and p95 mm: without correction, with the grid, with the model,
and with the model where it has support and its DH-only fit where not (``kinematics.support``),
and the share of positions without support.

Not a timed test: ``make bench ARGS=real`` (or ``.venv/bin/python bench/bench_real_grid.py``);
``--poses N`` changes the Series C poses of the model (default 300).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from accugrid.compensation.grid import GridModel  # noqa: E402
from accugrid.compensation.interpolation import CORNERS  # noqa: E402
from accugrid.kinematics.frames import rotation_angle_deg  # noqa: E402
from accugrid.kinematics.identification import rigid_fit  # noqa: E402
from bench.real_ur10 import REAL, Series, calibrate, random_pick, read_series  # noqa: E402

GRID = (np.arange(650, 1001, 50), np.arange(-600, 601, 100), np.arange(400, 901, 100))  # mm
STEPS = (100, 200, 300)  # mm
ANGLE_BINS = (0.0, 1.0, 20.0, 40.0, 60.0, 180.0)  # deg from the grid's orientation


def grid_rows(a: Series) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row: its grid index (N, 3) (-1 rows off the grid), its orientation id (N,) and the id
    of the orientation with the most grid positions."""
    index = np.stack([np.searchsorted(g, np.round(a.p[:, k])) for k, g in enumerate(GRID)], 1)
    index = np.minimum(index, [len(g) - 1 for g in GRID])
    snapped = np.stack([GRID[k][index[:, k]] for k in range(3)], 1)
    index[np.abs(snapped - a.p).max(axis=1) > 1.0] = -1
    _, orient = np.unique(np.round(a.rot.reshape(-1, 9), 3), axis=0, return_inverse=True)
    orient = orient.reshape(-1)
    on = (index >= 0).all(axis=1)
    counts = [len(np.unique(index[on & (orient == o)], axis=0)) for o in range(orient.max() + 1)]
    return index, orient, int(np.argmax(counts))


def vertex_errors(index: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean error (nx, ny, nz, 3) mm per grid position of rows ``index`` (N, 3) (repeats
    averaged) and whether each position was measured (nx, ny, nz)."""
    shape = tuple(len(g) for g in GRID)
    total, count = np.zeros((*shape, 3)), np.zeros(shape)
    np.add.at(total, tuple(index.T), e)
    np.add.at(count, tuple(index.T), 1.0)
    with np.errstate(invalid="ignore"):
        return total / count[..., None], count > 0


def subgrid(measured: np.ndarray, step: int) -> tuple[tuple[slice, ...] | None, int]:
    """The complete box of the grid subsampled at ``step`` mm with the most vertices: its index
    slices into the full grid and its vertex count (None, 0: none complete)."""
    strides = [step // int(g[1] - g[0]) for g in GRID]
    ranges = [
        [
            slice(lo, lo + (count - 1) * s + 1, s)
            for lo in range(n)
            for count in range(2, n)
            if lo + (count - 1) * s < n
        ]
        for n, s in zip(measured.shape, strides, strict=True)
    ]
    best, size = None, 0
    for cut in itertools.product(*ranges):
        sub = measured[cut]
        if sub.size > size and sub.all():
            best, size = cut, sub.size
    return best, size


def configuration(q: np.ndarray) -> np.ndarray:
    """The arm's configuration (N,) int of joints q (N, 6) rad: elbow (sin A3 > 0) and wrist
    (sin A5 > 0) as bits 0 and 1."""
    return (np.sin(q[:, 2]) > 0) * 1 + (np.sin(q[:, 4]) > 0) * 2


def stats_row(label: str, r: np.ndarray) -> str:
    """A Table 4 row: max, min, std per axis and 3D mean, max of residuals r (N, 3) mm."""
    d = np.linalg.norm(r, axis=1)
    cells = [*r.max(axis=0), *r.min(axis=0), *r.std(axis=0), d.mean(), d.max()]
    return f"| {label} | {len(r)} | " + " | ".join(f"{v:.3f}" for v in cells) + " |"


def table4(a: Series, index: np.ndarray, orient: np.ndarray, o_grid: int, e: np.ndarray) -> dict:
    """Table 1 (printed); returns the subsampled grid models by step."""
    rows = (orient == o_grid) & (index >= 0).all(axis=1)
    errors, measured = vertex_errors(index[rows], e[rows])
    config = np.full(measured.shape, -1)
    config[tuple(index[rows].T)] = configuration(a.q[rows])
    kinds = np.unique(config[measured], return_counts=True)
    print(
        f"Series A, grid orientation: {measured.sum()} of {measured.size} grid positions; "
        "their arm configurations (elbow, wrist bits): "
        + ", ".join(f"{k}: {c}" for k, c in zip(*kinds, strict=True))
        + "\n"
    )
    print(
        "| step mm | positions | max X | max Y | max Z | min X | min Y | min Z | std X | std Y "
        "| std Z | mean 3D | max 3D |"
    )
    print("|---|" + "---|" * 12)
    full = np.stack(np.meshgrid(*GRID, indexing="ij"), axis=-1)
    print(stats_row("none", errors[measured]))
    models = {}
    for step in STEPS:
        cut, size = subgrid(measured, step)
        if cut is None:
            print(f"| {step} | no complete grid |")
            continue
        vertices = full[cut]
        grid = GridModel(vertices[0, 0, 0], np.full(3, float(step)), errors[cut])
        between = measured.copy()
        between[cut] = False
        inside = (full >= grid.origin - 1e-6).all(axis=-1) & (full <= grid.upper + 1e-6).all(
            axis=-1
        )
        targets = np.argwhere(between & inside)
        points = full[tuple(targets.T)]
        r = errors[tuple(targets.T)] - grid.predict(points, "idw", 1.0)
        cell = np.clip(np.floor((points - grid.origin) / step), 0, grid.counts - 2).astype(int)
        corners = config[cut][tuple((cell[:, None, :] + CORNERS[None]).transpose(2, 0, 1))]
        same = (corners == config[tuple(targets.T)][:, None]).all(axis=1)
        print(stats_row(f"{step}, {size} vertices", r))
        print(stats_row(f"{step}, one configuration", r[same]))
        models[step] = grid
    return models


def orientations_table(a, index, orient, o_grid, e, grid: GridModel, poses: int) -> None:
    """Table 2 (printed)."""
    t0 = time.perf_counter()
    c = read_series("C")
    fit = calibrate(c, random_pick(len(c), poses))
    result, selection, support = fit.default, fit.selection, fit.support
    took, groups = time.perf_counter() - t0, len(selection.chosen)
    own = orient == o_grid
    arm, fallback = result.robot.true_robot(), support.fallback.true_robot()
    model_p, dh_p = arm.fk(a.q)[:, :3, 3], fallback.fk(a.q)[:, :3, 3]

    def residual(predicted: np.ndarray) -> np.ndarray:
        frame = rigid_fit(predicted[own], a.m[own])  # Series A's tracker frame by the model
        measured = (a.m - frame[:3, 3]) @ frame[:3, :3]
        return np.linalg.norm(measured - predicted, axis=1)

    model_r, dh_r = residual(model_p), residual(dh_p)
    flagged = support.ratio(a.q) > 1.0
    guarded = np.where(flagged, dh_r, model_r)
    inside = (a.p >= grid.origin - 1e-6).all(axis=1) & (a.p <= grid.upper + 1e-6).all(axis=1)
    grid_r = np.full(len(e), np.nan)
    grid_r[inside] = np.linalg.norm(e[inside] - grid.predict(a.p[inside], "idw", 1.0), axis=1)
    angle = rotation_angle_deg(a.rot, a.rot[np.flatnonzero(own)[0]])
    print(
        f"\nmodel: identify from {poses} random Series C poses ({groups} joint-error groups "
        f"chosen, {took:.0f} s); the 100 mm grid at A's other orientations (positions inside "
        "its box); remaining 3D error, mean / p95 mm\n"
    )
    print(
        "| angle from the grid's | rows | none | grid 100 mm | model | model, DH-only fit "
        "where no support | no support |"
    )
    print("|---|---|---|---|---|---|---|")
    for lo, hi in zip(ANGLE_BINS[:-1], ANGLE_BINS[1:], strict=True):
        rows = inside & ~own & (angle >= lo) & (angle < hi)
        if not rows.any():
            continue
        cells = [np.linalg.norm(e[rows], axis=1), grid_r[rows], model_r[rows], guarded[rows]]
        text = " | ".join(f"{c.mean():.3f} / {np.quantile(c, 0.95):.3f}" for c in cells)
        print(f"| {lo:g}-{hi:g} deg | {rows.sum()} | {text} | {flagged[rows].mean():.0%} |")


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=300)
    args, _ = parser.parse_known_args(argv)
    if not REAL.is_dir():
        print(f"{REAL} is missing: the real data sit beside the checkout (../shared/realdata)")
        return
    a = read_series("A")
    index, orient, o_grid = grid_rows(a)
    on = (index >= 0).all(axis=1)
    frame = rigid_fit(a.p[on & (orient == o_grid)], a.m[on & (orient == o_grid)])
    e = a.p - (a.m - frame[:3, 3]) @ frame[:3, :3]  # e = P - M, robot frame
    models = table4(a, index, orient, o_grid, e)
    if "--grid-only" in argv:
        return
    orientations_table(a.rows(on), index[on], orient[on], o_grid, e[on], models[100], args.poses)


if __name__ == "__main__":
    main(sys.argv[1:])
