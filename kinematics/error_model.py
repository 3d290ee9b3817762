"""The differential DH error model of seed Eq. 3-7, batched over N joint vectors.

Each link's error (Δa, Δd, Δα, Δθ) changes A_i by dA_i (Eq. 3); to first order the TCP pose
changes by dT = Σ_i U_(i-1) · dA_i · V_(i+1) (Eq. 5-6), with U the links before i and V the links
after i and the tool. The 24 columns are link-major: (Δa_1, Δd_1, Δα_1, Δθ_1, Δa_2, ...).
Rows: TCP position error dx, dy, dz (mm) and small rotation δx, δy, δz (rad), both in the robot
frame. Lengths in mm, angles in radians.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.dh import chain, link_derivatives
from accugrid.kinematics.frames import invert
from accugrid.kinematics.robot import Robot

__all__ = ["error_jacobian", "predicted_error"]


def error_jacobian(robot: Robot, q: np.ndarray) -> np.ndarray:
    """∂(TCP position, orientation)/∂(24 DH parameter errors): (N, 6, 24) for q (N, 6) rad."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n, dh = len(q), robot.dh
    frames = chain(dh, q)
    tcp = frames[-1] @ robot.flange_T_tool
    rot_t = np.swapaxes(tcp[:, :3, :3], 1, 2)
    theta = dh.theta(q)
    jac = np.empty((n, 6, 4 * dh.n))
    for i in range(dh.n):
        before = frames[i - 1] if i > 0 else np.broadcast_to(np.eye(4), (n, 4, 4))
        after = invert(frames[i]) @ tcp  # V_(i+1): link i+1 .. n and the tool
        d_link = link_derivatives(theta[:, i], dh.d[i], dh.a[i], dh.alpha[i])
        d_tcp = before[:, None] @ d_link @ after[:, None]  # (N, 4 parameters, 4, 4)
        cols = slice(4 * i, 4 * i + 4)
        jac[:, :3, cols] = np.swapaxes(d_tcp[:, :, :3, 3], 1, 2)
        skew = d_tcp[:, :, :3, :3] @ rot_t[:, None]  # dR · R^T, skew-symmetric to first order
        omega = np.stack([skew[:, :, 2, 1], skew[:, :, 0, 2], skew[:, :, 1, 0]], axis=1)
        jac[:, 3:, cols] = omega
    return jac


def predicted_error(robot: Robot, q: np.ndarray, errors: np.ndarray) -> np.ndarray:
    """First-order TCP deviation (true − nominal) (N, 6) for parameter errors (6, 4) at q (N, 6).

    Columns dx, dy, dz mm and δx, δy, δz rad in the robot frame; ``errors`` rows are links, columns
    Δa mm, Δd mm, Δα rad, Δθ rad (seed Table 1 layout).
    """
    return error_jacobian(robot, q) @ np.asarray(errors, dtype=float).reshape(-1)
