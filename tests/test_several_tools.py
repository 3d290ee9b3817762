"""Several tools: the cell's ``tool_data``, and each position of a rewritten program corrected
with the tool its program selects (KRL FDAT TOOL_NO / $TOOL / BAS(#TOOL), G-code T M6 G43,
RAPID tooldata names).

Expected numbers are computed here without the code under test: with the constant error grid
the correction is E_CONST in the robot frame; with a calibrated model the rewritten command,
solved by the nominal arm with the position's own tool, must land that tool's TCP of the
calibrated arm on the original target (its FK)."""

from __future__ import annotations

import csv
import re
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import E_CONST, RAPID_BASE, write_cell, write_grid, write_rapid_cell
from test_gcode_rs274 import canonical

from accugrid.app.cli import main
from accugrid.codegen.cell import load_cell
from accugrid.compensation import GridModel
from accugrid.compensation.policy import ORIENTATION, OTHER_TOOL, Policy
from accugrid.compensation.settings import CorrectionSettings
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix, pose_from_xyzabc
from accugrid.kinematics.robot import load_robot

REALISTIC = resources.files("accugrid.kinematics").joinpath("robots", "kr210-realistic.yaml")
# tool 1 is the cell's (tip 250 mm out); tool 2 half a millimetre beside it (within the default
# correction.tool_distance of 1 mm); tool 3 a longer drill, 150 mm further out and tilted
TOOLS = {
    1: (0.0, 0.0, 250.0, 0.0, 0.0, 0.0),
    2: (0.5, 0.0, 250.0, 0.0, 0.0, 0.0),
    3: (0.0, 0.0, 400.0, 0.0, 0.0, 10.0),
}
TOOL_DATA = (
    "tool_data:\n  2: {x: 0.5, y: 0, z: 250, name: tNear}\n"
    "  3: {x: 0, y: 0, z: 400, a: 0, b: 0, c: 10, name: tLong}\n"
)


def _grid_cell(tmp_path: Path) -> Path:
    cell = write_cell(tmp_path, field="constant")
    cell.write_text(cell.read_text() + TOOL_DATA)
    return cell


def _model_cell(tmp_path: Path) -> Path:
    """The nominal kr210 corrected by the calibrated kr210-realistic alone (no grid), in KUKA
    Status 6."""
    cal = tmp_path / "cal.yaml"
    cal.write_text(REALISTIC.read_text() + "tool: {x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n")
    cell = tmp_path / "cell.yaml"
    cell.write_text(
        "robot: kr210\ntool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n"
        "base: {number: 1, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}\n"
        + TOOL_DATA
        + "correction: {model: cal.yaml}\nconfiguration: {status: 6}\n"
    )
    return cell


def _report(path: Path) -> dict[int, dict]:
    with path.open(newline="") as f:
        return {int(r["line"]): r for r in csv.DictReader(f)}


def _rewrite(tmp_path: Path, cell: Path, files: dict[str, str], *options: str) -> dict[int, dict]:
    """Write ``files`` (name -> text) and rewrite them with ``--allow-partial``: the report's
    rows by line."""
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    out = tmp_path / ("out" if len(files) > 1 else "out" + Path(next(iter(files))).suffix)
    report = tmp_path / "r.csv"
    argv = ["rewrite", *(str(tmp_path / n) for n in files), "--cell", str(cell), *options]
    assert main([*argv, "--allow-partial", "--report", str(report), "-o", str(out)]) == 0
    return _report(report)


def _new(row: dict) -> np.ndarray:
    return np.array([float(row[k]) for k in ("x_new", "y_new", "z_new")])


def _old(row: dict) -> np.ndarray:
    return np.array([float(row[k]) for k in ("x", "y", "z")])


