"""Sampling plans: what the tracker operator measures, in which order (seed Sec. 4.2-4.3, 5).

- Grid plan: the vertices of a regular grid over a region, visited in serpentine (boustrophedon)
  order. Every move of that order goes to a neighbouring vertex, so its length is
  (N - 1) * step, the shortest possible for N vertices spaced one step apart.
- Experiment plan (seed Sec. 4.2 / 5): for every centre and every step, the cube's 8 vertices
  C1..C8 and its 9 test points P1..P9 (compensation.cube_points), measured ``repeats`` times.
- Identification plan: the poses of a kinematic identification, chosen from random candidates
  in a region at orientations within a tilt of the drilling orientation, reachable in one Status:
  Bayesian D-optimal for the structure search's candidate library
  (``kinematics.pose_design.library_poses``) or D-optimal for a given model
  (``kinematics.identification.select_poses``).

A plan is a list of commanded positions (robot frame, mm) at one fixed orientation (KUKA ABC deg;
an identification plan has one per row) with an id per row and, for experiments, the centre
name, step, label and repeat of each row.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from accugrid.compensation.cube_points import (
    TEST_LABELS,
    VERTEX_LABELS,
    cube_test_points,
    cube_vertices,
)
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import pose_from_xyzabc

if TYPE_CHECKING:
    from accugrid.kinematics.configuration import Configuration
    from accugrid.kinematics.model import RobotModel

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
    "grid_vertices",
    "path_length",
    "reach_in_one_status",
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
MIN_A5_DEG = 10.0  # identification poses keep |A5| at least this far from the wrist singularity
MEAS_COLUMNS = ("x_meas", "y_meas", "z_meas")


@dataclass
class Plan:
    """Commanded positions in measuring order: points (N, 3) mm, abc (3,) deg (or (N, 3), one
    per row), ids (N,) and optional extra columns (name -> N strings) written between c and
    x_meas."""

    points: np.ndarray
    abc: np.ndarray
    ids: list[str]
    extra: dict[str, list[str]] = field(default_factory=dict)

    def path_length(self) -> float:
        """Straight-line travel between consecutive positions, mm."""
        return path_length(self.points)

    def abc_rows(self) -> np.ndarray:
        """The orientation of every row, (N, 3) KUKA deg."""
        return np.broadcast_to(np.asarray(self.abc, dtype=float), (len(self.points), 3))

    def csv_text(self) -> str:
        """The plan as CSV: id,x,y,z,a,b,c, extra columns, then empty x_meas,y_meas,z_meas for
        the operator to fill in. Numbers with 4 decimals (docs/formats.md measurement format)."""
        header = list(PLAN_COLUMNS) + list(self.extra) + list(MEAS_COLUMNS)
        xyz = [f"{x:.4f},{y:.4f},{z:.4f}" for x, y, z in self.points]
        abc = [f"{a:.4f},{b:.4f},{c:.4f}" for a, b, c in self.abc_rows()]
        lines = [",".join(header)]
        for i, ident in enumerate(self.ids):
            extra = "".join("," + col[i] for col in self.extra.values())
            lines.append(f"{ident},{xyz[i]},{abc[i]}{extra},,,")
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


def grid_vertices(region: list[float], step_mm: float) -> tuple[np.ndarray, list[str]]:
    """Vertices (N, 3) mm of the grid from each ``region`` (xmin, xmax, ymin, ymax, zmin, zmax)
    minimum in ``step_mm`` up to the maximum (x outermost, z innermost; a measurement grid, as
    ``accugrid simulate`` measures it), and notes for axes whose maximum is not on the step."""
    if step_mm is None or not step_mm > 0:
        raise InputError(f"--step must be positive, got {step_mm}")
    check_vertex_count(np.floor(np.ptp(np.reshape(region, (3, 2)), axis=1) / step_mm) + 1, step_mm)
    axes, notes = [], []
    for name, lo, hi in zip("XYZ", region[0::2], region[1::2], strict=True):
        if not lo < hi:
            raise InputError(f"--region: {name} minimum {lo:g} must be below maximum {hi:g}")
        count = int(np.floor((hi - lo) / step_mm + 1e-9)) + 1
        values = lo + step_mm * np.arange(count)
        if hi - values[-1] > 1e-6:
            notes.append(f"{name} stops at {values[-1]:g} (region maximum {hi:g} is off the step)")
        axes.append(values)
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([m.ravel() for m in mesh]), notes


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


def _nearest_neighbour_order(points: np.ndarray) -> np.ndarray:
    """A short visiting order of points (N, 3): from the first, always the nearest unvisited."""
    order, left = [0], np.ones(len(points), dtype=bool)
    left[0] = False
    for _ in range(len(points) - 1):
        distance = np.linalg.norm(points - points[order[-1]], axis=1)
        distance[~left] = np.inf
        order.append(int(np.argmin(distance)))
        left[order[-1]] = False
    return np.array(order)


def _cube_order() -> np.ndarray:
    """A short visiting order of the 17 points of a cube (C1..C8 then P1..P9 as indices 0..16):
    nearest-neighbour tour from C1 on the unit cube; the same for every cube (shapes scale)."""
    pts = np.concatenate(
        [cube_vertices(np.zeros((1, 3)), 1.0)[0], cube_test_points(np.zeros((1, 3)), 1.0)[0]]
    )
    return _nearest_neighbour_order(pts)


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


def identification_plan(
    robot,
    lo,
    hi,
    count: int,
    tilt_deg: float,
    abc,
    status: int,
    candidates: int = 2000,
    repeats: int = 1,
    seed: int = 0,
    min_a5_deg: float = MIN_A5_DEG,
    compliance: bool = False,
    harmonics: tuple[tuple[int, int], ...] = (),
    gravity: tuple = (),
    design: str = "library",
    max_order: int | None = None,
) -> tuple[Plan, float, int]:
    """``count`` poses for ``accugrid identify``: ``candidates`` random positions in the box
    lo..hi (mm) at random orientations within ``tilt_deg`` (rotation angle) of ``abc`` (deg),
    kept where the nominal IK in KUKA ``status`` is within the joint limits and |A5| >=
    ``min_a5_deg`` (away from the wrist singularity), then ``count`` of them, visited in a
    nearest-neighbour order, ``repeats`` rounds. Column ``s`` holds the Status.
    ``design`` "library": Bayesian D-optimal for the structure search's candidate library
    (``kinematics.pose_design``, harmonic orders 1..``max_order``, default the search's K) with
    the ``harmonics`` and, with ``compliance``, the gravity groups pinned; "dh": D-optimal for
    the model given by ``compliance``, ``harmonics``, ``gravity`` (mass-free gravity groups) only
    (``identification.select_poses``). Returns (plan, O1 of the chosen set for DH + TCP and the
    given terms, number of usable candidates)."""
    from scipy.spatial.transform import Rotation

    from accugrid.kinematics.frames import xyzabc_from_pose
    from accugrid.kinematics.identification import pose_o1, select_poses
    from accugrid.kinematics.pose_design import library_poses
    from accugrid.kinematics.structure import DEFAULT_MAX_ORDER

    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if not np.all(lo < hi):
        raise InputError("the region's minimum must be below its maximum on every axis")
    if not 0.0 <= tilt_deg <= 90.0:
        raise InputError(f"--tilt must be 0..90 deg, got {tilt_deg:g}")
    if design not in ("library", "dh"):
        raise InputError(f"the design must be 'library' or 'dh', got {design!r}")
    if repeats < 1 or candidates < count:
        raise InputError(f"need repeats >= 1 and candidates >= count, got {repeats}, {candidates}")
    rng = np.random.default_rng(seed)
    points = lo + rng.random((candidates, 3)) * (hi - lo)
    direction = rng.normal(size=(candidates, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    angle = np.radians(tilt_deg) * np.cbrt(rng.random(candidates))  # uniform in the ball
    tilt = Rotation.from_rotvec(direction * angle[:, None])
    rotation = Rotation.from_euler("ZYX", _abc(abc), degrees=True) * tilt  # about tool axes
    poses = np.tile(np.eye(4), (candidates, 1, 1))
    poses[:, :3, :3], poses[:, :3, 3] = rotation.as_matrix(), points
    sol = robot.ik(poses, status=status)
    usable = np.flatnonzero(sol.ok & (np.abs(sol.q[:, 4]) >= np.radians(min_a5_deg)))
    if len(usable) < count:
        raise InputError(
            f"only {len(usable)} of {candidates} candidate poses are reachable in Status "
            f"{status} with |A5| >= {min_a5_deg:g} deg; need {count}: move or enlarge the "
            "region, change the tilt or lower the count"
        )
    if design == "library":
        order = DEFAULT_MAX_ORDER if max_order is None else max_order
        chosen = library_poses(robot, sol.q[usable], count, order, harmonics, compliance)
        o1 = pose_o1(robot, sol.q[usable][chosen], compliance, harmonics, gravity)
    else:
        chosen, o1 = select_poses(
            robot, sol.q[usable], count, compliance=compliance, harmonics=harmonics, gravity=gravity
        )
    rows = usable[chosen][_nearest_neighbour_order(points[usable[chosen]])]
    xyzabc = xyzabc_from_pose(poses[rows])
    ids = [
        f"I{k + 1}" + (f"_R{r + 1}" if repeats > 1 else "")
        for r in range(repeats)
        for k in range(count)
    ]
    plan = Plan(
        np.tile(xyzabc[:, :3], (repeats, 1)),
        np.tile(xyzabc[:, 3:], (repeats, 1)),
        ids,
        {"s": [str(int(status))] * (count * repeats)},
    )
    return plan, o1, len(usable)


def reach_in_one_status(
    plan: Plan, robot: RobotModel, status: int | None = None
) -> tuple[Configuration, int]:
    """The configuration (N,) of every plan position (``kinematics.configuration``) and the
    configuration code used (``status``, or the IK default's at the first position): linear
    moves keep the configuration of the first joint move, so the whole plan must be reachable
    in it. InputError naming the first position that is not."""
    poses = pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()]))
    from accugrid.kinematics.configuration import (  # IK: only when asked
        Configuration,
        quarters,
        solve_in_one_status,
    )

    sol, status = solve_in_one_status(robot, poses, status)
    if not sol.ok.all():
        bad = np.flatnonzero(~sol.ok)
        i = int(bad[0])
        x, y, z = plan.points[i]
        raise InputError(
            f"{len(bad)} of {len(plan.points)} plan positions cannot be reached by {robot.name}"
            f"{'' if status is None else f' in Status {status}'}; first: {plan.ids[i]} "
            f"X {x:.3f} Y {y:.3f} Z {z:.3f} ({sol.reason[i]})"
        )
    return Configuration.of_code(sol.status, quarters(sol.q)), int(status)
