"""The model path end to end, as the demo runs it: `simulate --poses` (a tracker session at a
plan's scattered poses) -> `identify` -> `correct --model`, checked by driving the controller with
the written commands."""

from __future__ import annotations

import csv

import numpy as np

from accugrid.app.cli import main
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

TOOL = ["--tool", "0", "0", "250", "0", "0", "0"]
HEADER = "id,x,y,z,a,b,c,s,x_meas,y_meas,z_meas\n"


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
    plan.write_text(HEADER + body)
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    sim = ["simulate", "--robot", "kr210-paper", "--poses", str(plan), *TOOL, "-o", str(meas)]
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


def test_a_residual_grid_measured_with_another_tool_is_refused(tmp_path, capsys):
    # a model identified with the 250 mm drill, a residual grid measured at a fixed orientation
    # with another tool whose SMR sits 1.5 mm off: every vertex carries the 1.5 mm, far beyond
    # the model's validated error; refused, and the grid of the model's tool is accepted
    planned = ["plan", "identify", "--robot", "kr210", *TOOL, "--count", "40", "--tilt", "25"]
    assert main([*planned, "-o", str(tmp_path / "plan")]) == 0
    plan = tmp_path / "plan" / "measure_identify.csv"
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    sim = ["simulate", "--robot", "kr210-paper", "--poses", str(plan), *TOOL, "-o", str(meas)]
    assert main([*sim, "--noise-tracker", "0.01"]) == 0
    assert main(["identify", str(meas), "--robot", "kr210", *TOOL, "-o", str(cal)]) == 0
    region = ["--region", "1300", "1900", "-300", "300", "1300", "1900", "--step", "300"]
    grids = {"same": tmp_path / "grid_same.csv", "other": tmp_path / "grid_other.csv"}
    grid_sim = ["simulate", "--robot", "kr210-paper", *region, *TOOL, "--status", "6"]
    assert main([*grid_sim, "-o", str(grids["same"])]) == 0
    lines = grids["same"].read_text().splitlines(keepends=True)
    header = lines[1].strip().split(",")
    rows = [line.strip().split(",") for line in lines[2:]]
    for row in rows:
        row[header.index("x_meas")] = f"{float(row[header.index('x_meas')]) + 1.5:.4f}"
    grids["other"].write_text("".join(lines[:2]) + "".join(",".join(r) + "\n" for r in rows))
    targets = tmp_path / "targets.csv"
    targets.write_text("id,x,y,z,a,b,c\nH1,1500,100,1400,0,90,0\n")
    out = tmp_path / "out.csv"
    argv = ["correct", str(targets), "--model", str(cal), "-o", str(out), "--grid"]
    capsys.readouterr()
    assert main([*argv, str(grids["other"])]) == 2
    err = capsys.readouterr().err
    assert f"{grids['other']}: the residual grid is offset from the model by" in err
    assert "another tool" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
    assert main([*argv, str(grids["same"])]) == 0
