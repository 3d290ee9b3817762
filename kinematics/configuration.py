"""Robot configuration: which of a pose's inverse-kinematics branches the arm is in.

A ``Configuration`` is the robot-neutral value, computed from joint angles: per joint vector the
shoulder (the wrist point behind the A1 axis: the overhead area), the elbow (A3 at or beyond
phi, the A3 angle at which the A2 axis, the A3 axis and the wrist point are in line, arm
stretched; -1.957 deg for the KR 210, -atan(41/1200); 0 for a UR), the wrist (A5 < 0, flipped)
and, per axis, whether the angle is negative (the sign of each axis' turn). A3 - phi and A5 are
taken mod 360 deg (a whole turn does not change the configuration); the wrist point is DH frame
5's origin (frame 4's on a spherical wrist), so on a UR the 8 solutions of a pose are the 8
codes: shoulder left/right, elbow up/down, wrist flipped or not. Each controller's words come
from it:
``to_kuka`` gives the KUKA Status and Turn (docs/formats.md; checked against the KUKA, Siemens and
Beckhoff descriptions: Status bit 0 shoulder, bit 1 elbow, bit 2 wrist; Turn bit i set when
A(i+1) < 0).

The joint angles themselves are the neutral data: a vendor whose words need more than these
flags takes them from q. ABB ``confdata`` [cf1, cf4, cf6, cfx] (``abb_confdata``, RAPID
reference manual, data type confdata): cf1, cf4, cf6 are the quadrant numbers of axes 1, 4 and 6
(``abb_quadrant``: floor(angle / 90 deg), 0 for 0..90 deg, -1 for -90..0 deg, ...); cfx for a
serial 6-axis arm is 4 * (wrist centre behind axis 1) + 2 * (wrist centre behind the lower arm)
+ (axis 5 negative), the manual's table of cfx 0..7. "Behind axis 1" is the shoulder flag;
"behind the lower arm" is the side of the line through axes 2 and 3 the wrist centre lies on,
the normal (elbow-up) side being "in front" (``abb_front``; within the IRB 6700's axis 3 range
it is the elbow flag negated). ``select_confdata`` picks the solution of a wanted confdata.

Branch selection (``select``: the one joint solution ``Robot.ik`` returns for a wanted Status, or
the one nearest a reference) and the ``IKSolution`` record live here too, so the DH robot
(``kinematics.robot``) and the URDF robot (``kinematics.urdf``) share them without importing each
other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.kinematics import ik as closed
from accugrid.kinematics.dh import chain

if TYPE_CHECKING:
    from accugrid.kinematics.model import RobotModel
    from accugrid.kinematics.robot import Robot

__all__ = [
    "CONFDATA_TOL_RAD",
    "HOME_RAD",
    "Configuration",
    "IKSolution",
    "abb_confdata",
    "abb_cfx",
    "abb_front",
    "abb_quadrant",
    "kuka_status",
    "kuka_turn",
    "kuka_words",
    "select",
    "select_confdata",
    "solve_in_one_status",
    "status_turn",
]

HOME_RAD = np.radians([0.0, -90.0, 90.0, 0.0, 0.0, 0.0])  # KUKA home, the default IK reference


@dataclass(frozen=True)
class IKSolution:
    """Result of ``Robot.ik`` for N poses (see the field comments for shapes)."""

    q: np.ndarray  # (N, 6) rad, NaN rows where there is no solution
    ok: np.ndarray  # (N,) bool
    reason: np.ndarray  # (N,) object: "" when ok, else why not
    # (N,) int KUKA Status of q: the configuration code shoulder + 2 elbow + 4 wrist, the
    # same number on any DH arm (-1 where there is no solution)
    status: np.ndarray
    turn: np.ndarray  # (N,) int KUKA Turn of q (-1 where there is no solution)


@dataclass(frozen=True)
class Configuration:
    """The configuration of joint vectors of any shape (...): shoulder, elbow, wrist (...) bool
    (module doc) and negative (..., 6) bool, axis angle < 0."""

    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    negative: np.ndarray

    @classmethod
    def of_joints(cls, robot: Robot, q: np.ndarray) -> Configuration:
        """The configuration (N,) of joint vectors q (N, 6) rad of a DH robot."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        shoulder, elbow, wrist = _arm_bits(robot, q, _wrist_points(robot, q))
        return cls(shoulder, elbow, wrist, q < 0)

    @classmethod
    def from_kuka(cls, status: np.ndarray, turn: np.ndarray) -> Configuration:
        """The configuration of KUKA Status and Turn integers (same shape)."""
        status, turn = np.asarray(status, dtype=int), np.asarray(turn, dtype=int)
        negative = np.empty((*turn.shape, 6), dtype=bool)  # bit i of Turn, axis by axis
        for i in range(6):
            negative[..., i] = (turn >> i) & 1 == 1
        return cls(status & 1 == 1, status & 2 == 2, status & 4 == 4, negative)

    def to_kuka(self) -> tuple[np.ndarray, np.ndarray]:
        """KUKA Status and Turn integers (...) of this configuration."""
        return (
            kuka_status(self.shoulder, self.elbow, self.wrist),
            kuka_turn(self.negative),
        )


