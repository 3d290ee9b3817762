"""ABB RAPID: the generated drilling module (quaternions, confdata against the IK, the module
frame), the pre-flight rewrite of the real RAPID programs in ../shared/realworld/rapid with a
constant error field (every changed number checked against the frame maths done here), bad
input, and the KRL and G-code outputs pinned to what they were before RAPID came in."""

from __future__ import annotations

import csv
import re
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest
from conftest import EXAMPLES
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import E_CONST, REALWORLD_RAPID, write_rapid_cell
from rewrite_helpers import RAPID_BASE as BASE
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.codegen.rapid.configuration import abb_confdata, ik_confdata
from accugrid.codegen.rapid.rewrite import code_of_cfx
from accugrid.kinematics.configuration import ik_codes
from accugrid.kinematics.robot import load_robot

NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
TARGET = re.compile(
    rf"CONST robtarget (\w+):=\[\[({NUM}),({NUM}),({NUM})\],\[({NUM}),({NUM}),({NUM}),({NUM})\],"
    rf"\[({NUM}),({NUM}),({NUM}),({NUM})\],\[9E\+09(?:,9E\+09){{5}}\]\];"
)
TOOL = np.eye(4)
TOOL[2, 3] = 250.0  # examples/cell_irb6700.yaml: tool z 250
ROBOT_T_WOBJ = np.eye(4)  # examples/cell_irb6700.yaml: base x 2000 y 300 z 1200, a -90 b 0 c 90
ROBOT_T_WOBJ[:3, :3] = Rotation.from_euler("ZYX", [-90, 0, 90], degrees=True).as_matrix()
ROBOT_T_WOBJ[:3, 3] = [2000.0, 300.0, 1200.0]


def _robtargets(text: str):
    """name -> (position (3,) mm in the work object, quaternion (4,), confdata (4,) int)."""
    out = {}
    for m in TARGET.finditer(text):
        v = [float(x) for x in m.groups()[1:]]
        out[m.group(1)] = (np.array(v[:3]), np.array(v[3:7]), np.array(v[7:11], dtype=int))
    return out


@settings(max_examples=8)
@given(
    xy=st.lists(
        st.tuples(st.floats(0, 600), st.floats(150, 450), st.floats(-5, 5), st.floats(-8, 8)),
        min_size=1,
        max_size=4,
    ),
)
def test_every_robtarget_has_the_confdata_of_its_ik_solution(tmp_path_factory, xy):
    tmp = tmp_path_factory.mktemp("rapid")
    rows = ["id,x,y,z,i,j,k"]
    for n, (x, y, tilt_x, tilt_y) in enumerate(xy):
        axis = Rotation.from_euler("xy", [tilt_x, tilt_y], degrees=True).apply([0, 0, -1])
        rows.append(f"H{n},{x:.3f},{y:.3f},0," + ",".join(f"{a:.6f}" for a in axis))
    (tmp / "p.csv").write_text("\n".join(rows) + "\n")
    out = tmp / "JOB.mod"
    cell = EXAMPLES / "cell_irb6700.yaml"
    assert main(["rapid", str(tmp / "p.csv"), "--cell", str(cell), "-o", str(out)]) == 0
    targets = _robtargets(out.read_text())
    assert len(targets) == 4 * len(xy)
    names = [f"p{h}_{s}" for h in range(1, len(xy) + 1) for s in ("APP", "CLR", "BOT", "RET")]
    assert list(targets) == names  # every pose, in program order
    pos = np.array([targets[n][0] for n in names])
    quat = np.array([targets[n][1] for n in names])
    conf = np.array([targets[n][2] for n in names])
    np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, rtol=0, atol=1e-9)
    assert (quat[:, 0] >= 0).all()
    wobj_T_tcp = np.tile(np.eye(4), (len(names), 1, 1))
    wobj_T_tcp[:, :3, :3] = Rotation.from_quat(np.roll(quat, -1, axis=1)).as_matrix()
    wobj_T_tcp[:, :3, 3] = pos
    poses = ROBOT_T_WOBJ @ wobj_T_tcp
    robot = load_robot("irb6700").with_tool(TOOL)
    # the controller's solution in the written confdata reaches the pose ...
    sol = ik_confdata(robot, poses, conf)
    assert sol.ok.all(), sol.reason
    np.testing.assert_allclose(robot.fk(sol.q)[:, :3, 3], poses[:, :3, 3], atol=1e-6)
    # ... and is the program's IK solution: one Status, the first pose's IK default
    first = robot.ik(poses[:1])
    own = robot.ik(poses, status=int(first.status[0]))
    assert own.ok.all()
    np.testing.assert_array_equal(abb_confdata(robot, own.q), conf)
    # the rewrite's reading of a cfx as a KUKA Status is the Status of that joint solution
    np.testing.assert_array_equal(code_of_cfx(conf[:, 3]), ik_codes(robot, sol.q)[0])


