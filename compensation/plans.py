"""Sampling plans: what the tracker operator measures, in which order (seed Sec. 4.2-4.3, 5).

- Grid plan: the vertices of a regular grid over a region, visited in serpentine (boustrophedon)
  order. Every move of that order goes to a neighbouring vertex, so its length is
  (N - 1) * step, the shortest possible for N vertices spaced one step apart.
- Experiment plan (seed Sec. 4.2 / 5): for every centre and every step, the cube's 8 vertices
  C1..C8 and its 9 test points P1..P9 (compensation.cube_points), measured ``repeats`` times.

A plan is a list of commanded positions (robot frame, mm) at one fixed orientation (KUKA ABC deg)
with an id per row and, for experiments, the centre name, step, label and repeat of each row.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from accugrid.compensation.cube_points import (
    TEST_LABELS,
    VERTEX_LABELS,
    cube_test_points,
    cube_vertices,
)
from accugrid.kinematics.errors import InputError

__all__ = [
    "CUBE_LABELS",
    "CUBE_ORDER",
    "MAX_GRID_VERTICES",
    "MEAS_COLUMNS",
    "PLAN_COLUMNS",
    "SEED_ABC",
    "SEED_CENTRES",
    "SEED_REGION",
    "SEED_REPEATS",
    "SEED_STEPS",
    "Plan",
    "check_vertex_count",
    "cube_plan",
    "experiment_plan",
    "grid_axes",
    "grid_plan",
    "path_length",
    "serpentine_order",
]

#: Seed Table 3: the five cube centres D-H (robot frame, mm); orientation ABC 0 90 0 for all.
SEED_CENTRES: dict[str, tuple[float, float, float]] = {
    "D": (1700.0, 0.0, 1500.0),
    "E": (2000.0, -350.0, 1800.0),
    "F": (1400.0, 350.0, 1900.0),
    "G": (1400.0, -350.0, 1400.0),
    "H": (2000.0, 350.0, 1400.0),
}
SEED_ABC = (0.0, 90.0, 0.0)
#: Seed Sec. 5: cube steps from 20 mm to 500 mm every 60 mm (9 steps).
SEED_STEPS = tuple(float(s) for s in range(20, 501, 60))
SEED_REPEATS = 5
#: Seed Sec. 5 region (1000 x 1200 x 1000 mm), placed here so that centres D-H lie inside:
#: X 1200..2200, Y -600..600, Z 1100..2100 (mm). The seed does not give its placement.
SEED_REGION = ((1200.0, -600.0, 1100.0), (2200.0, 600.0, 2100.0))

PLAN_COLUMNS = ("id", "x", "y", "z", "a", "b", "c")
MEAS_COLUMNS = ("x_meas", "y_meas", "z_meas")


@dataclass
class Plan:
    """Commanded positions in measuring order: points (N, 3) mm, abc (3,) deg, ids (N,) and
    optional extra columns (name -> N strings) written between c and x_meas."""

    points: np.ndarray
    abc: np.ndarray
    ids: list[str]
    extra: dict[str, list[str]] = field(default_factory=dict)

    def path_length(self) -> float:
        """Straight-line travel between consecutive positions, mm."""
        return path_length(self.points)

    def csv_text(self) -> str:
        """The plan as CSV: id,x,y,z,a,b,c, extra columns, then empty x_meas,y_meas,z_meas for
        the operator to fill in. Numbers with 4 decimals (DESIGN.md measurement format)."""
        header = list(PLAN_COLUMNS) + list(self.extra) + list(MEAS_COLUMNS)
        abc = ",".join(f"{v:.4f}" for v in self.abc)
        xyz = [f"{x:.4f},{y:.4f},{z:.4f}" for x, y, z in self.points]
        lines = [",".join(header)]
        for i, ident in enumerate(self.ids):
            extra = "".join("," + col[i] for col in self.extra.values())
            lines.append(f"{ident},{xyz[i]},{abc}{extra},,,")
        return "\n".join(lines) + "\n"


def path_length(points: np.ndarray) -> float:
    """Sum of the distances between consecutive rows of points (N, 3) mm, in mm."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


