"""Numerical inverse kinematics of any 6R DH arm, batched: damped Newton from seeds.

For arms the closed form (``kinematics.ik``) does not serve, above all those without a spherical
wrist (a UR's axes 4, 5, 6 do not meet). A pose is solved in a wanted configuration
(``Configuration``: shoulder, elbow, wrist as the code shoulder + 2 elbow + 4 wrist) from up to
``SEEDS`` start joint vectors aimed at it (axis 1 turned so the arm plane passes the wrist point
on the shoulder's side, the elbow bent 90 deg the elbow's way, axis 5 at 90 deg of the wrist's
sign; axes 2 and 4 turned by 0, +-90 or 180 deg from seed to seed): the first seed for every
pose, then the others together for the poses it left, all poses at once. A start converges when
its flange misses the pose by less than ``TOL_MM`` and ``TOL_RAD``, and counts when the
solution is in the wanted configuration. Measured on the UR10: every one of 12,000 random joint
vectors 0.1 rad (sin) from the stretched elbow and the wrist flip and 50 mm from the shoulder
singularity found again in its configuration; nearer the singularities a few are missed.
Lengths in mm, angles in radians.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics import ik as closed
from accugrid.kinematics.configuration import HOME_RAD, Configuration
from accugrid.kinematics.dh import DHArm, DHTable, chain

__all__ = ["MAX_ITERATIONS", "SEEDS", "TOL_MM", "TOL_RAD", "select", "solve", "solve_in"]

MAX_ITERATIONS = 30
TOL_MM = 1e-9  # flange position error of a converged solution
TOL_RAD = 1e-12  # flange rotation error of a converged solution
SEEDS = 16
_LENGTH_MM = 1000.0  # weight of the rotation error (mm per rad) in the Newton step
_DAMPING = 1.0  # mm^2: Levenberg-Marquardt damping (J^T J holds ~1e6 mm^2 per rad^2)
_MAX_STEP_RAD = 0.5  # largest joint step per iteration
# a start still this far off after this many iterations is given up (those that converge are
# within microns by then: Newton's quadratic convergence)
_STALLED_AFTER, _STALLED_MM = 12, 1.0


def solve(dh: DHTable, flange: np.ndarray, seeds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint vectors q (M, 6) rad whose flange poses (DH table ``dh``) are ``flange`` (M, 4, 4)
    mm, by damped Newton from ``seeds`` (M, 6) rad, and whether each converged (M,) bool (rows
    that did not: the last iterate)."""
    q = np.array(seeds, dtype=float)
    flange = np.asarray(flange, dtype=float)
    converged = np.zeros(len(q), bool)
    active = np.arange(len(q))
    for iteration in range(MAX_ITERATIONS):
        frames = chain(dh, q[active])
        error = _pose_error(flange[active], frames[-1])  # (m, 6) mm, rad
        miss_mm = np.linalg.norm(error[:, :3], axis=1)
        done = (miss_mm < TOL_MM) & (np.linalg.norm(error[:, 3:], axis=1) < TOL_RAD)
        converged[active[done]] = True
        keep = ~done & ((iteration < _STALLED_AFTER) | (miss_mm < _STALLED_MM))
        active, frames, error = active[keep], [f[keep] for f in frames], error[keep]
        if not active.size:
            break
        jac = _jacobian(dh, frames)  # (m, 6, 6)
        jac[:, 3:] *= _LENGTH_MM
        error[:, 3:] *= _LENGTH_MM
        jt = np.swapaxes(jac, 1, 2)
        normal = jt @ jac + _DAMPING * np.eye(6)
        step = np.linalg.solve(normal, (jt @ error[:, :, None]))[:, :, 0]
        largest = np.abs(step).max(axis=1, keepdims=True)
        q[active] += step * np.minimum(1.0, _MAX_STEP_RAD / np.maximum(largest, 1e-300))
    return q, converged


