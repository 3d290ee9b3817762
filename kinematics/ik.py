"""Closed-form inverse kinematics of a 6R arm with a spherical wrist (KUKA KR, ABB IRB), batched.

Supported DH structure (checked by ``closed_form_supported``): alpha_1, alpha_3, alpha_4, alpha_5 =
±90°, alpha_2 = 0, d_2 = d_3 = 0, a_4 = a_5 = d_5 = 0 (axes 4, 5, 6 meet in the wrist point).
Every reachable flange pose has up to 8 solutions: 2 shoulder (wrist point in front of or behind
the A1 axis) × 2 elbow × 2 wrist (A5 sign). Lengths in mm, angles in radians.
"""

from __future__ import annotations

import numpy as np

from accugrid.kinematics.dh import DHTable

__all__ = [
    "SINGULAR_A5_RAD",
    "all_solutions",
    "arm_elbows",
    "arm_solutions",
    "arm_wrists",
    "chosen_wrists",
    "closed_form_supported",
    "upper_arm",
    "wrap",
    "wrist_angles",
    "wrist_points",
]

_TOL = 1e-9
SINGULAR_A5_RAD = 1e-12  # |A5| below this: on the wrist singularity, either wrist flag fits


def closed_form_supported(table: DHTable) -> bool:
    """True when ``table`` has the spherical-wrist structure the closed form needs."""
    if table.n != 6:
        return False
    right = np.abs(np.abs(np.sin(table.alpha[[0, 2, 3, 4]])) - 1.0) < 1e-12
    zero = np.abs(np.array([table.alpha[1], table.d[1], table.d[2], table.a[3], table.a[4]]))
    return bool(right.all() and (zero < 1e-12).all() and abs(table.d[4]) < 1e-12)


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles (any shape) rad wrapped into (-pi, pi] (a new array)."""
    angle = np.asarray(angle)
    out = np.divide(angle, 2 * np.pi, out=np.empty(angle.shape))  # in place from here on
    np.round(out, out=out)
    out *= 2 * np.pi
    np.subtract(angle, out, out=out)
    np.add(out, 2 * np.pi, out=out, where=out <= -np.pi)
    return out


def wrist_points(table: DHTable, flange: np.ndarray) -> np.ndarray:
    """Wrist point (intersection of axes 4, 5, 6) (N, 3) mm for flange poses (N, 4, 4)."""
    rot = flange[:, :3, :3]
    c, s = np.cos(-table.alpha[5]), np.sin(-table.alpha[5])
    z = rot[:, :, 1] * -s + rot[:, :, 2] * c  # column 2 of R6 = rot · Rot(X, -alpha_6)
    return flange[:, :3, 3] - table.a[5] * rot[:, :, 0] - table.d[5] * z


def _r6(table: DHTable, flange: np.ndarray) -> list[list[np.ndarray]]:
    """R6 = flange rotation · Rot(X, -alpha_6) entry by entry: [k][j] (N,) for row k, column j."""
    rot = flange[:, :3, :3]
    c, s = np.cos(-table.alpha[5]), np.sin(-table.alpha[5])
    return [
        [rot[:, k, 0], rot[:, k, 1] * c + rot[:, k, 2] * s, rot[:, k, 1] * -s + rot[:, k, 2] * c]
        for k in range(3)
    ]


def all_solutions(table: DHTable, flange: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All 8 joint solutions for flange poses (N, 4, 4) mm.

    Returns KUKA joint angles (N, 8, 6) rad wrapped into (-pi, pi] and a (N, 8) mask of candidates
    whose wrist point is reachable (others are NaN). Joint limits are not applied here.
    Candidate order: shoulder (2) x elbow (2) x wrist (2).
    """
    flange = np.asarray(flange, dtype=float).reshape(-1, 4, 4)
    n = len(flange)
    th1, th2, th3, reach = arm_solutions(table, flange)
    r6 = [[entry[:, None, None] for entry in row] for row in _r6(table, flange)]
    wrist = wrist_angles(table, th1[:, :, None], r6, th2 + th3)  # (N, 2, 2) each
    arm = np.stack([np.repeat(th1[:, :, None], 2, axis=2), th2, th3], axis=-1).reshape(n * 4, 3)
    q = _joints(table, arm, *(w.reshape(-1) for w in wrist))
    q = q.reshape(n, 8, 6)
    ok = np.repeat(reach.reshape(n, 4), 2, axis=1)
    q[~ok] = np.nan
    return q, ok


def arm_solutions(table: DHTable, flange: np.ndarray) -> tuple[np.ndarray, ...]:
    """DH angles of the 4 arm solutions for flange poses (N, 4, 4) mm: theta_1 (N, 2 shoulder),
    theta_2 and theta_3 (N, 2 shoulder, 2 elbow) rad, and (N, 2, 2) whether the wrist point is
    reachable (NaN angles where not)."""
    th1, th3, reach, plane = arm_elbows(table, wrist_points(table, flange))
    th2 = upper_arm(table, plane)  # (N, 2 shoulder, 2 elbow)
    return th1, th2, th3, np.repeat(reach[:, :, None], 2, axis=2)