def _lands(cal: Path, tool: int, command: np.ndarray, abc: np.ndarray) -> np.ndarray:
    """Where the calibrated arm puts the TCP of ``tool`` when the nominal controller, with
    that tool, is commanded to ``command`` (N, 3) at robot-frame ``abc`` (N, 3) deg, Status 6."""
    flange_T_tool = pose_from_xyzabc(np.array(TOOLS[tool]))
    poses = np.tile(np.eye(4), (len(command), 1, 1))
    poses[:, :3, :3] = abc_to_matrix(abc)
    poses[:, :3, 3] = command
    sol = load_robot("kr210").with_tool(flange_T_tool).ik(poses, status=6)
    assert sol.ok.all()
    return load_robot(cal).true_robot().with_tool(flange_T_tool).fk(sol.q)[:, :3, 3]


KRL = """DEF T()
DECL FDAT F2={TOOL_NO 2,BASE_NO 1,IPO_FRAME #BASE}
DECL FDAT F3={TOOL_NO 3,BASE_NO 1,IPO_FRAME #BASE}
FDAT_ACT=F2
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
FDAT_ACT=F3
LIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0}
$TOOL=TOOL_DATA[7]
LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}
BAS(#TOOL,1)
LIN {X 1500,Y -100,Z 1500,A 0,B 90,C 0}
END
"""


def test_krl_fdat_tools_with_a_grid(tmp_path, capsys):
    cell = _grid_cell(tmp_path)
    src = tmp_path / "t.src"
    src.write_text(KRL)
    argv = ["rewrite", str(src), "--cell", str(cell), "--base", "1", "--decimals", "4"]
    assert main([*argv, "-o", str(tmp_path / "refused.src")]) == 2
    err = capsys.readouterr().err
    assert "t.src:7:" in err and "another tool than the grid's" in err
    assert "not placed in the robot frame" in err  # tool 7
    assert not (tmp_path / "refused.src").exists()
    rows = _rewrite(tmp_path, cell, {"t.src": KRL}, "--base", "1", "--decimals", "4")
    for line in (5, 11):  # tool 2 (0.5 mm from the grid's tool), tool 1 again
        assert rows[line]["status"] == "corrected"
        np.testing.assert_allclose(_new(rows[line]) - _old(rows[line]), E_CONST, atol=1e-9)
    assert rows[7]["status"] == "skipped"
    assert "tool 3: its TCP is 150.000 mm from" in rows[7]["reason"]
    assert rows[9]["reason"] == "tool 7 is not declared in the cell file (tool, tool_data)"
    text = (tmp_path / "out.src").read_text()
    assert "LIN {X 1500,Y 100,Z 1400,A 0,B 90,C 0}" in text  # tool 3 as written
    assert "LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}" in text  # tool 7 as written


def test_krl_tools_with_a_model_land_each_tcp_on_its_target(tmp_path):
    cell = _model_cell(tmp_path)
    program = {"t.src": KRL.replace("$TOOL=TOOL_DATA[7]", "$TOOL=TOOL_DATA[2]")}
    rows = _rewrite(tmp_path, cell, program, "--base", "1", "--decimals", "6")
    for line, tool in ((5, 2), (7, 3), (9, 2), (11, 1)):
        row = rows[line]
        assert row["status"] == "corrected", row
        reached = _lands(tmp_path / "cal.yaml", tool, _new(row)[None], np.array([[0, 90, 0]]))
        assert np.linalg.norm(reached[0] - _old(row)) < 2e-3, (line, reached, row)
    # the far tool's command differs from the cell tool's at the same target: its own TCP
    other = _lands(tmp_path / "cal.yaml", 1, _new(rows[7])[None], np.array([[0, 90, 0]]))
    assert np.linalg.norm(other[0] - _old(rows[7])) > 0.01


def test_krl_tool_set_in_one_branch_only_is_reported(tmp_path, capsys):
    cell = _grid_cell(tmp_path)
    program = (
        "DEF T()\nBAS(#TOOL,1)\nIF $IN[1] THEN\n$TOOL=TOOL_DATA[2]\nENDIF\n"
        "LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}\nEND\n"
    )
    reason = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1")[6]["reason"]
    assert reason.startswith("tool unknown: $TOOL set in one branch of IF at line 3")