def solve_in_one_status(
    robot: RobotModel, poses: np.ndarray, status: int | None = None, first: np.ndarray | None = None
) -> tuple[IKSolution, int | None]:
    """IK of TCP poses (N, 4, 4) mm all in one KUKA Status, as a program that starts with one PTP
    and continues with LIN keeps its configuration: ``status``, or the Status of the IK default
    at ``first`` (a (4, 4) pose; default the first pose). Returns the solution (check ``ok``)
    and the Status used (None when ``first`` is unreachable or the robot has no KUKA Status)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
    if status is None and len(poses):
        start = robot.ik(poses[:1] if first is None else np.reshape(first, (1, 4, 4)))
        status = int(start.status[0]) if start.ok[0] and start.status[0] >= 0 else None
    return robot.ik(poses, status=status), status


def kuka_status(shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """KUKA Status bits 0, 1, 2 from the shoulder, elbow and wrist flags (int array)."""
    return np.asarray(shoulder).astype(int) + 2 * np.asarray(elbow) + 4 * np.asarray(wrist)


def kuka_turn(negative: np.ndarray) -> np.ndarray:
    """KUKA Turn (...) from per-axis negative flags (..., 6): bit i set when A(i+1) < 0."""
    negative = np.asarray(negative)
    turn = np.zeros(negative.shape[:-1], dtype=int)
    for i in range(negative.shape[-1]):  # axis by axis: no (..., 6) integer temporaries
        turn |= negative[..., i].astype(int) << i
    return turn


def status_turn(robot: Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """KUKA Status and Turn (N,) int for joint vectors q (N, 6) rad of a DH robot."""
    return Configuration.of_joints(robot, q).to_kuka()


def _wrist_points(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Wrist points (N, 3) mm, robot frame, of joint vectors q (N, 6) rad: the origin of DH
    frame 5, where axes 5 and 6 cross the common normal of axis 5 (of frame 4 where that is
    the same point: a spherical wrist, a5 = d5 = 0)."""
    dh = robot.dh
    if dh.a[4] or dh.d[4]:  # a wrist with an offset (a UR's): the chain to frame 5
        return chain(dh, q, links=5)[4][:, :3, 3]
    base_T_3 = chain(dh, q, links=3)[2]  # the wrist point is the origin of frame 4
    theta4 = dh.theta(q)[:, 3]
    offset = np.stack(
        [dh.a[3] * np.cos(theta4), dh.a[3] * np.sin(theta4), np.full_like(theta4, dh.d[3])]
    )
    return np.einsum("nij,jn->ni", base_T_3[:, :3, :3], offset) + base_T_3[:, :3, 3]


def _arm_bits(robot: Robot, q: np.ndarray, wrist: np.ndarray) -> tuple[np.ndarray, ...]:
    """Shoulder, elbow, wrist flags (N,) of joint vectors q (N, 6) rad with wrist points (N, 3)."""
    a1 = robot.dh.sign[0] * q[:, 0] + robot.dh.theta_offset[0]
    x_a1 = wrist[:, 0] * np.cos(a1) + wrist[:, 1] * np.sin(a1)
    return x_a1 < 0, closed.wrap(q[:, 2] - robot.phi_rad) >= 0, closed.wrap(q[:, 4]) < 0


