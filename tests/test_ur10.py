"""The built-in UR10, an arm without a spherical wrist: its nominal FK against the real data
(Series C of ../shared/realdata/ipa-ur10: the FK of the joints the UR controller logged
reproduces the positions it was commanded to), its numerical IK in the neutral configuration
words, the model path through the CLI, and identify on the real data, whose controller has its
own calibration."""

from __future__ import annotations

import csv
import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.codegen.rapid.configuration import ik_confdata
from accugrid.infra.errors import InputError
from accugrid.kinematics.configuration import ik_codes, wrist_points_of
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


# --- inverse kinematics: the UR has no spherical wrist, so ``Robot.ik`` solves it numerically

UR10 = load_robot("ur10").with_tool(TMAC)
MARGIN_RAD = 0.1  # |sin| of A3 and A5 at least this: away from the stretched arm and wrist flip
SHOULDER_MARGIN_MM = 50.0  # wrist point at least this outside the cylinder axis 1 cannot reach


def regular(q: np.ndarray) -> np.ndarray:
    """(N,) bool: joint vectors (N, 6) rad off the UR's singularities by the margins above."""
    radius = np.hypot(*wrist_points_of(UR10, q)[:, :2].T)
    return (
        (np.abs(np.sin(q[:, 2])) >= MARGIN_RAD)
        & (np.abs(np.sin(q[:, 4])) >= MARGIN_RAD)
        & (radius - UR10.dh.d[3] >= SHOULDER_MARGIN_MM)
    )


def assert_same_pose(reached: np.ndarray, wanted: np.ndarray) -> None:
    np.testing.assert_allclose(reached[:, :3, 3], wanted[:, :3, 3], rtol=0, atol=1e-6)
    turn = np.einsum("nji,njk->nik", reached[:, :3, :3], wanted[:, :3, :3])
    angle = np.degrees(Rotation.from_matrix(turn).magnitude())
    assert angle.max() <= 1e-6


LOW = np.arcsin(MARGIN_RAD) + 1e-9


@st.composite
def joint_vectors(draw) -> np.ndarray:
    """UR joint vectors (6,) rad in (-360, 360) deg, none 0 (its Turn bit is then clear either
    way), A3 and A5 at |sin| >= MARGIN_RAD (their angle mod 180 deg in [LOW, 180 deg - LOW])."""
    q = np.empty(6)
    for axis in range(6):
        low = LOW if axis in (2, 4) else 1e-3
        angle = draw(st.floats(low, np.pi - low))  # (0, 180) deg
        if draw(st.booleans()):
            angle -= np.pi  # (-180, 0): the other half turn
        if draw(st.booleans()):
            angle += 2 * np.pi if angle < 0 else -2 * np.pi  # the same angle one turn off
        q[axis] = angle
    return q


@settings(max_examples=40)
@given(joint_vectors())
def test_ur10_ik_returns_the_joints_of_the_asked_configuration(q):
    """IK(FK(q)) in q's configuration (shoulder, elbow, wrist) and turns is q itself."""
    q = q[None]
    assume(regular(q)[0])  # the shoulder margin
    status, turn = ik_codes(UR10, q)
    pose = UR10.fk(q)
    sol = UR10.ik(pose, status=status, turn=turn)
    assert sol.ok[0], sol.reason[0]
    np.testing.assert_allclose(sol.q, q, rtol=0, atol=1e-9)
    assert sol.status[0] == status[0] and sol.turn[0] == turn[0]
    assert_same_pose(UR10.fk(sol.q), pose)


def test_ur10_ik_batch_every_regular_pose_in_its_configuration():
    """500 random regular joint vectors at once: every one found again in its configuration."""
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, (2000, 6))
    q = q[regular(q)][:500]
    status = ik_codes(UR10, q)[0]
    sol = UR10.ik(UR10.fk(q), status=status)
    assert sol.ok.all(), set(sol.reason[~sol.ok])
    np.testing.assert_allclose(sol.q, q, rtol=0, atol=1e-9)  # (-180, 180] without turns


