"""`accugrid plan identify`: D-optimal identification poses, then simulate and identify them."""

from __future__ import annotations

import numpy as np
import pytest

from accugrid.app.cli import main
from accugrid.compensation.plans import identification_plan
from accugrid.infra.csvtable import read_table
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc, rotation_angle_deg
from accugrid.kinematics.robot import load_robot

TOOL = ["20", "-10", "250", "0", "0", "0"]
ROBOT = load_robot("kr210").with_tool(pose_from_xyzabc([20.0, -10.0, 250.0, 0, 0, 0]))
LO, HI = (1200.0, -600.0, 1100.0), (2200.0, 600.0, 2100.0)


def test_plan_rows_are_reachable_within_the_tilt_and_region():
    plan, o1, usable = identification_plan(ROBOT, LO, HI, 30, 25.0, (0, 90, 0), 6, candidates=500)
    assert len(plan.points) == 30 and o1 > 0 and 30 <= usable <= 500
    assert np.all(plan.points >= np.array(LO) - 1e-9) and np.all(plan.points <= np.array(HI))
    angle = rotation_angle_deg(abc_to_matrix(plan.abc_rows()), abc_to_matrix([0.0, 90.0, 0.0]))
    assert angle.max() <= 25.0 + 1e-6
    sol = ROBOT.ik(pose_from_xyzabc(np.column_stack([plan.points, plan.abc_rows()])), status=6)
    assert sol.ok.all() and np.all(np.abs(np.degrees(sol.q[:, 4])) >= 10.0 - 1e-6)
    assert plan.extra["s"] == ["6"] * 30


def test_unreachable_region_is_refused():
    with pytest.raises(InputError, match="candidate poses are reachable"):
        identification_plan(ROBOT, (5000, 0, 0), (5100, 100, 100), 30, 20.0, (0, 90, 0), 6)


