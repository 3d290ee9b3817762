"""FANUC TP: the built-in R-2000iC/165F against the ROS-Industrial description of the arm, the
generated ``.ls`` program (numbered lines, positions, W/P/R and CONFIG recomputed here with scipy
and the arm's joint chain written out here), the pre-flight rewrite of the real TP programs in
../shared/realworld/fanuc with a constant error field (only numbers change, every changed number
checked against the frame maths done here), the reader's rules, and bad input."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import E_CONST, changed_lines, write_grid
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.kinematics.robot import load_robot

NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)"
POSITION = re.compile(
    rf"P\[(\d+)(?::[^\]]*)?\]\s*\{{\s*GP1:\s*UF\s*:\s*(\d+),\s*UT\s*:\s*(\d+),\s*"
    rf"(?:\w+\s*:\s*'([^']*)',\s*)?X\s*=\s*({NUM})\s*mm,\s*Y\s*=\s*({NUM})\s*mm,\s*"
    rf"Z\s*=\s*({NUM})\s*mm,\s*W\s*=\s*({NUM})\s*deg,\s*P\s*=\s*({NUM})\s*deg,\s*"
    rf"R\s*=\s*({NUM})\s*deg"
)
CELL = EXAMPLES / "cell_fanuc.yaml"
ROBOT_T_BASE = np.eye(4)  # examples/cell_fanuc.yaml: base x 1700 y 300 z 400, a -90 b 0 c 90
ROBOT_T_BASE[:3, :3] = Rotation.from_euler("ZYX", [-90, 0, 90], degrees=True).as_matrix()
ROBOT_T_BASE[:3, 3] = [1700.0, 300.0, 400.0]
TOOL = np.eye(4)
TOOL[2, 3] = 250.0  # examples/cell_fanuc.yaml: tool z 250


def urdf_chain(j: np.ndarray, links: int = 6) -> np.ndarray:
    """The pose (4, 4) mm of link ``links`` (6: tool0, the faceplate) of the R-2000iC/165F in
    FANUC's world frame, from the ROS-Industrial description (fanuc_r2000ic_support,
    r2000ic165f_macro.xacro: joint origins and axes, tool0 rpy (pi, -pi/2, 0)) at its joint
    values j (6,) rad, whose joint 3 is J2 + J3 (FANUC's J3 is the forearm's angle above the
    horizontal)."""
    origins = [(0, 0, 0), (312, 0, 0), (0, 0, 1075), (0, 0, 225), (1280, 0, 0), (215, 0, 0)]
    axes = [(0, 0, 1), (0, 1, 0), (0, -1, 0), (-1, 0, 0), (0, -1, 0), (-1, 0, 0)]
    pose = np.eye(4)
    for origin, axis, angle in list(zip(origins, axes, j, strict=True))[:links]:
        step = np.eye(4)
        step[:3, 3] = origin
        step[:3, :3] = Rotation.from_rotvec(np.array(axis) * angle).as_matrix()
        pose = pose @ step
    if links == 6:
        tool0 = np.eye(4)
        tool0[:3, :3] = Rotation.from_euler("xyz", [np.pi, -np.pi / 2, 0]).as_matrix()
        pose = pose @ tool0
    return pose


def urdf_joints(q: np.ndarray) -> np.ndarray:
    """The ROS-Industrial joint values of the robot file's axis angles q (6,) rad: FANUC's J1,
    J2, J4, J5, J6 and q3 = -(J2 + J3), so joint 3 = J2 + J3 = -q3."""
    j = np.array(q, dtype=float)
    j[2] = -q[2]
    return j


@settings(max_examples=10, deadline=None)
@given(q=st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_robot_file_is_the_ros_industrial_arm(q):
    robot = load_robot("r2000ic-165f")
    q = np.array(q)
    np.testing.assert_allclose(robot.fk(q[None])[0], urdf_chain(urdf_joints(q)), atol=1e-9)


def test_fanuc_j3_is_the_forearm_angle_above_the_horizontal():
    robot = load_robot("r2000ic-165f")
    for j2 in (-40.0, 0.0, 30.0):  # J3 = 0 keeps the forearm horizontal at any J2
        q = np.radians([0.0, j2, -j2, 0.0, 0.0, 0.0])  # q3 = -(J2 + J3)
        flange = robot.fk(q[None])[0]
        wrist = flange[:3, 3] - 215.0 * flange[:3, 2]
        elbow = urdf_chain(urdf_joints(q), links=3)[:3, 3]
        forearm = wrist - elbow - 225.0 * np.array([0, 0, 1.0])
        assert abs(forearm[2]) < 1e-9 and forearm[0] > 1279.0


def _positions(text: str) -> dict[int, tuple]:
    """P number -> (uf, ut, config, xyz (3,), wpr (3,)) of every Cartesian /POS entry."""
    out = {}
    for m in POSITION.finditer(text):
        v = [float(x) for x in m.groups()[4:]]
        out[int(m.group(1))] = (int(m.group(2)), int(m.group(3)), m.group(4), v[:3], v[3:])
    return out


def _config_of(q: np.ndarray) -> str:
    """CONFIG of the robot file's joints q (6,) rad, worked out here from the arm's geometry:
    flipped when J5 >= 0, the elbow up when J3's axis lies above the line from J2's axis to the
    wrist centre (in the arm's plane), top when the wrist centre is in front of J1; the turns
    of J1, J4, J6 counted from -180..180 deg."""
    j = urdf_joints(q)
    p2, p3 = urdf_chain(j, 2)[:3, 3], urdf_chain(j, 3)[:3, 3]
    wrist = urdf_chain(j, 5)[:3, 3]
    turn = Rotation.from_euler("z", -q[0]).as_matrix()  # into the arm's plane: x forward
    (x2, _, z2), (x3, _, z3), (xw, _, zw) = turn @ p2, turn @ p3, turn @ wrist
    up = (xw - x2) * (z3 - z2) - (zw - z2) * (x3 - x2) > 0
    flip = np.degrees(np.angle(np.exp(1j * q[4]))) >= 0
    turns = np.floor((np.degrees(q[[0, 3, 5]]) + 180.0) / 360.0).astype(int)
    return "{} {} {}, {}, {}, {}".format(
        "F" if flip else "N", "U" if up else "D", "T" if xw >= 0 else "B", *turns
    )


def _reaches_in_config(robot, pose: np.ndarray, config: str) -> bool:
    """Whether one joint solution of the TCP pose (4, 4) in the robot file's limits has the
    CONFIG ``config`` and reaches the pose through the ROS-Industrial chain."""
    candidates, reach = robot.ik_all(pose[None])
    letters, *turns = (s.strip() for s in config.split(","))
    limits = np.radians(robot.joint_limits_deg)
    for q, ok in zip(candidates[0], reach[0], strict=True):
        if not ok:
            continue
        q = q.copy()
        q[[0, 3, 5]] += 2 * np.pi * np.array([int(t) for t in turns])
        if _config_of(q) != f"{letters}, {', '.join(turns)}":
            continue
        if np.any(q < limits[:, 0] - 1e-9) or np.any(q > limits[:, 1] + 1e-9):
            continue
        if np.allclose(urdf_chain(urdf_joints(q)) @ TOOL, pose, atol=1e-6):
            return True
    return False


@settings(max_examples=4, deadline=None)
@given(
    holes=st.lists(
        st.tuples(st.floats(0, 600), st.floats(150, 450), st.floats(-8, 8), st.floats(-8, 8)),
        min_size=1,
        max_size=4,
    ),
)
def test_every_position_is_its_hole_reached_in_its_config(tmp_path_factory, holes):
    tmp = tmp_path_factory.mktemp("fanuc")
    rows = ["id,x,y,z,i,j,k"]
    for n, (x, y, tilt_x, tilt_y) in enumerate(holes):
        axis = Rotation.from_euler("xy", [tilt_x, tilt_y], degrees=True).apply([0, 0, -1])
        rows.append(f"H{n},{x:.3f},{y:.3f},0," + ",".join(f"{a:.6f}" for a in axis))
    written = [[float(v) for v in row.split(",")[1:]] for row in rows[1:]]  # as the CSV has them
    (tmp / "p.csv").write_text("\n".join(rows) + "\n")
    out = tmp / "drill_job.ls"
    argv = ["fanuc", str(tmp / "p.csv"), "--cell", str(CELL), "-o", str(out), "--no-correction"]
    cell = tmp / "cell.yaml"  # the example cell without its program name: the file's stem
    cell.write_text(CELL.read_text().replace("  program: WING ", "  # program"))
    argv[3] = str(cell)
    assert main(argv) == 0
    text = out.read_bytes().decode("ascii")
    assert text.startswith("/PROG  DRILL_JOB\r\n") and text.endswith("/END\r\n")
    mn = text[text.index("/MN\r\n") + 5 : text.index("/POS\r\n")].splitlines()
    assert [int(line[:4]) for line in mn] == list(range(1, len(mn) + 1))
    assert all(line[4] == ":" for line in mn)
    assert f"LINE_COUNT\t= {len(mn)};" in text
    moves = [re.match(r"....:(J|L) P\[(\d+)\]", line) for line in mn]
    moves = [(m.group(1), int(m.group(2))) for m in moves if m]
    assert moves == [
        (kind, 4 * h + s + 1) for h in range(len(holes)) for s, kind in enumerate("JLLL")
    ]
    assert "  UFRAME_NUM=1 ;" in text and "  UTOOL_NUM=1 ;" in text
    positions = _positions(text)
    assert sorted(positions) == list(range(1, 4 * len(holes) + 1))
    robot = load_robot("r2000ic-165f").with_tool(TOOL)
    for h, (x, y, z, *axis) in enumerate(written):
        hole, axis = np.array([x, y, z]), np.array(axis) / np.linalg.norm(axis)
        for s, along in enumerate((-30.0, -2.0, 6.5, -30.0)):  # APP, CLR, BOT (depth), RET
            uf, ut, config, xyz, wpr = positions[4 * h + s + 1]
            assert (uf, ut) == (1, 1)
            np.testing.assert_allclose(xyz, hole + along * axis, atol=6e-4)
            base_T_tcp = np.eye(4)
            base_T_tcp[:3, :3] = Rotation.from_euler("xyz", wpr, degrees=True).as_matrix()
            base_T_tcp[:3, 3] = xyz
            np.testing.assert_allclose(base_T_tcp[:3, 2], axis, atol=2e-5)  # the drill axis
            assert _reaches_in_config(robot, ROBOT_T_BASE @ base_T_tcp, config), config


def test_a_constant_error_moves_every_position_by_it_in_the_user_frame(tmp_path):
    write_grid(tmp_path / "grid.csv", (-3000,) * 3, (3000,) * 3, 1500.0, field="constant")
    cell = tmp_path / "cell.yaml"
    cell.write_text(
        CELL.read_text().replace("grid: grid_r2000ic_200mm.csv", f"grid: {tmp_path / 'grid.csv'}")
    )
    points = EXAMPLES / "wing_panel_points.csv"
    plain, corrected = tmp_path / "plain.ls", tmp_path / "corrected.ls"
    assert (
        main(["fanuc", str(points), "--cell", str(cell), "-o", str(plain), "--no-correction"]) == 0
    )
    assert main(["fanuc", str(points), "--cell", str(cell), "-o", str(corrected)]) == 0
    before, after = _positions(plain.read_text()), _positions(corrected.read_text())
    shift = ROBOT_T_BASE[:3, :3].T @ E_CONST  # P' = P + e, e in the robot frame
    assert len(before) == 4 * 72
    for n, (*_, xyz, wpr) in before.items():
        np.testing.assert_allclose(after[n][3], np.array(xyz) + shift, atol=1.5e-3)
        assert after[n][4] == wpr


REALWORLD_BASE = (400.0, -250.0, 300.0, 30.0, 10.0, -20.0)  # the cell's user frame, mm, deg
# ../shared/realworld/fanuc programs -> (the cell's user frame and tool frame numbers, extra
# options, how many positions must be corrected at least, the line and reason of the first
# position a motion commands that is left uncorrected, None: none is)
REALWORLD = {
    "Creearc__welding_project__layers_splitter_data_cub_2.ls": (
        6,
        5,
        [],
        0,
        (688, "COORD) at line 17"),
    ),
    "GilbertPan97__SnapMaster__datas_LeiChi-12.22_cam0_calib_0.ls": (
        1,
        1,
        ["--ignore-external-axes"],
        0,
        (55, "tool frame 0 is not the cell's"),
    ),
    "JuniorNatalin__VASC__BVTU_Backups_07.10.24_KJBVTU211160R01_ENGLISH_UP021.LS": (
        1,
        1,
        ["--ignore-external-axes"],
        70,
        (537, "Tool_Offset at line 79"),
    ),
    "JuniorNatalin__VASC__BVTU_Backups_07.10.24_KJBVTU211160R01_GERMAN_UP021.LS": (
        1,
        1,
        ["--ignore-external-axes"],
        70,
        (537, "WKZ_Offset at line 79"),
    ),
    "JuniorNatalin__VASC__KJLTVX_Descarregar_LTVL_1670R01_UP022.LS": (
        1,
        2,
        [],
        0,
        (380, "remote-TCP position"),
    ),
    "Surfacerobot__crs_application_sizen__src_collaborative-robotic-sanding_crs_process_data_"
    "data_main_toolpaths_surface.ls": (1, 1, [], 0, (43, "Tool_Offset at line 24")),
    "WILDER-SYSTEMS-LLC__git-ftp__a10defaste.ls": (
        9,
        1,
        ["--ignore-external-axes"],
        0,
        (75, "user frame 9 is set at run time (line 37)"),
    ),
    "WILDER-SYSTEMS-LLC__git-ftp__auto_calib_drill.ls": (1, 1, [], 0, (28, "PR[73]: a position")),
    "kamilkozdro__FanucProgramAnalyze__FanucProgramAnalyze_fanucPrograms_gratowanie.ls": (
        7,
        1,
        [],
        0,
        (53, "Offset at line 30"),
    ),
    "kamilkozdro__FanucProgramAnalyze__FanucProgramAnalyze_fanucPrograms_odkladanie.ls": (
        7,
        1,
        [],
        1,
        (193, "Offset at line 85"),
    ),
    "ros-industrial__fanuc__fanuc_driver_tpe_ros_movesm.ls": (
        1,
        1,
        [],
        0,
        (43, "PR[2]: a position"),
    ),
    "rpiRobotics__fanuc_motion_program_exec__tp_EXAMPLE.LS": (1, 1, [], 6, None),
    "rpiRobotics__fanuc_motion_program_exec__tp_EXAMPLE_COOR.LS": (
        1,
        2,
        [],
        0,
        (27, "COORD) at line 22"),
    ),
    "rpiRobotics__fanuc_motion_program_exec__tp_TMPA.LS": (1, 1, [], 2, None),
    "salmanTaj__MPL_Spain_Enclosure__TP_clean1.ls": (1, 1, [], 0, (53, "PR[115]: a position")),
}


def write_fanuc_cell(folder: Path, uf: int, ut: int) -> Path:
    """cell.yaml of an R-2000iC/165F with a constant error field over +-6 m, user frame ``uf``
    at ``REALWORLD_BASE`` and tool frame ``ut``."""
    write_grid(folder / "grid.csv", (-6000,) * 3, (6000,) * 3, 3000.0, field="constant")
    x, y, z, a, b, c = REALWORLD_BASE
    (folder / "cell.yaml").write_text(
        f"robot: r2000ic-165f\ngrid: grid.csv\ntool: {{number: {ut}, x: 0, y: 0, z: 250}}\n"
        f"base: {{number: {uf}, x: {x}, y: {y}, z: {z}, a: {a}, b: {b}, c: {c}}}\n"
    )
    return folder / "cell.yaml"


@pytest.mark.parametrize("name", sorted(REALWORLD))
def test_realworld_fanuc_rewrite_changes_only_the_corrected_numbers(
    realworld, tmp_path, capsys, name
):
    uf, ut, options, at_least, first = REALWORLD[name]
    program = realworld / "fanuc" / name
    cell = write_fanuc_cell(tmp_path, uf, ut)
    out, report = tmp_path / name, tmp_path / "r.csv"
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(out), *options]
    if first is not None:
        line, why = first
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"{program}:{line}: " in err and why in err, err
        assert not out.exists()
    assert main([*argv, "--allow-partial", "--report", str(report)]) == 0, capsys.readouterr()
    rows = list(csv.DictReader(report.open()))
    assert all(r["reason"] for r in rows if r["status"] != "corrected")
    corrected = {int(r["line"]): r for r in rows if r["status"] == "corrected"}
    assert len(corrected) >= at_least
    old, new = program.read_bytes().decode("latin-1"), out.read_bytes().decode("latin-1")
    lines = changed_lines(old, new)  # every other token byte for byte
    rot = Rotation.from_euler("ZYX", REALWORLD_BASE[3:], degrees=True).as_matrix()
    before, after = _positions(old), _positions(new)
    changed = 0
    for n, (p_uf, *_, xyz, wpr) in before.items():
        entry = re.compile(rf"P\[{n}[\]:]").search(old, old.index("/POS"))
        line = old[: entry.start()].count("\n") + 1
        if line not in corrected:
            assert after[n] == before[n]
            continue
        changed += 1
        e = E_CONST if p_uf == 0 else rot.T @ E_CONST  # the correction in the user frame
        places = max(2, max(len(v.partition(".")[2]) for v in re.findall(NUM, str(xyz))))
        np.testing.assert_allclose(after[n][3], np.array(xyz) + e, atol=0.5 * 10.0**-places)
        assert after[n][:3] == before[n][:3] and after[n][4] == wpr
    assert changed == len(corrected)
    pos_at = old[: old.index("/POS")].count("\n") + 1 if "/POS" in old else 10**9
    assert all(line >= pos_at for line in lines)  # numbers of /POS only
    # with the header: remarks at the top of /MN, the lines after them renumbered, numbers only
    headed = tmp_path / "headed" / name
    assert main([*argv, "--allow-partial", "--header", "-o", str(headed)]) == 0
    text = headed.read_bytes().decode("latin-1")
    added = text.count("\n") - new.count("\n")  # the header's remarks, right after /MN
    at = text.index("\n", text.index("/MN")) + 1
    lines = text[at:].split("\n")
    assert added > 3 and all(re.match(r" *\d+:  !.* ;\r?$", line) for line in lines[:added])
    changed_lines(new, text[:at] + "\n".join(lines[added:]))
    body = text[text.index("/MN") : text.index("/POS") if "/POS" in text else len(text)]
    top = [int(n) for n in re.findall(r"(?m)^[ \t]{0,4}(\d+):", body)]
    assert top == list(range(1, len(top) + 1))


def _rewrite(tmp_path, text: str, capsys, *extra: str) -> tuple[int, str, list[dict]]:
    program = tmp_path / "T.ls"
    program.write_bytes(text.encode("latin-1"))
    cell = write_fanuc_cell(tmp_path, 1, 1)
    report = tmp_path / "r.csv"
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(tmp_path / "out.ls")]
    code = main([*argv, "--report", str(report), *extra])
    err = capsys.readouterr().err
    return code, err, list(csv.DictReader(report.open())) if report.exists() else []


def _entry(n: int, uf: int = 1, ut: int = 1, body: str = "") -> str:
    body = body or (
        "X = 100.000 mm, Y = 20.000 mm, Z = 30.000 mm,\n W = 180.000 deg, P = 0.000 deg, "
        "R = 0.000 deg"
    )
    return f"P[{n}]{{\n   GP1:\n UF : {uf}, UT : {ut}, CONFIG : 'N U T, 0, 0, 0',\n {body}\n}};\n"


def _program(mn: list[str], positions: list[str]) -> str:
    """A TP program of /MN instructions ``mn`` (numbered in order; one that starts with ``:``
    continues the one before) and /POS entries."""
    lines, k = [], 0
    for line in mn:
        if line.startswith(":"):
            lines.append(f"    {line}\n")
        else:
            k += 1
            lines.append(f"{k:4d}:{line}\n")
    lines = "".join(lines)
    return f"/PROG  T\n/ATTR\n/MN\n{lines}/POS\n{''.join(positions)}/END\n"


def test_what_the_rewrite_leaves_it_reports_with_the_reason(tmp_path, capsys):
    mn = [
        "  UFRAME_NUM=1 ;",
        "  UTOOL_NUM=1 ;",
        "J P[1] 100% FINE ;",
        "L P[2] 100mm/sec FINE Offset,PR[3] ;",
        "L P[3] 100mm/sec FINE ;",
        "C P[4] ",
        ":  P[5] 100mm/sec FINE ;",
        "  PR[1]=P[6] ;",
        "L P[6] 100mm/sec FINE ;",
        "L P[7] 100mm/sec FINE ;",
        "J P[8] 50% CNT100 ;",
        "L PR[2] 100mm/sec FINE ;",
        "L P[10] 100mm/sec FINE ;",
    ]
    joint = "J1 = 1.000 deg, J2 = 2.000 deg, J3 = 3.000 deg,\n J4 = 4.000 deg, J5 = 5.000 deg"
    positions = [_entry(1), _entry(2), _entry(3, uf=2), _entry(4), _entry(5), _entry(6)]
    positions += [_entry(7, ut=3), f"P[8]{{\n   GP1:\n UF : 1, UT : 1,\n {joint}\n}};\n"]
    positions += [_entry(9)]
    text = _program(mn, positions)
    code, err, rows = _rewrite(tmp_path, text, capsys, "--allow-partial")
    assert code == 0, err
    by = {r["name"]: r for r in rows}
    assert [r["name"] for r in rows if r["status"] == "corrected"] == ["P[1]", "P[4]", "P[5]"]
    assert "Offset at line 7" in by["P[2]"]["reason"]
    assert "user frame 2" in by["P[3]"]["reason"]
    assert "read at line 11" in by["P[6]"]["reason"]  # file lines: /MN from line 4
    assert "tool frame 3" in by["P[7]"]["reason"]
    assert "joint position" in by["P[8]"]["reason"]
    assert "not used by a motion" in by["P[9]"]["reason"]
    assert "position register" in by["PR[2]"]["reason"] and by["PR[2]"]["line"] == "15"
    assert "no position P[n] in /POS" in by["P[10]"]["reason"]
    code, err, _ = _rewrite(tmp_path, text, capsys, "--force")  # a motion left: the job fails
    assert code == 2 and "T.ls:24: 6 position(s) cannot be corrected" in err, err


def test_header_is_remarks_at_the_top_and_the_lines_after_it_renumbered(tmp_path, capsys):
    text = _program(["  UFRAME_NUM=1 ;", "J P[1] 100% FINE ;"], [_entry(1)])
    code, err, _ = _rewrite(tmp_path, text, capsys, "--header")
    assert code == 0, err
    new = (tmp_path / "out.ls").read_text()
    mn = new[new.index("/MN\n") + 4 : new.index("/POS")].splitlines()
    assert [int(line.split(":")[0]) for line in mn] == list(range(1, len(mn) + 1))
    assert all(re.match(r"   \d:  !| {2}\d\d:  !", line) for line in mn[:-2]) and len(mn) > 4
    k = len(mn) - 2  # the header's remarks
    assert mn[-2:] == [f"   {k + 1}:  UFRAME_NUM=1 ;", f"   {k + 2}:J P[1] 100% FINE ;"]


@pytest.mark.parametrize(
    "text, where, why",
    [
        # a gap in the line numbers
        (
            "/PROG  T\n/MN\n   1:  UFRAME_NUM=1 ;\n   3:J P[1] 100% FINE ;\n/POS\n/END\n",
            ":4:4",
            "3",
        ),
        # /POS text that is no position
        ("/PROG  T\n/MN\n   1:J P[1] 100% FINE ;\n/POS\nP[1]{ junk };\n/END\n", ":5:", "P[1]"),
        ("/PROG  T\n/MN\n   1:J P[1] 100% FINE ;\n/POS\nX = 1 ;\n/END\n", ":5:1", "/POS"),
        # a position whose X is in degrees
        (
            "/PROG  T\n/MN\n   1:J P[1] 100% FINE ;\n/POS\n"
            + _entry(1).replace("X = 100.000 mm", "X = 100.000 deg"),
            ":8:",
            "X is in mm",
        ),
        ("MODULE X\n", ":1:1", "/PROG"),
    ],
)
def test_a_program_the_reader_cannot_read_is_a_located_error(tmp_path, capsys, text, where, why):
    code, err, _ = _rewrite(tmp_path, text, capsys)
    assert code == 2 and f"T.ls{where}" in err and why in err, err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "out.ls").exists()


@pytest.mark.parametrize(
    "change, out, key",
    [
        (("robot: r2000ic-165f", "robot: kr210"), "WING.ls", "KUKA controller"),
        (("base: {number: 1,", "base: {number: 12,"), "WING.ls", "base.number"),
        (("tool: {number: 1,", "tool: {number: 11,"), "WING.ls", "tool.number"),
        (("  program: WING ", "  program: 9WING "), "WING.ls", "fanuc.program"),
        (("  program: WING ", "  program: " + "W" * 37 + " "), "WING.ls", "at most 36"),
        (("  program: WING ", "  # program"), "1WING.ls", "1WING"),
        (("  approach: 50 ", "  approach: 50.5 "), "WING.ls", "speeds.approach"),
    ],
)
def test_a_cell_or_name_the_controller_refuses_is_a_located_error(
    tmp_path, capsys, change, out, key
):
    cell = tmp_path / "cell.yaml"
    cell.write_text(CELL.read_text().replace(*change))
    target = tmp_path / out
    points = EXAMPLES / "wing_panel_points.csv"
    argv = ["fanuc", str(points), "--cell", str(cell), "-o", str(target), "--no-correction"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert key in err and err.count("\n") == 1, err
    assert (str(target) if out == "1WING.ls" else f"{cell}:") in err
    assert not target.exists()


def test_the_example_cell_reaches_the_wing_panel(tmp_path):
    out = tmp_path / "WING.ls"
    points = EXAMPLES / "wing_panel_points.csv"
    assert main(["fanuc", str(points), "--cell", str(CELL), "-o", str(out), "--no-correction"]) == 0
    assert len(_positions(out.read_text())) == 4 * 72


def _literal(value: float, places: int, bare: bool) -> str:
    """``value`` written with ``places`` decimals, without its leading zero when ``bare``."""
    text = f"{value:.{places}f}"
    if bare and text.lstrip("-").startswith("0."):
        text = text.replace("0.", ".", 1)
    return text


@settings(max_examples=25, deadline=None)
@given(
    data=st.lists(
        st.tuples(
            st.lists(st.floats(-2000, 2000), min_size=3, max_size=3),
            st.integers(1, 6),  # decimals
            st.booleans(),  # bare (.5)
            st.sampled_from([" ", "\t", "  "]),  # separator
            st.booleans(),  # CONFIG given
            st.booleans(),  # a label P[n:"..."]
        ),
        min_size=1,
        max_size=5,
    ),
    crlf=st.booleans(),
    tab_numbers=st.booleans(),
)
def test_rewrite_finds_every_position_in_any_layout(tmp_path_factory, data, crlf, tab_numbers):
    tmp = tmp_path_factory.mktemp("layout")
    mn, pos = [], []
    for n, (xyz, places, bare, sep, config, label) in enumerate(data, start=1):
        name = f'P[{n}:""]' if label else f"P[{n}]"
        mn.append(f"{'L' if n > 1 else 'J'} {name} 100mm/sec FINE ;")
        numbers = [_literal(v, places, bare) for v in xyz]
        words = f"CONFIG : 'N U T, 0, 0, 0',{sep}" if config else ""
        pos.append(
            f"{name}{{\n   GP1:\n{sep}UF : 1, UT : 1,{sep}{words}\n"
            f"{sep}X ={sep}{numbers[0]}{sep}mm,{sep}Y ={sep}{numbers[1]}{sep}mm,{sep}Z ={sep}"
            f"{numbers[2]}{sep}mm,\n{sep}W = 180.000 deg,{sep}P = 0.000 deg,{sep}R = 0.000 deg"
            "\n};\n"
        )
    text = _program(mn, pos)
    if tab_numbers:
        text = re.sub(r"(?m)^ +(\d+):", "\t\\1:", text)
    if crlf:
        text = text.replace("\n", "\r\n")
    program, out = tmp / "T.ls", tmp / "out.ls"
    program.write_bytes(text.encode("latin-1"))
    cell = write_fanuc_cell(tmp, 1, 1)
    assert main(["rewrite", str(program), "--cell", str(cell), "-o", str(out)]) == 0
    new = out.read_bytes().decode("latin-1")
    changed_lines(text, new)  # numbers only
    rot = Rotation.from_euler("ZYX", REALWORLD_BASE[3:], degrees=True).as_matrix()
    e = rot.T @ E_CONST
    after = _positions(new)
    places = max(2, max(p for _, p, *_ in data))
    for n, (xyz, *_) in enumerate(data, start=1):
        written = np.array([float(_literal(v, data[n - 1][1], False)) for v in xyz])
        np.testing.assert_allclose(after[n][3], written + e, atol=0.5 * 10.0**-places + 1e-9)


def test_frame_entries_are_the_pose_in_fixed_xyz_angles():
    from accugrid.codegen.dialects import plugin_of

    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_euler("xyz", [10.0, -20.0, 30.0], degrees=True).as_matrix()
    pose[:3, 3] = [1700.0, 300.0, 400.0]
    assert plugin_of("fanuc").base_line(3, pose) == (
        "UFRAME[3]: X = 1700.000 mm, Y = 300.000 mm, Z = 400.000 mm, W = 10.000 deg, "
        "P = -20.000 deg, R = 30.000 deg"
    )
    turned = np.eye(4)
    turned[:3, :3] = Rotation.from_euler("y", 90.0, degrees=True).as_matrix()
    turned[2, 3] = 250.0
    line = plugin_of("fanuc").tool_line(1, turned)
    assert line.startswith("UTOOL[1]: X = 0.000 mm, Y = 0.000 mm, Z = 250.000 mm, ")
    wpr = [float(v) for v in re.findall(rf"[WPR] = ({NUM}) deg", line)]
    np.testing.assert_allclose(
        Rotation.from_euler("xyz", wpr, degrees=True).as_matrix(), turned[:3, :3], atol=1e-6
    )


def test_a_feed_the_controller_cannot_take_is_a_located_error(tmp_path, capsys):
    points = tmp_path / "p.csv"
    points.write_text("id,x,y,z,i,j,k,feed\nH1,100,200,0,0,0,-1,5\nH2,120,200,0,0,0,-1,2.5\n")
    out = tmp_path / "WING.ls"
    argv = ["fanuc", str(points), "--cell", str(CELL), "-o", str(out), "--no-correction"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{points}:3:8: " in err and "whole number of mm/sec" in err, err
    assert not out.exists()


@settings(max_examples=60, deadline=None)
@given(q=st.tuples(*(st.floats(lo, hi) for lo, hi in load_robot("r2000ic-165f").joint_limits_deg)))
def test_config_words_are_the_arm_geometry_of_any_joints(q):
    from accugrid.codegen.fanuc.configuration import configuration_words, read_configuration
    from accugrid.kinematics.configuration import Configuration

    robot = load_robot("r2000ic-165f")
    q = np.radians(q)
    if min(abs(np.degrees(q[4])), abs(np.degrees(q[4]) % 180.0 - 180.0)) < 1e-6:
        return  # J5 on the wrist singularity: either wrist
    words = configuration_words(Configuration.of_joints(robot, q[None]))[0]
    letters = "{} {} {}".format("NF"[words[0]], "DU"[words[1]], "TB"[words[2]])
    assert f"{letters}, {words[3]}, {words[4]}, {words[5]}" == _config_of(q)
    back = read_configuration(words)  # the words read back name the same configuration
    np.testing.assert_array_equal(configuration_words(back), words)
