"""The wrist axes in a program: A4 and A6 follow the short way within their limits, and a
configuration change between holes names the axis that turns and its two angles."""

from __future__ import annotations

import re
import shutil

import numpy as np
from conftest import EXAMPLES

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.kinematics.frames import pose_from_xyzabc
from accugrid.kinematics.robot import load_robot


def test_a_wrist_axis_past_its_limit_is_named_with_its_angles(tmp_path, capsys):
    """A spins the drill about its axis by 120 deg per hole (B 0, C 180): A6 follows the short
    way until the next hole would take it past +350 deg, then it must turn back 240 deg. The
    grid holds at one orientation only, so the spun holes are written uncorrected
    (--allow-partial): the axis check covers every pose, corrected or not."""
    for name in ("cell.yaml", "grid_200mm.csv"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    points = tmp_path / "spin.csv"
    rows = [
        f"{h},{25 * k},300,0,{a},0,180" for k, (h, a) in enumerate(zip("ABCD", SPIN_A, strict=True))
    ]
    points.write_text("id,x,y,z,a,b,c\n" + "\n".join(rows) + "\n")
    argv = ["krl", points, "--cell", tmp_path / "cell.yaml", "-o", tmp_path / "krl"]
    assert main([str(a) for a in [*argv, "--allow-partial"]]) == 2
    err = capsys.readouterr().err
    found = re.search(
        r"hole 'D': A(\d) turns (\d+) deg from the previous pose \((\S+) to (\S+) deg;", err
    )
    assert found, err
    axis, turned, before, after = int(found[1]), int(found[2]), float(found[3]), float(found[4])
    assert axis == 6 and turned > 180 and abs(abs(after - before) - turned) <= 1
    assert before > 180 and after + 360 > 350  # beyond 180 deg; a turn on would pass the limit
    assert f"{points}:5:" in err and not (tmp_path / "krl").exists()


SPIN_A = (-90, 30, 150, -90)  # KUKA A of the holes, deg


def test_a_forced_status_keeps_the_wrist_turning_the_short_way(tmp_path):
    """With Status 2 the wrist of the example panel passes 180 deg between two holes: the poses
    take the angle beyond 180 deg (within the +-350 deg limits) instead of flipping by 357 deg.
    Checked from the written E6POS alone: each one's IK in its own S and T is reachable, and no
    axis moves more than 180 deg from one pose to the next. The example grid holds in Status 6
    only, so the holes are written uncorrected (--allow-partial); the axes are chosen alike."""
    for name in ("cell.yaml", "grid_200mm.csv", "wing_panel_points.csv"):
        shutil.copy(EXAMPLES / name, tmp_path / name)
    cell_file = tmp_path / "cell.yaml"
    cell_file.write_text(cell_file.read_text().replace("  # status: 2 ", "  status: 2   "))
    argv = ["krl", tmp_path / "wing_panel_points.csv", "--cell", cell_file, "-o", tmp_path / "krl"]
    assert main([str(a) for a in [*argv, "--allow-partial"]]) == 0
    dat = (tmp_path / "krl" / "WING_PANEL.dat").read_text()
    number = r"(-?[\d.]+)"
    found = re.findall(
        rf"DECL E6POS XH\d+_(\w+)=\{{X {number},Y {number},Z {number},A {number},B {number},"
        rf"C {number},S (\d+),T (\d+)",
        dat,
    )
    cell = load_cell(cell_file)
    robot = load_robot(cell.robot_name).with_tool(cell.flange_T_tool)
    order = {"APP": 0, "CLR": 1, "BOT": 2}  # the program's order within a hole: APP CLR BOT APP
    poses = [f for f in found if f[0] in order]
    xyzabc = np.array([[float(v) for v in f[1:7]] for f in poses])
    robot_T_tcp = cell.robot_T_base @ pose_from_xyzabc(xyzabc)
    status = np.array([int(f[7]) for f in poses])
    turn = np.array([int(f[8]) for f in poses])
    assert set(status) == {2}
    sol = robot.ik(robot_T_tcp, status=status, turn=turn)
    assert sol.ok.all()
    q = np.degrees(sol.q)
    assert np.abs(np.diff(q, axis=0)).max() < 180.0
    assert np.abs(q[:, 5]).max() > 180.0  # the wrist did go past 180 deg