def arm_elbows(table: DHTable, pw: np.ndarray) -> tuple[np.ndarray, ...]:
    """``arm_solutions`` without theta_2, for wrist points pw (N, 3) mm: theta_1 (N, 2
    shoulder), theta_3 (N, 2 shoulder, 2 elbow) rad, reachable (N, 2 shoulder), and the arm
    plane (px, py, gamma) (N, 2) of each shoulder that ``upper_arm`` takes (any rows of it)."""
    # Shoulder: the arm plane contains the A1 axis, so theta_1 points at the wrist or away.
    toward = np.arctan2(pw[:, 1], pw[:, 0])
    th1 = np.stack([toward, toward + np.pi], axis=1)  # (N, 2)
    # Wrist point in frame 1 (after Rot(X, alpha_1)): planar two-link problem in its x-y plane;
    # along the arm plane the wrist point lies at +r (toward it) or -r from the A1 axis.
    r = np.hypot(pw[:, 0], pw[:, 1])
    radial = np.stack([r, -r], axis=1) - table.a[0]
    height = pw[:, None, 2] - table.d[0]
    sa1 = np.sin(table.alpha[0])
    px, py = radial, sa1 * height
    a2, l3, beta = _links(table)
    cos_g = (px**2 + py**2 - a2**2 - l3**2) / (2 * a2 * l3)  # (N, 2)
    reach = np.abs(cos_g) <= 1 + _TOL
    gamma = np.arccos(np.clip(cos_g, -1.0, 1.0))  # elbow angle >= 0; the other elbow: -gamma
    th3 = np.empty((*gamma.shape, 2))  # (N, 2 shoulder, 2 elbow)
    np.subtract(gamma, beta, out=th3[..., 0])
    np.subtract(-gamma, beta, out=th3[..., 1])
    return th1, th3, reach, (px, np.broadcast_to(py, px.shape), gamma)


def upper_arm(table: DHTable, plane: tuple[np.ndarray, ...], elbow=None) -> np.ndarray:
    """DH theta_2 rad in the arm plane (px, py, gamma) of ``arm_elbows`` (rows of it, shape
    (...)): of elbow solution ``elbow`` (0 or 1 (...)), or of both (..., 2) when None."""
    px, py, gamma = plane
    a2, l3, _ = _links(table)
    # sin and atan2 are odd, cos even: the -gamma elbow's terms are the +gamma ones negated
    lean = np.arctan2(l3 * np.sin(gamma), a2 + l3 * np.cos(gamma))
    toward_wrist = np.arctan2(py, px)
    if elbow is None:
        return np.stack([toward_wrist - lean, toward_wrist + lean], axis=-1)
    return np.where(np.asarray(elbow) == 0, toward_wrist - lean, toward_wrist + lean)


def _links(table: DHTable) -> tuple[float, float, float]:
    """Upper arm length a2 mm, forearm length l3 mm (A3 axis to the wrist point) and the
    forearm's angle beta rad from the DH x3 axis."""
    bx, by = table.a[2], -np.sin(table.alpha[2]) * table.d[3]
    return table.a[1], np.hypot(bx, by), np.arctan2(by, bx)


def arm_wrists(
    table: DHTable, flange: np.ndarray, th1: np.ndarray, th2: np.ndarray, th3: np.ndarray
) -> np.ndarray:
    """The 2 wrist solutions of one arm solution per pose: flange poses (M, 4, 4) mm, DH angles
    th1, th2, th3 (M,) rad -> KUKA joint angles (M, 2, 6) rad wrapped into (-pi, pi]; the same
    numbers ``all_solutions`` gives for that arm solution."""
    wrist = wrist_angles(table, th1, _r6(table, flange), th2 + th3)
    return _joints(table, np.stack([th1, th2, th3], axis=-1), *wrist).reshape(-1, 2, 6)


