"""The job rule for positions a rewrite cannot place in the robot frame: a Cartesian position a
motion commands that is left uncorrected lands off by the robot's error, so it fails the job
unless --allow-partial, like a position the policy refuses; a joint target, a frame or offset,
tool data and data no motion uses are not positions to correct and do not count. The same rule
for KRL, G-code and RAPID."""

from __future__ import annotations

import csv

import pytest
from rewrite_helpers import write_cell, write_rapid_cell

from accugrid.app.cli import main

GOOD = "LIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0}"  # inside the grid, base 1 = robot frame

# (case, lines after the corrected LIN, the .dat's lines, the line of the uncorrected position)
COUNTED = {
    "unknown_base": (["$BASE=BASE_DATA[7]", GOOD], [], 5),
    "base_from_a_variable": (["$BASE=MYFRAME", GOOD], [], 5),
    "relative_motion_start_not_known": (["IF $IN[1] THEN", "LIN_REL {Z 10}", "ENDIF"], [], 5),
    "frame_arithmetic": (["LIN XOFF:{X 1500,Y 100,Z 1400,A 0,B 90,C 0}"], [], 4),
    "variable_set_at_run_time": (["LIN XRUN"], ["DECL E6POS XRUN"], 4),
    "undeclared_name": (["LIN XNOWHERE"], [], 4),
    "partial_aggregate": (["LIN {Z 1200}"], [], 4),
}
NOT_COUNTED = {
    "joint_target": (["PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}"], []),
    "relative_joint_target": (["PTP_REL {A1 10}"], []),
    "declared_axis_target": (["PTP XHOME"], ["DECL E6AXIS XHOME"]),
    "tool_data": (["$TOOL=TOOL_DATA[1]"], ["DECL FRAME TOOL_DATA_X={X 0,Y 0,Z 250,A 0,B 0,C 0}"]),
    "unused_position_in_the_dat": ([], ["DECL E6POS XSPARE={X 1,Y 2,Z 3,A 0,B 90,C 0}"]),
}


def _job(folder, body, dat):
    cell = write_cell(folder)
    src, dat_file = folder / "job.src", folder / "job.dat"
    src.write_text("\n".join(["DEF job( )", "$BASE=BASE_DATA[1]", GOOD, *body, "END"]) + "\n")
    dat_file.write_text("\n".join(["DEFDAT job", *dat, "ENDDAT"]) + "\n")
    return cell, src, dat_file