def test_module_frame_tool_and_work_object():
    text = (EXAMPLES / "WING.mod").read_bytes().decode("ascii")
    assert text.startswith("MODULE WING\r\n    ! accugrid ")
    assert text.rstrip().endswith("ENDMODULE")
    assert "PERS tooldata tDrill:=[TRUE,[[0.000,0.000,250.000],[1.000000000," in text
    q = Rotation.from_matrix(ROBOT_T_WOBJ[:3, :3]).as_quat()  # x, y, z, w
    q = np.roll(q, 1) * np.sign(q[3])
    wobj = re.search(
        rf"PERS wobjdata wobjPanel:=\[FALSE,TRUE,\"\",\[\[({NUM}),({NUM}),({NUM})\],"
        rf"\[({NUM}),({NUM}),({NUM}),({NUM})\]\]",
        text,
    )
    np.testing.assert_allclose([float(v) for v in wobj.groups()], [2000, 300, 1200, *q], atol=1e-9)
    moves = re.findall(r"^ +(MoveJ|MoveL|WaitTime|SetDO)", text, re.M)
    assert moves[0] == "SetDO" and moves[-1] == "SetDO"
    assert moves[1:-1] == ["MoveJ", "MoveL", "MoveL", "WaitTime", "MoveL"] * 72


def test_module_name_over_32_characters_is_a_located_error(tmp_path, capsys):
    cell = tmp_path / "cell.yaml"
    grid = EXAMPLES / "grid_irb6700_200mm.csv"
    text = (
        (EXAMPLES / "cell_irb6700.yaml").read_text().replace(f"grid: {grid.name}", f"grid: {grid}")
    )
    cell.write_text(text.replace("module: WING ", "module: " + "M" * 33))
    points = EXAMPLES / "wing_panel_points.csv"
    assert main(["rapid", str(points), "--cell", str(cell), "-o", str(tmp_path / "a.mod")]) == 2
    err = capsys.readouterr().err
    assert f"{cell}:" in err and "rapid.module" in err and "32" in err
    cell.write_text(text.replace("  module: WING ", "  # module"))
    long = tmp_path / ("W" * 33 + ".mod")
    assert main(["rapid", str(points), "--cell", str(cell), "-o", str(long)]) == 2
    assert str(long) in capsys.readouterr().err
    assert not long.exists()


