"""Positions a program commands with a tool the rewrite cannot prove to be the one it corrects
for are reported, never corrected with the cell's tool: a ``$TOOL`` literal frame, another
TOOL_DATA number, ``BAS(#TOOL, n)``, an FDAT's TOOL_NO (KRL), ``T n M6 G43`` (G-code), a move's
tooldata (RAPID).

Expected statuses follow from the programs as written: the cell's tool is TOOL_DATA[1], X 0,
Y 0, Z 250 mm, A 0, B 0, C 0; with the constant grid a corrected position moves by E_CONST."""

from __future__ import annotations

import numpy as np
from rewrite_helpers import E_CONST, write_cell, write_rapid_cell
from test_several_tools import TOOL_DATA, _new, _old, _rewrite

# line: the tool each LIN is commanded with, as the program selects it
KRL = """DEF T()
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
$TOOL={FRAME: X -30.000,Y 0.000,Z 40.000,A 0.000,B -60.000,C 0.000}
LIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}
$TOOL={X 0.0,Y 0.0,Z 250.0,A 0.0,B 0.0,C 0.0}
LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}
$TOOL={X 0.5,Y 0,Z 250,A 0,B 0,C 0}
LIN {X 1500,Y 300,Z 1500,A 0,B 90,C 0}
$TOOL=TOOL_DATA[2]
LIN {X 1500,Y 400,Z 1500,A 0,B 90,C 0}
$TOOL=TOOL_DATA[1]
LIN {X 1500,Y 500,Z 1500,A 0,B 90,C 0}
BAS(#TOOL,3)
LIN {X 1500,Y 600,Z 1500,A 0,B 90,C 0}
$TOOL=$NULLFRAME
LIN {X 1500,Y 700,Z 1500,A 0,B 90,C 0}
FDAT_ACT={TOOL_NO 2,BASE_NO 1,IPO_FRAME #BASE}
LIN {X 1500,Y 800,Z 1500,A 0,B 90,C 0}
FDAT_ACT={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}
LIN {X 1500,Y 900,Z 1500,A 0,B 90,C 0}
END
"""
CELL_TOOL = (2, 6, 12, 20)  # no tool set yet, X 0 Y 0 Z 250 (its decimals), TOOL_DATA[1], TOOL_NO 1


def _corrected(row: dict) -> None:
    assert row["status"] == "corrected", row
    np.testing.assert_allclose(_new(row) - _old(row), E_CONST, atol=1e-9)


def test_krl_without_tool_data_reports_every_other_tool(tmp_path):
    cell = write_cell(tmp_path, field="constant")
    rows = _rewrite(tmp_path, cell, {"t.src": KRL}, "--base", "1", "--decimals", "4")
    for line in CELL_TOOL:
        _corrected(rows[line])
    unproven = {
        4: "tool unknown: $TOOL set to a literal frame (line 3) that is not the cell's tool",
        8: "tool unknown: $TOOL set to a literal frame (line 7) that is not the cell's tool",
        10: "tool 2 is not the cell's tool 1",
        14: "tool 3 is not the cell's tool 1",
        16: "tool 0 is not the cell's tool 1",
        18: "tool 2 is not the cell's tool 1",
    }
    for line, reason in unproven.items():
        assert rows[line]["status"] == "skipped", rows[line]
        assert rows[line]["reason"].startswith(reason), rows[line]
    text = (tmp_path / "out.src").read_text()
    for line in unproven:  # as written
        assert KRL.splitlines()[line - 1] in text.splitlines()


def test_krl_tool_literal_within_its_written_decimals(tmp_path):
    """The cell's tool 0.0004 mm off X 0: ``X 0`` (half a unit: 0.5 mm) is that tool,
    ``X 0.000`` (0.0005 mm) is, ``X 0.0000`` (0.00005 mm) is not."""
    cell = write_cell(tmp_path, field="constant")
    cell.write_text(
        cell.read_text().replace("tool: {number: 1, x: 0,", "tool: {number: 1, x: 0.0004,")
    )
    program = (
        "DEF T()\n"
        + "".join(
            f"$TOOL={{X {x},Y 0,Z 250,A 0,B 0,C 0}}\nLIN {{X 1500,Y {k},Z 1500,A 0,B 90,C 0}}\n"
            for k, x in enumerate(("0", "0.000", "0.0000"))
        )
        + "END\n"
    )
    rows = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1", "--decimals", "4")
    _corrected(rows[3])
    _corrected(rows[5])
    assert rows[7]["status"] == "skipped"
    assert rows[7]["reason"].startswith("tool unknown: $TOOL set to a literal frame (line 6)")


