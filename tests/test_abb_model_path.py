"""The model and grid paths for the ABB IRB 6700, end to end through the CLI as for the KUKA arm:
`simulate` (a tracker session of an IRB 6700 with DH errors) -> `identify --robot irb6700` ->
`correct --model`, and `simulate` grid -> `correct --grid`; checked by driving the controller
(the nominal irb6700) with the written commands and the true arm's FK."""

from __future__ import annotations

import csv
from importlib import resources

import numpy as np

from accugrid.app.cli import main
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

TOOL = ["--tool", "0", "0", "250", "0", "0", "0"]
# parameter errors of the size of seed Table 1 (mm, mm, rad, rad per DH row)
ERRORS = """errors:
  - {da_mm: 0.41, dd_mm: -1.2, dalpha_rad: 3.0e-5, dtheta_rad: -2.5e-4}
  - {da_mm: -1.1, dd_mm: 0.0, dalpha_rad: 4.0e-5, dtheta_rad: 1.2e-3}
  - {da_mm: 0.65, dd_mm: 0.0, dalpha_rad: 1.8e-4, dtheta_rad: -6.0e-4}
  - {da_mm: -0.2, dd_mm: -0.35, dalpha_rad: -7.0e-5, dtheta_rad: 1.4e-4}
  - {da_mm: 0.03, dd_mm: 0.0, dalpha_rad: -5.0e-4, dtheta_rad: -5.0e-4}
  - {da_mm: 0.0, dd_mm: 0.08, dalpha_rad: 4.0e-4, dtheta_rad: 0.0}
"""
# tool 45 deg below the horizontal, pointing away from axis 1: axis 5 near +45 deg, far from
# the wrist singularity; KUKA Status 2 (in front of axis 1 and of the lower arm, axis 5 > 0)
ABC = (0.0, 135.0, 0.0)
STATUS = "2"
TARGETS = "id,x,y,z,a,b,c\nH1,1700,100,1300,0,135,0\nH2,1850,-250,1450,12,125,-8\n"


def true_robot_file(tmp_path):
    """The built-in irb6700 with parameter errors: a robot YAML whose true arm misses."""
    nominal = resources.files("accugrid.kinematics").joinpath("robots", "irb6700.yaml")
    path = tmp_path / "irb6700_true.yaml"
    path.write_text(nominal.read_text().replace("name: irb6700", "name: irb6700-true") + ERRORS)
    return path


def landed(out, robot_file, corrected=True):
    """Where the true arm's TCP lands (N, 3) mm when the controller (nominal irb6700 with the
    250 mm tool, Status 2) is commanded the x_cmd, y_cmd, z_cmd of ``out`` (with ``corrected``
    False: its x, y, z) at the rows' a, b, c; and the goals x, y, z (N, 3) mm."""
    rows = list(csv.DictReader(line for line in out.open() if not line.startswith("#")))
    keys = ("x_cmd", "y_cmd", "z_cmd") if corrected else "xyz"
    command = np.array([[float(r[k]) for k in keys] for r in rows])
    goal = np.array([[float(r[k]) for k in "xyzabc"] for r in rows])
    tool = pose_from_xyzabc([0, 0, 250, 0, 0, 0])
    controller = load_robot("irb6700").with_tool(tool)
    poses = np.array([pose_from_xyzabc([*c, *g[3:]]) for c, g in zip(command, goal, strict=True)])
    sol = controller.ik(poses, status=int(STATUS))
    assert sol.ok.all(), sol.reason
    arm = load_robot(robot_file).with_tool(tool).true_robot()
    return arm.fk(sol.q)[:, :3, 3], goal[:, :3]


def test_session_identify_and_correct_land_on_the_targets(tmp_path, capsys):
    # geometric errors only, noise-free data: the identified model is exact up to the logged
    # 4 decimals, so the commands correct --model writes put the true arm on the targets
    robot_file = true_robot_file(tmp_path)
    region = ["--region", "1400", "2000", "-400", "400", "1000", "1600"]
    planned = ["plan", "identify", "--robot", "irb6700", *TOOL, *region, "--count", "40"]
    assert main([*planned, "--abc", *map(str, ABC), "--tilt", "25", "-o", str(tmp_path)]) == 0
    plan = tmp_path / "measure_identify.csv"
    assert f"Status {STATUS}" in capsys.readouterr().out
    meas, cal = tmp_path / "meas.csv", tmp_path / "cal.yaml"
    sim = ["simulate", "--robot", str(robot_file), "--poses", str(plan), *TOOL, "-o", str(meas)]
    assert main(sim) == 0, capsys.readouterr().err
    assert main(["identify", str(meas), "--robot", "irb6700", *TOOL, "-o", str(cal)]) == 0
    assert "irb6700 calibrated from 40 poses" in capsys.readouterr().out
    targets = tmp_path / "targets.csv"
    targets.write_text(TARGETS)
    out = tmp_path / "out.csv"
    argv = ["correct", str(targets), "--model", str(cal), "--status", STATUS, "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    reached, goal = landed(out, robot_file)
    assert np.abs(reached - goal).max() < 0.005
    missed, _ = landed(out, robot_file, corrected=False)
    assert np.linalg.norm(missed - goal, axis=1).min() > 1.0  # the arm's own error: mm


def test_grid_of_the_irb6700_corrects_its_targets(tmp_path, capsys):
    # the seed's method on the ABB arm: a grid measured at one orientation in one Status, the
    # targets corrected by inverse-distance weighting; the miss shrinks from mm to a few hundredths
    robot_file = true_robot_file(tmp_path)
    grid = tmp_path / "grid.csv"
    region = ["--region", "1600", "2000", "-400", "200", "1200", "1600", "--step", "100"]
    sim = ["simulate", "--robot", str(robot_file), *region, *TOOL, "--abc", *map(str, ABC)]
    assert main([*sim, "--status", STATUS, "-o", str(grid)]) == 0, capsys.readouterr().err
    targets = tmp_path / "targets.csv"
    targets.write_text("id,x,y,z,a,b,c\nH1,1705,105,1305,0,135,0\nH2,1850,-250,1450,0,135,0\n")
    out = tmp_path / "out.csv"
    assert main(["correct", str(targets), "--grid", str(grid), "-o", str(out)]) == 0
    reached, goal = landed(out, robot_file)
    missed, _ = landed(out, robot_file, corrected=False)
    assert np.linalg.norm(missed - goal, axis=1).min() > 1.0
    assert np.linalg.norm(reached - goal, axis=1).max() < 0.1