@pytest.mark.parametrize("case", sorted(COUNTED))
def test_an_unplaced_commanded_position_fails_the_job_unless_allow_partial(tmp_path, capsys, case):
    body, dat, line = COUNTED[case]
    cell, src, dat_file = _job(tmp_path, body, dat)
    out, report = tmp_path / "out", tmp_path / "r.csv"
    argv = ["rewrite", str(src), str(dat_file), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"job.src:{line}:" in err and "1 not placed in the robot frame" in err, err
    assert not out.exists()  # nothing written
    assert main([*argv, "--allow-partial", "--report", str(report)]) == 0
    assert "1 not placed in the robot frame" in capsys.readouterr().err
    rows = list(csv.DictReader(report.open()))
    left = [r for r in rows if r["file"] == "job.src" and r["line"] == str(line)]
    assert left and all(r["status"] == "skipped" and r["reason"] for r in left)
    kept = (out / "job.src").read_text().splitlines()
    assert kept[line - 1] == src.read_text().splitlines()[line - 1]


@pytest.mark.parametrize("case", sorted(NOT_COUNTED))
def test_joint_targets_frames_and_unused_data_do_not_fail_the_job(tmp_path, capsys, case):
    body, dat = NOT_COUNTED[case]
    cell, src, dat_file = _job(tmp_path, body, dat)
    out = tmp_path / "out"
    argv = ["rewrite", str(src), str(dat_file), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "left uncorrected" not in capsys.readouterr().err


def test_a_frame_used_with_a_colon_is_not_counted_but_the_motion_is(tmp_path, capsys):
    # LIN XOFF:XP1: the motion lands off (counted once); XOFF and XP1 are operands, not holes
    body = ["LIN XOFF:XP1"]
    dat = ["DECL FRAME XOFF={X 0,Y 0,Z 5,A 0,B 0,C 0}", "DECL E6POS XP1={X 1,Y 2,Z 3,A 0,B 0,C 0}"]
    cell, src, dat_file = _job(tmp_path, body, dat)
    argv = ["rewrite", str(src), str(dat_file), "--cell", str(cell), "-o", str(tmp_path / "o")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "1 position(s) cannot be corrected (1 not placed in the robot frame)" in err, err
    assert "job.src:4:" in err


@pytest.mark.parametrize(
    ("program", "counted"),
    [
        ("G90 G21\nG1 X1500 Y100 Z1400 F100\nG28\nG1 Z1300\nM2\n", 1),  # after G28: unknown X, Y
        ("G90 G21\nG1 X1500 Y100 Z1400 F100\nG53 G0 Z0\nM2\n", 0),  # machine coordinates
        ("G90 G21\nG0 Z1450\nG1 X1500 Y100 Z1400 F100\nM2\n", 1),  # Z before any X, Y
        ("G90 G21\nG1 X1500 Y100 Z1400 F100\nG1 X#1\nM2\n", 1),  # a parameter
    ],
)
def test_gcode_moves_that_cannot_be_placed_count_except_machine_moves(
    tmp_path, capsys, program, counted
):
    cell = write_cell(tmp_path)
    ngc = tmp_path / "p.ngc"
    ngc.write_text(program)
    argv = ["rewrite", str(ngc), "--cell", str(cell), "-o", str(tmp_path / "o.ngc")]
    assert main(argv) == (2 if counted else 0)
    err = capsys.readouterr().err
    if counted:
        assert f"{counted} not placed in the robot frame" in err, err


def test_a_program_whose_holes_are_all_in_called_routines_is_not_a_silent_success(
    realworld, tmp_path, capsys
):
    # a LinuxCNC program that drills only through `o<drill> call`: no position is read, so the
    # rewrite corrects nothing; it came back byte-identical with exit 0
    program = realworld / "gcode" / "lagun_HEMA-P005.cnc"
    cell = write_cell(tmp_path)
    out = tmp_path / "o.cnc"
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{program}: no position corrected" in err and not out.exists()
    assert main([*argv, "--allow-partial"]) == 0
    assert out.read_bytes() == program.read_bytes()


# RAPID: a module with a corrected robtarget pOk (line 2), robtarget pA at line 3, main's body from
# line 6; the cell's tool tDrill and work object wobjPanel
ROB = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
CELL_MOVE = "v10, fine, tDrill\\WObj:=wobjPanel;"
PA = f"CONST robtarget pA:={ROB};"
DRILL = ["PROC Drill(robtarget p)", f"MoveL p, {CELL_MOVE}", "ENDPROC"]
# case -> (pA's line, main's body, routines after main, the line and count of unplaced ones)
RAPID_COUNTED = {
    "offs_operand": (PA, [f"MoveL Offs(pA,0,0,10), {CELL_MOVE}"], [], 3, 1),
    "reltool_operand": (PA, [f"MoveJ RelTool(pA,0,0,-10), {CELL_MOVE}"], [], 3, 1),
    "other_work_object": (PA, ["MoveL pA, v10, fine, tDrill\\WObj:=wobjOther;"], [], 3, 1),
    "other_tool": (PA, ["MoveL pA, v10, fine, tOther\\WObj:=wobjPanel;"], [], 3, 1),
    "reassigned_at_run_time": (PA, ["pA := CRobT();", f"MoveL pA, {CELL_MOVE}"], [], 3, 1),
    "external_axes": (PA.replace("[9E+09,", "[250,", 1), [f"MoveL pA, {CELL_MOVE}"], [], 3, 1),
    "inline_in_other_work_object": (
        PA,
        [f"MoveL {ROB}, v10, fine, tDrill\\WObj:=wobjOther;"],
        [],
        6,
        1,
    ),
    "work_object_changed": (
        PA,
        ["wobjPanel.oframe.trans.z := 5;", f"MoveL pA, {CELL_MOVE}"],
        [],
        2,
        2,
    ),
    "custom_move_routine": (PA, ["Drill pA;"], DRILL, 3, 1),
    "move_like_instruction": (
        PA,
        ["ArcL pA, v10, seam1, weld1, z5, tDrill\\WObj:=wobjPanel;"],
        [],
        3,
        1,
    ),
}
RAPID_NOT_COUNTED = {
    "joint_target": (
        "CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];",
        ["MoveAbsJ jHome, v100, fine, tDrill;"],
    ),
    "tool_data": (
        "PERS tooldata tOther:=[TRUE,[[0,0,100],[1,0,0,0]],[1,[0,0,0],[1,0,0,0],0,0,0]];",
        [],
    ),
    "work_object_data": (
        'PERS wobjdata wobjOther:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];',
        [],
    ),
    "pose": ("CONST pose peOff:=[[0,0,10],[1,0,0,0]];", []),
    "unused_robtarget": (PA, []),
    "robtarget_read_by_a_non_motion": (PA, ['TPWrite "at"\\Pos:=pA.trans;']),
    "offs_operand_of_an_assignment": (PA, ["pB := Offs(pA,0,0,10);"]),
}


def _module(folder, decl, body, routines=()):
    cell = write_rapid_cell(folder, "tDrill", "wobjPanel")
    module = folder / "job.mod"
    lines = ["MODULE JOB", f"CONST robtarget pOk:={ROB};", decl, "PROC main()"]
    lines += [f"MoveL pOk, {CELL_MOVE}", *body, "ENDPROC", *routines, "ENDMODULE"]
    module.write_text("\n".join(lines) + "\n")
    return cell, module


@pytest.mark.parametrize("case", sorted(RAPID_COUNTED))
def test_an_unplaced_robtarget_a_motion_commands_fails_the_job_unless_allow_partial(
    tmp_path, capsys, case
):
    decl, body, routines, line, count = RAPID_COUNTED[case]
    cell, module = _module(tmp_path, decl, body, routines)
    out, report = tmp_path / "out.mod", tmp_path / "r.csv"
    argv = ["rewrite", str(module), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"job.mod:{line}:" in err and f"({count} not placed in the robot frame)" in err, err
    assert not out.exists()
    assert main([*argv, "--allow-partial", "--report", str(report)]) == 0
    assert f"{count} not placed in the robot frame" in capsys.readouterr().err
    rows = list(csv.DictReader(report.open()))
    left = [r for r in rows if r["line"] == str(line)]
    assert left and all(r["status"] == "skipped" and r["reason"] for r in left)
    assert out.read_text().splitlines()[line - 1] == module.read_text().splitlines()[line - 1]


@pytest.mark.parametrize("case", sorted(RAPID_NOT_COUNTED))
def test_rapid_joint_targets_frames_and_unmoved_robtargets_do_not_fail_the_job(
    tmp_path, capsys, case
):
    cell, module = _module(tmp_path, *RAPID_NOT_COUNTED[case])
    out, report = tmp_path / "out.mod", tmp_path / "r.csv"
    argv = ["rewrite", str(module), "--cell", str(cell), "-o", str(out), "--report", str(report)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "left uncorrected" not in capsys.readouterr().err
    rows = {r["name"]: r for r in csv.DictReader(report.open())}
    assert rows["pOk"]["status"] == "corrected"
