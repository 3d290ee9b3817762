"""Robot configuration: which of a pose's inverse-kinematics branches the arm is in, robot-neutral.

A ``Configuration`` is computed from joint angles: per joint vector the shoulder (the wrist point
behind the A1 axis: the overhead area), the elbow (A3 at or beyond phi, the A3 angle at which the
A2 axis, the A3 axis and the wrist point are in line, arm stretched; -1.957 deg for the KR 210,
-atan(41/1200); 0 for a UR: the normal, elbow-up side), the wrist (A5 < 0, flipped) and, per
axis, the quarter turn the angle is in, floor(angle / 90 deg) (its sign, its quadrant and its
whole turns follow). A3 - phi and A5 are taken mod 360 deg (a whole turn does not change the
configuration); the wrist point is DH frame 5's origin (frame 4's on a spherical wrist), so on a
UR the 8 solutions of a pose are the 8 flag combinations: shoulder left/right, elbow up/down,
wrist flipped or not. Each dialect maps it to its controller's words
(``DialectPlugin.configuration_words``, in the dialect's folder).

The IK (``Robot.ik``) takes and returns the configuration as two integer codes: the
configuration code shoulder + 2 elbow + 4 wrist (``configuration_code``, 0..7) and the sign code,
bit i set when axis i + 1 is negative (``sign_code``, 0..63). Branch selection (``select``: the
one joint solution ``Robot.ik`` returns for a wanted code, or the one nearest a reference) lives
here too. The functions read of a DH robot only its ``DHArm`` members (``kinematics.dh``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from accugrid.kinematics import ik as closed
from accugrid.kinematics.dh import DHArm, chain

if TYPE_CHECKING:
    from accugrid.kinematics.model import IKSolution, RobotModel

__all__ = [
    "HOME_RAD",
    "OFF_AXIS_MM",
    "QUARTER_RAD",
    "Configuration",
    "arm_flags",
    "configuration_code",
    "ik_codes",
    "ik_codes_at",
    "quarters",
    "select",
    "sign_code",
    "solve_in_one_status",
    "wrist_points_of",
]

HOME_RAD = np.radians([0.0, -90.0, 90.0, 0.0, 0.0, 0.0])  # the default IK reference
QUARTER_RAD = np.pi / 2  # a quarter turn
_BLOCK = 1 << 16  # angles ``quarters`` turns into numbers at a time


@dataclass(frozen=True)
class Configuration:
    """The configuration of joint vectors of any shape (...) (module doc): shoulder (wrist point
    behind A1), elbow (up: A3 at or beyond phi), wrist (flipped: A5 < 0) (...) bool, and
    ``quarter`` (..., 6) int8, the quarter turn of each axis: floor(angle / 90 deg), 0 for
    0 <= angle < 90 deg, 1 for 90..180, -1 for -90 <= angle < 0, -2 for -180..-90, ...
    Indexing takes the same rows of every field."""

    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    quarter: np.ndarray

    @classmethod
    def of_joints(cls, robot: DHArm, q: np.ndarray) -> Configuration:
        """The configuration (N,) of joint vectors q (N, 6) rad of a DH robot."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        shoulder, elbow, wrist = arm_flags(robot, q, wrist_points_of(robot, q))
        return cls(shoulder, elbow, wrist, quarters(q))

    @classmethod
    def of_code(cls, code: np.ndarray, quarter: np.ndarray) -> Configuration:
        """The configuration of configuration codes (...) int (``configuration_code``) and
        quarter turns (..., 6) int."""
        code = np.asarray(code)
        return cls(code & 1 == 1, code & 2 == 2, code & 4 == 4, np.asarray(quarter, np.int8))

    @property
    def code(self) -> np.ndarray:
        """The configuration code (...) int: shoulder + 2 elbow + 4 wrist."""
        return configuration_code(self.shoulder, self.elbow, self.wrist)

    @property
    def negative(self) -> np.ndarray:
        """Whether each axis angle is negative (..., 6) bool."""
        return self.quarter < 0

    @property
    def turns(self) -> np.ndarray:
        """The whole turn of each axis (..., 6) int: t for -180 + 360 t <= angle < 180 + 360 t
        deg (0 for -180..180)."""
        return (self.quarter.astype(int) + 2) // 4

    def __getitem__(self, index) -> Configuration:
        return Configuration(
            self.shoulder[index], self.elbow[index], self.wrist[index], self.quarter[index]
        )


def quarters(q: np.ndarray) -> np.ndarray:
    """The quarter turn (..., 6) int8 of joint angles q (..., 6) rad: floor(angle / 90 deg) (NaN
    angles: any number)."""
    q = np.asarray(q, dtype=float)
    out = np.empty(q.shape, np.int8)
    flat, into = q.reshape(-1), out.reshape(-1)
    with np.errstate(invalid="ignore"):
        for start in range(0, len(flat), _BLOCK):  # in blocks: small float temporaries
            part = flat[start : start + _BLOCK] / QUARTER_RAD
            into[start : start + _BLOCK] = np.floor(part, out=part)
    return out


def solve_in_one_status(
    robot: RobotModel, poses: np.ndarray, status: int | None = None, first: np.ndarray | None = None
) -> tuple[IKSolution, int | None]:
    """IK of TCP poses (N, 4, 4) mm all in one configuration code, as a program that starts with
    one joint move and continues with linear ones keeps its configuration: ``status``, or the
    code of the IK default at ``first`` (a (4, 4) pose; default the first pose). Returns the
    solution (check ``ok``) and the code used (None when ``first`` is unreachable or the robot
    has no configuration code)."""
    poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
    if status is None and len(poses):
        start = robot.ik(poses[:1] if first is None else np.reshape(first, (1, 4, 4)))
        status = int(start.status[0]) if start.ok[0] and start.status[0] >= 0 else None
    return robot.ik(poses, status=status), status