GCODE = """G21 G90 G17
T1 M6
G43
G0 X1500 Y0 Z1500
T2 M6 G43
G0 X1500 Y50 Z1500
T3 M6 G43
G0 X1500 Y100 Z1400
G43 H9
G0 X1500 Y150 Z1500
G43 H2
T1 M6
G0 X1500 Y200 Z1500
G49
G0 X1500 Y-100 Z1500
M2
"""


def test_gcode_tools_with_a_grid(tmp_path):
    cell = _grid_cell(tmp_path)
    rows = _rewrite(tmp_path, cell, {"t.ngc": GCODE}, "--decimals", "4")
    for line in (4, 6, 15):  # tool 1, tool 2 (near), no length offset: the cell's tool
        assert rows[line]["status"] == "corrected"
        np.testing.assert_allclose(_new(rows[line]) - _old(rows[line]), E_CONST, atol=1e-9)
    assert "tool 3: its TCP is 150.000 mm from" in rows[8]["reason"]
    assert rows[10]["reason"] == "tool 9 is not declared in the cell file (tool, tool_data)"
    assert rows[13]["reason"].startswith(
        "tool unknown: tool 1 loaded at line 12 while the length offset of tool 2 stays"
    )


def test_gcode_tools_with_a_model(tmp_path):
    cell = _model_cell(tmp_path)
    rows = _rewrite(tmp_path, cell, {"t.ngc": GCODE.replace("G43 H9", "G43 H3")}, "--decimals", "6")
    # no A, B, C words: the cell's configuration.reference (default 0, 90, 0), robot frame
    for line, tool in ((4, 1), (6, 2), (8, 3), (10, 3), (15, 1)):
        row = rows[line]
        assert row["status"] == "corrected", row
        reached = _lands(tmp_path / "cal.yaml", tool, _new(row)[None], np.array([[0, 90, 0]]))
        assert np.linalg.norm(reached[0] - _old(row)) < 2e-3, (line, reached, row)


def test_gcode_tool_program_still_reads_in_rs274(rs274, tmp_path):
    """rs274 runs the rewritten program with the same canonical commands (tool changes and
    length offsets included); the moves of the corrected tools end E_CONST away, the others
    where they were."""
    cell = _grid_cell(tmp_path)
    text = GCODE.replace("G43 H9\nG0 X1500 Y150 Z1500\n", "")  # rs274's tool table: 1..3
    out = tmp_path / "o.ngc"
    (tmp_path / "t.ngc").write_text(text)
    argv = ["rewrite", str(tmp_path / "t.ngc"), "--cell", str(cell), "--decimals", "4"]
    assert main([*argv, "--allow-partial", "-o", str(out)]) == 0
    before, canon_before = canonical(rs274, tmp_path, text)
    after, canon_after = canonical(rs274, tmp_path, out.read_text())
    calls = [re.sub(r"\(.*", "", line.split()[2]) for line in canon_before.splitlines()[:-1]]
    assert calls == [re.sub(r"\(.*", "", line.split()[2]) for line in canon_after.splitlines()[:-1]]
    assert "USE_TOOL_LENGTH_OFFSET" in calls and "CHANGE_TOOL" in calls
    shift = after[:, :3] - before[:, :3]
    corrected = [0, 1, 4]  # tool 1, tool 2 (near), after G49; tool 3 far, tool 1 under H2
    np.testing.assert_allclose(shift[corrected], np.tile(E_CONST, (3, 1)), atol=1e-9)
    np.testing.assert_array_equal(shift[[2, 3]], 0.0)


