"""ABB confdata [cf1, cf4, cf6, cfx] (RAPID reference manual, data type confdata): the RAPID words
of a robot configuration (``kinematics.configuration``) and the joint solution a confdata names.

cf1, cf4, cf6 are the quadrant numbers of axes 1, 4 and 6 (``abb_quadrant``: floor(angle / 90
deg), the configuration's ``quarter``); cfx for a serial 6-axis arm is 4 * (wrist centre behind
axis 1) + 2 * (wrist centre behind the lower arm) + (axis 5 negative), the manual's table of cfx
0..7. "Behind axis 1" is the shoulder flag; "behind the lower arm" is the side of the line
through axes 2 and 3 the wrist centre lies on, the normal (elbow-up) side being "in front"
(``abb_front``; within the IRB 6700's axis 3 range it is the elbow flag negated, the reading of a
written cfx, ``read_configuration``). ``ik_confdata`` solves the poses of wanted confdata.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from accugrid.kinematics import ik as closed
from accugrid.kinematics.configuration import (
    OFF_AXIS_MM,
    QUARTER_RAD,
    Configuration,
    arm_flags,
    wrist_points_of,
)

if TYPE_CHECKING:
    from accugrid.kinematics.model import IKSolution
    from accugrid.kinematics.robot import Robot

__all__ = [
    "CONFDATA_TOL_RAD",
    "abb_cfx",
    "abb_confdata",
    "abb_front",
    "abb_quadrant",
    "configuration_words",
    "ik_confdata",
    "read_configuration",
    "select_confdata",
]

_ABB_AXES = [0, 3, 5]  # the axes cf1, cf4, cf6 name


def configuration_words(configuration: Configuration) -> np.ndarray:
    """The confdata (..., 4) int [cf1, cf4, cf6, cfx] of a configuration (...): its quarters of
    axes 1, 4 and 6, and cfx with "behind the lower arm" read as the elbow flag negated (the
    arms whose axis 3 range keeps them on one side of the folded line, as the IRB 6700's)."""
    c = configuration
    out = np.empty((*np.shape(c.shoulder), 4), dtype=int)
    out[..., :3] = c.quarter[..., _ABB_AXES]
    out[..., 3] = 4 * np.asarray(c.shoulder, int) + 2 * ~np.asarray(c.elbow) + c.wrist
    return out


def read_configuration(confdata: np.ndarray) -> Configuration:
    """The configuration (...) a confdata (..., 4) int names: shoulder, elbow and wrist from cfx
    (the elbow up where the wrist centre is in front of the lower arm), the quarters of axes 1,
    4 and 6 from cf1, cf4, cf6 and 0 (0..90 deg) for the others, which confdata does not name
    (cfx 0..7)."""
    confdata = np.asarray(confdata, dtype=np.int64)
    cfx = confdata[..., 3]
    quarter = np.zeros((*cfx.shape, 6), np.int8)
    quarter[..., _ABB_AXES] = confdata[..., :3]
    return Configuration((cfx >> 2) & 1 == 1, (cfx >> 1) & 1 == 0, cfx & 1 == 1, quarter)


def ik_confdata(robot: Robot, robot_T_tcp: np.ndarray, confdata: np.ndarray) -> IKSolution:
    """Joint solutions (ABB axis angles) for TCP poses (N, 4, 4) mm in ABB confdata
    [cf1, cf4, cf6, cfx] ((4,) or (N, 4) int): the one solution whose ``abb_confdata`` is the
    given one (``select_confdata``), then the joint limits."""
    flange, wrist = robot.flange_wrist(robot_T_tcp)
    q, reason = select_confdata(robot, flange, wrist, confdata)
    return robot.within_limits(q, reason == "", reason, wrist)


CONFDATA_TOL_RAD = 1e-9  # an angle this close to its wanted quadrant is moved onto its edge


def abb_quadrant(angle: np.ndarray) -> np.ndarray:
    """ABB quadrant numbers (...) int of axis angles (...) rad: floor(angle / 90 deg), i.e.
    0 for 0 <= angle < 90 deg, 1 for 90..180, -1 for -90 <= angle < 0, -2 for -180..-90, ...
    (the manual's "0-90", "90-180", "0 to -90"; it leaves the exact multiples of 90 deg open:
    ``select_confdata`` accepts either neighbour there)."""
    return np.floor(np.asarray(angle, dtype=float) / QUARTER_RAD).astype(int)


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
    behind, _, negative_a5 = arm_flags(robot, q, wrist)
    return 4 * behind.astype(int) + 2 * ~abb_front(robot, q) + negative_a5


def abb_confdata(robot: Robot, q: np.ndarray) -> np.ndarray:
    """ABB confdata [cf1, cf4, cf6, cfx] (N, 4) int of joint vectors q (N, 6) rad (ABB axis
    angles) of a DH robot."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    out = np.empty((len(q), 4), dtype=int)
    out[:, :3] = abb_quadrant(q[:, [0, 3, 5]])
    out[:, 3] = abb_cfx(robot, q, wrist_points_of(robot, q))
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
    off_axis = (np.abs(wrist[:, 0]) >= OFF_AXIS_MM) | (np.abs(wrist[:, 1]) >= OFF_AXIS_MM)
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
    centre = (k + 0.5) * QUARTER_RAD
    turned = angle + 2 * np.pi * np.round((centre - angle) / (2 * np.pi))
    inside = np.abs(turned - centre) <= QUARTER_RAD / 2 + tol_rad
    turned = np.clip(turned, centre - QUARTER_RAD / 2, centre + QUARTER_RAD / 2)
    for _ in range(4):  # an edge itself may belong to the next quadrant: step inwards
        turned = np.where(abb_quadrant(turned) == k, turned, np.nextafter(turned, centre))
    return turned, inside & (abb_quadrant(turned) == k)
