"""`accugrid identify`: the calibrated robot YAML and URDF from a measurement CSV, and refusals."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import yaml

from accugrid.app.cli import main
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.frames import pose_from_xyzabc, xyzabc_from_pose
from accugrid.kinematics.robot import load_robot

TOOL = ["20", "-10", "250", "0", "0", "0"]
PAPER = load_robot("kr210-paper").with_tool(pose_from_xyzabc([20.0, -10.0, 250.0, 0, 0, 0]))
LOW = np.radians([-60.0, -120.0, 20.0, -150.0, 20.0, -150.0])
HIGH = np.radians([60.0, -40.0, 120.0, 150.0, 110.0, 150.0])


def joints(n: int, seed: int) -> np.ndarray:
    """Random joints (n, 6) rad, as the controller logs them: 4 decimals in degrees."""
    q = LOW + np.random.default_rng(seed).random((n, 6)) * (HIGH - LOW)
    return np.radians(np.round(np.degrees(q), 4))


def write_csv(path, q, noise=0.0, logged=True, seed=0, status=False, repeats=1):
    """A tracker session of kr210-paper (Table 1 errors) at joints q: commanded pose, measured
    position (4 decimals), optionally the logged joints and the Status."""
    q = np.repeat(q, repeats, axis=0)
    commanded = xyzabc_from_pose(PAPER.fk(q))
    measured = PAPER.true_robot().fk(q)[:, :3, 3]
    measured += np.random.default_rng(seed).normal(0.0, noise, measured.shape)
    header = "id,x,y,z,a,b,c,x_meas,y_meas,z_meas"
    header += ",a1,a2,a3,a4,a5,a6" if logged else ""
    header += ",s" if status else ""
    lines = ["# a comment line", header]
    codes = ik_codes(PAPER, q)[0]  # the Status of the visited joints
    for i in range(len(q)):
        cells = [f"P{i}"] + [f"{v:.4f}" for v in (*commanded[i], *measured[i])]
        cells += [f"{v:.4f}" for v in np.degrees(q[i])] if logged else []
        cells += [str(codes[i])] if status else []
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")
    return path


def identify(tmp_path, csv, *extra):
    out = tmp_path / "cal.yaml"
    code = main(["identify", str(csv), "--robot", "kr210", "--tool", *TOOL, "-o", str(out), *extra])
    return code, out


def test_identify_writes_a_loadable_calibrated_robot_and_urdf(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(60, 1), noise=0.02)
    urdf = tmp_path / "cal.urdf"
    code, out = identify(tmp_path, csv, "--urdf", str(urdf))
    assert code == 0
    printed = capsys.readouterr().out
    assert "22 of 27 parameters identifiable" in printed  # no joint-error term chosen
    assert "expected accuracy (nested 5-fold cross-validation" in printed
    cal = load_robot(out)
    assert cal.name == "kr210-calibrated"
    # the calibrated arm predicts new poses of the real one to well below the raw error
    q_new = joints(100, 2)
    true = PAPER.true_robot().fk(q_new)[:, :3, 3]
    raw = np.abs(PAPER.fk(q_new)[:, :3, 3] - true).max()
    left = np.abs(cal.true_robot().fk(q_new)[:, :3, 3] - true).max()
    assert raw > 2.0 and left < 0.1
    summary = yaml.safe_load(out.read_text())["identification"]
    assert summary["robot"] == "kr210" and summary["poses"] == 60
    assert summary["structure"]["nested"]["folds"] == 5 and summary["structure"]["chosen"] == []
    assert len(summary["parameters"]) == 27
    assert urdf.read_text().startswith("<?xml")


def test_same_inputs_give_the_same_bytes(tmp_path):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 3), noise=0.01)
    first = identify(tmp_path, csv)[1].read_bytes()
    assert identify(tmp_path, csv, "--force")[0] == 0
    assert (tmp_path / "cal.yaml").read_bytes() == first


def test_without_logged_joints_the_status_column_selects_the_ik(tmp_path):
    q = joints(40, 4)
    csv = write_csv(tmp_path / "meas.csv", q, logged=False, status=True, repeats=2)
    code, out = identify(tmp_path, csv, "--folds", "4")
    assert code == 0
    cal = load_robot(out)
    q_new = joints(50, 5)
    true = PAPER.true_robot().fk(q_new)[:, :3, 3]
    assert np.abs(cal.true_robot().fk(q_new)[:, :3, 3] - true).max() < 1e-3  # 4-decimal data


def refused(capsys, code, tmp_path, message):
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("accugrid identify: error: ")
    assert message in err
    assert not (tmp_path / "cal.yaml").exists() and not (tmp_path / "cal.urdf").exists()


def test_too_few_poses(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(12, 6))
    code, _ = identify(tmp_path, csv, "--urdf", str(tmp_path / "cal.urdf"))
    refused(capsys, code, tmp_path, "meas.csv: 12 distinct poses for 22 identifiable parameters")


def test_wrong_tool_message_names_lines_and_the_tool(tmp_path, capsys):
    """Logged joints 50 mm off their commanded positions: no controller calibration is that
    far off; refused, naming the rows and the tool the rows were commanded with."""
    csv = write_csv(tmp_path / "meas.csv", joints(30, 7))
    out = tmp_path / "cal.yaml"
    wrong = ["--tool", "20", "-10", "300", "0", "0", "0"]
    code = main(["identify", str(csv), "--robot", "kr210", *wrong, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "30 of 30 rows miss their commanded position" in err
    assert "line 3 (50.0000 mm), line 4 (50.0000 mm)" in err
    assert "a tool at x 20.000 y -10.000 z 250.000 mm on the flange brings every row" in err
    assert "is the --tool wrong?" in err
    assert not out.exists()


def test_swapped_joint_columns_are_refused_naming_them(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(30, 7))
    lines = csv.read_text().splitlines()
    lines[1] = lines[1].replace("a2,a3", "a3,a2")  # the header names the columns the other way
    csv.write_text("\n".join(lines) + "\n")
    code, _ = identify(tmp_path, csv)
    refused(capsys, code, tmp_path, "columns a2 and a3 swapped? (they fit the limits exchanged)")


def controller_csv(tmp_path, q):
    """kr210-paper's session as a controller with its own calibration logs it: the commanded
    positions are its calibrated model's FK of the joints (tenths of a mm from the nominal),
    the joints and the measured positions those of the real arm."""
    own = replace(PAPER, dh=PAPER.dh.with_errors(CONTROLLER_ERRORS))
    csv = write_csv(tmp_path / "meas.csv", q)
    lines = csv.read_text().splitlines()
    commanded = own.fk(q)[:, :3, 3]
    for i in range(len(q)):
        cells = lines[2 + i].split(",")
        cells[1:4] = [f"{v:.4f}" for v in commanded[i]]
        lines[2 + i] = ",".join(cells)
    csv.write_text("\n".join(lines) + "\n")
    mismatch = np.linalg.norm(np.round(commanded, 4) - PAPER.fk(q)[:, :3, 3], axis=1)
    return csv, mismatch


# the controller's own model against the nominal: per DH row da mm, dd mm, dalpha rad, dtheta rad
CONTROLLER_ERRORS = np.array(
    [
        [0.05, -0.1, 2e-5, 3e-5],
        [0.1, 0.0, -1e-5, -4e-5],
        [-0.08, 0.0, 3e-5, 2e-5],
        [0.0, 0.06, 0.0, 5e-5],
        [0.0, 0.0, -4e-5, 0.0],
        [0.0, 0.02, 0.0, 0.0],
    ]
)


def test_controller_calibration_is_reported_and_identified_from_the_joints(tmp_path, capsys):
    """A controller whose own model is tenths of a mm from the nominal: identify measures the
    mismatch, prints and records it, and identifies the arm from the logged joints."""
    q = joints(60, 1)
    csv, mismatch = controller_csv(tmp_path, q)
    assert 0.05 < mismatch.mean() < 0.5  # a factory calibration's size
    report = tmp_path / "report.html"
    code, out = identify(tmp_path, csv, "--structure", "dh", "--report-html", str(report))
    printed = capsys.readouterr().out
    assert code == 0
    expected = f"by {mismatch.mean():.4f} mm mean, {mismatch.max():.4f} max (60 of 60 rows"
    assert expected in printed and "identified from the logged joints" in printed
    summary = yaml.safe_load(out.read_text())["identification"]
    recorded = summary["controller_mismatch"]
    assert recorded["rows"] == 60
    assert recorded["mean_mm"] == pytest.approx(mismatch.mean(), abs=1e-9)
    assert recorded["max_mm"] == pytest.approx(mismatch.max(), abs=1e-9)
    assert "controller mismatch" in report.read_text() and "own calibration" in report.read_text()
    # identified from the joints: the calibrated arm predicts the real one, not the controller
    q_new = joints(50, 5)
    true = PAPER.true_robot().fk(q_new)[:, :3, 3]
    assert np.abs(load_robot(out).true_robot().fk(q_new)[:, :3, 3] - true).max() < 1e-3


def test_without_logged_joints_identify_says_what_to_log(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 4), logged=False, status=True)
    report = tmp_path / "report.html"
    code, out = identify(tmp_path, csv, "--structure", "dh", "--report-html", str(report))
    printed = capsys.readouterr().out
    assert code == 0
    assert "joints not logged" in printed
    assert "log the controller's actual joint angles as columns a1..a6" in printed
    assert "log the controller&#39;s actual joint angles as columns a1..a6" in report.read_text()
    assert "controller_mismatch" not in yaml.safe_load(out.read_text())["identification"]


def test_logged_joints_that_agree_add_no_controller_line(tmp_path, capsys):
    code, out = identify(
        tmp_path,
        write_csv(tmp_path / "meas.csv", joints(40, 3)),
        "--folds",
        "0",
        "--structure",
        "dh",
    )
    printed = capsys.readouterr().out
    assert code == 0 and "controller" not in printed and "joints not logged" not in printed
    assert "controller_mismatch" not in yaml.safe_load(out.read_text())["identification"]


def test_orientation_missing(tmp_path, capsys):
    (tmp_path / "meas.csv").write_text(
        "x,y,z,x_meas,y_meas,z_meas\n" + "1500,0,1500,1500,0,1500\n" * 30
    )
    code, _ = identify(tmp_path, tmp_path / "meas.csv")
    refused(capsys, code, tmp_path, "columns a,b,c")


def test_existing_output_needs_force(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 8))
    (tmp_path / "cal.yaml").write_text("old")
    code, out = identify(tmp_path, csv)
    assert code == 2 and out.read_text() == "old"
    assert "--force" in capsys.readouterr().err


@pytest.mark.parametrize("folds", ["1", "-2"])
def test_bad_folds(tmp_path, capsys, folds):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 9))
    code, _ = identify(tmp_path, csv, "--folds", folds)
    refused(capsys, code, tmp_path, "--folds must be 0 (none) or at least 2")


def test_compliance_without_a_gravity_model_is_refused(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 10))
    code, _ = identify(tmp_path, csv, "--compliance")
    refused(capsys, code, tmp_path, "robot kr210 has no gravity model")


def test_compliance_with_the_realistic_robot_writes_joint_errors(tmp_path):
    csv = write_csv(tmp_path / "meas.csv", joints(40, 11), noise=0.01)
    out = tmp_path / "cal.yaml"
    code = main(
        [
            "identify",
            str(csv),
            "--robot",
            "kr210-realistic",
            "--tool",
            *TOOL,
            "--compliance",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    cal = load_robot(out)
    assert cal.joint_errors is not None and len(cal.joint_errors.masses) == 4
    # kr210-paper has no compliance: the identified coefficients stay near 0 (true sag of
    # 1e-7 rad/N.m would be ~1 mm; these data show none)
    assert np.all(np.abs(cal.joint_errors.compliance) < 2e-8)