def test_rapid_tooldata_names(tmp_path):
    cell = write_rapid_cell(tmp_path, "tDrill", "wobjPanel")
    cell.write_text(cell.read_text() + TOOL_DATA)
    q = "[0.5,0,0.866025404,0]"
    target = "[[{x},{y},{z}]," + q + ",[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
    moves = [
        ("tDrill", (100, 50, 30)),
        ("tNear", (120, 50, 30)),
        ("tLong", (140, 50, 30)),
        ("tOther", (160, 50, 30)),
    ]
    body = "".join(
        f"    MoveL {target.format(x=x, y=y, z=z)}, v10, fine, {tool}\\WObj:=wobjPanel;\n"
        for tool, (x, y, z) in moves
    )
    module = f"MODULE T\n  PROC main()\n{body}  ENDPROC\nENDMODULE\n"
    rows = _rewrite(tmp_path, cell, {"t.mod": module}, "--decimals", "4")
    # the correction in the work object: R^T e with R the base's rotation
    expected = abc_to_matrix(np.array(RAPID_BASE[3:])).T @ E_CONST
    for line in (3, 4):
        assert rows[line]["status"] == "corrected"
        np.testing.assert_allclose(_new(rows[line]) - _old(rows[line]), expected, atol=6e-5)
    assert "tool 3: its TCP is 150.000 mm from" in rows[5]["reason"]
    assert rows[6]["reason"].startswith("moved with tool tOther at line 6, which the cell does")
    # the module's own tooldata: tNear as the cell gives it, tLong 20 mm shorter
    declared = (
        "  PERS tooldata tNear:=[TRUE,[[0.5,0,250],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n"
        "  PERS tooldata tLong:=[TRUE,[[0,0,380],[1,0,0,0]],[1,[0,0,1],[1,0,0,0],0,0,0]];\n"
    )
    module = module.replace("MODULE T\n", "MODULE T\n" + declared)
    again = tmp_path / "again"
    again.mkdir()
    rows = _rewrite(again, cell, {"t.mod": module}, "--decimals", "4")
    assert rows[6]["status"] == "corrected"  # tNear, line 6 now
    reason = "the module's tooldata tlong is not the TCP the cell gives it (line 7)"
    assert rows[7]["reason"] == reason


def test_without_tool_data_other_tools_are_skipped_as_before(tmp_path):
    cell = write_cell(tmp_path, field="constant")
    assert load_cell(cell).tool_data is None
    rows = _rewrite(tmp_path, cell, {"t.src": KRL}, "--base", "1")
    assert rows[5]["reason"] == (
        "FDAT F2 (line 2) has TOOL_NO 2: the cell's tool, which the grid holds for, is 1"
    )
    # nor is BAS(#TOOL, 1): line 11 keeps the reason of the FDAT F3 in effect
    assert rows[11]["reason"].startswith("FDAT F3 (line 3) has TOOL_NO 3")


def test_cell_reads_tool_data(tmp_path):
    cell = load_cell(_grid_cell(tmp_path))
    assert sorted(cell.tool_data) == [0, 1, 2, 3]
    assert cell.tool_data[1] is cell.flange_T_tool
    np.testing.assert_array_equal(cell.tool_data[0], np.eye(4))  # the flange
    for n, xyzabc in TOOLS.items():
        np.testing.assert_allclose(cell.tool_data[n], pose_from_xyzabc(np.array(xyzabc)))
    assert cell.dialects["rapid"].tool_names == {"tool0": 0, "tnear": 2, "tlong": 3}
    assert cell.correction.tool_distance_mm == 1.0


BASE = (
    "robot: kr210\ntool: {number: 1, x: 0, y: 0, z: 250, a: 0, b: 0, c: 0}\n"
    "base: {number: 1, x: 0, y: 0, z: 0, a: 0, b: 0, c: 0}\n"
)