def test_ur10_ik_eight_configurations_are_eight_solutions():
    """A pose in the middle of the workspace has 8 solutions, one per configuration code
    (shoulder + 2 elbow + 4 wrist), each reaching the pose; without a status, the one nearest
    the reference joints is taken."""
    pose = UR10.fk(np.radians([[10.0, -80.0, 100.0, -110.0, -80.0, 30.0]]))
    solutions = []
    for code in range(8):
        sol = UR10.ik(pose, status=code)
        assert sol.ok[0] and sol.status[0] == code, (code, sol.reason[0])
        assert_same_pose(UR10.fk(sol.q), pose)
        solutions.append(sol.q[0])
    assert len({tuple(np.round(s, 6)) for s in solutions}) == 8
    reference = solutions[5] + 0.05
    nearest = UR10.ik(pose, reference=reference)
    np.testing.assert_allclose(nearest.q[0], solutions[5], atol=1e-9)


def test_ur10_ik_unreachable_pose_is_named():
    pose = pose_from_xyzabc([3000.0, 0.0, 500.0, 0.0, 0.0, 0.0])[None]
    sol = UR10.ik(pose, status=0)
    assert not sol.ok[0] and sol.reason[0] == "unreachable" and np.isnan(sol.q).all()


# --- the model path end to end through the CLI, as for the KUKA and ABB arms

TOOL = ["--tool", "0", "0", "109", "0", "0", "0"]
# DH errors of the size of seed Table 1 (mm, mm, rad, rad per row): the simulated "true" UR10
ERRORS = """errors:
  - {da_mm: 0.41, dd_mm: -1.2, dalpha_rad: 3.0e-5, dtheta_rad: -2.5e-4}
  - {da_mm: -1.1, dd_mm: 0.0, dalpha_rad: 4.0e-5, dtheta_rad: 1.2e-3}
  - {da_mm: 0.65, dd_mm: 0.0, dalpha_rad: 1.8e-4, dtheta_rad: -6.0e-4}
  - {da_mm: -0.2, dd_mm: -0.35, dalpha_rad: -7.0e-5, dtheta_rad: 1.4e-4}
  - {da_mm: 0.03, dd_mm: 0.0, dalpha_rad: -5.0e-4, dtheta_rad: -5.0e-4}
  - {da_mm: 0.0, dd_mm: 0.08, dalpha_rad: 4.0e-4, dtheta_rad: 0.0}
"""
TARGETS = "id,x,y,z,a,b,c\nH1,700,100,400,0,180,0\nH2,800,-200,500,12,170,-8\n"


