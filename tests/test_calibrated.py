"""The calibrated robot file and its URDF: reload to the same FK, Pinocchio agrees, wrong robot."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from accugrid.infra.errors import InputError
from accugrid.kinematics.calibrated import calibrated_yaml, check_same_robot
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import Robot, load_robot

KR210 = load_robot("kr210")
Q = np.radians(
    [[0, -90, 90, 0, 0, 0], [30, -60, 100, 45, 60, -80], [-120, -130, 10, -170, -100, 300]]
)


def calibrated(errors: np.ndarray, tool_xyzabc) -> Robot:
    return Robot(
        "kr210-cal", KR210.dh, KR210.joint_limits_deg, pose_from_xyzabc(tool_xyzabc), errors
    )


small = st.floats(-2.0, 2.0, allow_nan=False)
angles = st.floats(-180.0, 180.0, allow_nan=False)


@given(
    errors=arrays(float, (6, 4), elements=st.floats(-1e-2, 1e-2, allow_nan=False)),
    tool=st.tuples(small, small, st.floats(0, 400), angles, st.floats(-89, 89), angles),
)
def test_written_yaml_reloads_to_the_same_fk(tmp_path_factory, errors, tool):
    robot = calibrated(errors, tool)
    path = tmp_path_factory.mktemp("cal") / "cal.yaml"
    summary = {"robot": "kr210", "poses": 40, "parameters": [{"name": "da1", "value": 1.0}]}
    path.write_text(calibrated_yaml(robot, summary, header="a header\nof two lines"))
    loaded = load_robot(path)
    np.testing.assert_array_equal(loaded.errors, robot.errors)
    np.testing.assert_allclose(loaded.true_robot().fk(Q), robot.true_robot().fk(Q), atol=1e-9)
    np.testing.assert_allclose(loaded.fk(Q), robot.fk(Q), atol=1e-9)


def test_header_lines_are_comments_and_identification_is_kept(tmp_path):
    text = calibrated_yaml(calibrated(np.zeros((6, 4)), [0, 0, 100, 0, 0, 0]), {"poses": 60}, "h")
    assert text.startswith("# h\nname: kr210-cal\n")
    assert yaml.safe_load(text)["identification"] == {"poses": 60}


def test_urdf_through_pinocchio_gives_the_calibrated_fk(tmp_path):
    from accugrid.kinematics.urdf_export import urdf_text

    rng = np.random.default_rng(0)
    errors = load_robot("kr210-paper").errors
    robot = calibrated(errors, [20.1, -9.8, 250.3, 10, 20, 30])
    (tmp_path / "cal.urdf").write_text(urdf_text(robot))
    (tmp_path / "cal.yaml").write_text("name: from-urdf\nurdf: cal.urdf\ntip: tcp\n")
    urdf_robot = load_robot(tmp_path / "cal.yaml")
    q = rng.uniform(-2.0, 2.0, (50, 6))
    np.testing.assert_allclose(urdf_robot.fk(q), robot.true_robot().fk(q), atol=1e-6)
    # the URDF joint value is the KUKA axis angle: the KUKA limits, in rad
    np.testing.assert_allclose(urdf_robot.joint_limits_deg, KR210.joint_limits_deg)


def test_model_of_another_robot_is_refused():
    other_dh = KR210.dh.with_errors(np.array([[0, 0, 0, 0], [50.0, 0, 0, 0]] + [[0] * 4] * 4))
    other = Robot("kr240", other_dh, KR210.joint_limits_deg)
    with pytest.raises(
        InputError,
        match=r"cal.yaml: model kr240 is of another robot than kr210: "
        r"dh\[1\].a_mm 1200 vs 1150",
    ):
        check_same_robot(other, KR210, "cal.yaml")
    check_same_robot(load_robot("kr210-paper"), KR210)  # same nominal model: accepted


def test_compliance_section_reloads(tmp_path):
    from accugrid.kinematics.joint_errors import JointErrors

    masses = load_robot("kr210-realistic").joint_errors.masses
    moves = JointErrors.from_compliance([0, 1.5e-7, 2.5e-7, 0, 0, 0], masses)
    robot = Robot("c", KR210.dh, KR210.joint_limits_deg, np.eye(4), np.zeros((6, 4)), "", moves)
    path = tmp_path / "cal.yaml"
    path.write_text(calibrated_yaml(robot))
    loaded = load_robot(path)
    np.testing.assert_array_equal(loaded.joint_errors.compliance, moves.compliance)
    np.testing.assert_array_equal(loaded.true_robot().fk(Q), robot.true_robot().fk(Q))


def test_the_structure_read_back_keeps_the_chosen_order_of_the_gravity_groups():
    """identify orders a model's parameters as its structure chose the groups; a file that chose
    A3's group before A2's must give back the same columns, or every command refuses it (the
    support's and the budget's parameters no longer match)."""
    from accugrid.kinematics.calibrated import model_structure

    robot = load_robot("kr210")
    chosen = ["gravity A3 forearm", "gravity A2 upper arm", "A2 k15"]
    _, _, gravity = model_structure(robot, chosen)
    assert [t.name for t in gravity] == ["gravity A3 forearm", "gravity A2 upper arm"]