@pytest.mark.parametrize(
    ("text", "key", "line"),
    [
        ("tool_data: {x: {z: 1}}\n", "tool_data.x", 4),
        ("tool_data:\n  1: {z: 1}\n", "tool_data.1", 5),
        ("tool_data:\n  0: {z: 1}\n", "tool_data.0", 5),
        ("tool_data:\n  2: {z: 1, q: 2}\n", "tool_data.2.q", 5),
        ("tool_data:\n  2: {z: one}\n", "tool_data.2.z", 5),
        ("tool_data:\n  2: {z: 1, name: 9x}\n", "tool_data.2.name", 5),
        ("tool_data:\n  2: {z: 1, name: t}\n  3: {z: 2, name: T}\n", "tool_data.3.name", 6),
        ("tool_data: [1, 2]\n", "tool_data", 4),
        ("correction: {tool_distance: -1}\n", "correction.tool_distance", 4),
    ],
)
def test_tool_data_errors_are_located(tmp_path, capsys, text, key, line):
    path = tmp_path / "cell.yaml"
    path.write_text(BASE + text)
    with pytest.raises(InputError) as err:
        load_cell(path)
    assert f"{key}" in str(err.value) and err.value.line == line, str(err.value)
    src = tmp_path / "t.src"
    src.write_text(KRL)
    assert main(["rewrite", str(src), "--cell", str(path), "-o", str(tmp_path / "o.src")]) == 2
    message = capsys.readouterr().err.strip()
    assert re.search(rf"cell\.yaml:{line}(:\d+)?: .*{re.escape(key)}", message), message
    assert "\n" not in message and "Traceback" not in message


def test_a_grid_checks_the_orientation_of_its_own_tool(tmp_path):
    """A tool whose TCP is the grid's but whose frame is turned: the grid's orientation check
    sees the grid's tool at the same flange pose (turned back), not the written A, B, C."""
    cell = write_cell(tmp_path, field="constant")
    write_grid(tmp_path / "grid.csv", field="constant", abc=(0, 90, 0))
    cell.write_text(cell.read_text() + "tool_data:\n  4: {x: 0, y: 0, z: 250, a: 0, b: 0, c: 30}\n")
    program = (
        "DEF T()\nDECL FDAT F4={TOOL_NO 4,BASE_NO 1,IPO_FRAME #BASE}\nFDAT_ACT=F4\n"
        "LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 30}\nLIN {X 1500,Y 0,Z 1400,A 0,B 90,C 0}\nEND\n"
    )
    rows = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1")
    # C 30 of tool 4 is C 0 of the grid's tool: as measured; C 0 of tool 4 is 30 deg off
    assert rows[4]["status"] == "corrected" and not rows[4]["reason"]
    assert rows[5]["status"] == "skipped" and "orientation 30.0 deg" in rows[5]["reason"]


PAIR_SRC = """DEF P()
PDAT_ACT=PPDAT1
FDAT_ACT=FP1
BAS(#PTP_PARAMS,100)
PTP XP1
FDAT_ACT=FP2
BAS(#CP_PARAMS,0.2)
LIN XP2
FDAT_ACT=FP3
LIN XP3
FDAT_ACT=FP1
LIN XP3
END
"""
PAIR_DAT = """DEFDAT P
DECL E6POS XP1={X 1500,Y 0,Z 1500,A 0,B 90,C 0,S 6,T 2,E1 0,E2 0,E3 0,E4 0,E5 0,E6 0}
DECL FDAT FP1={TOOL_NO 2,BASE_NO 1,IPO_FRAME #BASE}
DECL E6POS XP2={X 1500,Y 100,Z 1500,A 0,B 90,C 0,S 6,T 2,E1 0,E2 0,E3 0,E4 0,E5 0,E6 0}
DECL FDAT FP2={TOOL_NO 3,BASE_NO 1,IPO_FRAME #BASE}
DECL E6POS XP3={X 1500,Y 200,Z 1500,A 0,B 90,C 0,S 6,T 2,E1 0,E2 0,E3 0,E4 0,E5 0,E6 0}
DECL FDAT FP3={TOOL_NO 1,BASE_NO 1,IPO_FRAME #BASE}
ENDDAT
"""


def test_krl_stored_positions_take_the_tool_of_their_motions(tmp_path):
    cell = _grid_cell(tmp_path)
    rows = _rewrite(tmp_path, cell, {"p.src": PAIR_SRC, "p.dat": PAIR_DAT}, "--decimals", "4")
    assert rows[2]["status"] == "corrected"  # XP1: tool 2, 0.5 mm from the grid's tool
    np.testing.assert_allclose(_new(rows[2]) - _old(rows[2]), E_CONST, atol=1e-9)
    assert "tool 3: its TCP is 150.000 mm from" in rows[4]["reason"]  # XP2
    assert rows[6]["reason"] == "XP3 is moved to with different tools (lines 10, 12)"


