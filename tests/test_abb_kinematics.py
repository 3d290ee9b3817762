"""The built-in ABB IRB 6700-200/2.60: FK against an independent description of the arm (the
joint origins and axes of ROS-Industrial's URDF, composed in plain numpy), ABB's published
figures, ABB confdata (cf1, cf4, cf6 quadrants; cfx from the RAPID manual's table) and the IK
that solves a pose in a given confdata."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from accugrid.codegen.rapid.configuration import abb_confdata, abb_quadrant, ik_confdata
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

TOOL = pose_from_xyzabc([12.0, -30.0, 250.0, 10.0, 20.0, -5.0])
# ROS-Industrial abb_irb6700_support, irb6700_200_260: joint origins (mm) and axes; tool0 turned
# by +90 deg about the flange's Y
URDF_JOINTS = (
    ((0.0, 0.0, 780.0), "z"),
    ((320.0, 0.0, 0.0), "y"),
    ((0.0, 0.0, 1125.0), "y"),
    ((0.0, 0.0, 200.0), "x"),
    ((1142.5, 0.0, 0.0), "y"),
    ((200.0, 0.0, 0.0), "x"),
)
# ABB data sheet working range, deg
LIMITS_DEG = ((-170, 170), (-65, 85), (-180, 70), (-300, 300), (-130, 130), (-360, 360))


@lru_cache(maxsize=2)
def robot(tool: bool = False):
    r = load_robot("irb6700")
    return r.with_tool(TOOL) if tool else r


def within_limits(n: int, margin_deg: float = 0.0):
    """Random joint vectors (n, 6) rad inside the data sheet's working range (less a margin)."""
    limits = np.radians(np.array(LIMITS_DEG, dtype=float))
    lo, hi = limits[:, 0] + np.radians(margin_deg), limits[:, 1] - np.radians(margin_deg)
    return arrays(float, (n, 6), elements=st.floats(0.0, 1.0)).map(lambda u: lo + u * (hi - lo))


def urdf_frames(q: np.ndarray) -> list[np.ndarray]:
    """Per joint vector q (6,) rad: the pose of every joint frame after its rotation, then tool0
    (4, 4) mm, composed from ``URDF_JOINTS`` as a URDF does."""
    pose, frames = np.eye(4), []
    for (origin, axis), angle in zip(URDF_JOINTS, q, strict=True):
        step = np.eye(4)
        step[:3, 3] = origin
        step[:3, :3] = Rotation.from_euler(axis, angle).as_matrix()
        pose = pose @ step
        frames.append(pose)
    tool0 = np.eye(4)
    tool0[:3, :3] = Rotation.from_euler("y", 90, degrees=True).as_matrix()
    frames.append(pose @ tool0)
    return frames


def manual_cfx(q: np.ndarray) -> int:
    """cfx by the RAPID manual's table, from the URDF chain's points: wrist centre (axis 5's
    origin) behind axis 1 (negative along the arm's forward direction), behind the lower arm
    (on the far side of the line axis 2 -> axis 3 from where the forearm leans in the zero
    pose), axis 5 negative."""
    frames = urdf_frames(q)
    axis2, axis3, wrist = frames[1][:3, 3], frames[2][:3, 3], frames[4][:3, 3]
    forward, side = frames[0][:3, 0], frames[0][:3, 1]  # axis 1's turned X and Y
    behind_axis1 = wrist[:2] @ forward[:2] < 0
    behind_arm = np.cross(axis3 - axis2, wrist - axis2) @ side < 0
    return 4 * int(behind_axis1) + 2 * int(behind_arm) + int(q[4] < 0)


def off_singularities(q: np.ndarray) -> np.ndarray:
    """The rows of q (n, 6) rad at least 1 deg off the wrist singularity (axis 5 = 0) and the
    stretched or folded arm, with the wrist centre 10 mm off axis 1: where a pose has 8 distinct
    solutions, so its confdata names one joint vector."""
    r = robot()
    wrist = np.array([urdf_frames(qk)[4][:3, 3] for qk in q]).reshape(-1, 3)
    bend = q[:, 2] - r.phi_rad  # 0 stretched, +-180 deg folded
    away = np.radians(1.0)
    keep = (np.abs(np.sin(q[:, 4])) > np.sin(away)) & (np.abs(np.sin(bend)) > np.sin(away))
    return q[keep & (np.hypot(wrist[:, 0], wrist[:, 1]) > 10.0)]


