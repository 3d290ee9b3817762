"""Identification poses for the candidate library: which reachable poses to measure so that
``identify``'s structure search (``kinematics.structure``) can tell its candidate terms apart.

D-optimality for DH + TCP alone (``identification.select_poses``) puts the poses at the corners
of the region and tilt: each axis's angles cluster at a few values, between which reducer
harmonics of neighbouring orders look alike. A D-optimal design over the whole library (DH +
TCP, orders 1..K on every axis, the mass-free gravity groups: ~230 parameters) is not defined
for 60 poses (180 equations). Its **Bayesian** form is: with the Jacobian's columns scaled to
unit RMS over the candidate poses and the noise as unit, each candidate term gets a prior of
precision ``LIBRARY_PRIOR`` (an RMS effect on the TCP of 3 × the noise), the DH errors, TCP and
pinned terms a flat one, and the design maximises det(JᵀJ + diag(precision)): the information the
poses add to what is known before measuring. Greedy: each step adds the pose that multiplies that
determinant most, det(I + J_i A⁻¹ J_iᵀ), with A⁻¹ kept as diag(1 / precision) − U Uᵀ (U grows by
three columns per pose), so a step costs one product of the candidates' rows with three columns.

``library_share`` is the measure the plan reports and the tests compare designs by (an
A-criterion, which the design does not maximise itself): the mean share of the candidate terms'
prior variance that the poses remove, 0 (they tell nothing) to 1 (each term determined). Joints
(N, 6) rad.
"""

from __future__ import annotations

import numpy as np

from accugrid.infra.errors import InputError
from accugrid.kinematics.candidates import gravity_terms
from accugrid.kinematics.identification import Terms, planned_columns
from accugrid.kinematics.robot import Robot

__all__ = ["LIBRARY_PRIOR", "bayesian_d_greedy", "library_poses", "library_share"]

#: (noise / a candidate term's RMS TCP effect)²: terms of ~3 × the noise are the ones the
#: search must tell apart; larger ones stand out anyway, smaller ones it leaves out.
LIBRARY_PRIOR = 1.0 / 9.0
_FLAT = 1e-6  # prior precision of the DH errors, TCP and pinned terms (noise 1, unit columns)


def _library_rows(
    robot: Robot, q: np.ndarray, max_order: int, pinned: Terms, compliance: bool, prior: float
) -> tuple[np.ndarray, np.ndarray, int]:
    """The library's scaled Jacobian rows (P, 3, p) at joints q (P, 6) rad (columns of unit RMS
    over q; those that do not move the TCP, e.g. A6 harmonics with the TCP on A6's axis, left
    out), each column's prior precision (p,) and the number of DH + TCP columns (first)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    pinned = tuple(pinned)
    free = tuple(
        (a, k) for a in range(1, 7) for k in range(1, max_order + 1) if (a, k) not in pinned
    )
    base, extra = planned_columns(robot, q, pinned + free, gravity_terms(robot))
    harmonic = np.full(2 * len(pinned + free), prior)
    harmonic[: 2 * len(pinned)] = _FLAT
    grav = np.full(extra.shape[1] - len(harmonic), _FLAT if compliance else prior)
    precision = np.concatenate([np.full(base.shape[1], _FLAT), harmonic, grav])
    columns = np.column_stack([base, extra])
    scale = np.sqrt(np.mean(columns**2, axis=0))
    moves = scale > 1e-9 * scale.max()
    rows = (columns[:, moves] / scale[moves]).reshape(len(q), 3, -1)
    return rows, precision[moves], base.shape[1]


def bayesian_d_greedy(rows: np.ndarray, precision: np.ndarray, count: int) -> np.ndarray:
    """Greedy Bayesian D-optimal choice of ``count`` of the candidates' rows (M, k, p) under the
    prior precision (p,) > 0: each step takes the candidate that most increases
    log det(diag(precision) + Σ chosen J_iᵀ J_i) (the first on ties). Returns the chosen
    indices (count,) in choice order."""
    m_rows, k, p = rows.shape
    inverse0 = 1.0 / precision  # A⁻¹ = diag(inverse0) − U Uᵀ
    u = np.zeros((p, 0))
    m = (rows * inverse0) @ np.swapaxes(rows, 1, 2)  # (M, k, k): J_i A⁻¹ J_iᵀ
    flat = rows.reshape(-1, p)
    chosen: list[int] = []
    free = np.ones(m_rows, dtype=bool)
    for _ in range(count):
        gain = np.linalg.slogdet(np.eye(k) + m)[1]
        gain[~free] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        free[best] = False
        j = rows[best]
        b = inverse0[:, None] * j.T - u @ (u.T @ j.T)  # A⁻¹ Jᵀ (p, k)
        new = b @ np.linalg.cholesky(np.linalg.inv(np.eye(k) + j @ b))  # Woodbury, rank k
        u = np.column_stack([u, new])
        moved = (flat @ new).reshape(m_rows, k, k)
        m -= moved @ np.swapaxes(moved, 1, 2)
    return np.array(chosen, dtype=int)


def library_poses(
    robot: Robot,
    q: np.ndarray,
    count: int,
    max_order: int,
    pinned: Terms = (),
    compliance: bool = False,
    prior: float = LIBRARY_PRIOR,
) -> np.ndarray:
    """``count`` of the candidate joints q (M, 6) rad, Bayesian D-optimal for the library: DH +
    TCP, the ``pinned`` harmonics and, with ``compliance``, the gravity groups with a flat prior;
    the other harmonics of orders 1..``max_order`` (and the gravity groups without
    ``compliance``) with precision ``prior``. Returns the chosen rows (count,) in choice order.
    InputError when count is not 1..M or too small for the DH + TCP parameters."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if not 1 <= count <= len(q):
        raise InputError(f"cannot choose {count} poses from {len(q)} candidates")
    rows, precision, base = _library_rows(robot, q, max_order, pinned, compliance, prior)
    if count * 3 < base:
        raise InputError(
            f"{count} poses cannot identify {base} parameters: choose at least {-(-base // 3)}"
        )
    return bayesian_d_greedy(rows, precision, count)


def library_share(
    robot: Robot,
    q: np.ndarray,
    max_order: int,
    pinned: Terms = (),
    compliance: bool = False,
    prior: float = LIBRARY_PRIOR,
) -> float:
    """The mean share (0..1) of the candidate terms' prior variance that poses q (P, 6) rad
    remove: 1 − precision · diag((JᵀJ + diag(precision))⁻¹) averaged over the parameters of
    ``prior`` precision (the library's harmonics and gravity groups less those pinned)."""
    rows, precision, _ = _library_rows(robot, q, max_order, pinned, compliance, prior)
    flat = rows.reshape(-1, rows.shape[2])
    covariance = np.linalg.inv(flat.T @ flat + np.diag(precision))
    searched = precision == prior
    return float(np.mean(1.0 - prior * np.diag(covariance)[searched]))