def test_model_with_a_residual_grid_corrects_a_far_tool_by_the_model_alone(tmp_path):
    """The residual grid (what the model leaves, measured with the cell's tool) is applied
    to the near tool and not to the far one, which the model corrects alone, flagged."""
    cell = _model_cell(tmp_path)
    grid = tmp_path / "residual.csv"
    simulate = ["simulate", "--robot", "kr210-realistic", "--region", "1200", "2200", "-500"]
    simulate += ["500", "1100", "2100", "--step", "500", "--abc", "0", "90", "0", "--tool"]
    assert main([*simulate, "0", "0", "250", "0", "0", "0", "-o", str(grid)]) == 0
    program = {"t.src": KRL.replace("$TOOL=TOOL_DATA[7]", "$TOOL=TOOL_DATA[2]")}
    rows = _rewrite(tmp_path, cell, program, "--grid", str(grid), "--base", "1", "--decimals", "6")
    for line, tool in ((5, 2), (7, 3), (9, 2), (11, 1)):
        row = rows[line]
        assert row["status"] == "corrected", row
        reached = _lands(tmp_path / "cal.yaml", tool, _new(row)[None], np.array([[0, 90, 0]]))
        assert np.linalg.norm(reached[0] - _old(row)) < 2e-3, (line, reached, row)
    assert rows[7]["reason"].startswith("flag: tool 3: corrected by the model alone")
    assert "corrected by the model alone" not in rows[5]["reason"]


def test_krl_tool_data_set_otherwise_than_the_cell_is_reported(tmp_path):
    """A program (or its $config.dat) that sets TOOL_DATA[n] to another TCP than the cell's
    tool n, or at run time, leaves the positions of tool n uncorrected; the same TCP is fine."""
    cell = _grid_cell(tmp_path)
    program = (
        "DEF T()\nTOOL_DATA[2]={X 0.5,Y 0,Z 250,A 0,B 0,C 0}\nTOOL_DATA[3]={X 0,Y 0,Z 380,A 0,"
        "B 0,C 10}\nBAS(#TOOL,2)\nLIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}\nBAS(#TOOL,3)\n"
        "LIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}\nEND\n"
    )
    rows = _rewrite(tmp_path, cell, {"t.src": program}, "--base", "1", "--decimals", "4")
    assert rows[5]["status"] == "corrected"
    assert rows[7]["reason"] == "tool unknown: TOOL_DATA[3] (t.src:3) is not the cell's tool 3"
    again = tmp_path / "again"
    again.mkdir()
    config = again / "config.dat"
    config.write_text("DEFDAT $CONFIG\nTOOL_DATA[2].Z=260\nENDDAT\n")
    rows = _rewrite(again, cell, {"t.src": program}, "--base", "1", "--config-dat", str(config))
    assert rows[5]["reason"] == (
        "tool unknown: TOOL_DATA[2] is set otherwise than as a literal frame ($config.dat:2)"
    )


def _smooth_grid() -> GridModel:
    """A 5 x 5 x 5 grid (robot frame, 250 mm step) of a smooth error field, measured at
    A 0, B 90, C 0 with the cell's tool."""
    axes = [np.arange(1000.0, 2001.0, 250.0), np.arange(-500.0, 501.0, 250.0)]
    axes.append(np.arange(1000.0, 2001.0, 250.0))
    commanded = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    x, y, z = commanded.T
    error = np.stack([0.2 + 1e-4 * x, -0.1 + 2e-4 * z, 0.3 - 1e-4 * y], axis=1)
    abc = np.tile([0.0, 90.0, 0.0], (len(commanded), 1))
    return GridModel.from_measurements(commanded, commanded - error, abc)


GRID = _smooth_grid()
CELL_TOOL = pose_from_xyzabc(np.array(TOOLS[1]))