MAX_GRID_VERTICES = 10**6
"""Most vertices a grid may have (a 20 mm step over the seed's region has 158,000)."""


def check_vertex_count(counts, step_mm: float) -> None:
    """InputError when a grid of ``counts`` (3,) vertices per axis (floats: checked before any
    array is made) exceeds ``MAX_GRID_VERTICES``."""
    total = float(np.prod(np.asarray(counts, dtype=float)))
    if not total <= MAX_GRID_VERTICES:
        raise InputError(
            f"grid step {step_mm:g} mm would make {total:.3g} vertices, more than "
            f"{MAX_GRID_VERTICES:,}: use a larger step"
        )


def grid_axes(lo, hi, step_mm: float) -> list[np.ndarray]:
    """Vertex coordinates per axis of a regular grid spanning the box lo..hi (mm) exactly.

    Each side is cut into ceil(side / step_mm) equal cells, so the step of an axis is step_mm when
    it divides the side and a little smaller otherwise (the seed's "convenience of the region
    partition"); the grid never leaves the box.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))) or np.any(hi <= lo):
        raise InputError(f"region must have min < max on every axis (got {lo} .. {hi})")
    if not np.isfinite(step_mm) or step_mm <= 0:
        raise InputError(f"grid step must be > 0 mm, got {step_mm:g}")
    cells = np.maximum(np.ceil((hi - lo) / step_mm - 1e-9), 1)
    check_vertex_count(cells + 1, step_mm)
    cells = cells.astype(int)
    return [np.linspace(lo[k], hi[k], cells[k] + 1) for k in range(3)]


def serpentine_order(counts) -> np.ndarray:
    """Visiting order of the vertices of an (nx, ny, nz) grid as flat indices into the
    ``indexing="ij"`` raveled grid: layers along z, rows along y reversing every layer, x
    reversing every row, so that each move goes to a neighbouring vertex."""
    nx, ny, nz = (int(n) for n in counts)
    k = np.repeat(np.arange(nz), nx * ny)
    j_in = np.tile(np.repeat(np.arange(ny), nx), nz)
    i_in = np.tile(np.arange(nx), ny * nz)
    j = np.where(k % 2 == 1, ny - 1 - j_in, j_in)
    row = k * ny + j_in  # running row number along the path
    i = np.where(row % 2 == 1, nx - 1 - i_in, i_in)
    return (i * ny + j) * nz + k


def grid_plan(lo, hi, step_mm: float, abc, order: str = "serpentine") -> Plan:
    """Vertices of the grid over lo..hi at step_mm (see grid_axes) as a Plan, in serpentine or
    naive (x-major raster, ``indexing="ij"`` ravel) order. Ids are ``G<i>_<j>_<k>``."""
    axes = grid_axes(lo, hi, step_mm)
    counts = [len(a) for a in axes]
    mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    idx = np.stack(np.meshgrid(*[np.arange(n) for n in counts], indexing="ij"), axis=-1)
    idx = idx.reshape(-1, 3)
    if order == "serpentine":
        perm = serpentine_order(counts)
    elif order == "naive":
        perm = np.arange(len(mesh))
    else:
        raise InputError(f"unknown order '{order}' (use serpentine or naive)")
    ids = [f"G{i}_{j}_{k}" for i, j, k in idx[perm]]
    return Plan(mesh[perm], _abc(abc), ids)


def _abc(abc) -> np.ndarray:
    abc = np.asarray(abc, dtype=float).reshape(-1)
    if abc.shape != (3,) or not np.all(np.isfinite(abc)):
        raise InputError("orientation must be three finite angles A B C in degrees")
    return abc


def _cube_order() -> np.ndarray:
    """A short visiting order of the 17 points of a cube (C1..C8 then P1..P9 as indices 0..16):
    nearest-neighbour tour from C1 on the unit cube; the same for every cube (shapes scale)."""
    pts = np.concatenate(
        [cube_vertices(np.zeros((1, 3)), 1.0)[0], cube_test_points(np.zeros((1, 3)), 1.0)[0]]
    )
    order, left = [0], set(range(1, len(pts)))
    while left:
        cand = np.array(sorted(left))
        dist = np.linalg.norm(pts[cand] - pts[order[-1]], axis=1)
        nxt = int(cand[np.argmin(dist)])
        order.append(nxt)
        left.remove(nxt)
    return np.array(order)


CUBE_LABELS = VERTEX_LABELS + TEST_LABELS
CUBE_ORDER = _cube_order()


def _mm_text(value: float) -> str:
    """A length for ids and the step column: 4 decimals without trailing zeros ("200", "12.5")."""
    return f"{value:.4f}".rstrip("0").rstrip(".")


def _name(name: str) -> str:
    text = str(name).strip()
    if not text or any(ch in text for ch in ',"\r\n#'):
        raise InputError(f"centre name {name!r} must be non-empty without commas, quotes or '#'")
    return text


def experiment_plan(
    centres: dict[str, tuple[float, float, float]], steps, repeats: int, abc
) -> Plan:
    """The seed's experiment: for each centre (name -> (x, y, z) mm), each step (mm) and each
    repeat, the 8 vertices and 9 test points of the cube in a short order.

    Rows are grouped centre by centre, step by step; within a cube the whole 17-point round is
    repeated ``repeats`` times (so the repeats capture the robot's repeatability, as in
    ISO 9283 cycling). Extra columns: centre, step, label (C1..C8, P1..P9), repeat (1-based).
    """
    if not centres:
        raise InputError("an experiment needs at least one centre")
    names = [_name(n) for n in centres]
    if len(set(names)) != len(names):
        raise InputError("centre names must be unique")
    steps = np.asarray(steps, dtype=float).reshape(-1)
    if len(steps) == 0:
        raise InputError("an experiment needs at least one step")
    if len(np.unique(steps)) != len(steps):
        raise InputError("experiment steps must be distinct")
    if int(repeats) != repeats or repeats < 1:
        raise InputError(f"repeats must be a whole number >= 1, got {repeats}")
    repeats = int(repeats)
    xyz = np.asarray([centres[n] for n in centres], dtype=float).reshape(-1, 3)
    n_c, n_s = len(names), len(steps)
    cen = np.repeat(xyz, n_s, axis=0)
    stp = np.tile(steps, n_c)
    pts = np.concatenate([cube_vertices(cen, stp), cube_test_points(cen, stp)], axis=1)
    pts = pts[:, CUBE_ORDER, :]  # (C*S, 17, 3)
    pts = np.repeat(pts[:, None, :, :], repeats, axis=1).reshape(-1, 3)
    per_cube = repeats * len(CUBE_ORDER)
    labels = np.array(CUBE_LABELS)[CUBE_ORDER]
    col_centre = [n for n in names for _ in range(n_s * per_cube)]
    col_step = [_mm_text(s) for s in stp for _ in range(per_cube)]
    col_label = [str(lab) for _ in range(n_c * n_s * repeats) for lab in labels]
    col_rep = [str(r + 1) for _ in range(n_c * n_s) for r in range(repeats) for _ in labels]
    ids = [
        f"{c}_S{s}_R{r}_{lab}"
        for c, s, r, lab in zip(col_centre, col_step, col_rep, col_label, strict=True)
    ]
    extra = {"centre": col_centre, "step": col_step, "label": col_label, "repeat": col_rep}
    return Plan(pts, _abc(abc), ids, extra)


def cube_plan(centre, step_mm: float, repeats: int, abc, name: str = "CUBE") -> Plan:
    """One cube's 8 vertices and 9 test points (an experiment with one centre and one step)."""
    return experiment_plan({name: tuple(np.asarray(centre, dtype=float))}, [step_mm], repeats, abc)
