"""Error-field simulation: where the true robot goes when its controller uses the nominal model.

For commanded TCP positions at a fixed orientation: nominal IK (the controller), then FK of the
"true" robot (nominal DH plus parameter errors) gives the reached position. Optional Gaussian noise
models the robot's repeatability and the laser tracker. Positions (N, 3) mm, robot frame.
"""

from __future__ import annotations

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix
from accugrid.kinematics.model import RobotModel

__all__ = [
    "FIG3_ABC",
    "FIG3_X",
    "FIG3_Y",
    "FIG3_Z",
    "commanded_joints",
    "commanded_poses",
    "fig3_field",
    "grid_status",
    "reached_positions",
    "simulate_measurements",
    "simulate_pose_measurements",
]

# The plane of seed Fig. 3 / Table 2: X, Y ranges and Z (mm), the TCP orientation (KUKA deg)
FIG3_X = (1000.0, 2000.0)
FIG3_Y = (-500.0, 500.0)
FIG3_Z = 1800.0
FIG3_ABC = (0.0, 90.0, 0.0)


def commanded_poses(points: np.ndarray, abc_deg: np.ndarray) -> np.ndarray:
    """TCP poses (N, 4, 4) at positions (N, 3) mm with one KUKA orientation abc_deg (3,)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    poses = np.tile(np.eye(4), (len(points), 1, 1))
    poses[:, :3, :3] = abc_to_matrix(np.asarray(abc_deg, dtype=float).reshape(3))
    poses[:, :3, 3] = points
    return poses


def grid_status(robot: RobotModel, points: np.ndarray, abc_deg: np.ndarray) -> int | None:
    """The one KUKA Status a measurement run keeps: the IK default's Status at the first point.

    A real KUKA LIN program keeps one Status for every point; letting the default configuration
    choose per point would flip the wrist between neighbouring points (A5 sign, A4 by 180 deg)
    and put jumps of the true robot's error into the field. InputError if the first point fails.
    None for robots without KUKA Status (URDF robots: numeric IK from one start for every point).
    """
    sol = robot.ik(commanded_poses(np.asarray(points, dtype=float).reshape(-1, 3)[:1], abc_deg))
    if not sol.ok[0]:
        _unreachable(robot, points, abc_deg, sol)
    return int(sol.status[0]) if sol.status[0] >= 0 else None


def commanded_joints(
    robot: RobotModel, points: np.ndarray, abc_deg: np.ndarray, status: int | None = None
) -> np.ndarray:
    """Nominal-model joints (N, 6) rad for the commanded positions in one KUKA Status (default:
    ``grid_status``); InputError if any point fails."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros((0, 6))
    if status is None:
        status = grid_status(robot, points, abc_deg)  # still None for a URDF robot
    sol = robot.ik(commanded_poses(points, abc_deg), status=status)
    if not sol.ok.all():
        _unreachable(robot, points, abc_deg, sol)
    return sol.q


def _unreachable(robot: RobotModel, points: np.ndarray, abc_deg: np.ndarray, sol) -> None:
    bad = np.flatnonzero(~sol.ok)
    first = bad[0]
    x, y, z = np.asarray(points, dtype=float).reshape(-1, 3)[first]
    raise InputError(
        f"{len(bad)} of {len(sol.ok)} points cannot be reached by {robot.name} at "
        f"A B C = {' '.join(f'{v:g}' for v in np.ravel(abc_deg))} deg; first: "
        f"X {x:g} Y {y:g} Z {z:g} ({sol.reason[first]})"
    )


def reached_positions(
    robot: RobotModel, points: np.ndarray, abc_deg: np.ndarray, status: int | None = None
) -> np.ndarray:
    """Positions (N, 3) mm the true robot's TCP reaches when commanded to points (N, 3) at abc_deg.

    The controller solves every point in one KUKA ``status`` (default: ``grid_status``, the IK
    default's Status at the first point). Without parameter errors (no true robot) the reached
    positions equal the commanded ones up to round-off. Raises InputError if a point is
    unreachable in that Status or needs a joint outside its limits.
    """
    q = commanded_joints(robot, points, abc_deg, status)
    true = robot.true_robot() or robot
    return true.fk(q)[:, :3, 3]


