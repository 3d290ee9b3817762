"""Frame maths: homogeneous transforms and KUKA ABC angles.

Conventions (DESIGN.md): lengths in mm, angles in degrees at the boundary. KUKA ABC is
R = Rz(A)·Ry(B)·Rx(C) (intrinsic Z-Y'-X''). ``a_T_b`` is the pose of frame b in frame a.
Every function accepts a single item or a stack: (3,) or (N, 3) angles, (4, 4) or (N, 4, 4) poses.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def abc_to_matrix(abc_deg: np.ndarray) -> np.ndarray:
    """KUKA A, B, C in degrees, (3,) or (N, 3) -> rotation matrices (3, 3) or (N, 3, 3)."""
    return Rotation.from_euler("ZYX", np.asarray(abc_deg, dtype=float), degrees=True).as_matrix()


def matrix_to_abc(rot: np.ndarray) -> np.ndarray:
    """Rotation matrices (3, 3) or (N, 3, 3) -> KUKA A, B, C in degrees, (3,) or (N, 3).

    B is in [-90, 90]; at B = ±90 (gimbal lock) scipy sets C = 0 and puts the rotation into A.
    """
    rot = np.asarray(rot, dtype=float)
    return Rotation.from_matrix(rot).as_euler("ZYX", degrees=True)


def pose_from_xyzabc(xyzabc: np.ndarray) -> np.ndarray:
    """X, Y, Z (mm) and A, B, C (deg), (6,) or (N, 6) -> homogeneous poses (4, 4) or (N, 4, 4)."""
    xyzabc = np.asarray(xyzabc, dtype=float)
    single = xyzabc.ndim == 1
    rows = np.atleast_2d(xyzabc)
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :3] = abc_to_matrix(rows[:, 3:6])
    poses[:, :3, 3] = rows[:, :3]
    return poses[0] if single else poses


def xyzabc_from_pose(pose: np.ndarray) -> np.ndarray:
    """Homogeneous poses (4, 4) or (N, 4, 4) -> X, Y, Z (mm), A, B, C (deg) as (6,) or (N, 6)."""
    pose = np.asarray(pose, dtype=float)
    single = pose.ndim == 2
    stack = pose[None] if single else pose
    out = np.empty((len(stack), 6))
    out[:, :3] = stack[:, :3, 3]
    out[:, 3:] = matrix_to_abc(stack[:, :3, :3])
    return out[0] if single else out


def invert(pose: np.ndarray) -> np.ndarray:
    """Inverse of rigid transforms (4, 4) or (N, 4, 4), without a general matrix inverse."""
    pose = np.asarray(pose, dtype=float)
    rot_t = np.swapaxes(pose[..., :3, :3], -1, -2)
    out = np.zeros_like(pose)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rot_t, pose[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def transform_points(a_T_b: np.ndarray, points_b: np.ndarray) -> np.ndarray:
    """Map points given in frame b, (N, 3) mm, into frame a with one pose a_T_b (4, 4)."""
    a_T_b = np.asarray(a_T_b, dtype=float)
    points_b = np.asarray(points_b, dtype=float)
    return points_b @ a_T_b[:3, :3].T + a_T_b[:3, 3]


def rotate_vectors(a_T_b: np.ndarray, vectors_b: np.ndarray) -> np.ndarray:
    """Rotate direction vectors (N, 3) from frame b into frame a (translation ignored)."""
    return np.asarray(vectors_b, dtype=float) @ np.asarray(a_T_b, dtype=float)[:3, :3].T
