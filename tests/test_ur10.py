"""The built-in UR10 against real data: the nominal model's FK of the joints the UR controller
logged reproduces the positions it was commanded to (Series C of ../shared/realdata/ipa-ur10)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

SERIES_C = Path("ipa-ur10", "Series_C", "measurements_random_poses.csv")
JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
# the data set's commanded TCP: the T-Mac probe's origin 109 mm along the flange z, its frame
# turned 90 deg about z (the commanded orientations are the flange's turned so, within 0.1 deg)
TMAC = pose_from_xyzabc([0.0, 0.0, 109.0, 90.0, 0.0, 0.0])


def read_series(path: Path) -> dict[str, np.ndarray]:
    """The columns of one of the data set's files as it comes (``;`` separated, decimal comma)."""
    lines = path.read_text().splitlines()
    names = lines[0].split(";")
    values = np.array([line.replace(",", ".").split(";") for line in lines[1:]], dtype=float)
    return dict(zip(names, values.T, strict=True))


@pytest.fixture(scope="module")
def series_c(realdata: Path) -> dict[str, np.ndarray]:
    return read_series(realdata / SERIES_C)


def commanded(series: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Logged joints (N, 6) rad and the commanded TCP positions (N, 3) mm, robot base frame."""
    q = np.stack([series[name] for name in JOINTS], axis=1)
    return q, 1000.0 * np.stack([series[f"Goal {axis}"] for axis in "xyz"], axis=1)


def test_ur10_zero_pose_is_the_stretched_arm():
    flange = load_robot("ur10").fk(np.zeros((1, 6)))[0]
    np.testing.assert_allclose(flange[:3, 3], [1184.3, 256.141, 11.6], atol=1e-9)
    np.testing.assert_allclose(flange[:3, :3], [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], atol=1e-12)


def test_ur10_nominal_fk_of_logged_joints_reproduces_the_commanded_tcp(series_c):
    """The controller's own calibration moves the TCP 0.03-0.4 mm from the nominal model (the
    data set's README: 0.04-0.15 mm typical); a wrong base convention, axis zero or link
    length would miss by tens to thousands of mm."""
    q, goal = commanded(series_c)
    assert len(q) == 2773
    tcp = load_robot("ur10").with_tool(TMAC).fk(q)
    miss = np.linalg.norm(tcp[:, :3, 3] - goal, axis=1)
    assert 0.04 <= miss.mean() <= 0.15, miss.mean()
    assert np.percentile(miss, 95) <= 0.2
    assert miss.max() <= 0.45
    # orientation: R = Rz(yaw) Ry(pitch) Rx(roll) of the commanded roll, pitch, yaw (rad)
    rpy = np.stack([series_c[f"Goal {k}"] for k in ("roll", "pitch", "yaw")], axis=1)
    goal_rot = Rotation.from_euler("xyz", rpy).as_matrix()
    cos_angle = (np.einsum("nij,nij->n", tcp[:, :3, :3], goal_rot) - 1) / 2
    assert np.degrees(np.arccos(np.clip(cos_angle, -1, 1))).max() <= 0.1