def _pose_error(target: np.ndarray, reached: np.ndarray) -> np.ndarray:
    """(M, 6): position error (mm) and rotation vector (rad) that take ``reached`` to ``target``
    (both (M, 4, 4) mm), in the robot frame."""
    out = np.empty((len(target), 6))
    out[:, :3] = target[:, :3, 3] - reached[:, :3, 3]
    turn = target[:, :3, :3] @ np.swapaxes(reached[:, :3, :3], 1, 2)  # target_R_reached
    skew = np.stack(
        [
            turn[:, 2, 1] - turn[:, 1, 2],
            turn[:, 0, 2] - turn[:, 2, 0],
            turn[:, 1, 0] - turn[:, 0, 1],
        ],
        axis=1,
    )
    sin_angle = 0.5 * np.linalg.norm(skew, axis=1)
    cos_angle = 0.5 * (np.trace(turn, axis1=1, axis2=2) - 1.0)
    angle = np.arctan2(sin_angle, cos_angle)
    scale = np.where(sin_angle > 1e-300, angle / np.maximum(2 * sin_angle, 1e-300), 0.5)
    out[:, 3:] = skew * scale[:, None]
    return out


def _jacobian(dh: DHTable, frames: list[np.ndarray]) -> np.ndarray:
    """Geometric Jacobian (M, 6, 6) of the flange in the robot frame: rows x, y, z (mm per rad)
    and rotation x, y, z (rad per rad), columns the joint angles q (dtheta/dq = sign), from the
    link frames base_T_i (``dh.chain``)."""
    m = len(frames[0])
    origins = [np.zeros((m, 3))] + [f[:, :3, 3] for f in frames[:-1]]
    axes = [np.broadcast_to([0.0, 0.0, 1.0], (m, 3))] + [f[:, :3, 2] for f in frames[:-1]]
    tip = frames[-1][:, :3, 3]
    jac = np.empty((m, 6, 6))
    for i in range(6):
        (ax, ay, az), (rx, ry, rz) = axes[i].T, (tip - origins[i]).T  # axis x lever
        jac[:, 0, i], jac[:, 1, i], jac[:, 2, i] = (
            ay * rz - az * ry,
            az * rx - ax * rz,
            ax * ry - ay * rx,
        )
        jac[:, 3:, i] = axes[i]
        if dh.sign[i] < 0:
            jac[:, :, i] *= -1.0
    return jac


# seed k: axis 2 at the reference's angle plus _ARM_TURNS[k % 4], axis 4 plus _WRIST_TURNS[k // 4]
_ARM_TURNS = np.array([0.0, np.pi / 2, -np.pi / 2, np.pi])
_WRIST_TURNS = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2])


