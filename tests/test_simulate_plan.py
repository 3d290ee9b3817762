"""`accugrid simulate --plan`: a tracker session at a plan's scattered poses, each row at its own
orientation, with the logged joints a1..a6 and s that `accugrid identify` reads."""

from __future__ import annotations

import csv

import numpy as np

from accugrid.codegen.cli import main
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

TOOL = ["--tool", "0", "0", "250", "0", "0", "0"]
PLAN = """id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas
I1,1500,0,1500,0,90,0,6,,,
I2,1600,100,1600,10,80,5,6,,,
I3,1400,-200,1400,-10,95,-5,6,,,
"""


def run(tmp_path, plan_text=PLAN, *extra):
    plan = tmp_path / "plan.csv"
    plan.write_text(plan_text)
    out = tmp_path / "meas.csv"
    argv = ["simulate", "--robot", "kr210-realistic", "--plan", str(plan), *TOOL]
    return main([*argv, "-o", str(out), *extra]), out


def rows_of(out):
    lines = out.read_text().splitlines()
    assert lines[0].startswith("# accugrid simulate: robot kr210-realistic, plan plan.csv")
    return list(csv.DictReader(lines[1:]))


def test_each_row_is_reached_at_its_own_orientation_and_logs_its_joints(tmp_path):
    code, out = run(tmp_path, PLAN, "--repeats", "2")
    assert code == 0
    rows = rows_of(out)
    assert list(rows[0]) == ("id x y z a b c x_meas y_meas z_meas a1 a2 a3 a4 a5 a6 s".split())
    assert [r["id"] for r in rows] == ["I1", "I1", "I2", "I2", "I3", "I3"]
    assert {r["s"] for r in rows} == {"6"}
    assert all(len(r["a3"].split(".")[1]) == 4 for r in rows)
    realistic = load_robot("kr210-realistic").with_tool(pose_from_xyzabc([0, 0, 250, 0, 0, 0]))
    q = np.radians([[float(r[f"a{k}"]) for k in range(1, 7)] for r in rows])
    commanded = np.array([[float(r[k]) for k in "xyzabc"] for r in rows])
    measured = np.array([[float(r[k]) for k in ("x_meas", "y_meas", "z_meas")] for r in rows])
    nominal = realistic.fk(q)
    # the logged joints reproduce each commanded pose (position and orientation) to round-off
    assert np.abs(nominal[:, :3, 3] - commanded[:, :3]).max() < 0.01
    want = np.array([pose_from_xyzabc([0, 0, 0, *c[3:]])[:3, :3] for c in commanded])
    assert np.abs(nominal[:, :3, :3] - want).max() < 1e-5
    # without noise the measured position is the true robot's FK at those joints
    assert np.abs(realistic.true_robot().fk(q)[:, :3, 3] - measured).max() < 0.01


def test_its_logged_joints_pass_identify_round_off_check(tmp_path, capsys):
    rng = np.random.default_rng(3)
    xyz = rng.uniform([1300, -300, 1300], [1800, 300, 1800], (40, 3))
    abc = np.array([0.0, 90.0, 0.0]) + rng.uniform(-15, 15, (40, 3))
    body = "".join(
        f"P{i},{','.join(f'{v:.3f}' for v in (*p, *a))},6,,,\n"
        for i, (p, a) in enumerate(zip(xyz, abc, strict=True))
    )
    code, out = run(tmp_path, PLAN.splitlines(keepends=True)[0] + body, "--noise-tracker", "0.01")
    assert code == 0
    cal = tmp_path / "cal.yaml"
    argv = ["identify", str(out), "--robot", "kr210", *TOOL, "-o", str(cal), "--folds", "0"]
    assert main(argv) == 0, capsys.readouterr().err
    assert "calibrated from 40 poses (40 rows)" in capsys.readouterr().out


def test_status_column_and_option_must_agree(tmp_path, capsys):
    code, out = run(tmp_path, PLAN, "--status", "2")
    assert code == 2 and not out.exists()
    assert "column s has 6" in capsys.readouterr().err
    mixed = PLAN.replace("-5,6,", "-5,2,")
    code, out = run(tmp_path, mixed)
    assert code == 2 and not out.exists()


def test_a_plan_without_orientation_is_refused(tmp_path, capsys):
    code, out = run(tmp_path, "id,x,y,z\nI1,1500,0,1500\n")
    assert code == 2 and not out.exists()
    assert "a,b,c" in capsys.readouterr().err


def test_plan_session_identify_and_correct_land_on_the_targets(tmp_path, capsys):
    # kr210-paper has only geometric errors: from noise-free data the model is exact, so the
    # commands correct --model writes, run by the controller with its own tool (not the
    # identified TCP), put the true arm on the targets
    rng = np.random.default_rng(5)
    xyz = rng.uniform([1300, -400, 1300], [1900, 400, 1900], (40, 3))
    abc = np.array([0.0, 90.0, 0.0]) + rng.uniform(-20, 20, (40, 3))
    body = "".join(
        f"P{i},{','.join(f'{v:.3f}' for v in (*p, *a))},6,,,\n"
        for i, (p, a) in enumerate(zip(xyz, abc, strict=True))
    )
    plan = tmp_path / "plan.csv"
    plan.write_text(PLAN.splitlines(keepends=True)[0] + body)
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    sim = ["simulate", "--robot", "kr210-paper", "--plan", str(plan), *TOOL, "-o", str(meas)]
    assert main(sim) == 0
    assert main(["identify", str(meas), "--robot", "kr210", *TOOL, "-o", str(cal)]) == 0
    targets = tmp_path / "targets.csv"
    targets.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\nH2,1750,-250,1650,12,75,-8\n")
    out = tmp_path / "out.csv"
    argv = ["correct", str(targets), "--model", str(cal), "--status", "6", "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    rows = list(csv.DictReader(line for line in out.open() if not line.startswith("#")))
    command = np.array([[float(r[k]) for k in ("x_cmd", "y_cmd", "z_cmd")] for r in rows])
    goal = np.array([[float(r[k]) for k in "xyzabc"] for r in rows])
    tool = pose_from_xyzabc([0, 0, 250, 0, 0, 0])
    controller = load_robot("kr210-paper").with_tool(tool)
    poses = np.array([pose_from_xyzabc([*c, *g[3:]]) for c, g in zip(command, goal, strict=True)])
    sol = controller.ik(poses, status=6)
    landed = controller.true_robot().fk(sol.q)[:, :3, 3]
    # the 4-decimal logged joints and positions limit the model to a few micrometres
    assert np.abs(landed - goal[:, :3]).max() < 0.005
