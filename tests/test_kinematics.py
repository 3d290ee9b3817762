"""Robot model: FK against independent references, closed-form IK with KUKA Status/Turn, limits,
robot YAML errors."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.infra.errors import InputError
from accugrid.kinematics.configuration import Configuration, ik_codes
from accugrid.kinematics.dh import chain
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "kinematics" / "robots"
TOOL = pose_from_xyzabc([12.0, -30.0, 250.0, 10.0, 20.0, -5.0])


@lru_cache(maxsize=4)
def robot(name: str = "kr210", tool: bool = False):
    r = load_robot(name)
    return r.with_tool(TOOL) if tool else r


def joints_within_limits(n: int, margin_deg: float = 0.0):
    """Random joint vectors (n, 6) rad inside the KR 210 limits (less a margin)."""
    limits = np.radians(robot().joint_limits_deg)
    lo, hi = limits[:, 0] + np.radians(margin_deg), limits[:, 1] - np.radians(margin_deg)
    return arrays(float, (n, 6), elements=st.floats(0.0, 1.0)).map(lambda u: lo + u * (hi - lo))


def reference_fk(yaml_path: Path, q: np.ndarray) -> np.ndarray:
    """Seed Eq. 2 per pose in plain numpy, read straight from the robot YAML: (N, 4, 4) mm."""
    rows = yaml.safe_load(yaml_path.read_text())["dh"]
    out = []
    for qk in q:
        pose = np.eye(4)
        for row, angle in zip(rows, qk, strict=True):
            theta = row["sign"] * angle + np.radians(row["theta_offset_deg"])
            alpha = np.radians(row["alpha_deg"])
            rot_z = np.array(
                [
                    [np.cos(theta), -np.sin(theta), 0, 0],
                    [np.sin(theta), np.cos(theta), 0, 0],
                    [0, 0, 1, 0],
                    [0, 0, 0, 1],
                ]
            )
            trans_z = np.eye(4)
            trans_z[2, 3] = row["d_mm"]
            trans_x = np.eye(4)
            trans_x[0, 3] = row["a_mm"]
            rot_x = np.array(
                [
                    [1, 0, 0, 0],
                    [0, np.cos(alpha), -np.sin(alpha), 0],
                    [0, np.sin(alpha), np.cos(alpha), 0],
                    [0, 0, 0, 1],
                ]
            )
            pose = pose @ rot_z @ trans_z @ trans_x @ rot_x
        out.append(pose)
    return np.array(out)


@pytest.mark.parametrize("name", ["kr210", "kr210-paper"])
def test_home_pose_is_the_kuka_data_sheet_pose(name):
    home = np.radians([[0.0, -90.0, 90.0, 0.0, 0.0, 0.0]])
    pose = load_robot(name).fk(home)[0]
    np.testing.assert_allclose(pose[:3, 3], [1765.0, 0.0, 1784.0], atol=1e-9)
    np.testing.assert_allclose(pose[:3, :3], abc_to_matrix([0.0, 90.0, 0.0]), atol=1e-12)


@given(q=joints_within_limits(8))
def test_batched_fk_equals_plain_numpy_product_of_eq2(q):
    np.testing.assert_allclose(robot().fk(q), reference_fk(ROBOTS / "kr210.yaml", q), atol=1e-9)


@pytest.mark.parametrize("name", ["kr210", "irb6700"])
@given(q=joints_within_limits(8))
def test_fk_equals_pinocchio_forward_kinematics(name, q):
    r = robot(name, tool=True)
    model, frame = r.pinocchio_model()
    data = model.createData()
    expected = []
    for qk in q:
        pin.forwardKinematics(model, data, qk * r.dh.sign)
        pin.updateFramePlacements(model, data)
        expected.append(data.oMf[frame].homogeneous)
    np.testing.assert_allclose(r.fk(q), np.array(expected), atol=1e-9)


def test_true_robot_differs_by_the_table1_errors():
    q = np.radians([[10.0, -80.0, 100.0, 30.0, 40.0, 50.0]])
    nominal, true = robot("kr210-paper"), robot("kr210-paper").true_robot()
    assert robot("kr210").true_robot() is None
    gap = np.linalg.norm(true.fk(q)[0, :3, 3] - nominal.fk(q)[0, :3, 3])
    assert 0.5 < gap < 10.0  # seed: errors of a few mm


@settings(max_examples=40)
@given(q=joints_within_limits(16, margin_deg=0.5), tool=st.booleans())
def test_ik_with_the_status_and_turn_of_a_pose_gives_back_that_pose(q, tool):
    r = robot(tool=tool)
    q = q[np.abs(q[:, 4]) > 1e-3]  # off the wrist singularity (A5 = 0)
    target = r.fk(q)
    status, turn = ik_codes(r, q)
    sol = r.ik(target, status=status, turn=turn)
    assert sol.ok.all(), sol.reason[~sol.ok]
    reached = r.fk(sol.q)
    np.testing.assert_allclose(reached[:, :3, 3], target[:, :3, 3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(reached[:, :3, :3], target[:, :3, :3], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(sol.status, status)
    np.testing.assert_array_equal(sol.turn, turn)
    np.testing.assert_array_equal(ik_codes(r, sol.q)[0], status)
    # Status and Turn pick exactly one of the 8 x turns solutions: the joint vector itself.
    np.testing.assert_allclose(sol.q, q, atol=1e-6)


@settings(max_examples=30)
@given(q=joints_within_limits(16, margin_deg=0.5))
def test_default_ik_solves_the_pose_and_reports_its_status(q):
    r = robot()
    target = r.fk(q)
    sol = r.ik(target)
    good = sol.ok
    np.testing.assert_allclose(r.fk(sol.q[good]), target[good], atol=1e-9)
    np.testing.assert_array_equal(sol.status[good] & 3, 2)  # basic area, A3 >= phi
    s, t = ik_codes(r, sol.q[good])
    np.testing.assert_array_equal(s, sol.status[good])
    np.testing.assert_array_equal(t, sol.turn[good])


@given(
    xyz=arrays(float, (20, 3), elements=st.floats(-3500.0, 3500.0)),
    abc=arrays(float, (20, 3), elements=st.floats(-180.0, 180.0)),
    status=st.integers(0, 7),
)
def test_every_solution_is_within_limits_or_reported(xyz, abc, status):
    r = robot()
    poses = np.array([pose_from_xyzabc([*p, *o]) for p, o in zip(xyz, abc, strict=True)])
    sol = r.ik(poses, status=status)
    lo, hi = np.radians(r.joint_limits_deg).T
    q_ok = sol.q[sol.ok]
    assert ((q_ok >= lo - 1e-9) & (q_ok <= hi + 1e-9)).all()
    np.testing.assert_allclose(r.fk(q_ok), poses[sol.ok], atol=1e-8)
    assert all(reason == "" for reason in sol.reason[sol.ok])
    for k in np.flatnonzero(~sol.ok):
        reason = sol.reason[k]
        assert reason
        if reason.startswith("A"):  # "A<i> outside limits lo..hi deg": that axis really is
            axis = int(reason[1]) - 1
            assert not lo[axis] - 1e-9 <= sol.q[k, axis] <= hi[axis] + 1e-9


def test_unreachable_and_out_of_limit_poses_are_reported():
    r = robot()
    far = pose_from_xyzabc([5000.0, 0.0, 1000.0, 0.0, 90.0, 0.0])
    below_a2 = r.fk(np.radians([[0.0, -2.0, 90.0, 0.0, 30.0, 0.0]]))[0]  # A2 limit is -5
    sol = r.ik(np.array([far, below_a2]), status=2)
    assert not sol.ok.any()
    assert sol.reason[0] == "unreachable"
    assert sol.reason[1] == "A2 outside limits -140..-5 deg"


def test_phi_is_where_a2_axis_a3_axis_and_wrist_point_are_in_line():
    r = robot()
    assert np.degrees(r.phi_rad) == pytest.approx(-np.degrees(np.arctan(41.0 / 1200.0)))
    for a3, in_line in [(r.phi_rad, True), (r.phi_rad + 0.01, False)]:
        q = np.array([[0.3, -1.2, a3, 0.4, 0.5, 0.6]])
        frames = chain(r.dh, q)
        a2_axis, a3_axis, wrist = frames[0][0, :3, 3], frames[1][0, :3, 3], frames[3][0, :3, 3]
        cross = np.cross(a3_axis - a2_axis, wrist - a3_axis)
        assert (np.linalg.norm(cross) < 1e-6) == in_line
        # stretched: the wrist is as far from the A2 axis as it can be
        if in_line:
            reach = np.linalg.norm(wrist - a2_axis)
            assert reach == pytest.approx(1150.0 + np.hypot(41.0, 1200.0))
    status, _ = ik_codes(r, np.radians([[0, -90, 90, 0, 20, 0], [0, -90, -10, 0, -20, 0]]))
    assert list(status) == [2, 4]  # A3 = 90 >= phi, A5 > 0; A3 = -10 < phi, A5 < 0


def test_status_bit0_is_the_overhead_area():
    r = robot()
    # A2 = -135 deg leans the upper arm back past vertical, A3 = -30 deg stretches the forearm
    # further back: the wrist point is behind the A1 axis (checked from the chain below).
    behind = np.radians([[30.0, -135.0, -30.0, 0.0, 30.0, 0.0]])
    front = np.radians([[30.0, -90.0, 90.0, 0.0, 30.0, 0.0]])
    for q, sign in [(behind, -1), (front, 1)]:
        wrist = chain(r.dh, q)[3][0, :3, 3]
        assert np.sign(wrist[:2] @ [np.cos(-q[0, 0]), np.sin(-q[0, 0])]) == sign  # A1 turns -z
    assert ik_codes(r, behind)[0][0] & 1 == 1
    assert ik_codes(r, front)[0][0] & 1 == 0


def test_turn_bits_are_the_negative_axes():
    q = np.radians([[-1.0, -90.0, 90.0, -200.0, 10.0, 5.0]])
    assert ik_codes(robot(), q)[1][0] == 0b001011


def test_unknown_robot_name_is_a_clear_error():
    with pytest.raises(InputError, match="unknown robot 'kr999'.*kr210, kr210-paper"):
        load_robot("kr999")


def test_missing_robot_file_is_an_error(tmp_path):
    with pytest.raises(InputError, match="robot file not found"):
        load_robot(tmp_path / "none.yaml")


def _yaml_with(tmp_path: Path, old: str, new: str) -> Path:
    text = (ROBOTS / "kr210.yaml").read_text()
    assert old in text
    path = tmp_path / "robot.yaml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("d_mm: 675.0", "d_mm: abc", r"11:36: 'dh\[0\]\.d_mm' must be a finite number, got 'abc'"),
        ("a_mm: 1150.0, ", "", r"12:5: missing key 'dh\[1\]\.a_mm'"),
        ("sign: -1}", "sign: 2}", r"'dh\[0\]\.sign' must be 1 or -1"),
        (
            "  - [-140.0, -5.0]\n",
            "  - [-5.0, -140.0]\n",
            r"20:5: 'limits_deg\[1\]': min must be below max",
        ),
        ("  - [-125.0, 125.0]\n", "", r"'limits_deg' must have 6 entries, has 5"),
        ("name: kr210\n", "", "missing key 'name'"),
        ("dh:\n", "dh: [\n", "robot.yaml"),
    ],
)
def test_malformed_robot_yaml_names_the_key(tmp_path, old, new, message):
    path = _yaml_with(tmp_path, old, new)
    with pytest.raises(InputError, match=message) as info:
        load_robot(path)
    assert str(info.value).startswith(str(path))


def test_robot_yaml_error_carries_the_line(tmp_path):
    path = _yaml_with(tmp_path, "d_mm: 1200.0", "d_mm: .nan")
    with pytest.raises(InputError) as info:
        load_robot(path)
    assert info.value.line == 14  # the dh[3] row


def test_neutral_configuration_names_the_branches_and_round_trips_kuka():
    q = np.radians([[0, -90, 90, 0, 20, 0], [30.0, -135.0, -30.0, 0.0, -30.0, -5.0]])
    config = Configuration.of_joints(robot(), q)
    np.testing.assert_array_equal(config.shoulder, [False, True])  # second: behind the A1 axis
    np.testing.assert_array_equal(config.elbow, [True, False])  # A3 = 90 >= phi; -30 < phi
    np.testing.assert_array_equal(config.wrist, [False, True])  # A5 < 0
    np.testing.assert_array_equal(config.negative, q < 0)
    np.testing.assert_array_equal(config.code, [2, 5])
    np.testing.assert_array_equal(config.quarter, np.floor(np.degrees(q) / 90))
    back = Configuration.of_code(config.code, config.quarter)
    for name in ("shoulder", "elbow", "wrist", "quarter"):
        np.testing.assert_array_equal(getattr(back, name), getattr(config, name))


def _flange_poses_near_branches(q: np.ndarray, r) -> np.ndarray:
    """Flange poses (N, 4, 4) of joint vectors q (N, 6) rad, with A5 = 0 (the wrist
    singularity) and A5 = +-1e-13 for some of them."""
    q = q.copy()
    q[::7, 4] = 0.0
    q[1::7, 4] = 1e-13
    q[2::7, 4] = -1e-13
    return r.fk(q) @ np.linalg.inv(r.flange_T_tool)


@settings(max_examples=60, deadline=None)
@given(
    xy=arrays(
        float,
        (30, 2),
        elements=st.one_of(
            st.floats(-3000, 3000),
            st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 1e-200, 1e-310, 1e-12]),
        ),
    ),
    z=st.floats(-500, 2500),
    name=st.sampled_from(["kr210", "kr210-paper"]),
)
def test_the_shoulder_bits_of_the_arm_solutions_are_the_shoulder_sign_test(xy, z, name):
    """``_arm_status`` takes the shoulder bit from the solution's index off the A1 axis: the
    same bits as the sign of the wrist point along each solution's A1 direction, also for
    wrist points on the axis or a subnormal distance from it."""
    from accugrid.kinematics import ik
    from accugrid.kinematics.configuration import _arm_status

    r = robot(name)
    wrist = np.column_stack([xy, np.full(len(xy), z)])
    th1, th3, _, _ = ik.arm_elbows(r.dh, wrist)
    dh = r.dh
    a1 = ik.wrap((th1 - dh.theta_offset[0]) * dh.sign[0])  # KUKA A1, then back to DH
    dh_a1 = dh.sign[0] * a1 + dh.theta_offset[0]
    behind = wrist[:, None, 0] * np.cos(dh_a1) + wrist[:, None, 1] * np.sin(dh_a1) < 0
    bits = _arm_status(r, th1, th3, wrist)  # (N, 2 shoulder, 2 elbow)
    np.testing.assert_array_equal(bits & 1 == 1, np.repeat(behind[:, :, None], 2, axis=2))


@settings(max_examples=25, deadline=None)
@given(
    q=joints_within_limits(40),
    status=arrays(int, 40, elements=st.integers(0, 7)),
    name=st.sampled_from(["kr210", "kr210-paper"]),
)
def test_branch_selection_is_the_pick_over_all_8_candidates(q, status, name):
    """``select`` solves only the wrists of the arm solution with the wanted Status bits where
    one fits; its pick must be, number for number, the first match over all 8 candidates."""
    from accugrid.kinematics import ik
    from accugrid.kinematics.configuration import _select_all, select

    r = robot(name, tool=True)
    flange = _flange_poses_near_branches(q, r)
    wrist = ik.wrist_points(r.dh, flange)
    rows = np.arange(len(q))
    for want in (status, np.full(len(q), status[0])):
        got, found, _ = select(r, flange, wrist, want, None)
        every, every_found = _select_all(r, flange, wrist, want, rows, None)
        np.testing.assert_array_equal(found, every_found)
        np.testing.assert_array_equal(got, every)
    got, found, _ = select(r, flange, wrist, None, None)  # the default: nearest the reference
    every, every_found = _select_all(r, flange, wrist, 2, rows, None)
    np.testing.assert_array_equal(found, every_found)
    np.testing.assert_array_equal(got, every)