def _seed(robot: DHArm, wrist: np.ndarray, code: np.ndarray, reference: np.ndarray, k: int):
    """Start joint vectors (M, 6) rad number k (0 .. SEEDS - 1) for flange poses whose wrist
    points (frame 5's origin) are ``wrist`` (M, 3) mm, aimed at configuration codes ``code``
    (M,) int, other axes from ``reference`` (M, 6) rad."""
    dh = robot.dh
    toward = np.arctan2(wrist[:, 1], wrist[:, 0])
    radius = np.maximum(np.hypot(wrist[:, 0], wrist[:, 1]), 1e-9)
    lateral = np.sin(dh.alpha[0]) * (dh.d[1] + dh.d[2] + dh.d[3])  # the arm plane's offset on z1
    aside = np.arcsin(np.clip(lateral / radius, -1.0, 1.0))
    theta1 = np.where(code & 1 == 0, toward + aside, toward + np.pi - aside)  # DH
    out = np.array(reference, dtype=float)
    out[:, 0] = (theta1 - dh.theta_offset[0]) * dh.sign[0]
    out[:, 1] += _ARM_TURNS[k % 4]
    out[:, 2] = robot.phi_rad + np.where(code & 2 == 2, np.pi / 2, -np.pi / 2)
    out[:, 3] += _WRIST_TURNS[k // 4]
    out[:, 4] = np.where(code & 4 == 4, -np.pi / 2, np.pi / 2)
    return out


def solve_in(
    robot: DHArm, flange: np.ndarray, code: np.ndarray, reference: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint vectors (N, 6) rad in (-pi, pi] for flange poses (N, 4, 4) mm in configurations
    ``code`` (N,) int (on a wrist singularity, |A5| < ``SINGULAR_A5_RAD``, either wrist bit
    fits), seeded from ``reference`` (N, 6) rad, whether each was found (N,) bool (rows not
    found: NaN) and whether any start reached the pose in whatever configuration (N,) bool
    (the pose is reachable). The first seed for every pose, then the others together for the
    poses it did not solve; of those, the lowest seed number that solves one."""
    n = len(flange)
    wrist = closed.wrist_points(robot.dh, flange)
    q = np.full((n, 6), np.nan)
    found = np.zeros(n, bool)
    reached = np.zeros(n, bool)
    for first, last in ((0, 1), (1, SEEDS)):
        rows = np.flatnonzero(~found)
        if not rows.size:
            break
        seeds = np.arange(first, last)
        rows_k = np.repeat(rows, len(seeds))  # (row, seed) pairs, seed inner
        start = np.empty((len(rows_k), 6))
        for i, k in enumerate(seeds):
            start[i :: len(seeds)] = _seed(robot, wrist[rows], code[rows], reference[rows], k)
        qk, ok = solve(robot.dh, flange[rows_k], start)
        reached[rows_k[ok]] = True
        qk = closed.wrap(qk)
        got = Configuration.of_joints(robot, np.where(ok[:, None], qk, 0.0)).code
        singular = np.abs(qk[:, 4]) < closed.SINGULAR_A5_RAD
        ok &= (got == code[rows_k]) | (singular & ((got & 3) == (code[rows_k] & 3)))
        ok = ok.reshape(len(rows), len(seeds))
        hit = ok.any(axis=1)
        pick = np.argmax(ok, axis=1) + np.arange(len(rows)) * len(seeds)
        q[rows[hit]], found[rows[hit]] = qk[pick[hit]], True
    return q, found, reached


def select(robot: DHArm, flange: np.ndarray, status, reference) -> tuple[np.ndarray, ...]:
    """The solution ``Robot.ik`` picks per flange pose (N, 4, 4) mm, before turns and limits:
    q (N, 6) rad in (-pi, pi] (NaN where none), found (N,), reachable (N,): some start reached
    the pose, whatever its configuration (with ``status``: the starts aimed at it).

    ``status`` (int or (N,) ints): the configuration code (``solve_in``); None: of the
    solutions in all 8 configurations the one nearest (sum of squared wrapped joint
    differences) ``reference`` ((6,) or (N, 6) rad; default ``HOME_RAD``)."""
    n = len(flange)
    ref = np.array(np.broadcast_to(HOME_RAD if reference is None else reference, (n, 6)))
    if status is not None:
        want = np.broadcast_to(np.asarray(status, dtype=int), (n,))
        return solve_in(robot, flange, want, ref)
    cand, got = _every_configuration(robot, flange, ref)  # (N, 8, 6), (N, 8)
    distance = np.where(got, (closed.wrap(cand - ref[:, None]) ** 2).sum(axis=2), np.inf)
    q = cand[np.arange(n), np.argmin(distance, axis=1)]
    found = got.any(axis=1)
    return q, found, found


def _every_configuration(robot: DHArm, flange: np.ndarray, reference: np.ndarray):
    """``solve_in`` of flange poses (N, 4, 4) mm in each of the 8 configurations: joint vectors
    (N, 8, 6) rad (configuration code = index) and found (N, 8) bool."""
    n = len(flange)
    codes = np.tile(np.arange(8), n)
    q, found, _ = solve_in(
        robot, np.repeat(flange, 8, axis=0), codes, np.repeat(reference, 8, axis=0)
    )
    return q.reshape(n, 8, 6), found.reshape(n, 8)