def _arm_status(robot: Robot, th1: np.ndarray, th3: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """KUKA Status bits 0 and 1 (N, 2, 2) of the 4 arm solutions per pose: DH angles th1 (N, 2
    shoulder), th3 (N, 2 shoulder, 2 elbow) rad, wrist points (N, 3) mm. The numbers of
    ``_status`` on the arm's joint vectors (A1 and A3 wrapped as ``wrap(axis_angles)`` does),
    without the other four axes; the shoulder bit once per shoulder solution."""
    dh = robot.dh
    a3 = closed.wrap((th3 - dh.theta_offset[2]) * dh.sign[2])
    # x_a1 (the wrist point along the A1 arm direction) is +r for the shoulder toward the
    # wrist point and -r for the other, r = hypot(x, y) > 0, within a few ulps of r: the bit
    # is the shoulder's index. Worked out only where r is 0 or subnormal (on the A1 axis).
    behind = np.zeros(th1.shape, bool)
    behind[:, 1] = True
    axis = np.flatnonzero((np.abs(wrist[:, 0]) < _NORMAL) & (np.abs(wrist[:, 1]) < _NORMAL))
    if axis.size:
        a1 = closed.wrap((th1[axis] - dh.theta_offset[0]) * dh.sign[0])
        dh_a1 = dh.sign[0] * a1 + dh.theta_offset[0]
        x_a1 = wrist[axis, None, 0] * np.cos(dh_a1) + wrist[axis, None, 1] * np.sin(dh_a1)
        behind[axis] = x_a1 < 0
    return kuka_status(behind[:, :, None], a3 >= robot.phi_rad, False)


_NORMAL = 1e-100  # mm: |x|, |y| of a wrist point off the A1 axis are far above this


def _status(robot: Robot, q: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """KUKA Status (N,) of joint vectors q (N, 6) rad whose wrist point is ``wrist`` (N, 3) mm."""
    return kuka_status(*_arm_bits(robot, q, wrist))


def kuka_words(robot: Robot, q: np.ndarray, wrist: np.ndarray) -> tuple[np.ndarray, ...]:
    """KUKA Status and Turn (N,) of joint vectors q (N, 6) rad whose wrist points ``wrist``
    (N, 3) mm are known (saves the forward kinematics of ``status_turn``)."""
    return _status(robot, q, wrist), kuka_turn(q < 0)


def select(robot: Robot, flange, wrist, status, reference) -> tuple[np.ndarray, ...]:
    """The solution ``Robot.ik`` picks per flange pose (N, 4, 4), before Turn and limits: q (N, 6)
    rad in (-pi, pi] (NaN where none), found (N,), any candidate reachable (N,).

    Status bits 0 and 1 (shoulder, elbow) follow from the 4 arm solutions alone (theta_2 is
    solved only for the chosen one); where one arm solution has the wanted bits, only its 2
    wrists are solved, and with a given Status only the joints of the wrist with the wanted
    bit 2 are built. Poses where that does not settle it (several arm solutions fit, or neither
    wrist has the wanted bit 2) take all 8 candidates, so the pick is the same as over all 8
    in candidate order."""
    n, dh = len(flange), robot.dh
    th1, th3, reach, plane = closed.arm_elbows(dh, wrist)
    reach = np.repeat(reach, 2, axis=1)  # (N, 4): per shoulder and elbow
    bits = _arm_status(robot, th1, th3, wrist).reshape(n, 4)
    want = 2 if status is None else np.broadcast_to(np.asarray(status, dtype=int), (n,))
    fits = reach & (bits == np.bitwise_and(want, 3)[..., None])
    fitting = fits[:, 0].astype(np.int8)
    for k in range(1, 4):  # column by column: a reduction over the short axis is slow
        fitting += fits[:, k]
    one = fitting == 1
    several = np.flatnonzero(fitting > 1)  # the pick among them needs all 8 candidates
    q = np.full((n, 6), np.nan)
    found = np.zeros(n, bool)
    rows = np.flatnonzero(one)
    every = len(rows) == n  # then rows are all poses in order: no gathers

    def of_rows(x: np.ndarray) -> np.ndarray:
        return x if every else x[rows]

    chosen_fits = of_rows(fits)
    a = chosen_fits[:, 1] + 2 * chosen_fits[:, 2].astype(np.int64) + 3 * chosen_fits[:, 3]
    s, e = a // 2, a % 2
    line = np.arange(len(rows))
    th2 = closed.upper_arm(dh, [of_rows(part)[line, s] for part in plane], e)  # chosen arm only
    arm = (of_rows(th1)[line, s], th2, of_rows(th3)[line, s, e])
    if status is None:
        cand = closed.arm_wrists(dh, of_rows(flange), *arm)  # (m, 2, 6)
        ref = HOME_RAD if reference is None else np.asarray(reference, dtype=float)
        ref = np.broadcast_to(ref, (n, 6))[rows, None]
        pick = np.argmin((closed.wrap(cand - ref) ** 2).sum(axis=2), axis=1)
        q[rows] = cand[np.arange(len(rows)), pick]
        found[rows] = True
        rest = several
    else:
        # the arm solution has the wanted bits 0 and 1 (its Status, the same numbers as its
        # candidates' ``_status``): the wrist with the wanted bit 2 (A5 < 0) is the match
        chosen, settled = closed.chosen_wrists(dh, of_rows(flange), *arm, of_rows(want) & 4 != 0)
        done = rows[settled]
        if len(done) == n:  # every pose: no scatter
            q, found = chosen, np.ones(n, bool)
        else:
            q[done] = chosen[settled]
            found[done] = True
        rest = np.concatenate([several, rows[~settled]])
    if rest.size:
        q[rest], found[rest] = _select_all(robot, flange[rest], wrist[rest], want, rest, reference)
    return q, found, reach[:, 0] | reach[:, 2]  # reach repeats each shoulder's for 2 elbows


def _select_all(robot: Robot, flange, wrist, want, rows, reference):
    """``select`` over all 8 candidates for poses ``rows``; want = 2 means the default."""
    m = len(flange)
    cand, reach = closed.all_solutions(robot.dh, flange)
    cand_status = _status(robot, cand.reshape(-1, 6), np.repeat(wrist, 8, axis=0)).reshape(m, 8)
    if np.ndim(want) == 0:
        match = reach & ((cand_status & 3) == 2)
        ref = HOME_RAD if reference is None else np.asarray(reference, dtype=float)
        if ref.ndim == 2:
            ref = ref[rows]
        ref = np.broadcast_to(ref, (m, 6))[:, None]
        distance = np.where(match, (closed.wrap(cand - ref) ** 2).sum(axis=2), np.inf)
        pick = np.argmin(distance, axis=1)
    else:
        match = reach & _status_match(
            cand.reshape(-1, 6), cand_status.reshape(-1), want[rows].repeat(8)
        ).reshape(m, 8)
        pick = np.argmax(match, axis=1)
    found = match.any(axis=1)
    q = cand[np.arange(m), pick]
    q[~found] = np.nan
    return q, found


def _status_match(q: np.ndarray, cand_status: np.ndarray, want: np.ndarray) -> np.ndarray:
    """Candidates (M, 6) with the wanted Status; on the wrist singularity (A5 = 0) either bit 2
    fits."""
    singular_wrist = np.abs(q[:, 4]) < closed.SINGULAR_A5_RAD
    return (cand_status == want) | (singular_wrist & ((cand_status & 3) == (want & 3)))


CONFDATA_TOL_RAD = 1e-9  # an angle this close to its wanted quadrant is moved onto its edge
_QUARTER = np.pi / 2


def abb_quadrant(angle: np.ndarray) -> np.ndarray:
    """ABB quadrant numbers (...) int of axis angles (...) rad: floor(angle / 90 deg), i.e.
    0 for 0 <= angle < 90 deg, 1 for 90..180, -1 for -90 <= angle < 0, -2 for -180..-90, ...
    (the manual's "0-90", "90-180", "0 to -90"; it leaves the exact multiples of 90 deg open:
    ``select_confdata`` accepts either neighbour there)."""
    return np.floor(np.asarray(angle, dtype=float) / _QUARTER).astype(int)


def abb_front(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Whether the wrist centre is in front of the lower arm (N,) bool for joint vectors q (N, 6)
    rad: on the side of the line through axes 2 and 3 that the forearm leans to in the normal
    (elbow-up) pose, seen along axis 2 turned with axis 1. In DH terms (x2 along the lower arm,
    z2 = -sin(alpha_1) times the horizontal normal of the arm plane):
    -sin(alpha_1) * sin(theta_3 + beta) >= 0, beta the forearm's angle from x3."""
    dh = robot.dh
    bx, by = dh.a[2], -np.sin(dh.alpha[2]) * dh.d[3]
    theta3 = dh.sign[2] * np.asarray(q, dtype=float)[..., 2] + dh.theta_offset[2]
    return -np.sin(dh.alpha[0]) * np.sin(theta3 + np.arctan2(by, bx)) >= 0


def abb_cfx(robot: Robot, q: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """ABB cfx (N,) int 0..7 of joint vectors q (N, 6) rad whose wrist centres are ``wrist``
    (N, 3) mm, robot frame: 4 * behind axis 1 + 2 * behind the lower arm + axis 5 < 0."""
    q = np.asarray(q, dtype=float)
    behind, _, negative_a5 = _arm_bits(robot, q, wrist)
    return 4 * behind.astype(int) + 2 * ~abb_front(robot, q) + negative_a5


def abb_confdata(robot: Robot, q: np.ndarray) -> np.ndarray:
    """ABB confdata [cf1, cf4, cf6, cfx] (N, 4) int of joint vectors q (N, 6) rad (ABB axis
    angles) of a DH robot."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    out = np.empty((len(q), 4), dtype=int)
    out[:, :3] = abb_quadrant(q[:, [0, 3, 5]])
    out[:, 3] = abb_cfx(robot, q, _wrist_points(robot, q))
    return out


def select_confdata(
    robot: Robot,
    flange: np.ndarray,
    wrist: np.ndarray,
    confdata: np.ndarray,
    tol_rad: float = CONFDATA_TOL_RAD,
) -> tuple[np.ndarray, np.ndarray]:
    """The solution of each flange pose (N, 4, 4) mm (wrist centres (N, 3) mm) whose ABB
    confdata is ``confdata`` ((4,) or (N, 4) int), before joint limits: q (N, 6) rad (NaN rows
    where there is none) and the reason (N,) object ("" where found).

    cfx picks one of the 8 closed-form solutions (``_cfx_branch``); axes 1, 4 and 6 then take
    the turn (+- k * 360 deg) that puts them in quadrants cf1, cf4, cf6. An angle within
    ``tol_rad`` of its quadrant is moved onto the quadrant's edge; one farther off has no
    solution there (cf1 disagrees with the cfx shoulder bit, or cf4/cf6 with the cfx axis 5
    bit). Axes 2, 3 and 5, which confdata does not name, take the turn inside the joint limits
    where the angle in (-180, 180] deg is outside them (an axis 3 of -180 deg)."""
    n = len(flange)
    want = np.broadcast_to(np.asarray(confdata, dtype=int), (n, 4))
    q, reason = _cfx_branch(robot, flange, wrist, want[:, 3])
    found = reason == ""
    q[~found] = 0.0
    lo, hi = np.radians(robot.joint_limits_deg).T
    for axis in (1, 2, 4):
        angle = q[:, axis]
        outside = (angle < lo[axis] - tol_rad) | (angle > hi[axis] + tol_rad)
        turned = angle - np.copysign(2 * np.pi, angle)
        back = outside & (turned >= lo[axis] - tol_rad) & (turned <= hi[axis] + tol_rad)
        q[:, axis] = np.where(back, turned, angle)
    for axis, k in zip((0, 3, 5), want[:, :3].T, strict=True):
        q[:, axis], inside = _into_quadrant(q[:, axis], k, tol_rad)
        missed = found & ~inside
        reason[missed] = f"A{axis + 1} cannot be in quadrant cf{axis + 1} with this cfx"
        found &= inside
    q[~found] = np.nan
    return q, reason


_CLEAR = 1e-9  # |sin| of the elbow angle above this: the elbow index alone gives the lower-arm bit


def _cfx_branch(
    robot: Robot, flange: np.ndarray, wrist: np.ndarray, cfx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The first of the 8 closed-form solutions (candidate order) with ABB cfx (N,) int per
    flange pose (N, 4, 4) mm, wrist centres (N, 3) mm: q (N, 6) rad in (-pi, pi] (NaN rows where
    there is none) and the reason (N,) object ("" where found).

    Where the wrist centre is off axis 1 and the arm is neither stretched nor folded, cfx names
    the arm solution by itself (shoulder index = its bit 2; elbow index 0, theta_3 + beta =
    gamma >= 0, is in front of the lower arm when sin(alpha_1) < 0) and only its 2 wrists are
    solved (``closed.chosen_wrists``); elsewhere the 8 candidates are compared
    (``_cfx_candidates``), which gives the same numbers."""
    n, dh = len(flange), robot.dh
    cfx = np.asarray(cfx)
    th1, th3, reach, plane = closed.arm_elbows(dh, wrist)
    line = np.arange(n)
    s = (cfx >> 2) & 1
    e = ((cfx >> 1) & 1 == 0) != (np.sin(dh.alpha[0]) < 0)
    e = e.astype(int)
    off_axis = (np.abs(wrist[:, 0]) >= _NORMAL) | (np.abs(wrist[:, 1]) >= _NORMAL)
    easy = reach[line, s] & (np.abs(np.sin(plane[2][line, s])) > _CLEAR) & off_axis
    easy &= (cfx >= 0) & (cfx <= 7)
    rows = np.flatnonzero(easy)
    q = np.full((n, 6), np.nan)
    reason = np.full(n, "", dtype=object)
    settled = np.ones(0, bool)
    if rows.size:
        sr, er = s[rows], e[rows]
        th2 = closed.upper_arm(dh, [part[rows, sr] for part in plane], er)
        arm = (th1[rows, sr], th2, th3[rows, sr, er])
        q[rows], settled = closed.chosen_wrists(dh, flange[rows], *arm, cfx[rows] & 1 == 1)
    hard = np.concatenate([np.flatnonzero(~easy), rows[~settled]])
    if hard.size:
        q[hard], reason[hard] = _cfx_candidates(robot, flange[hard], wrist[hard], cfx[hard])
    return q, reason


def _cfx_candidates(
    robot: Robot, flange: np.ndarray, wrist: np.ndarray, cfx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``_cfx_branch`` over all 8 candidates: the first whose ``abb_cfx`` is cfx (on the wrist
    singularity, |axis 5| < ``SINGULAR_A5_RAD``, either axis 5 sign fits)."""
    n = len(flange)
    cand, reach = closed.all_solutions(robot.dh, flange)  # (N, 8, 6), (N, 8)
    cand_cfx = abb_cfx(robot, cand.reshape(-1, 6), np.repeat(wrist, 8, axis=0)).reshape(n, 8)
    singular = np.abs(cand[:, :, 4]) < closed.SINGULAR_A5_RAD
    wanted = np.asarray(cfx)[:, None]
    match = reach & ((cand_cfx == wanted) | (singular & ((cand_cfx | 1) == (wanted | 1))))
    found = match.any(axis=1)
    q = cand[np.arange(n), np.argmax(match, axis=1)]
    q[~found] = np.nan
    reason = np.full(n, "", dtype=object)
    reason[~found] = "no solution with the requested cfx"
    reason[~reach.any(axis=1)] = "unreachable"
    return q, reason


def _into_quadrant(angle: np.ndarray, k: np.ndarray, tol_rad: float) -> tuple[np.ndarray, ...]:
    """Angles (M,) rad turned by whole turns into ABB quadrants k (M,) where they fit (within
    ``tol_rad`` of it: moved onto its edge), and whether they do (M,)."""
    centre = (k + 0.5) * _QUARTER
    turned = angle + 2 * np.pi * np.round((centre - angle) / (2 * np.pi))
    inside = np.abs(turned - centre) <= _QUARTER / 2 + tol_rad
    turned = np.clip(turned, centre - _QUARTER / 2, centre + _QUARTER / 2)
    for _ in range(4):  # an edge itself may belong to the next quadrant: step inwards
        turned = np.where(abb_quadrant(turned) == k, turned, np.nextafter(turned, centre))
    return turned, inside & (abb_quadrant(turned) == k)