def test_ur10_plan_identify_correct_validate(tmp_path, capsys):
    """plan identify -> simulate (a UR10 with DH errors) -> identify --robot ur10 -> correct
    --model -> simulate the corrected commands on the true arm -> validate: the true arm lands
    on the targets (noise-free data: within microns), and uncorrected it misses by about 1 mm."""
    nominal = resources.files("accugrid.kinematics").joinpath("robots", "ur10.yaml")
    robot_file = tmp_path / "ur10_true.yaml"
    robot_file.write_text(nominal.read_text().replace("name: ur10", "name: ur10-true") + ERRORS)
    region = ["--region", "500", "900", "-300", "300", "200", "600", "--count", "40"]
    plan = ["plan", "identify", "--robot", "ur10", *TOOL, *region, "--abc", "0", "180", "0"]
    assert main([*plan, "--tilt", "25", "-o", str(tmp_path)]) == 0, capsys.readouterr().err
    status = re.search(r"Status (\d)", capsys.readouterr().out).group(1)
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    poses = ["--poses", str(tmp_path / "measure_identify.csv")]
    assert main(["simulate", "--robot", str(robot_file), *poses, *TOOL, "-o", str(meas)]) == 0
    assert main(["identify", str(meas), "--robot", "ur10", *TOOL, "-o", str(cal)]) == 0
    assert "ur10 calibrated from 40 poses" in capsys.readouterr().out
    targets, out = tmp_path / "targets.csv", tmp_path / "out.csv"
    targets.write_text(TARGETS)
    argv = ["correct", str(targets), "--model", str(cal), "--status", status, "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    for source, name in ((out, "after.csv"), (targets, "plain.csv")):
        sim = ["simulate", "--robot", str(robot_file), "--poses", str(source), *TOOL]
        assert main([*sim, "--status", status, "-o", str(tmp_path / name)]) == 0
    capsys.readouterr()
    assert main(["validate", str(tmp_path / "after.csv"), "--model", str(cal)]) == 0
    assert "PASS" in capsys.readouterr().out
    missed = read_measured(tmp_path / "plain.csv")
    assert np.linalg.norm(missed[:, 3:] - missed[:, :3], axis=1).min() > 0.5
    reached = read_measured(tmp_path / "after.csv")
    assert np.abs(reached[:, 3:] - reached[:, :3]).max() < 0.005


def read_measured(path: Path) -> np.ndarray:
    """(N, 6): x, y, z (targets) and x_meas, y_meas, z_meas of a simulated measurement CSV."""
    rows = list(csv.DictReader(line for line in path.open() if not line.startswith("#")))
    keys = ("x", "y", "z", "x_meas", "y_meas", "z_meas")
    return np.array([[float(row[k]) for k in keys] for row in rows])


# --- the controller's own calibration on real data: identify goes on from the logged joints


def series_c_csv(series: dict[str, np.ndarray], rows: np.ndarray, path: Path) -> Path:
    """Rows of Series C as a measurement CSV: commanded x, y, z (the Goal, m -> mm, robot
    frame), the tracker's x_meas, y_meas, z_meas (mm, tracker frame) and the logged joints
    a1..a6 (rad -> deg)."""
    q, goal = commanded(series)
    measured = np.stack([series[f"measurement_{axis}"] for axis in "xyz"], axis=1)
    table = np.column_stack([goal, measured, np.degrees(q)])[rows]
    lines = ["id,x,y,z,x_meas,y_meas,z_meas,a1,a2,a3,a4,a5,a6"]
    lines += [
        f"C{r}," + ",".join(f"{v:.6f}" for v in row) for r, row in zip(rows, table, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_series_c_controller_mismatch_is_reported_and_the_arm_identified(
    series_c, tmp_path, capsys
):
    """80 poses of the real UR10: the commanded positions are the controller's calibrated
    model's, 0.04-0.15 mm from the nominal FK of the logged joints; identify reports that and
    identifies the arm (DH + TCP + tracker frame) from the joints: 200 poses it never saw are
    predicted to well under a mm (the nominal model with a fitted tracker frame: 5.3 mm)."""
    rows = np.arange(0, 2773, 34)[:80]
    csv = series_c_csv(series_c, rows, tmp_path / "c80.csv")
    out = tmp_path / "cal.yaml"
    argv = ["identify", str(csv), "--robot", "ur10", "--tool", "0", "0", "109", "0", "0", "0"]
    assert main([*argv, "--base-frame", "--structure", "dh", "-o", str(out)]) == 0
    assert "identified from the logged joints" in capsys.readouterr().out
    summary = yaml.safe_load(out.read_text())["identification"]
    mismatch = summary["controller_mismatch"]
    assert mismatch["rows"] == 80
    assert 0.04 <= mismatch["mean_mm"] <= 0.15 and mismatch["max_mm"] <= 0.45
    held_out = np.setdiff1d(np.arange(2773), rows)[::12][:200]
    q, _ = commanded(series_c)
    robot_T_tcp = load_robot(out).true_robot().fk(q[held_out])
    tracker_T_robot = pose_from_xyzabc([summary["tracker_T_robot"][k] for k in "xyzabc"])
    predicted = robot_T_tcp[:, :3, 3] @ tracker_T_robot[:3, :3].T + tracker_T_robot[:3, 3]
    measured = np.stack([series_c[f"measurement_{k}"] for k in "xyz"], axis=1)[held_out]
    miss = np.linalg.norm(predicted - measured, axis=1)
    assert miss.mean() < 0.8 and np.percentile(miss, 95) < 1.5, (miss.mean(), miss.max())


def test_ur10_has_no_closed_form_or_confdata_ik():
    """The closed form's 8 candidates and ABB confdata need a spherical wrist: asked of the UR10
    they are refused with the reason, not answered with another arm's solutions."""
    pose = UR10.fk(np.radians([[10.0, -80.0, 100.0, -110.0, -80.0, 30.0]]))
    for ask in (lambda: UR10.ik_all(pose), lambda: ik_confdata(UR10, pose, [0, 0, 0, 0])):
        with pytest.raises(InputError, match="no closed-form inverse"):
            ask()