def test_krl_tool_literal_selects_the_declared_tool(tmp_path):
    """With ``tool_data`` a literal frame equal to a declared tool is that tool: 2 (0.5 mm from
    the cell's, corrected by the grid), 3 (150 mm further out, refused by the grid); a frame
    that is none of them is reported."""
    cell = write_cell(tmp_path, field="constant")
    cell.write_text(cell.read_text() + TOOL_DATA)
    program = """DEF T()
$TOOL={FRAME: X 0.5,Y 0,Z 250,A 0,B 0,C 0}
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
$TOOL={X 0,Y 0,Z 400,A 0,B 0,C 10}
LIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}
$TOOL={X -30,Y 0,Z 40,A 0,B -60,C 0}
LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}
END
"""
    rows = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1", "--decimals", "4")
    _corrected(rows[3])
    assert "tool 3: its TCP is 150.000 mm from" in rows[5]["reason"]
    assert rows[7]["reason"].startswith(
        "tool unknown: $TOOL set to a literal frame (line 6) that is not any tool of the cell"
    )


# line: the tool whose length offset is in effect (LinuxCNC: T selects, M6 loads, G43 applies)
GCODE = """G21 G90 G17
G0 X1500 Y0 Z1500
T2 M6 G43
G0 X1500 Y100 Z1500
G49
G0 X1500 Y200 Z1500
T1 M6 G43 H1
G0 X1500 Y300 Z1500
G43.1 Z10
G0 X1500 Y400 Z1500
M2
"""


def test_gcode_without_tool_data_reports_another_tools_offset(tmp_path):
    """Lines 2 (no offset), 6 (G49) and 8 (tool 1's) are the cell's tool; line 4 moves tool 2's
    tip, line 10 a length offset given in words."""
    cell = write_cell(tmp_path, field="constant")
    rows = _rewrite(tmp_path, cell, {"t.ngc": GCODE}, "--decimals", "4")
    for line in (2, 6, 8):
        _corrected(rows[line])
    assert rows[4]["status"] == "skipped"
    assert rows[4]["reason"].startswith("tool 2 is not the cell's tool 1")
    assert rows[10]["status"] == "skipped"
    assert rows[10]["reason"].startswith("tool unknown: G43.1 at line 9")
    lines = (tmp_path / "out.ngc").read_text().splitlines()
    assert lines[3] == "G0 X1500 Y100 Z1500" and lines[9] == "G0 X1500 Y400 Z1500"


def test_rapid_without_tool_data_reports_another_tooldata(tmp_path):
    """A move with the cell's tooldata (rapid.tool tDrill) is corrected, one with another
    tooldata is reported and written as given."""
    cell = write_rapid_cell(tmp_path, "tDrill", "wobjPanel")
    target = "[[{y},50,30],[0.5,0,0.866025404,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    module = (
        "MODULE T\n  PROC main()\n"
        f"    MoveL {target.format(y=100)}, v10, fine, tDrill\\WObj:=wobjPanel;\n"
        f"    MoveL {target.format(y=120)}, v10, fine, tOther\\WObj:=wobjPanel;\n"
        "  ENDPROC\nENDMODULE\n"
    )
    rows = _rewrite(tmp_path, cell, {"t.mod": module}, "--decimals", "4")
    assert rows[3]["status"] == "corrected"
    assert rows[4]["status"] == "skipped"
    assert rows[4]["reason"].startswith("moved with tool tOther at line 4, not the cell's")
    assert "MoveL [[120,50,30]," in (tmp_path / "out.mod").read_text()


