"""`accugrid identify`: the calibrated robot YAML and URDF from a measurement CSV, and refusals."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from accugrid.app.cli import main
from accugrid.kinematics.configuration import status_turn
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
    codes = status_turn(PAPER, q)[0]  # the Status of the visited joints
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


def test_wrong_tool_message_names_lines(tmp_path, capsys):
    csv = write_csv(tmp_path / "meas.csv", joints(30, 7))
    out = tmp_path / "cal.yaml"
    code = main(
        [
            "identify",
            str(csv),
            "--robot",
            "kr210",
            "--tool",
            "20",
            "-10",
            "251",
            "0",
            "0",
            "0",
            "-o",
            str(out),
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and "30 of 30 rows do not reproduce the commanded position" in err
    assert "line 3 (1.0000 mm), line 4 (1.0000 mm)" in err and "--tool" in err
    assert not out.exists()


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