@given(q=within_limits(8))
def test_fk_is_the_urdf_chain_of_ros_industrial(q):
    expected = np.array([urdf_frames(qk)[-1] for qk in q])
    np.testing.assert_allclose(robot().fk(q), expected, rtol=0, atol=1e-9)


def test_limits_are_the_data_sheet_working_range():
    np.testing.assert_array_equal(robot().joint_limits_deg, np.array(LIMITS_DEG, dtype=float))


def test_zero_position_is_abbs_calibration_pose():
    # all axes 0: lower arm vertical, forearm horizontal; flange 780 + 1125 + 200 = 2105 high,
    # 320 + 1142.5 + 200 = 1662.5 in front of axis 1, tool0 Z forward and X down (RAPID orient
    # [0.70711, 0, 0.70711, 0], q1 = w first)
    pose = robot().fk(np.zeros(6))[0]
    np.testing.assert_allclose(pose[:3, 3], [1662.5, 0.0, 2105.0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(pose[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(pose[:3, 0], [0.0, 0.0, -1.0], atol=1e-12)
    x, y, z, w = Rotation.from_matrix(pose[:3, :3]).as_quat()
    np.testing.assert_allclose(np.abs([w, x, y, z]), [0.5**0.5, 0, 0.5**0.5, 0], atol=1e-12)
    wrist = pose[:3, 3] - 200.0 * pose[:3, 2]
    np.testing.assert_allclose(wrist, [1462.5, 0.0, 2105.0], rtol=0, atol=1e-9)


def test_stretched_arm_reaches_the_catalogue_260_m():
    # "IRB 6700-200/2.60": 2.60 m reach, axis 1 to the wrist centre with the arm stretched out
    # horizontally (axis 3 at phi: axes 2, 3 and the wrist centre in line)
    r = robot()
    q = np.array([[0.0, np.pi / 2, r.phi_rad, 0.0, 0.0, 0.0]])
    pose = r.fk(q)[0]
    wrist = pose[:3, 3] - 200.0 * pose[:3, 2]
    np.testing.assert_allclose(wrist[1:], [0.0, 780.0], atol=1e-9)
    assert round(wrist[0] / 1000, 2) == 2.60
    np.testing.assert_allclose(wrist[0], 320 + 1125 + np.hypot(1142.5, 200), atol=1e-9)


def test_positive_axes_turn_the_abb_way():
    # axis 1 counter-clockwise from above, axis 2 leans forward, axis 3 tips the forearm down
    r = robot()
    base = r.fk(np.zeros(6))[0, :3, 3]
    turned = r.fk(np.radians([[30, 0, 0, 0, 0, 0]]))[0, :3, 3]
    assert turned[1] > 0
    leaned = r.fk(np.radians([[0, 10, 0, 0, 0, 0]]))[0, :3, 3]
    assert leaned[0] > base[0] and leaned[2] < base[2]
    tipped = r.fk(np.radians([[0, 0, 10, 0, 0, 0]]))[0, :3, 3]
    assert tipped[2] < base[2]


@pytest.mark.parametrize(
    ("deg", "quadrant"),
    [
        (0.0, 0),
        (-0.0, 0),
        (45.0, 0),
        (90.0, 1),
        (179.0, 1),
        (180.0, 2),
        (300.0, 3),
        (360.0, 4),
        (-1e-9, -1),
        (-45.0, -1),
        (-90.0, -1),
        (-91.0, -2),
        (-180.0, -2),
        (-300.0, -4),
    ],
)
def test_quadrants_are_numbered_as_the_rapid_manual(deg, quadrant):
    # quadrant 0 is 0..90 deg in the positive direction, 1 is 90..180, -1 is 0..-90, ...; an
    # exact multiple of 90 deg starts its quadrant (floor)
    assert abb_quadrant(np.radians(deg)) == quadrant


def test_confdata_of_known_poses():
    r = robot()
    cases = {
        (0, 0, 0, 0, 30, 0): [0, 0, 0, 0],
        (0, 0, 0, 0, -30, 0): [0, 0, 0, 1],
        (100, 0, 0, -100, 30, 200): [1, -2, 2, 0],
        (-10, 0, -90, 10, 30, -10): [-1, 0, -1, 2],  # forearm raised past the lower arm's line
        (0, -60, -30, 0, 30, 0): [0, 0, 0, 4],  # lower arm leaning back: behind axis 1
        (0, -60, -150, 0, 30, 0): [0, 0, 0, 6],  # and the forearm raised past its line
    }
    for q_deg, expected in cases.items():
        q = np.radians([q_deg])
        assert manual_cfx(q[0]) == expected[3], q_deg
        np.testing.assert_array_equal(abb_confdata(r, q)[0], expected, err_msg=str(q_deg))


@given(q=within_limits(16))
def test_cfx_is_the_rapid_manual_table(q):
    expected = [manual_cfx(qk) for qk in q]
    np.testing.assert_array_equal(abb_confdata(robot(), q)[:, 3], expected)


@settings(max_examples=40)
@given(q=within_limits(16), tool=st.booleans())
def test_ik_in_the_confdata_of_a_pose_gives_back_that_pose(q, tool):
    r = robot(tool=tool)
    q = off_singularities(q)
    confdata = abb_confdata(r, q)
    sol = ik_confdata(r, r.fk(q), confdata)
    assert sol.ok.all(), sol.reason[~sol.ok]
    np.testing.assert_allclose(sol.q, q, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(abb_confdata(r, sol.q), confdata)
    np.testing.assert_array_equal(sol.status, ik_codes(r, sol.q)[0])


@settings(max_examples=30)
@given(q=within_limits(8), cfx=st.integers(0, 7))
def test_every_cfx_gives_the_branch_with_that_confdata_or_a_reason(q, cfx):
    # the pose's branch with that cfx (found among all 8 by the manual's table), asked for with
    # its own cf1/cf4/cf6 so the request is consistent; a pose without it has no solution
    r = robot()
    q = off_singularities(q)
    target = r.fk(q)
    every, reach = r.ik_all(target)
    flat = zip(every.reshape(-1, 6), reach.reshape(-1), strict=True)
    cand_cfx = np.array([manual_cfx(c) if ok else -1 for c, ok in flat]).reshape(len(q), 8)
    has = (cand_cfx == cfx).any(axis=1)
    branch = every[np.arange(len(q)), np.argmax(cand_cfx == cfx, axis=1)]
    wanted = abb_confdata(r, np.where(has[:, None], branch, q))
    wanted[:, 3] = cfx
    sol = ik_confdata(r, target, wanted)
    assert (sol.reason[~has] == "no solution with the requested cfx").all()
    # axes 1, 4, 6: the branch's own turn (its quadrants were asked for); 2, 3, 5 any turn
    lo, hi = np.radians(r.joint_limits_deg).T - [[1e-9], [-1e-9]]
    turns = branch[:, :, None] + np.array([0.0, -2 * np.pi, 2 * np.pi])
    fits = (turns >= lo[:, None]) & (turns <= hi[:, None])
    inside = fits[:, [0, 3, 5], 0].all(axis=1) & fits[:, [1, 2, 4]].any(axis=2).all(axis=1)
    np.testing.assert_array_equal(sol.ok, has & inside)
    assert all("outside limits" in reason for reason in sol.reason[has & ~inside])
    found = has & inside
    np.testing.assert_allclose(sol.q[found][:, [0, 3, 5]], branch[found][:, [0, 3, 5]], atol=1e-9)
    gap = (sol.q[found] - branch[found] + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(gap, 0.0, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(abb_confdata(r, sol.q[found]), wanted[found])
    np.testing.assert_allclose(r.fk(sol.q[found]), target[found], rtol=0, atol=1e-9)


def test_wrong_or_unreachable_confdata_is_refused_with_the_reason():
    r = robot()
    q = np.radians([[20.0, 10.0, -20.0, 40.0, 50.0, 60.0]])
    pose = r.fk(q)
    good = abb_confdata(r, q)[0]
    np.testing.assert_array_equal(good, [0, 0, 0, 0])
    cases = [
        ([2, 0, 0, 0], "A1 cannot be in quadrant cf1 with this cfx"),  # cf1 says behind axis 1
        ([-1, 0, 0, 0], "A1 cannot be in quadrant cf1 with this cfx"),
        ([0, 1, 0, 0], "A4 cannot be in quadrant cf4 with this cfx"),
        ([0, 2, 0, 0], "A4 cannot be in quadrant cf4 with this cfx"),  # the flipped wrist's
        ([0, 0, 3, 0], "A6 cannot be in quadrant cf6 with this cfx"),
        ([0, -3, 0, 0], "A4 cannot be in quadrant cf4 with this cfx"),
        ([0, -4, 0, 0], "A4 outside limits -300..300 deg"),  # 40 - 360 deg
        ([0, 4, 0, 0], "A4 outside limits -300..300 deg"),  # 40 + 360 deg
        ([0, 0, 0, 2], "A6 cannot be in quadrant cf6 with this cfx"),  # elbow down: A6 94 deg
        ([2, 0, 0, 4], "no solution with the requested cfx"),  # behind axis 1: out of reach
    ]
    for confdata, reason in cases:
        sol = ik_confdata(r, pose, confdata)
        assert not sol.ok[0], confdata
        assert sol.reason[0] == reason, (confdata, sol.reason[0])
    elbow_down = ik_confdata(r, pose, [0, 0, 1, 2])
    assert elbow_down.ok[0], elbow_down.reason[0]
    np.testing.assert_array_equal(abb_confdata(r, elbow_down.q)[0], [0, 0, 1, 2])
    np.testing.assert_allclose(r.fk(elbow_down.q), pose, rtol=0, atol=1e-9)
    far = pose.copy()
    far[0, :3, 3] = [4000.0, 0.0, 1000.0]
    sol = ik_confdata(r, far, good)
    assert not sol.ok[0] and sol.reason[0] == "unreachable"
    assert np.isnan(sol.q[0]).all()
    sol = ik_confdata(r, np.concatenate([pose, pose]), [good, [0, 4, 0, 0]])
    np.testing.assert_array_equal(sol.ok, [True, False])
    np.testing.assert_allclose(sol.q[0], q[0], atol=1e-9)
    np.testing.assert_allclose(sol.q[1, 3], q[0, 3] + 2 * np.pi, atol=1e-9)  # the turn asked for


def test_angles_on_a_quadrant_edge_keep_the_wanted_quadrant():
    # axis 1 at exactly 0, axis 4 at 90 and axis 6 at -90 deg: the IK's round-off must not move
    # them into the neighbouring quadrant; and as the manual leaves the edge itself open, a
    # confdata that names the quadrant on the other side of it is solved too (1 ulp inside it)
    r = robot()
    q = np.radians([[0.0, 10.0, -20.0, 90.0, 50.0, -90.0]])
    confdata = abb_confdata(r, q)
    np.testing.assert_array_equal(confdata, [[0, 1, -1, 0]])
    for wanted in ([0, 1, -1, 0], [-1, 0, -2, 0]):
        sol = ik_confdata(r, r.fk(q), wanted)
        assert sol.ok[0], sol.reason[0]
        np.testing.assert_array_equal(abb_confdata(r, sol.q)[0], wanted)
        np.testing.assert_allclose(sol.q, q, rtol=0, atol=1e-9)


@settings(max_examples=40)
@given(
    q=within_limits(40),
    cfx=arrays(int, 40, elements=st.integers(-1, 8)),
    tool=st.booleans(),
)
def test_cfx_branch_is_the_pick_over_all_8_candidates(q, cfx, tool):
    """``_cfx_branch`` solves only the wrists of the arm solution cfx names where that is clear;
    its numbers must be the first match over all 8 candidates, bit for bit (cfx -1 and 8, which
    name no solution, included)."""
    from accugrid.codegen.rapid.configuration import _cfx_branch, _cfx_candidates
    from accugrid.kinematics import ik

    r = robot(tool=tool)
    flange = r.fk(q) @ np.linalg.inv(r.flange_T_tool)
    wrist = ik.wrist_points(r.dh, flange)
    got, reason = _cfx_branch(r, flange, wrist, cfx)
    every, every_reason = _cfx_candidates(r, flange, wrist, cfx)
    np.testing.assert_array_equal(got, every)
    np.testing.assert_array_equal(reason, every_reason)
    assert (reason[(cfx < 0) | (cfx > 7)] == "no solution with the requested cfx").all()
