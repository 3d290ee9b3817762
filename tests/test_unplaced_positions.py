"""The job rule for positions a rewrite cannot place in the robot frame: a Cartesian position a
motion commands that is left uncorrected lands off by the robot's error, so it fails the job
unless --allow-partial, like a position the policy refuses; a joint target, a frame or offset,
tool data and data no motion uses are not positions to correct and do not count."""

from __future__ import annotations

import csv

import pytest
from rewrite_helpers import write_cell

from accugrid.codegen.cli import main

GOOD = "LIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0}"  # inside the grid, base 1 = robot frame

# (case, lines after the corrected LIN, the .dat's lines, the line of the uncorrected position)
COUNTED = {
    "unknown_base": (["$BASE=BASE_DATA[7]", GOOD], [], 5),
    "base_from_a_variable": (["$BASE=MYFRAME", GOOD], [], 5),
    "relative_motion": (["LIN_REL {Z 10}"], [], 4),
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
