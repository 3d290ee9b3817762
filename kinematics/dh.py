"""Standard Denavit-Hartenberg chains exactly as seed Eq. 2, batched over N joint vectors.

A_i = Rot(Z, theta_i) · Trans(0, 0, d_i) · Trans(a_i, 0, 0) · Rot(X, alpha_i), and the flange pose
is A_1 · A_2 · ... · A_6 (seed Eq. 1). The controller's axis angles (KUKA A1..A6, ABB axes 1..6)
map to DH angles through a per-joint sign and offset: theta_i = sign_i * A_i + theta_offset_i.
Lengths in mm, angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

__all__ = [
    "PARAMETERS",
    "DHArm",
    "DHTable",
    "chain",
    "flange_poses",
    "link_derivatives",
    "link_matrices",
]

# Order of the four parameters of one link, used by the error vector and the error Jacobian.
PARAMETERS = ("a", "d", "alpha", "theta")


@dataclass(frozen=True)
class DHTable:
    """One row per joint: a, d (mm), alpha, theta_offset (rad), sign (+1 or -1); arrays (n,)."""

    a: np.ndarray
    d: np.ndarray
    alpha: np.ndarray
    theta_offset: np.ndarray
    sign: np.ndarray

    @property
    def n(self) -> int:
        return len(self.a)

    def theta(self, q: np.ndarray) -> np.ndarray:
        """KUKA joint angles (N, n) rad -> DH angles theta (N, n) rad."""
        return np.asarray(q, dtype=float) * self.sign + self.theta_offset

    def axis_angles(self, theta: np.ndarray) -> np.ndarray:
        """DH angles theta (..., n) rad -> KUKA joint angles (..., n) rad (not wrapped)."""
        return (np.asarray(theta, dtype=float) - self.theta_offset) * self.sign

    def with_errors(self, errors: np.ndarray) -> DHTable:
        """The table with parameter errors (n, 4) [Δa mm, Δd mm, Δα rad, Δθ rad] added per row."""
        errors = np.asarray(errors, dtype=float).reshape(self.n, 4)
        return replace(
            self,
            a=self.a + errors[:, 0],
            d=self.d + errors[:, 1],
            alpha=self.alpha + errors[:, 2],
            theta_offset=self.theta_offset + errors[:, 3],
        )


class DHArm(Protocol):
    """What the configuration and the numerical IK read of a DH arm (``kinematics.robot.Robot``):
    its DH table and ``phi_rad``, the A3 angle (rad) at which the A2 axis, the A3 axis and the
    wrist point are in line (the arm stretched)."""

    dh: DHTable

    @property
    def phi_rad(self) -> float: ...


def link_matrices(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """Seed Eq. 2 for one row over N angles: theta (N,) rad -> A_i (N, 4, 4)."""
    out = np.zeros((len(theta), 4, 4))
    out[:, 3, 3] = 1.0
    return _fill_link(out, theta, d, a, alpha)


def _fill_link(out: np.ndarray, theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """Write seed Eq. 2 into ``out`` (N, 4, 4), whose entries (2, 0) and row 3 are already
    0, 0, 0, 0, 1; returns ``out``."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out[:, 0, 0] = ct
    out[:, 0, 1] = -st * ca
    out[:, 0, 2] = st * sa
    out[:, 0, 3] = a * ct
    out[:, 1, 0] = st
    out[:, 1, 1] = ct * ca
    out[:, 1, 2] = -ct * sa
    out[:, 1, 3] = a * st
    out[:, 2, 1] = sa
    out[:, 2, 2] = ca
    out[:, 2, 3] = d
    return out


def chain(table: DHTable, q: np.ndarray, links: int | None = None) -> list[np.ndarray]:
    """Cumulative link poses base_T_i for i = 1..links (default n) over N joint vectors q (N, n):
    list of (N, 4, 4)."""
    theta = table.theta(np.atleast_2d(q))
    frames = []
    pose = None
    for i in range(table.n if links is None else links):
        link = link_matrices(theta[:, i], table.d[i], table.a[i], table.alpha[i])
        pose = link if pose is None else pose @ link
        frames.append(pose)
    return frames


def flange_poses(table: DHTable, q: np.ndarray) -> np.ndarray:
    """Flange poses base_T_flange (N, 4, 4) mm for joint vectors q (N, n) rad.

    Like ``chain(table, q)[-1]`` without keeping the n - 1 intermediate (N, 4, 4) frames: three
    (N, 4, 4) buffers in all, the link matrices written in place and the products alternating
    between two (the same numbers as ``chain``)."""
    theta = table.theta(np.atleast_2d(q))
    pose = link_matrices(theta[:, 0], table.d[0], table.a[0], table.alpha[0])
    link, spare = np.zeros_like(pose), np.empty_like(pose)
    link[:, 3, 3] = 1.0
    for i in range(1, table.n):
        _fill_link(link, theta[:, i], table.d[i], table.a[i], table.alpha[i])
        np.matmul(pose, link, out=spare)
        pose, spare = spare, pose
    return pose


def link_derivatives(theta: np.ndarray, d: float, a: float, alpha: float) -> np.ndarray:
    """∂A_i/∂(a, d, alpha, theta) over N angles: (N, 4, 4, 4), parameter index first after N."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    n = len(theta)
    out = np.zeros((n, 4, 4, 4))
    # a: only the translation x/y terms depend on a.
    out[:, 0, 0, 3] = ct
    out[:, 0, 1, 3] = st
    # d: only the z translation.
    out[:, 1, 2, 3] = 1.0
    # alpha
    out[:, 2, 0, 1] = st * sa
    out[:, 2, 0, 2] = st * ca
    out[:, 2, 1, 1] = -ct * sa
    out[:, 2, 1, 2] = -ct * ca
    out[:, 2, 2, 1] = ca
    out[:, 2, 2, 2] = -sa
    # theta
    out[:, 3, 0, 0] = -st
    out[:, 3, 0, 1] = -ct * ca
    out[:, 3, 0, 2] = ct * sa
    out[:, 3, 0, 3] = -a * st
    out[:, 3, 1, 0] = ct
    out[:, 3, 1, 1] = -st * ca
    out[:, 3, 1, 2] = st * sa
    out[:, 3, 1, 3] = a * ct
    return out