def configuration_code(shoulder: np.ndarray, elbow: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """The configuration code shoulder + 2 elbow + 4 wrist (int array) of the flags."""
    return np.asarray(shoulder).astype(int) + 2 * np.asarray(elbow) + 4 * np.asarray(wrist)


def sign_code(negative: np.ndarray) -> np.ndarray:
    """The sign code (...) from per-axis negative flags (..., 6): bit i set when axis i + 1 is
    negative."""
    negative = np.asarray(negative)
    code = np.zeros(negative.shape[:-1], dtype=int)
    for i in range(negative.shape[-1]):  # axis by axis: no (..., 6) integer temporaries
        code |= negative[..., i].astype(int) << i
    return code


def ik_codes(robot: DHArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The configuration and sign codes (N,) int of joint vectors q (N, 6) rad of a DH robot."""
    c = Configuration.of_joints(robot, q)
    return c.code, sign_code(c.negative)


def wrist_points_of(robot: DHArm, q: np.ndarray) -> np.ndarray:
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


def arm_flags(robot: DHArm, q: np.ndarray, wrist: np.ndarray) -> tuple[np.ndarray, ...]:
    """Shoulder, elbow, wrist flags (N,) of joint vectors q (N, 6) rad with wrist points (N, 3)."""
    a1 = robot.dh.sign[0] * q[:, 0] + robot.dh.theta_offset[0]
    x_a1 = wrist[:, 0] * np.cos(a1) + wrist[:, 1] * np.sin(a1)
    return x_a1 < 0, closed.wrap(q[:, 2] - robot.phi_rad) >= 0, closed.wrap(q[:, 4]) < 0


def _arm_status(robot: DHArm, th1: np.ndarray, th3: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """Configuration code bits 0 and 1 (N, 2, 2) of the 4 arm solutions per pose: DH angles th1
    (N, 2 shoulder), th3 (N, 2 shoulder, 2 elbow) rad, wrist points (N, 3) mm. The numbers of
    ``_status`` on the arm's joint vectors (A1 and A3 wrapped as ``wrap(axis_angles)`` does),
    without the other four axes; the shoulder bit once per shoulder solution."""
    dh = robot.dh
    a3 = closed.wrap((th3 - dh.theta_offset[2]) * dh.sign[2])
    # x_a1 (the wrist point along the A1 arm direction) is +r for the shoulder toward the
    # wrist point and -r for the other, r = hypot(x, y) > 0, within a few ulps of r: the bit
    # is the shoulder's index. Worked out only where r is 0 or subnormal (on the A1 axis).
    behind = np.zeros(th1.shape, bool)
    behind[:, 1] = True
    axis = np.flatnonzero((np.abs(wrist[:, 0]) < OFF_AXIS_MM) & (np.abs(wrist[:, 1]) < OFF_AXIS_MM))
    if axis.size:
        a1 = closed.wrap((th1[axis] - dh.theta_offset[0]) * dh.sign[0])
        dh_a1 = dh.sign[0] * a1 + dh.theta_offset[0]
        x_a1 = wrist[axis, None, 0] * np.cos(dh_a1) + wrist[axis, None, 1] * np.sin(dh_a1)
        behind[axis] = x_a1 < 0
    return configuration_code(behind[:, :, None], a3 >= robot.phi_rad, False)


OFF_AXIS_MM = 1e-100  # mm: |x|, |y| of a wrist point off the A1 axis are far above this


def _status(robot: DHArm, q: np.ndarray, wrist: np.ndarray) -> np.ndarray:
    """Configuration code (N,) of joint vectors q (N, 6) rad whose wrist point is ``wrist``
    (N, 3) mm."""
    return configuration_code(*arm_flags(robot, q, wrist))


def ik_codes_at(robot: DHArm, q: np.ndarray, wrist: np.ndarray) -> tuple[np.ndarray, ...]:
    """Configuration and sign codes (N,) of joint vectors q (N, 6) rad whose wrist points
    ``wrist`` (N, 3) mm are known (saves the forward kinematics of ``ik_codes``)."""
    return _status(robot, q, wrist), sign_code(q < 0)


def select(robot: DHArm, flange, wrist, status, reference) -> tuple[np.ndarray, ...]:
    """The solution ``Robot.ik`` picks per flange pose (N, 4, 4), before the sign code and
    limits: q (N, 6) rad in (-pi, pi] (NaN where none), found (N,), any candidate reachable (N,).

    Code bits 0 and 1 (shoulder, elbow) follow from the 4 arm solutions alone (theta_2 is
    solved only for the chosen one); where one arm solution has the wanted bits, only its 2
    wrists are solved, and with a given code only the joints of the wrist with the wanted
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
        # the arm solution has the wanted bits 0 and 1 (its code, the same numbers as its
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


def _select_all(robot: DHArm, flange, wrist, want, rows, reference):
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
    """Candidates (M, 6) with the wanted code; on the wrist singularity (A5 = 0) either bit 2
    fits."""
    singular_wrist = np.abs(q[:, 4]) < closed.SINGULAR_A5_RAD
    return (cand_status == want) | (singular_wrist & ((cand_status & 3) == (want & 3)))