# file -> (the frame its corrected robtargets are written in: "robot" (wobj0) or "base" (the work
# object, the cell's base), None: nothing can be placed; the line and reason of the first
# robtarget a motion commands that is left uncorrected, which fails the job without
# --allow-partial; each read in the program), in the cell of rewrite_helpers.REALWORLD_RAPID
CASES = {
    # MoveL in Frame2 (line 25), whose literal frame is not the base
    "robodk_Program.mod": ("robot", 25, "wobjdata Frame2"),
    # MoveC Target_860,Target_10 at line 144: Target_10 (line 5) is an arc's end point
    "harshbhatt99_Module1.mod": ("base", 5, "circular move"),
    # Target_20 (line 3) goes to the custom routine Pick and to MoveL Offs(Target_20, ..)
    "juanlopezp_Module1.mod": ("robot", 3, "used by Pick at line 58"),
    # acercamiento (line 10): MoveJ to it, and MoveL Offs(acercamiento, +92.5, 0, 0) at 193
    "edgarivanmm_MainModule.modx": ("robot", 10, "Offs(...)"),
    # MoveJ Offs(Target_TAB_CONV, ..) at line 143: the move goes to a derived position
    "rparak_Module1.mod": (None, 50, "Offs(...) at line 143"),
    # INST_p10 (line 16) is moved in INST_workobject, whose oframe is not the base
    "mcoffman1_AA_example_script.mod": (None, 16, "wobjdata"),
    # p00 (line 13) moved with the stationary drill
    "mjkkirschner_test02_001.prg": (None, 13, "stationary"),
    # pWeldReady (line 2) has eax_a, eax_b, eax_c in use
    "zwj12_WeldTestModule.mod": (None, 2, "external axis eax_a"),
    # targets{i}.extax := .. at line 85 reassigns the array declared at line 61
    "kangoananya_iGPS_SC_Acc_Exp.mod": (None, 61, "reassigned at run time"),
    "kangoananya_user.sys": (None, 1, "no robtarget"),
    "taeyangshim-stack_user.sys": (None, 1, "no robtarget"),  # joint targets
    # placeap (line 7): the arm angle in eax_a, MoveJ placeap at line 53
    "bhomaidan1990_currLeft.mod": (None, 7, "external axis eax_a"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_realworld_rapid_rewrite_changes_only_the_corrected_numbers(
    realworld, tmp_path, capsys, name
):
    frame, line, why = CASES[name]
    program = realworld / "rapid" / name
    cell = write_rapid_cell(tmp_path, *REALWORLD_RAPID[name])
    out, report = tmp_path / name, tmp_path / "r.csv"
    argv = ["rewrite", str(program), "--cell", str(cell), "-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{program}:{line}: " in err and why in err, err
    if why != "no robtarget":
        assert "not placed in the robot frame" in err, err
    assert not out.exists()
    assert main([*argv, "--allow-partial", "--report", str(report)]) == 0, capsys.readouterr().err
    rows = list(csv.DictReader(report.open()))
    assert all(r["reason"] for r in rows if r["status"] != "corrected")
    if frame is None:
        assert out.read_bytes() == program.read_bytes()
        assert not any(r["status"] == "corrected" for r in rows)
        return
    old, new = program.read_bytes().decode("latin-1"), out.read_bytes().decode("latin-1")
    old_nums, new_nums = list(re.finditer(NUM, old)), list(re.finditer(NUM, new))
    assert re.split(NUM, old) == re.split(NUM, new)  # every other byte is the same
    # x, y, z of every robtarget literal (test's own reading): offset -> axis
    xyz = {}
    for m in re.finditer(rf"\[\s*\[\s*({NUM})\s*,\s*({NUM})\s*,\s*({NUM})\s*\]\s*,\s*\[", old):
        for axis in range(3):
            xyz[m.start(axis + 1)] = (axis, m)
    rot = Rotation.from_euler("ZYX", BASE[3:], degrees=True).as_matrix()
    e = E_CONST if frame == "robot" else rot.T @ E_CONST  # the correction in the program frame
    changed = 0
    for a, b in zip(old_nums, new_nums, strict=True):
        if a.group() == b.group():
            continue
        changed += 1
        axis, literal = xyz[a.start()]  # only robtarget positions change
        places = max(max(map(_places, literal.groups())), 2)
        assert len(b.group().partition(".")[2]) >= 2
        assert abs(float(b.group()) - (float(a.group()) + e[axis])) <= 0.5 * 10**-places + 1e-9
    assert changed >= 3


def _rewrite(tmp_path, text: str, capsys, *extra: str) -> tuple[int, str, str]:
    program = tmp_path / "t.mod"
    program.write_bytes(text.encode("latin-1"))
    cell = write_rapid_cell(tmp_path, "tDrill", "wobjPanel")
    out = tmp_path / "out.mod"
    report = tmp_path / "r.csv"
    code = main(
        [
            "rewrite",
            str(program),
            "--cell",
            str(cell),
            "-o",
            str(out),
            "--report",
            str(report),
            *extra,
        ]
    )
    err = capsys.readouterr().err
    return code, err, report.read_text() if report.exists() else ""


HEAD = "MODULE T\r\n"
GOOD = "[[1,2,3],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]"
MOVE = "tDrill\\WObj:=wobjPanel;\r\n"


def test_unbalanced_brackets_are_a_located_error(tmp_path, capsys):
    text = HEAD + f"CONST robtarget p1:={GOOD};\r\nCONST robtarget p2:=[[1,2,3],[1,0,0,0];\r\n"
    code, err, _ = _rewrite(tmp_path, text + "ENDMODULE\r\n", capsys)
    assert code == 2 and "t.mod:3:" in err and "unbalanced" in err
    assert not (tmp_path / "out.mod").exists()


def test_non_unit_quaternion_external_axes_and_offs_are_reported(tmp_path, capsys):
    text = (
        HEAD
        + f"CONST robtarget pBadQ:={GOOD.replace('[1,0,0,0]', '[0.9,0,0,0]')};\r\n"
        + f"CONST robtarget pExt:={GOOD.replace('[9E+09,', '[250,', 1)};\r\n"
        + f"CONST robtarget pOff:={GOOD};\r\nCONST robtarget pOk:={GOOD};\r\nPROC main()\r\n"
        + f"MoveL pBadQ, v10, fine, {MOVE}MoveL pExt, v10, fine, {MOVE}"
        + f"MoveL Offs(pOff,0,0,10), v10, fine, {MOVE}MoveL pOk, v10, fine, {MOVE}"
        + "ENDPROC\r\nENDMODULE\r\n"
    )
    code, err, _ = _rewrite(tmp_path, text, capsys)
    assert code == 2 and "t.mod:2:" in err, err  # moves to all three: a partly corrected job
    assert "3 position(s) cannot be corrected (3 not placed in the robot frame)" in err, err
    code, err, report = _rewrite(tmp_path, text, capsys, "--allow-partial")
    assert code == 0, err
    rows = {line.split(",")[2]: line for line in report.splitlines()[1:]}
    assert "not a unit quaternion" in rows["pBadQ"]
    assert "external axis eax_a" in rows["pExt"]
    assert "Offs" in rows["pOff"] and ",skipped," in rows["pOff"]
    assert ",corrected," in rows["pOk"]


def _places(literal: str) -> int:
    """Decimal places a corrected number must keep for the literal it replaces: those written
    (0.50: 2); for an exponent form 2, the 0.01 mm every correction keeps (docs/formats.md)."""
    return 2 if "e" in literal.lower() else max(-Decimal(literal).as_tuple().exponent, 0)


def _literal_text(value: float, places: int, exponent: bool) -> str:
    return f"{value:.{places}E}" if exponent else f"{value:.{places}f}"


@settings(max_examples=25)
@given(
    data=st.lists(
        st.tuples(
            st.sampled_from(["CONST", "PERS", "VAR", "TASK PERS", "LOCAL CONST"]),
            st.integers(1, 2),  # elements (2: an array {2})
            st.sampled_from(["", " ", "\r\n      ", "\n\t"]),  # spacing inside the aggregate
            st.integers(0, 5),  # decimals written
            st.booleans(),  # exponent form (1.25E+02)
            st.booleans(),  # moved in the cell's work object (else wobj0)
            st.lists(st.floats(-900, 900), min_size=6, max_size=6),
        ),
        min_size=1,
        max_size=5,
    ),
    crlf=st.booleans(),
)
def test_rewrite_finds_every_robtarget_in_any_layout(tmp_path_factory, data, crlf):
    tmp = tmp_path_factory.mktemp("layout")
    nl = "\r\n" if crlf else "\n"
    pieces: list[tuple[str, object]] = [(f"MODULE L{nl}  ! Größe: a Latin-1 comment{nl}", None)]
    moves = []
    for t, (kind, count, sp, places, exponent, in_wobj, values) in enumerate(data):
        name = f"p{t}"
        pieces.append((f"  {kind} robtarget {name}{'{2}' if count == 2 else ''} :={sp}", None))
        if count == 2:
            pieces.append(("[", None))
        for k in range(count):
            pieces.append((f"[{sp}[", None))
            for axis in range(3):
                text = _literal_text(values[3 * k + axis], places, exponent)
                pieces.append((text, (t, in_wobj)))
                pieces.append(("," + sp if axis < 2 else "],", None))
            pieces.append((f"[1,0,0,0],{sp}[0,0,0,0],[9E+09,9E9,9E+09,9e+09,9E+09,9E+09]]", None))
            pieces.append(("," if k + 1 < count else "", None))
        pieces.append(("]" if count == 2 else "", None))
        pieces.append((f";{nl}", None))
        wobj = "\\WObj:=wobjPanel" if in_wobj else ""
        for k in range(count):
            ref = f"{name}{{{k + 1}}}" if count == 2 else name
            moves.append(f"    MoveL {ref}, v10, fine, tDrill{wobj};{nl}")
    pieces.append((f"  PROC main(){nl}{''.join(moves)}  ENDPROC{nl}ENDMODULE{nl}", None))
    text = "".join(p for p, _ in pieces)
    program = tmp / "layout.mod"
    program.write_bytes(text.encode("latin-1"))
    cell = write_rapid_cell(tmp, "tDrill", "wobjPanel")
    out = tmp / "out.mod"
    assert main(["rewrite", str(program), "--cell", str(cell), "-o", str(out)]) == 0
    new = out.read_bytes().decode("latin-1")
    rot = Rotation.from_euler("ZYX", BASE[3:], degrees=True).as_matrix()
    # walk the new text piece by piece: fixed text equal, numbers corrected
    pos_new, count, axis = 0, 0, 0
    for piece, what in pieces:
        if what is None:
            assert new[pos_new : pos_new + len(piece)] == piece
            pos_new += len(piece)
            continue
        m = re.compile(NUM).match(new, pos_new)
        t, in_wobj = what
        e = rot.T @ E_CONST if in_wobj else E_CONST
        want = float(piece) + e[axis % 3]
        mine = [p for p, w in pieces if w is not None and w[0] == t]  # the target's literals
        places = max(max(map(_places, mine)), 2)
        assert abs(float(m.group()) - want) <= 0.5 * 10**-places + 1e-9, (piece, m.group())
        pos_new = m.end()
        axis += 1
        count += 1
    assert pos_new == len(new) and count == 3 * sum(d[1] for d in data)


def test_module_is_the_same_in_blocks_and_from_a_template_that_uses_the_lines_whole(
    tmp_path, monkeypatch
):
    points, cell = EXAMPLES / "wing_panel_points.csv", EXAMPLES / "cell_irb6700.yaml"
    whole = (EXAMPLES / "WING.mod").read_bytes()
    monkeypatch.setattr("accugrid.codegen.rapid.emit.BLOCK", 5)  # 72 holes: 15 blocks
    assert main(["rapid", str(points), "--cell", str(cell), "-o", str(tmp_path / "b.mod")]) == 0
    assert (tmp_path / "b.mod").read_bytes() == whole
    templates = tmp_path / "templates"
    templates.mkdir()
    source = (Path(__file__).parents[1] / "templates/rapid/program.mod.j2").read_text()
    # a user's copy that tests the lines: they are no longer printed plainly
    (templates / "program.mod.j2").write_text("{% if hole_lines %}{% endif %}" + source)
    out = tmp_path / "c.mod"
    args = ["rapid", str(points), "--cell", str(cell), "--templates", str(templates), "-o"]
    assert main([*args, str(out)]) == 0
    assert out.read_bytes() == whole


def test_header_goes_below_the_module_line_of_a_prg(tmp_path, capsys):
    text = (
        "%%%\r\n  VERSION:1\r\n  LANGUAGE:ENGLISH\r\n%%%\r\n\r\nMODULE T\r\n"
        f"  CONST robtarget p1:={GOOD};\r\n  PROC main()\r\n    MoveL p1, v10, fine, {MOVE}"
        "  ENDPROC\r\nENDMODULE\r\n"
    )
    program = tmp_path / "t.prg"
    program.write_bytes(text.encode("latin-1"))
    cell = write_rapid_cell(tmp_path, "tDrill", "wobjPanel")
    out = tmp_path / "out.prg"
    assert main(["rewrite", str(program), "--cell", str(cell), "-o", str(out), "--header"]) == 0
    lines = out.read_bytes().decode("latin-1").split("\r\n")
    assert lines[:6] == text.split("\r\n")[:6]  # %%% block and MODULE line as they were
    header = [line for line in lines[6:] if line.startswith("    ! ")]
    assert lines[6 : 6 + len(header)] == header and header[0].startswith("    ! accugrid ")
    assert any("largest correction" in line for line in header)
    assert "\n" not in out.read_bytes().decode("latin-1").replace("\r\n", "")


def test_the_rewritten_example_is_what_rewrite_writes(tmp_path):
    out = tmp_path / "cam_drill.mod"
    cell = EXAMPLES / "cell_irb6700.yaml"
    args = ["rewrite", str(EXAMPLES / "cam_drill.mod"), "--cell", str(cell), "--header"]
    assert main([*args, "-o", str(out)]) == 2  # pHole1 (Drill pHole1), pHole2 (Offs) not placed
    assert main([*args, "-o", str(out), "--allow-partial"]) == 0
    assert out.read_bytes() == (EXAMPLES / "cam_drill_rewritten.mod").read_bytes()


def test_a_robtarget_in_another_configuration_than_the_grid_is_refused(tmp_path, capsys):
    # examples/cam_drill.mod with pHole3 in cfx 0 (KUKA Status 2); the grid holds in Status 6
    text = (EXAMPLES / "cam_drill.mod").read_bytes().decode("latin-1")
    line = next(k for k in text.split("\r\n") if "pHole3:=" in k)
    text = text.replace(line, line.replace("[0,0,-1,1]", "[0,0,-1,0]"))
    program = tmp_path / "cam.mod"
    program.write_bytes(text.encode("latin-1"))
    cell, out = EXAMPLES / "cell_irb6700.yaml", tmp_path / "out.mod"
    assert main(["rewrite", str(program), "--cell", str(cell), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "(1 another Status than the grid's, 2 not placed in the robot frame)" in err
    assert not out.exists()
    report = tmp_path / "r.csv"
    args = ["rewrite", str(program), "--cell", str(cell), "-o", str(out), "--report", str(report)]
    assert main([*args, "--allow-partial"]) == 0
    rows = {r.split(",")[2]: r for r in report.read_text().splitlines()[1:]}
    assert ",corrected," not in rows["pHole3"] and "Status" in rows["pHole3"]
    assert ",corrected," in rows["inline MoveL"]


@pytest.mark.parametrize(
    ("command", "cell", "robot", "serving"),
    [
        ("rapid", "cell.yaml", "kr210-paper", "accugrid krl"),
        ("krl", "cell_irb6700.yaml", "irb6700", "accugrid rapid"),
    ],
)
def test_a_dialect_refuses_a_robot_it_does_not_serve(
    tmp_path, capsys, command, cell, robot, serving
):
    # finding: rapid took a KUKA cell and wrote ABB confdata computed from KUKA axes
    out = tmp_path / ("JOB.mod" if command == "rapid" else "krl")
    points = EXAMPLES / "wing_panel_points.csv"
    argv = [command, str(points), "--cell", str(EXAMPLES / cell), "-o", str(out)]
    assert main([*argv, "--allow-partial"]) == 2
    err = capsys.readouterr().err.strip()
    assert f"robot {robot}" in err and serving in err and "\n" not in err
    assert not out.exists()


def test_gcode_serves_a_robot_of_any_controller(tmp_path, capsys):
    out = tmp_path / "job.ngc"
    points = EXAMPLES / "wing_panel_points.csv"
    argv = ["gcode", str(points), "--cell", str(EXAMPLES / "cell_irb6700.yaml"), "-o", str(out)]
    assert main([*argv, "--allow-partial"]) == 0, capsys.readouterr().err


def test_rewrite_by_a_model_refuses_a_rapid_program_on_a_kuka_cell(tmp_path, capsys):
    out = tmp_path / "out.mod"
    argv = ["rewrite", str(EXAMPLES / "cam_drill.mod"), "--cell", str(EXAMPLES / "cell.yaml")]
    assert main([*argv, "--model", "kr210-paper", "--allow-partial", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "robot kr210-paper has a KUKA controller" in err and "accugrid krl" in err
    assert not out.exists()


def test_a_calibrated_robot_keeps_its_controller(tmp_path):
    from accugrid.kinematics.calibrated import calibrated_yaml

    model = tmp_path / "cal.yaml"
    model.write_text(calibrated_yaml(load_robot("irb6700")))
    assert load_robot(model).controller == "abb" and load_robot("kr210").controller == "kuka"