@settings(max_examples=60, deadline=None)
@given(
    offset=st.tuples(*[st.floats(-1.5, 1.5)] * 3),
    turn_deg=st.floats(0.0, 40.0),
    points=st.lists(
        st.tuples(st.floats(1010, 1990), st.floats(-490, 490), st.floats(1010, 1990)),
        min_size=1,
        max_size=5,
    ),
)
def test_a_grid_corrects_another_tool_only_near_its_own(offset, turn_deg, points):
    """Grid alone, correction.tool_distance 1 mm: a tool whose TCP is farther is refused for
    every position (command = target); a nearer one gets the command the cell's tool gets at
    the same target when it is written at the grid tool's orientation, and is refused for its
    orientation when the grid's tool at the same flange pose turns beyond the 15 deg limit."""
    policy = Policy.build(CorrectionSettings(), GRID, tools=(CELL_TOOL, CELL_TOOL))
    tool = pose_from_xyzabc(np.array([*offset, 0.0, 0.0, 0.0]) + np.array(TOOLS[1]))
    tool[:3, :3] = abc_to_matrix(np.array([0.0, 0.0, turn_deg]))  # turned about its X
    targets = np.array(points, dtype=float)
    grid_rotation = abc_to_matrix(np.array([0.0, 90.0, 0.0]))
    # written so that the grid's tool (no turn) is at the grid's orientation: R_grid R_tool
    as_measured = np.tile(grid_rotation @ tool[:3, :3], (len(targets), 1, 1))
    written = np.tile(grid_rotation, (len(targets), 1, 1))
    mine = policy.decide_tool(2, tool, targets, as_measured)
    theirs = policy.decide(targets, written)
    distance = float(np.linalg.norm(offset))
    if distance > 1.0:
        assert (mine.code == OTHER_TOOL).all()
        np.testing.assert_array_equal(mine.command, targets)
        return
    assert (mine.code == 0).all() and (theirs.code == 0).all()
    np.testing.assert_array_equal(mine.command, theirs.command)
    turned = policy.decide_tool(2, tool, targets, written)
    if abs(turn_deg - 15.0) > 1e-6:  # the limit itself: either, by rounding
        assert (turned.code == ORIENTATION).all() == (turn_deg > 15.0)
        assert (turned.code == 0).all() == (turn_deg < 15.0)


BRANCHES = """DEF T()
BAS(#TOOL,1)
M1:
LIN {X 1500,Y 0,Z 1500,A 0,B 90,C 0}
IF $IN[1] THEN
$TOOL=TOOL_DATA[2]
ENDIF
LIN {X 1500,Y 100,Z 1500,A 0,B 90,C 0}
BAS(#TOOL,1)
FOR I=1 TO 3
LIN {X 1500,Y 200,Z 1500,A 0,B 90,C 0}
BAS(#TOOL,2)
LIN {X 1500,Y 300,Z 1500,A 0,B 90,C 0}
ENDFOR
END
"""


def test_krl_tool_changed_on_some_paths_only(tmp_path):
    """A tool set in one branch, before a jump target or inside a loop is not known after it,
    with or without tool_data; without it, tool 2 is not the cell's tool either."""
    plain = tmp_path / "plain"
    plain.mkdir()
    rows = _rewrite(plain, write_cell(plain, field="constant"), {"t.src": BRANCHES}, "--base", "1")
    assert rows[8]["reason"] == "tool unknown: $TOOL set in one branch of IF at line 5 only"
    assert rows[13]["reason"].startswith("tool 2 is not the cell's tool 1")
    assert [rows[k]["status"] for k in (4, 8, 11, 13)] == ["skipped"] * 4
    rows = _rewrite(tmp_path, _grid_cell(tmp_path), {"t.src": BRANCHES}, "--base", "1")
    assert rows[4]["reason"] == (
        "tool unknown: after jump target M1 (line 3): $TOOL depends on the path taken"
    )
    assert rows[8]["reason"] == "tool unknown: $TOOL set in one branch of IF at line 5 only"
    assert rows[11]["reason"] == "tool unknown: $TOOL changes inside the loop FOR at line 10"
    assert rows[13]["status"] == "corrected"  # tool 2 on every pass
