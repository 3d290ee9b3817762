"""LinuxCNC's own interpreter accepts the generated G-code, and the canonical moves it prints
reproduce every corrected position (and A B C) to 0.001 mm.

``rs274 -g FILE`` runs the standalone RS274NGC interpreter and prints canonical machining
commands; under G21 STRAIGHT_TRAVERSE/STRAIGHT_FEED carry X, Y, Z in mm then A, B, C (checked:
USE_LENGTH_UNITS(CANON_UNITS_MM) is printed). Skipped with a reason only where rs274 is not
installed and CI is not set; on CI a missing rs274 is a failure.
"""

from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest
from program_helpers import cell, cell_with, grid, panel_points, robot

from accugrid.codegen.gcode.emit import render_gcode
from accugrid.codegen.program import build_program
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc

MOVE_RE = re.compile(r"(STRAIGHT_TRAVERSE|STRAIGHT_FEED)\(([^)]*)\)")
ROWS = np.array(
    [
        [x + (12.5 if y == 175.0 else 0.0), y]
        for y in (150.0, 175.0, 450.0)
        for x in range(0, 576, 25)
    ]
)
TOL_MM = 0.001


def canonical(rs274, tmp_path, text):
    """(M, 6) end points of the canonical straight moves rs274 prints for ``text``, and units."""
    path = tmp_path / "job.ngc"
    path.write_text(text)
    run = subprocess.run(
        [rs274, "-g", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        stdin=subprocess.DEVNULL,
    )
    out = run.stdout
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    # an interpreter error exits 1 (checked above); a complete run reaches the M2
    assert "PROGRAM_END()" in out, out[-2000:]
    assert "USE_LENGTH_UNITS(CANON_UNITS_MM)" in out
    rows = [[float(v) for v in m.group(2).split(",")[:6]] for m in MOVE_RE.finditer(out)]
    return np.array(rows), out


def check_against_program(moves, program, frame):
    pos, _ = program.in_frame(frame)
    rot = np.linalg.inv(frame[:3, :3]) @ program.cell.robot_T_base[:3, :3] @ program.rotations
    at = 0
    for i in range(len(program)):
        for k in range(4):
            while at < len(moves) and np.abs(moves[at, :3] - pos[i, k]).max() > TOL_MM:
                at += 1
            assert at < len(moves), f"hole {i} stage {k} {pos[i, k]} not among rs274's moves"
            np.testing.assert_allclose(abc_to_matrix(moves[at, 3:]), rot[i], atol=3e-5)
            at += 1


def test_example_program_through_rs274(rs274, tmp_path):
    program = build_program(panel_points(ROWS), cell(), robot(), grid())
    text = render_gcode(program, ["accugrid rs274 check"])
    moves, out = canonical(rs274, tmp_path, text)
    assert "DWELL(0.5000)" in out and "START_SPINDLE_CLOCKWISE" in out
    assert len(moves) >= 4 * len(program) - 1
    check_against_program(moves, program, cell().dialects["gcode"].robot_T_program)


@pytest.mark.parametrize(
    "change",
    [
        {"drilling": {"peck_mm": 2.5}},
        {"drilling": {"dwell_s": 0.0, "retract_mm": 45.0}},
        {"gcode": {"canned_cycles": False, "decimals": 4}},
        {
            "gcode": {
                "robot_T_program": pose_from_xyzabc(
                    np.array([1700.0, 100.0, 1200.0, 180.0, -90.0, 0.0])
                )
            }
        },
    ],
)
def test_variants_through_rs274(rs274, tmp_path, change):
    c = cell_with(**change)
    program = build_program(panel_points(ROWS[20:30]), c, robot(), grid())
    moves, _ = canonical(rs274, tmp_path, render_gcode(program, ["variant"]))
    check_against_program(moves, program, c.dialects["gcode"].robot_T_program)