def simulate_measurements(
    robot: RobotModel,
    points: np.ndarray,
    abc_deg: np.ndarray,
    repeats: int = 1,
    noise_tracker_mm: float = 0.0,
    noise_repeat_mm: float = 0.0,
    seed: int = 0,
    status: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A simulated laser-tracker session: (commanded (N*repeats, 3), measured (N*repeats, 3)) mm.

    Repeats are consecutive rows. Each row gets Gaussian repeatability noise (the robot lands a
    little elsewhere each visit, sigma ``noise_repeat_mm`` per axis) and tracker noise (sigma
    ``noise_tracker_mm`` per axis), drawn in that order from ``numpy.random.default_rng(seed)``.
    ``status``: as ``reached_positions`` (one KUKA Status for all points).
    """
    _check_session(repeats, noise_tracker_mm, noise_repeat_mm)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    reached = reached_positions(robot, points, abc_deg, status)
    commanded = np.repeat(points, repeats, axis=0)
    return commanded, _measured(reached, repeats, noise_tracker_mm, noise_repeat_mm, seed)


def _check_session(repeats: int, noise_tracker_mm: float, noise_repeat_mm: float) -> None:
    if repeats < 1:
        raise InputError(f"repeats must be at least 1, got {repeats}")
    if noise_tracker_mm < 0 or noise_repeat_mm < 0:
        raise InputError("noise must not be negative")


def _measured(
    reached: np.ndarray, repeats: int, noise_tracker_mm: float, noise_repeat_mm: float, seed: int
) -> np.ndarray:
    """Reached positions (N, 3) mm, each repeated ``repeats`` times in consecutive rows, plus
    repeatability then tracker noise from ``numpy.random.default_rng(seed)``."""
    measured = np.repeat(reached, repeats, axis=0)
    rng = np.random.default_rng(seed)
    measured = measured + rng.normal(0.0, noise_repeat_mm, measured.shape)
    return measured + rng.normal(0.0, noise_tracker_mm, measured.shape)


def simulate_pose_measurements(
    robot: RobotModel,
    poses: np.ndarray,
    status: int | np.ndarray | None = None,
    repeats: int = 1,
    noise_tracker_mm: float = 0.0,
    noise_repeat_mm: float = 0.0,
    seed: int = 0,
    smr_mm: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A simulated tracker session at TCP poses (N, 4, 4) mm of any orientation (identification
    poses): the controller's joints (N, 6) rad (nominal IK in ``status``: one int, (N,) ints or
    None for the IK default per pose) and the measured positions (N * repeats, 3) mm, noise as
    ``simulate_measurements``; ``smr_mm`` (N, 3): where the SMR really sits on the true arm's
    flange at each pose (a tool measured off its taught TCP; None: at the robot's TCP).
    InputError naming the first pose (0-based) the IK cannot reach."""
    _check_session(repeats, noise_tracker_mm, noise_repeat_mm)
    poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
    sol = robot.ik(poses, status=status)
    bad = np.flatnonzero(~sol.ok)
    if bad.size:
        raise InputError(
            f"{bad.size} of {len(poses)} poses cannot be reached by {robot.name}"
            + ("" if status is None else " in their Status")
            + f"; first: pose {bad[0]} ({sol.reason[bad[0]]})"
        )
    true = robot.true_robot() or robot
    reached = true.fk(sol.q)[:, :3, 3]
    if smr_mm is not None:
        flange = (robot.with_tool(np.eye(4)).true_robot() or robot.with_tool(np.eye(4))).fk(sol.q)
        reached = np.einsum("nij,nj->ni", flange[:, :3, :3], smr_mm) + flange[:, :3, 3]
    return sol.q, _measured(reached, repeats, noise_tracker_mm, noise_repeat_mm, seed)


def fig3_field(
    robot: RobotModel, samples: int = 51, status: int | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The seed Fig. 3 plane: X (s,), Y (s,) mm and the error e = P - M (s, s, 3) mm, in one
    KUKA Status (default: the IK default's at the plane's first point, X 1000 Y -500)."""
    xs = np.linspace(*FIG3_X, samples)
    ys = np.linspace(*FIG3_Y, samples)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    points = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, FIG3_Z)])
    error = points - reached_positions(robot, points, FIG3_ABC, status)
    return xs, ys, error.reshape(samples, samples, 3)