def chosen_wrists(
    table: DHTable,
    flange: np.ndarray,
    th1: np.ndarray,
    th2: np.ndarray,
    th3: np.ndarray,
    negative: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Of the 2 wrist solutions of one arm solution per pose, the first whose A5 < 0 is
    ``negative`` (M,) bool, or that sits on the wrist singularity (|A5| <
    ``SINGULAR_A5_RAD``, where either fits): KUKA joint angles (M, 6) rad in (-pi, pi] (rows
    without one: undefined) and whether there is one (M,). Flange poses (M, 4, 4) mm, DH
    angles th1, th2, th3 (M,) rad. The numbers of ``arm_wrists`` for the chosen solution,
    with half of its joint arithmetic."""
    th4, th5, th6 = wrist_angles(table, th1, _r6(table, flange), th2 + th3)
    a5 = wrap((np.stack([th5, -th5], axis=1) - table.theta_offset[4]) * table.sign[4])  # (M, 2)
    fits = ((a5 < 0) == np.asarray(negative)[:, None]) | (np.abs(a5) < SINGULAR_A5_RAD)
    second = ~fits[:, 0]
    th4, th5, th6 = (
        np.where(second, b, a)
        for a, b in zip((th4, th5, th6), _flipped(th4, th5, th6), strict=True)
    )
    theta = np.stack([th1, th2, th3, th4, th5, th6], axis=1)
    return wrap(table.axis_angles(theta)), fits.any(axis=1)


def _flipped(th4: np.ndarray, th5: np.ndarray, th6: np.ndarray) -> tuple[np.ndarray, ...]:
    """DH theta_4, theta_5, theta_6 of the other wrist solution (the same flange orientation)."""
    return th4 + np.pi, -th5, th6 + np.pi


def wrist_angles(
    table: DHTable, th1: np.ndarray, r6: list[list[np.ndarray]], phi: np.ndarray
) -> tuple[np.ndarray, ...]:
    """DH theta_4, theta_5 (>= 0), theta_6 rad of the first wrist solution, for DH th1 and
    phi = th2 + th3 rad and R6 entries ``r6[k][j]`` (all broadcast together).

    W = (base_R_3)^T R6 = Rz(th4) Rx(al4) Rz(th5) Rx(al5) Rz(th6), with base_R_3 =
    Rz(th1) Rx(al1) Rz(phi) Rx(al3) (alpha_2 = 0), entry W[i, j] = column i of base_R_3 dot
    column j of R6, written out for the entries the angles need.
    """
    c1, s1 = np.cos(th1), np.sin(th1)
    cphi, sphi = np.cos(phi), np.sin(phi)
    ca1, sa1 = np.cos(table.alpha[0]), np.sin(table.alpha[0])
    ca3, sa3 = np.cos(table.alpha[2]), np.sin(table.alpha[2])
    # columns of S = Rz(th1) Rx(al1) (row 2 of column 0 is 0), then of base_R_3 = S Rz(phi) Rx(al3)
    s0 = (c1, s1)
    s1_ = (-s1 * ca1, c1 * ca1, sa1)
    s2 = (s1 * sa1, -c1 * sa1, ca1)
    m0 = [cphi * s0[k] + sphi * s1_[k] for k in range(2)] + [sphi * s1_[2]]
    m1 = [ca3 * (cphi * s1_[k] - sphi * s0[k]) + sa3 * s2[k] for k in range(2)]
    m1.append(ca3 * cphi * s1_[2] + sa3 * s2[2])
    m2 = [sa3 * (sphi * s0[k] - cphi * s1_[k]) + ca3 * s2[k] for k in range(2)]
    m2.append(ca3 * s2[2] - sa3 * cphi * s1_[2])

    def w(m: list[np.ndarray], j: int) -> np.ndarray:  # W[i, j] for column i = m of base_R_3
        return m[0] * r6[0][j] + m[1] * r6[1][j] + m[2] * r6[2][j]

    s4, s5 = np.sign(np.sin(table.alpha[3])), np.sign(np.sin(table.alpha[4]))
    wx, wy, wz = w(m0, 2), w(m1, 2), w(m2, 2)
    across = np.hypot(wx, wy)
    singular = across < SINGULAR_A5_RAD  # sin A5 ~ A5 there
    th5 = np.arctan2(across, -s4 * s5 * wz)
    # Row 3 of W is s4 * (sin th5 cos th6, -sin th5 sin th6, -s5 cos th5) with th5 >= 0.
    th4 = np.arctan2(s5 * wy, s5 * wx)
    th6 = np.arctan2(-s4 * w(m2, 1), s4 * w(m2, 0))
    if singular.any():
        # On the wrist singularity (A5 = 0) only A4 + A6 matters: put it all into A6; there
        # W = Rx(alpha4 + alpha5) Rz(th6).
        turned = np.cos(table.alpha[3] + table.alpha[4])
        th4 = np.where(singular, 0.0, th4)
        th6 = np.where(singular, np.arctan2(turned * w(m1, 0), w(m0, 0)), th6)
    return th4, th5, th6


def _joints(
    table: DHTable, arm: np.ndarray, th4: np.ndarray, th5: np.ndarray, th6: np.ndarray
) -> np.ndarray:
    """KUKA angles (2M, 6) rad in (-pi, pi]: arm DH angles (M, 3) with both wrist solutions of
    th4, th5, th6 (M,) (the other one: A4 + 180 deg, -A5, A6 + 180 deg), wrist order inner."""
    other = _flipped(th4, th5, th6)
    th4, th5, th6 = (
        np.stack([a, b], axis=1).reshape(-1) for a, b in zip((th4, th5, th6), other, strict=True)
    )
    theta = np.empty((len(th4), 6))
    theta[:, :3] = np.repeat(arm, 2, axis=0)
    theta[:, 3], theta[:, 4], theta[:, 5] = th4, th5, th6
    return wrap(table.axis_angles(theta))
