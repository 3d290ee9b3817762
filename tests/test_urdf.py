"""URDF robots through Pinocchio: FK against a hand-written product, numeric IK, YAML errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.infra.errors import InputError
from accugrid.kinematics.model import RobotModel
from accugrid.kinematics.robot import load_robot

# A 6R arm with lengths in metres: Z, Y, Y joints to a wrist, then Z, Y, Z (spherical wrist).
URDF = """<?xml version="1.0"?>
<robot name="tiny">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
  <link name="l4"/><link name="l5"/><link name="flange"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.4"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0 0 0.6"/><axis xyz="0 1 0"/>
    <limit lower="-2.5" upper="2.5" effort="1" velocity="1"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.5 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="flange"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


def write_robot(folder, yaml_text="name: tiny\nurdf: tiny.urdf\ntip: flange\n"):
    (folder / "tiny.urdf").write_text(URDF)
    path = folder / "tiny.yaml"
    path.write_text(yaml_text)
    return path


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    out = np.eye(4)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


def trans(x: float, y: float, z: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = [x, y, z]
    return out


def hand_fk(q: np.ndarray) -> np.ndarray:
    """The URDF's chain written out, mm."""
    steps = [
        (trans(0, 0, 400), "z"),
        (trans(100, 0, 0), "y"),
        (trans(0, 0, 600), "y"),
        (trans(500, 0, 0), "x"),
        (trans(0, 0, 0), "y"),
        (trans(100, 0, 0), "x"),
    ]
    pose = np.eye(4)
    for (origin, axis), angle in zip(steps, q, strict=True):
        pose = pose @ origin @ rot(axis, angle)
    return pose


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    return load_robot(write_robot(tmp_path_factory.mktemp("urdf")))


def test_fk_matches_the_written_out_chain_in_mm(tiny):
    q = np.array([[0.3, -0.4, 0.7, 0.2, -0.5, 1.1], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(tiny.fk(q), np.array([hand_fk(qk) for qk in q]), atol=1e-9)
    np.testing.assert_allclose(tiny.joint_limits_deg[1], np.degrees([-2.0, 2.0]))


@settings(max_examples=15)
@given(u=arrays(float, (4, 6), elements=st.floats(0.1, 0.9)))
def test_numeric_ik_reaches_poses_of_the_arm(tiny, u):
    lo, hi = np.radians(tiny.joint_limits_deg).T
    target = tiny.fk(lo + u * (hi - lo))
    sol = tiny.ik(target)
    reached = tiny.fk(sol.q[sol.ok])
    np.testing.assert_allclose(reached[:, :3, 3], target[sol.ok, :3, 3], atol=1e-6)
    np.testing.assert_allclose(reached[:, :3, :3], target[sol.ok, :3, :3], atol=1e-9)
    assert all(reason for reason in sol.reason[~sol.ok])


def test_numeric_ik_solves_poses_of_the_arm_within_limits(tiny):
    lo, hi = np.radians(tiny.joint_limits_deg).T
    u = np.random.default_rng(3).uniform(0.1, 0.9, size=(40, 6))
    sol = tiny.ik(tiny.fk(lo + u * (hi - lo)))
    assert sol.ok.all(), sol.reason[~sol.ok]
    assert ((sol.q >= lo) & (sol.q <= hi)).all()


def test_unreachable_pose_and_status_are_reported(tiny):
    far = trans(5000, 0, 0)
    sol = tiny.ik(far[None])
    assert not sol.ok[0] and "unreachable" in sol.reason[0]
    with pytest.raises(InputError, match="no KUKA Status/Turn"):
        tiny.ik(far[None], status=2)


def test_bad_tip_and_missing_urdf_name_the_key(tmp_path):
    path = write_robot(tmp_path, "name: tiny\nurdf: tiny.urdf\ntip: hand\n")
    with pytest.raises(InputError, match=r"tiny.yaml:3:\d+: 'tip': no frame 'hand'"):
        load_robot(path)
    path.write_text("name: tiny\nurdf: none.urdf\ntip: flange\n")
    with pytest.raises(InputError, match="'urdf': URDF file not found"):
        load_robot(path)
    (tmp_path / "tiny.urdf").write_text("<robot name='x'><link></robot>")
    path.write_text("name: tiny\nurdf: tiny.urdf\ntip: flange\n")
    with pytest.raises(InputError, match="tiny.urdf"):
        load_robot(path)


def test_simulation_of_a_urdf_robot_reaches_the_commanded_points(tiny):
    from accugrid.kinematics.simulation import reached_positions

    points = np.array([[500.0, 0.0, 700.0], [550.0, 50.0, 750.0], [500.0, -60.0, 800.0]])
    np.testing.assert_allclose(reached_positions(tiny, points, [0, 90, 0]), points, atol=1e-6)


def test_dh_and_urdf_robots_are_robot_models(tiny):
    assert isinstance(load_robot("kr210"), RobotModel)
    assert isinstance(tiny, RobotModel)