def test_plan_simulate_identify_round_trip(tmp_path, capsys):
    code = main(
        [
            "plan",
            "identify",
            "--count",
            "36",
            "--tilt",
            "30",
            "--repeats",
            "2",
            "--tool",
            *TOOL,
            "--candidates",
            "800",
            "-o",
            str(tmp_path / "plan"),
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "identification plan (DH errors, TCP + candidates: harmonic orders 1..16" in out
    assert "chosen Bayesian D-optimally" in out
    csv = tmp_path / "plan" / "measure_identify.csv"
    src = (tmp_path / "plan" / "measure_identify.src").read_text()
    assert src.count("PTP XMP") == 72 and "LIN" not in src  # poses reorient: PTP with S/T
    # the operator measures: the true kr210-paper arm at the controller's joints
    table = read_table(csv)
    xyzabc = table.floats(["x", "y", "z", "a", "b", "c"])
    status = table.floats(["s"])[:, 0].astype(int)
    q = ROBOT.ik(pose_from_xyzabc(xyzabc), status=status).q
    paper = load_robot("kr210-paper").with_tool(ROBOT.flange_T_tool).true_robot()
    measured = paper.fk(q)[:, :3, 3]
    lines = csv.read_text().splitlines()
    filled = [lines[0]] + [
        line.rstrip(",") + "," + ",".join(f"{v:.4f}" for v in m)
        for line, m in zip(lines[1:], measured, strict=True)
    ]
    csv.write_text("\n".join(filled) + "\n")
    out = tmp_path / "cal.yaml"
    assert (
        main(
            [
                "identify",
                str(csv),
                "--robot",
                "kr210",
                "--tool",
                *TOOL,
                "-o",
                str(out),
                "--structure",
                "dh",
            ]
        )
        == 0
    )
    assert "from 36 poses (72 rows); 22 of 27 parameters identifiable" in capsys.readouterr().out
    cal = load_robot(out).true_robot()
    rng = np.random.default_rng(0)
    q_new = np.radians(
        rng.uniform([-30, -100, 40, -90, 30, -90], [30, -60, 100, 90, 90, 90], (50, 6))
    )
    assert np.abs(cal.fk(q_new)[:, :3, 3] - paper.fk(q_new)[:, :3, 3]).max() < 0.01


def test_simulate_poses_writes_logged_joints_that_identify_reads(tmp_path, capsys):
    plan_dir = tmp_path / "plan"
    assert main(["plan", "identify", "--count", "40", "--tool", *TOOL, "-o", str(plan_dir)]) == 0
    sim = tmp_path / "sim.csv"
    code = main(
        [
            "simulate",
            "--poses",
            str(plan_dir / "measure_identify.csv"),
            "--robot",
            "kr210-paper",
            "--tool",
            *TOOL,
            "--repeats",
            "2",
            "-o",
            str(sim),
        ]
    )
    assert code == 0
    table = read_table(sim)
    assert len(table) == 80 and table.text("id")[:2] == ["I1", "I1"]
    joints = np.radians(table.floats([f"a{i}" for i in range(1, 7)]))
    # the logged joints are the controller's: the nominal FK gives the commanded position
    commanded = table.floats(["x", "y", "z"])
    np.testing.assert_allclose(ROBOT.fk(joints)[:, :3, 3], commanded, atol=0.01)
    out = tmp_path / "cal.yaml"
    assert main(["identify", str(sim), "--robot", "kr210", "--tool", *TOOL, "-o", str(out)]) == 0
    paper = load_robot("kr210-paper").with_tool(ROBOT.flange_T_tool).true_robot()
    q_new = np.radians(np.random.default_rng(1).uniform(-40, 40, (30, 6)) + [0, -80, 70, 0, 0, 0])
    left = load_robot(out).true_robot().fk(q_new)[:, :3, 3] - paper.fk(q_new)[:, :3, 3]
    assert np.abs(left).max() < 0.01  # noise-free data printed to 4 decimals


def test_simulate_poses_excludes_a_grid(tmp_path, capsys):
    plan = tmp_path / "plan.csv"
    plan.write_text("x,y,z,a,b,c\n1500,0,1500,0,90,0\n")
    code = main(
        [
            "simulate",
            "--poses",
            str(plan),
            "--region",
            "0",
            "1",
            "0",
            "1",
            "0",
            "1",
            "--step",
            "1",
            "-o",
            str(tmp_path / "sim.csv"),
        ]
    )
    assert code == 2 and "exclude each other" in capsys.readouterr().err
    assert not (tmp_path / "sim.csv").exists()


def test_poses_chosen_for_the_harmonic_model_identify_it(tmp_path, capsys):
    # kr210-realistic with exact measurements: 40 poses chosen for DH + TCP + compliance + the
    # order-7 harmonics of A2/A3 identify exactly those terms (full rank, coefficients near the
    # robot's own 1.8e-4 and 8e-5 rad, which are only part of its errors)
    tool = ["--tool", "0", "0", "250", "0", "0", "0"]
    model = ["--compliance", "--harmonics", "A2:7", "A3:7"]
    planned = ["plan", "identify", "--robot", "kr210-realistic", *tool, "--count", "40"]
    assert main([*planned, "--tilt", "25", *model, "-o", str(tmp_path / "plan")]) == 0
    out = capsys.readouterr().out
    assert "identification plan (DH errors, TCP, compliance, 2 harmonics + candidates" in out
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    poses = str(tmp_path / "plan" / "measure_identify.csv")
    sim = ["simulate", "--robot", "kr210-realistic", "--poses", poses, *tool, "-o", str(meas)]
    assert main([*sim, "--noise-tracker", "0", "--noise-repeat", "0"]) == 0
    ident = [
        "identify",
        str(meas),
        "--robot",
        "kr210-realistic",
        *tool,
        *model,
        "--folds",
        "0",
        "--structure",
        "dh",
    ]
    assert main([*ident, "-o", str(cal)]) == 0
    terms = {(h.axis, h.order): h.amplitude_rad for h in load_robot(cal).joint_errors.harmonics}
    assert terms.keys() == {(2, 7), (3, 7)}
    # the other reducer terms (orders 1, 40, 150, 160) leak a little into the fit
    assert abs(terms[(2, 7)] - 1.8e-4) < 0.4e-4 and abs(terms[(3, 7)] - 8e-5) < 0.4e-4


def test_design_dh_keeps_the_d_optimal_dh_design_and_an_unknown_design_is_refused(tmp_path, capsys):
    common = ["plan", "identify", "--count", "30", "--candidates", "300", "--tool", *TOOL]
    assert main([*common, "--design", "dh", "-o", str(tmp_path / "dh")]) == 0
    assert "identification plan (DH errors, TCP): 30 poses x 1 repeats chosen D-optimally" in (
        capsys.readouterr().out
    )
    plan = read_table(tmp_path / "dh" / "measure_identify.csv").floats(["x", "y", "z"])
    expected = identification_plan(ROBOT, LO, HI, 30, 25.0, (0, 90, 0), 6, 300, design="dh")[0]
    np.testing.assert_allclose(plan, expected.points, atol=5e-4)
    with pytest.raises(SystemExit) as exit_info:
        main([*common, "--design", "optimal", "-o", str(tmp_path / "bad")])
    assert exit_info.value.code == 2 and not (tmp_path / "bad").exists()
