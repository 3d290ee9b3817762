"""Which correction, from how many measured points (issue 13 item 7): grid only (IDW, trilinear),
model only and model + residual grid, held out on a simulated robot.

The cell: a robot whose controller is its nominal model and whose arm is its ``true_robot()``
(e.g. kr210-realistic: seed Table 1 DH errors, compliance under gravity, reducer harmonics). Every
measurement is a simulated tracker session (``kinematics.simulation``: nominal IK in one KUKA
Status, the true FK, seeded repeatability and tracker noise). For each budget N (measured points):

- grid only: the regular grid over the region with at most N vertices and near-equal steps, at
  the grid orientation, P' = P + e(P) (IDW, seed Eq. 12-14; trilinear);
- model only: the N poses ``accugrid plan identify --design dh`` chooses
  (``identification_plan``: D-optimal among random candidates in the region tilted up to
  ``tilt_deg`` from the grid orientation);
  ``identify`` (DH errors, TCP, A2/A3 compliance when the robot has a gravity model);
  ``model_correct`` of each target at its own orientation, the controller keeping its tool;
- model + residual grid: that model plus a 27-vertex (3 x 3 x 3) residual grid measured at the
  grid orientation (``residual_grid``), trilinear;
- model + harmonics (with ``harmonics``, budgets that can identify it): the same with the reducer
  harmonics of the given (axis, order) terms identified too, from N poses chosen for that model;
  and that model + the residual grid;
- model + joint residual: that model plus its residual at the N poses (measured − model, mean of
  the repeats) interpolated in joint space (A1-A3, deg; thin-plate spline, smoothing
  ``JOINT_SMOOTHING``) at each target's joints: no extra points. Non-geometric errors (reducer
  harmonics) follow the joints, not the position (Appl. Sci. 14(24) 11682, 2024); k-fold
  cross-validation over the poses (``joint_residual_cv``) says whether it predicts.

Held out: targets inside the region (``margin_mm`` in) at the grid orientation and tilted up to
``target_tilt_deg``. The score is where the arm lands when commanded P' (noise-free: the
correction's own error): max |P - M| and std per axis, mm. Positions mm, angles deg.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.compensation.grid import GridModel
from accugrid.compensation.model_correction import model_correct, residual_grid
from accugrid.compensation.plans import identification_plan
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, matrix_to_abc, pose_from_xyzabc
from accugrid.kinematics.identification import identify, pose_set
from accugrid.kinematics.robot import Robot
from accugrid.kinematics.simulation import (
    commanded_poses,
    simulate_measurements,
    simulate_pose_measurements,
)

__all__ = [
    "METHODS",
    "RESIDUAL_COUNTS",
    "TARGET_SETS",
    "Comparison",
    "ComparisonRow",
    "compare_methods",
    "grid_counts",
    "joint_residual",
    "joint_residual_cv",
    "lattice",
    "tilted_abc",
]

METHODS = (
    "uncorrected",
    "grid idw",
    "grid trilinear",
    "model",
    "model + residual grid",
    "model + joint residual",
    "model + harmonics",
    "model + harmonics + residual grid",
)
JOINT_AXES = 3  # the joint residual is interpolated over A1..A3
JOINT_SMOOTHING = 1.0  # thin-plate spline smoothing (scipy RBFInterpolator), deg-scaled data
TARGET_SETS = ("grid orientation", "tilted")
RESIDUAL_COUNTS = (3, 3, 3)  # vertices per axis of the residual grid (27)
_SLACK_MM = 5.0  # a target is kept when the nominal IK also solves it this far off on each axis


@dataclass(frozen=True)
class ComparisonRow:
    """One method on one target set at one budget: points measured (distinct poses/vertices),
    max |P - M| (3,) and std (3,) per axis, mm."""

    budget: int
    targets: str
    method: str
    points: int
    max_mm: np.ndarray
    std_mm: np.ndarray


@dataclass(frozen=True)
class Comparison:
    """All rows, plus what was simulated (for the report)."""

    rows: list[ComparisonRow]
    joint_cv: dict  # budget -> (RMS (3,) without, RMS (3,) with the joint residual), mm
    robot: str
    status: int | None
    repeats: int
    n_targets: int
    skipped: tuple[str, ...] = ()  # "budget N: method: why" for rows a budget cannot have
    settings: str = ""  # what was simulated, one line (region, orientation, noise, seed, tilts)

    def row(self, budget: int, targets: str, method: str) -> ComparisonRow:
        """The row of that budget, target set and method."""
        for r in self.rows:
            if (r.budget, r.targets, r.method) == (budget, targets, method):
                return r
        raise KeyError((budget, targets, method))


def grid_counts(lo: np.ndarray, hi: np.ndarray, budget: int) -> np.ndarray:
    """Vertices per axis (3,) int >= 2 of the grid over lo..hi (mm) with at most ``budget``
    vertices and the smallest near-equal step (each axis's step = its span / (count - 1))."""
    span = np.asarray(hi, dtype=float) - np.asarray(lo, dtype=float)
    if budget < 8:
        raise InputError(f"a grid needs at least 8 vertices, budget {budget}")
    best = np.full(3, 2)
    for step in np.linspace(span.max(), span.max() / 60.0, 600):
        counts = np.maximum(2, np.round(span / step).astype(int) + 1)
        if np.prod(counts) <= budget and np.prod(counts) > np.prod(best):
            best = counts
    return best


def lattice(lo: np.ndarray, hi: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Vertices (n, 3) mm of the regular grid over lo..hi with ``counts`` (3,) per axis."""
    axes = [np.linspace(lo[a], hi[a], counts[a]) for a in range(3)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)


def tilted_abc(rng: np.random.Generator, n: int, abc_deg, tilt_deg: float) -> np.ndarray:
    """KUKA A, B, C (n, 3) deg: ``abc_deg`` turned about a random axis of the tool frame by an
    angle uniform in 0..tilt_deg."""
    from scipy.spatial.transform import Rotation

    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = np.radians(rng.uniform(0.0, tilt_deg, n))
    turn = Rotation.from_rotvec(axis * angle[:, None]).as_matrix()
    return matrix_to_abc(abc_to_matrix(np.asarray(abc_deg, dtype=float)) @ turn)


def _poses(points: np.ndarray, abc: np.ndarray) -> np.ndarray:
    """TCP poses (N, 4, 4) at positions (N, 3) mm and KUKA A, B, C (N, 3) deg."""
    return pose_from_xyzabc(np.column_stack([points, np.broadcast_to(abc, np.shape(points))]))


class _Cell:
    """The controller (``robot``, nominal model) and its arm (``robot.true_robot()``)."""

    def __init__(self, robot: Robot, status: int | None) -> None:
        self.robot, self.status = robot, status
        self.arm = robot.true_robot() or robot

    def solve(self, points: np.ndarray, abc: np.ndarray):
        return self.robot.ik(_poses(points, abc), status=self.status)

    def land(self, commands: np.ndarray, abc: np.ndarray) -> np.ndarray:
        """Where the arm's TCP goes (N, 3) mm for commands (N, 3) at abc (N, 3), noise-free."""
        sol = self.solve(commands, abc)
        if not sol.ok.all():
            raise InputError(
                f"a corrected command left Status {self.status} or the joint limits "
                f"({sol.reason[~sol.ok][0]}); give the region more margin"
            )
        return self.arm.fk(sol.q)[:, :3, 3]

    def reachable(self, points: np.ndarray, abc: np.ndarray) -> np.ndarray:
        """(N,) bool: solvable at the point and _SLACK_MM off it on every axis."""
        ok = np.ones(len(points), bool)
        for shift in (0.0, _SLACK_MM, -_SLACK_MM):
            ok &= self.solve(points + shift, abc).ok
        return ok


def joint_residual(q: np.ndarray, residual: np.ndarray):
    """r(q): the residual (n, 3) mm at joints q (n, 6) rad interpolated over A1..A3 (deg) by a
    smoothed thin-plate spline; call it with joints (m, 6) rad, get (m, 3) mm."""
    from scipy.interpolate import RBFInterpolator

    spline = RBFInterpolator(
        np.degrees(q[:, :JOINT_AXES]),
        residual,
        kernel="thin_plate_spline",
        smoothing=JOINT_SMOOTHING,
    )
    return lambda joints: spline(np.degrees(np.asarray(joints)[:, :JOINT_AXES]))


def joint_residual_cv(
    q: np.ndarray, residual: np.ndarray, folds: int = 5, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """k-fold over the poses: RMS per axis (3,) mm of the held-out residual without the joint
    residual and after subtracting its prediction from the other folds."""
    fold = np.random.default_rng(seed).permutation(len(q)) % folds
    left = np.empty_like(residual)
    for k in range(folds):
        held = fold == k
        left[held] = residual[held] - joint_residual(q[~held], residual[~held])(q[held])
    return np.sqrt(np.mean(residual**2, axis=0)), np.sqrt(np.mean(left**2, axis=0))


def _targets(cell, rng, lo, hi, abc, tilt_deg, n) -> tuple[np.ndarray, np.ndarray]:
    points, orient = np.zeros((0, 3)), np.zeros((0, 3))
    for _ in range(50):
        p = rng.uniform(lo, hi, (2 * n, 3))
        a = tilted_abc(rng, 2 * n, abc, tilt_deg) if tilt_deg > 0 else np.tile(abc, (2 * n, 1))
        ok = cell.reachable(p, a)
        points, orient = np.vstack([points, p[ok]]), np.vstack([orient, a[ok]])
        if len(points) >= n:
            return points[:n], orient[:n]
    raise InputError(f"fewer than {n} reachable targets in the region in Status {cell.status}")


def _score(budget, targets, method, points, residual) -> ComparisonRow:
    return ComparisonRow(
        budget, targets, method, points, np.abs(residual).max(axis=0), residual.std(axis=0)
    )


def compare_methods(
    robot: Robot,
    lo,
    hi,
    budgets: list[int],
    abc_deg=(0.0, 90.0, 0.0),
    status: int | None = None,
    tilt_deg: float = 25.0,
    target_tilt_deg: float = 25.0,
    n_targets: int = 200,
    candidates: int = 1500,
    repeats: int = 3,
    noise_tracker_mm: float = 0.02,
    noise_repeat_mm: float = 0.03,
    margin_mm: float = 50.0,
    seed: int = 0,
    progress=None,
    harmonics: tuple[tuple[int, int], ...] = (),
) -> Comparison:
    """Run the comparison (module docstring) for each budget in ``budgets`` over the box lo..hi
    (3,) mm; ``status`` None: the IK default's at the box centre. ``progress``: called with a
    text before each step (or None); ``harmonics``: (axis, order) reducer terms of the
    "model + harmonics" rows (none: no such rows). InputError for budgets that cannot identify
    the model."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    abc = np.asarray(abc_deg, dtype=float).reshape(3)
    if not np.all(hi - lo > 2 * margin_mm):
        raise InputError("the region must be larger than twice the margin on every axis")
    if status is None:
        first = robot.ik(commanded_poses((lo + hi) / 2, abc))
        if not first.ok[0]:
            raise InputError(f"the region centre is not reachable at A B C {abc} deg")
        status = int(first.status[0]) if first.status[0] >= 0 else None
    cell = _Cell(robot, status)
    rng = np.random.default_rng(seed)
    compliance = robot.joint_errors is not None and bool(robot.joint_errors.masses)
    noise = dict(noise_tracker_mm=noise_tracker_mm, noise_repeat_mm=noise_repeat_mm)
    say = progress or (lambda _text: None)
    tool = robot.flange_T_tool  # the controller's TOOL_DATA; the model identifies the real TCP

    inner = (lo + margin_mm, hi - margin_mm)
    target_sets = {
        "grid orientation": _targets(cell, rng, *inner, abc, 0.0, n_targets),
        "tilted": _targets(cell, rng, *inner, abc, target_tilt_deg, n_targets),
    }
    rows: list[ComparisonRow] = []
    joint_cv: dict = {}
    skipped: list[str] = []
    target_q = {}
    options = dict(tilt_deg=tilt_deg, candidates=candidates, repeats=repeats, noise=noise)
    for name, (points, orient) in target_sets.items():
        rows.append(_score(0, name, "uncorrected", 0, points - cell.land(points, orient)))
        target_q[name] = cell.solve(points, orient).q  # the controller's joints at the target

    residual_vertices = lattice(lo, hi, np.array(RESIDUAL_COUNTS))
    trilinear = CorrectionSettings(method="trilinear", outside="clamp", max_correction_mm=None)

    for budget in budgets:
        step_seed = seed + 1000 * budget  # the same draws whatever the other budgets
        say(f"budget {budget}: grid")
        counts = grid_counts(lo, hi, budget)
        vertices = lattice(lo, hi, counts)
        grid = GridModel.from_measurements(
            simulate_measurements(
                robot, vertices, abc, repeats, seed=step_seed, status=status, **noise
            )
        )
        say(f"budget {budget}: model from {budget} poses")
        data, fit = _calibrate(cell, lo, hi, budget, abc, step_seed, compliance, (), options)
        calibrated = fit.robot
        pose_residual = np.zeros((data.poses, 3))
        np.add.at(pose_residual, data.group, fit.residuals / repeats)
        pose_q = data.q[np.unique(data.group, return_index=True)[1]]
        joint_cv[budget] = joint_residual_cv(pose_q, pose_residual, seed=seed)
        joint_layer = joint_residual(pose_q, pose_residual)
        models = {"model": calibrated}
        if harmonics:
            say(f"budget {budget}: model + harmonics from {budget} poses")
            try:
                models["model + harmonics"] = _calibrate(
                    cell, lo, hi, budget, abc, step_seed, compliance, harmonics, options
                )[1].robot
            except InputError as error:  # too few poses for the extra parameters
                skipped.append(f"budget {budget}: model + harmonics: {error.message}")
        residual_session = simulate_measurements(
            robot, residual_vertices, abc, repeats, seed=step_seed + 2, status=status, **noise
        )
        residuals = {  # each model's residual grid from the one 27-vertex session
            name: residual_grid(model, residual_session, status, abc_deg=abc, controller_tool=tool)
            for name, model in models.items()
        }
        for name, (points, orient) in target_sets.items():
            for method in ("idw", "trilinear"):
                command = grid.correct(points, trilinear.but(method=method))
                rows.append(
                    _score(
                        budget,
                        name,
                        f"grid {method}",
                        len(vertices),
                        points - cell.land(command, orient),
                    )
                )
            # the arm lands at the model's position + r(q): aim the model at P - r(q)
            aim = points - joint_layer(target_q[name])
            runs = [
                ("model", "model", points, False),
                ("model + residual grid", "model", points, True),
                ("model + joint residual", "model", aim, False),
            ]
            if "model + harmonics" in models:
                runs += [
                    ("model + harmonics", "model + harmonics", points, False),
                    ("model + harmonics + residual grid", "model + harmonics", points, True),
                ]
            for method, model, goal, with_grid in runs:
                layer = residuals[model] if with_grid else None
                extra = len(residual_vertices) if with_grid else 0
                result = model_correct(
                    models[model], goal, orient, status, layer, trilinear, controller_tool=tool
                )
                if not result.ok.all():
                    raise InputError(f"model correction failed: {result.reason[result.failed[0]]}")
                landed = cell.land(result.command, orient)
                rows.append(_score(budget, name, method, budget + extra, points - landed))
    region = " ".join(f"{v:g}" for pair in zip(lo, hi, strict=True) for v in pair)
    settings = (
        f"{robot.name}: region {region} mm, "
        f"grid orientation A B C {' '.join(f'{v:g}' for v in abc)}, KUKA Status {status}, "
        f"{repeats} repeats, noise tracker {noise_tracker_mm:g} repeat {noise_repeat_mm:g} mm, "
        f"seed {seed}; model poses tilted up to {tilt_deg:g} deg; {n_targets} held-out targets "
        f"per set (tilted: up to {target_tilt_deg:g} deg); where the arm lands, noise-free, mm"
    )
    return Comparison(
        rows, joint_cv, robot.name, status, repeats, n_targets, tuple(skipped), settings
    )


def _calibrate(cell, lo, hi, budget, abc, seed, compliance, harmonics, options):
    """The ``budget`` poses ``plan identify`` chooses for this model, a simulated tracker session
    there and the identification: (PoseSet, Identification)."""
    robot, status, repeats = cell.robot, cell.status, options["repeats"]
    plan, _, _ = identification_plan(
        robot,
        lo,
        hi,
        budget,
        options["tilt_deg"],
        abc,
        status,
        candidates=options["candidates"],
        seed=seed,
        compliance=compliance,
        harmonics=harmonics,
        design="dh",  # the model is given: D-optimal for it
    )
    poses_p, poses_abc = plan.points, plan.abc_rows()
    _, measured = simulate_pose_measurements(
        robot, _poses(poses_p, poses_abc), status, repeats, seed=seed + 1, **options["noise"]
    )
    commanded = np.repeat(poses_p, repeats, axis=0)
    rows_abc = np.repeat(poses_abc, repeats, axis=0)
    data = pose_set(robot, commanded, measured, abc_deg=rows_abc, status=status)
    return data, identify(robot, data, compliance=compliance, harmonics=harmonics)
