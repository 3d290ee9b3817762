"""Identification poses for the candidate library: which reachable poses to measure so that
``identify``'s structure search (``kinematics.structure``) can tell its candidate terms apart.

D-optimality for DH + TCP alone (``identification.select_poses``) puts the poses at the corners
of the region and tilt: the joint angles of each axis cluster at a few values, between which
reducer harmonics of neighbouring orders look alike. A D-optimal design over the whole library
(DH + TCP, orders 1..K on every axis, the mass-free gravity groups: ~230 parameters) is not
defined for 60 poses (180 equations). Its **Bayesian** form is: each candidate term gets a prior
of zero mean and an RMS effect on the TCP of ``1 / sqrt(prior)`` times the measurement noise,
the DH errors and TCP (and pinned terms) a flat prior, and the design maximises
det(JᵀJ + diag(prior)) of the column-scaled Jacobian (columns of unit RMS over the candidate
poses, noise 1): the information the poses add to what is known before measuring. It is greedy
(each step adds the pose that multiplies that determinant most, det(I + J_i A⁻¹ J_iᵀ)), with
A⁻¹ kept as diag(1 / prior) − U Uᵀ, U growing by three columns per pose, so one step costs one
product of the candidates' rows with three columns.

``separation`` is the measure the design is judged by (and the plan reports): for each harmonic
candidate, the share of its two columns (smallest relative singular value) left beyond the
DH + TCP columns and the neighbouring orders k ± 1, k ± 2 of its axis: the aliasing the search
meets. Angles in rad, joints (N, 6) in the controller's axis convention.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.candidates import gravity_terms, harmonic_name
from accugrid.kinematics.errors import InputError
from accugrid.kinematics.identification import Terms, planned_columns
from accugrid.kinematics.robot import Robot

__all__ = ["LIBRARY_PRIOR", "NEIGHBOURS", "library_poses", "library_terms", "separation"]

#: (noise / a candidate term's RMS TCP effect)²: terms of ~3 × the noise are the ones the
#: search must tell apart; larger ones stand out anyway, smaller ones it leaves out.
LIBRARY_PRIOR = 1.0 / 9.0
NEIGHBOURS = 2  # separation: beyond the orders k ± 1 .. k ± NEIGHBOURS of the same axis
_FLAT = 1e-6  # prior precision of the DH errors, TCP and pinned terms (noise 1, unit columns)


def library_terms(max_order: int, pinned: Terms = ()) -> Terms:
    """The candidate harmonics (axis 1..6, order 1..``max_order``) not among ``pinned``."""
    pinned = set(pinned)
    return tuple(
        (a, k) for a in range(1, 7) for k in range(1, max_order + 1) if (a, k) not in pinned
    )


def library_poses(
    robot: Robot,
    q: np.ndarray,
    count: int,
    max_order: int,
    pinned: Terms = (),
    compliance: bool = False,
    prior: float = LIBRARY_PRIOR,
) -> np.ndarray:
    """Greedy Bayesian D-optimal choice of ``count`` of the candidate joints q (M, 6) rad for the
    library: DH + TCP, the ``pinned`` harmonics and, with ``compliance``, the gravity groups
    with a flat prior; the other harmonics of orders 1..``max_order`` (and the gravity groups
    without ``compliance``) with precision ``prior``. Returns the chosen rows (count,) in choice
    order. InputError when count is not 1..M or too small for the DH + TCP parameters."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if not 1 <= count <= len(q):
        raise InputError(f"cannot choose {count} poses from {len(q)} candidates")
    gravity = gravity_terms(robot)
    search = tuple(pinned) + library_terms(max_order, pinned)
    base, extra = planned_columns(robot, q, search, gravity)
    if count * 3 < base.shape[1]:
        raise InputError(
            f"{count} poses cannot identify {base.shape[1]} parameters: choose at least "
            f"{-(-base.shape[1] // 3)}"
        )
    harmonic = np.full(2 * len(search), prior)
    harmonic[: 2 * len(pinned)] = _FLAT
    grav = np.full(extra.shape[1] - 2 * len(search), _FLAT if compliance else prior)
    precision = np.concatenate([np.full(base.shape[1], _FLAT), harmonic, grav])
    columns = np.column_stack([base, extra])
    scale = np.sqrt(np.mean(columns**2, axis=0))
    moves = scale > 1e-9 * scale.max()  # e.g. A6 harmonics with the TCP on A6's axis: none
    rows = (columns[:, moves] / scale[moves]).reshape(len(q), 3, -1)  # (M, 3, p)
    inverse0 = 1.0 / precision[moves]  # A⁻¹ = diag(inverse0) − U Uᵀ
    u = np.zeros((rows.shape[2], 0))
    m = (rows * inverse0) @ np.swapaxes(rows, 1, 2)  # (M, 3, 3): J_i A⁻¹ J_iᵀ
    chosen: list[int] = []
    free = np.ones(len(q), dtype=bool)
    for _ in range(count):
        gain = np.linalg.slogdet(np.eye(3) + m)[1]
        gain[~free] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        free[best] = False
        j = rows[best]
        b = inverse0[:, None] * j.T - u @ (u.T @ j.T)  # A⁻¹ Jᵀ (p, 3)
        new = b @ np.linalg.cholesky(np.linalg.inv(np.eye(3) + j @ b))  # Woodbury, rank 3
        u = np.column_stack([u, new])
        moved = (rows.reshape(-1, rows.shape[2]) @ new).reshape(len(q), 3, 3)
        m -= moved @ np.swapaxes(moved, 1, 2)
    return np.array(chosen)


def separation(robot: Robot, q: np.ndarray, max_order: int) -> dict[str, float]:
    """Per harmonic candidate of orders 1..``max_order`` (name -> share 0..1) at joints q (P, 6)
    rad: the smallest singular value of its two columns (each of unit RMS) beyond the span of
    the DH + TCP columns and of the orders k ± 1..``NEIGHBOURS`` of its axis, over the largest of
    the two columns. 0: the poses cannot tell it from those; 1: orthogonal to them. Candidates
    that do not move the TCP at these poses are left out."""
    search = library_terms(max_order)
    base, extra = planned_columns(robot, np.atleast_2d(q), search, ())
    scale = np.sqrt(np.mean(extra**2, axis=0))
    out = {}
    for i, (axis, order) in enumerate(search):
        if scale[2 * i : 2 * i + 2].min() <= 1e-9 * scale.max():
            continue
        near = [
            j for j, (a, k) in enumerate(search) if a == axis and 0 < abs(k - order) <= NEIGHBOURS
        ]
        others = np.column_stack([base] + [extra[:, 2 * j : 2 * j + 2] for j in near])
        left, sing, _ = np.linalg.svd(others, full_matrices=False)
        basis = left[:, sing > 1e-9 * sing[0]]
        own = extra[:, 2 * i : 2 * i + 2] / scale[2 * i : 2 * i + 2]
        rest = own - basis @ (basis.T @ own)
        sing = np.linalg.svd(rest, compute_uv=False)
        out[harmonic_name(axis, order)] = float(sing[-1] / np.linalg.norm(own, 2))
    return out
