"""Frame maths: homogeneous transforms and KUKA ABC angles.

Conventions (docs/formats.md): lengths in mm, angles in degrees at the boundary. KUKA ABC is
R = Rz(A)·Ry(B)·Rx(C) (intrinsic Z-Y'-X''). ``a_T_b`` is the pose of frame b in frame a.
Every function accepts a single item or a stack: (3,) or (N, 3) angles, (4, 4) or (N, 4, 4) poses.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "BLAS_ROWS",
    "GIMBAL_LOCK_RAD",
    "MAX_TILT_DEG",
    "abc_to_matrix",
    "axis_angle_deg",
    "invert",
    "matrix_to_abc",
    "orient_along_axes",
    "pose_from_xyzabc",
    "rotate_vectors",
    "rotation_angle_deg",
    "rows_times",
    "stack_times",
    "times_stack",
    "too_tilted",
    "transform_points",
    "xyzabc_from_pose",
]

# |B| within this of 90 deg (rad) is gimbal lock: C is set to 0 and the rotation goes into A
# (scipy's Rotation.as_euler uses the same threshold and rule; it is the tests' peer).
GIMBAL_LOCK_RAD = 1e-7
MAX_TILT_DEG = 150.0  # drill axes further than this from the reference tool axis are refused
# rows per product in ``rows_times``: (rows x 3) @ (3 x 3) products this small run on the
# calling thread (OpenBLAS starts its threads above about 29,000 such rows)
BLAS_ROWS = 16384


def abc_to_matrix(abc_deg: np.ndarray) -> np.ndarray:
    """KUKA A, B, C in degrees, (3,) or (N, 3) -> rotation matrices (3, 3) or (N, 3, 3).

    R = Rz(A)·Ry(B)·Rx(C), written out (numpy only: the CLI's start-up needs no scipy).
    """
    ca, cb, cc = np.moveaxis(np.cos(np.radians(np.asarray(abc_deg, dtype=float))), -1, 0)
    sa, sb, sc = np.moveaxis(np.sin(np.radians(np.asarray(abc_deg, dtype=float))), -1, 0)
    rows = [
        [ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc],
        [sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc],
        [-sb, cb * sc, cb * cc],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def matrix_to_abc(rot: np.ndarray) -> np.ndarray:
    """Rotation matrices (3, 3) or (N, 3, 3) -> KUKA A, B, C in degrees, (3,) or (N, 3).

    A and C are in (-180, 180], B in [-90, 90]; at B = ±90 (gimbal lock, within
    ``GIMBAL_LOCK_RAD``) C is 0 and A carries the rotation about the vertical.
    """
    rot = np.asarray(rot, dtype=float)
    out = np.empty(rot.shape[:-2] + (3,))
    b = np.arctan2(-rot[..., 2, 0], np.hypot(rot[..., 0, 0], rot[..., 1, 0]))
    locked = np.pi / 2 - np.abs(b) <= GIMBAL_LOCK_RAD
    out[..., 0] = np.arctan2(rot[..., 1, 0], rot[..., 0, 0])
    out[..., 2] = np.arctan2(rot[..., 2, 1], rot[..., 2, 2])
    if locked.any():  # rare: the other formula only where it applies
        held = rot[locked]
        out[locked, 0] = np.arctan2(-held[..., 0, 1], held[..., 1, 1])
        out[locked, 2] = 0.0
    out[..., 1] = b
    return np.degrees(out, out=out)


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


def rows_times(rows: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``rows @ matrix`` for rows (N, k) (or one row (k,)) and a small matrix (k, j) or vector
    (k,), in blocks of ``BLAS_ROWS`` rows: the same numbers as one product, all on the calling
    thread. One product of 100,000 rows wakes BLAS's threads, which then spin on the cores for a
    while (on 2 cores: about 0.1 s of a 1e5-hole program's IK threads' time)."""
    rows = np.asarray(rows, dtype=float)
    if rows.ndim < 2 or len(rows) <= BLAS_ROWS:
        return rows @ matrix
    out = np.empty((len(rows),) + np.shape(matrix)[1:])
    for i in range(0, len(rows), BLAS_ROWS):
        out[i : i + BLAS_ROWS] = rows[i : i + BLAS_ROWS] @ matrix
    return out


def stack_times(stack: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``stack @ matrix`` for a stack of matrices (N, k, m) and one matrix (m, j): one product
    of all their rows (``rows_times``), the same numbers as numpy's product matrix by matrix
    (one BLAS call each, ~0.1 us) in a fifth of the time."""
    stack = np.asarray(stack, dtype=float)
    out = rows_times(stack.reshape(-1, stack.shape[-1]), matrix)
    return out.reshape(*stack.shape[:-1], np.shape(matrix)[-1])


def times_stack(matrix: np.ndarray, stack: np.ndarray) -> np.ndarray:
    """``matrix @ stack`` for one matrix (k, m) and a stack of matrices (N, m, j):
    (stack^T @ matrix^T)^T by ``stack_times``, the same numbers as numpy's product."""
    flipped = np.swapaxes(np.asarray(stack, dtype=float), -1, -2)
    return np.swapaxes(stack_times(flipped, np.asarray(matrix).T), -1, -2)


def transform_points(a_T_b: np.ndarray, points_b: np.ndarray) -> np.ndarray:
    """Map points given in frame b, (N, 3) mm, into frame a with one pose a_T_b (4, 4)."""
    a_T_b = np.asarray(a_T_b, dtype=float)
    return rows_times(points_b, a_T_b[:3, :3].T) + a_T_b[:3, 3]


def rotate_vectors(a_T_b: np.ndarray, vectors_b: np.ndarray) -> np.ndarray:
    """Rotate direction vectors (N, 3) from frame b into frame a (translation ignored)."""
    return rows_times(vectors_b, np.asarray(a_T_b, dtype=float)[:3, :3].T)


def rotation_angle_deg(rotations: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Angle (N,) deg (0..180) of the relative rotation between each rotation (N, 3, 3) and one
    reference (3, 3): how far a TCP orientation is from another, e.g. the one a grid was measured
    at."""
    # trace(R_ref^T R) = sum of the element-wise product
    trace = np.einsum("ij,nij->n", reference, rotations)
    return np.degrees(np.arccos(np.clip((trace - 1.0) / 2.0, -1.0, 1.0)))


def axis_angle_deg(axes: np.ndarray, reference_axis: np.ndarray) -> np.ndarray:
    """Angle (N,) deg between unit vectors (N, 3) and one unit vector (3,)."""
    return np.degrees(np.arccos(np.clip(rows_times(axes, reference_axis), -1.0, 1.0)))


def orient_along_axes(axis: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Tool rotations (N, 3, 3) whose Z axis is each drill axis (N, 3, unit), nearest ``reference``.

    The rule: each hole gets the reference orientation (3, 3) tilted by the smallest rotation that
    turns the reference tool Z onto the hole's drill axis (Rodrigues' formula about
    z_ref x axis). Of all rotations about the drill axis this is the one closest to the reference
    (smallest relative rotation angle), it is a smooth function of the axis, so neighbouring holes
    get neighbouring wrist angles, and it keeps the wrist where the reference puts it (the
    orientation the grid was measured at, well inside the joint limits). The rule degenerates at
    180 deg: callers refuse axes that ``too_tilted`` flags, naming the hole.
    """
    axis = np.asarray(axis, dtype=float)
    z_ref = reference[:, 2]
    cos = axis @ z_ref
    v = np.cross(z_ref, axis)
    # R_align = I + [v]x + [v]x^2 / (1 + cos); [v]x^2 = v v^T - |v|^2 I
    vx = np.zeros((len(axis), 3, 3))
    vx[:, 0, 1], vx[:, 0, 2], vx[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    vx[:, 1, 0], vx[:, 2, 0], vx[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = 1.0 / (1.0 + cos)
    align = np.eye(3) + vx + (vx @ vx) * scale[:, None, None]
    return stack_times(align, reference)


def too_tilted(axis: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(N,) bool: drill axes (N, 3) too far from the reference tool Z for ``orient_along_axes``."""
    return rows_times(axis, reference[:, 2]) < np.cos(np.radians(MAX_TILT_DEG))