def test_krl_fdat_tool_not_a_number_is_reported(tmp_path):
    """An FDAT whose TOOL_NO is a variable selects a tool not known before run time, with or
    without tool_data; its base alone does not place the position."""
    program = """DEF T()
DECL FDAT F1={TOOL_NO nTool,BASE_NO 1,IPO_FRAME #BASE}
FDAT_ACT=F1
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
FDAT_ACT={TOOL_NO nTool,BASE_NO 1,IPO_FRAME #BASE}
LIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}
FDAT_ACT={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}
LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}
END
"""
    for declared in (False, True):
        folder = tmp_path / str(declared)
        folder.mkdir()
        cell = write_cell(folder, field="constant")
        if declared:
            cell.write_text(cell.read_text() + TOOL_DATA)
        rows = _rewrite(folder, cell, {"t.src": program}, "--base", "1", "--decimals", "4")
        assert rows[4]["reason"] == "tool unknown: FDAT TOOL_NO nTool (line 2): not a number"
        assert rows[6]["reason"] == "tool unknown: FDAT TOOL_NO nTool (line 5): not a number"
        _corrected(rows[8])


WITH_TOOL = """DEF T()
DECL FDAT F3={TOOL_NO 3,BASE_NO 1,IPO_FRAME #BASE}
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0} WITH $TOOL = TOOL_DATA[2]
SPLINE WITH $TOOL = TOOL_DATA[2]
SLIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}
ENDSPLINE
SLIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0} WITH $TOOL = STOOL2(F3), $BASE = SBASE(F3.BASE_NO)
SLIN {X 1500,Y 300,Z 1500,A 0,B 90,C 0} WITH $TOOL = tVar
LIN {X 1500,Y 400,Z 1500,A 0,B 90,C 0}
END
"""


def test_krl_motion_with_its_own_tool(tmp_path):
    """A motion's (a spline block's) ``WITH $TOOL = ...`` is its tool, for it alone: tool 2 on
    lines 3 and 5, FDAT F3's tool 3 on line 7, a variable on line 8; line 9 is the cell's
    tool again. Without tool_data only line 9 is corrected; with it tool 2 (0.5 mm from the
    cell's) is corrected too, tool 3 (150 mm further out) is refused by the grid."""
    plain = tmp_path / "plain"
    plain.mkdir()
    cell = write_cell(plain, field="constant")
    rows = _rewrite(plain, cell, {"t.src": WITH_TOOL}, "--base", "1", "--decimals", "4")
    for line in (3, 5):
        assert rows[line]["reason"].startswith("tool 2 is not the cell's tool 1"), rows[line]
    assert rows[7]["reason"].startswith("FDAT F3 (line 2) has TOOL_NO 3")
    unknown = "tool unknown: WITH $TOOL = tVar (line 8): not a TOOL_DATA number"
    assert rows[8]["reason"] == unknown
    _corrected(rows[9])
    cell = write_cell(tmp_path, field="constant")
    cell.write_text(cell.read_text() + TOOL_DATA)
    rows = _rewrite(tmp_path, cell, {"t.src": WITH_TOOL}, "--base", "1", "--decimals", "4")
    for line in (3, 5, 9):
        _corrected(rows[line])
    assert "tool 3: its TCP is 150.000 mm from" in rows[7]["reason"]
    assert rows[8]["reason"] == unknown


def test_krl_program_that_redefines_the_cells_tool_number(tmp_path):
    """TOOL_DATA[1] written by the program 150 mm longer than the cell's tool 1: the tool the
    program then selects with that number is not the cell's, with or without tool_data."""
    program = """DEF T()
TOOL_DATA[1]={X 0,Y 0,Z 400,A 0,B 0,C 0}
$TOOL=TOOL_DATA[1]
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
END
"""
    cell = write_cell(tmp_path, field="constant")
    rows = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1", "--decimals", "4")
    assert rows[4]["reason"] == "tool unknown: TOOL_DATA[1] (t.src:2) is not the cell's tool 1"
    same = program.replace("Z 400", "Z 250")
    again = tmp_path / "same"
    again.mkdir()
    rows = _rewrite(
        again,
        write_cell(again, field="constant"),
        {"t.src": same},
        "--base",
        "1",
        "--decimals",
        "4",
    )
    _corrected(rows[4])
