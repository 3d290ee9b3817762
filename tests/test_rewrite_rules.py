"""Issue 11: what `accugrid rewrite` must never do (correct what is not a drilling position, round a
correction away, refuse a whole program for one unread line), each on its real or minimal case.

Expected values come from the constant error field of ``rewrite_helpers`` (e = E_CONST
everywhere, so a corrected base-frame position is p + R^T e) and from the rules, not from the
code under test.
"""

from __future__ import annotations

import csv
import math
import os
import stat

import numpy as np
import pytest
from rewrite_helpers import E_CONST, write_cell, write_grid

from accugrid.app.cli import main
from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.codegen.krl.parse import parse_krl
from accugrid.infra.errors import InputError
from accugrid.kinematics.frames import abc_to_matrix

GRID_ABC = (0.0, 90.0, 0.0)  # the orientation the test grids are measured at (robot frame)


def rewrite(*args) -> int:
    """``accugrid rewrite`` with --allow-partial: these rules are about what is left as it is
    and why (the job rule itself: tests/test_policy.py)."""
    return main(["rewrite", "--allow-partial", *map(str, args)])


def report(path) -> list[dict[str, str]]:
    return list(csv.DictReader(open(path, newline="")))


@pytest.fixture
def cell(tmp_path):
    """Constant error field, base 1 = robot frame, grid measured at A 0 B 90 C 0."""
    path = write_cell(tmp_path, field="constant")
    write_grid(tmp_path / "grid.csv", field="constant", abc=GRID_ABC)
    return path


def krl_src(*lines: str) -> str:
    return "DEF job( )\nBAS(#BASE,1)\n" + "\n".join(lines) + "\nEND\n"


# ---------------------------------------------------------------- item 1: orientation


def _tilted(deg: float) -> str:
    """A, B, C (robot frame = base 1) tilted ``deg`` from the grid's about the X axis."""
    rot = abc_to_matrix(np.array(GRID_ABC)) @ abc_to_matrix(np.array([0.0, 0.0, deg]))
    # about the tool's own X axis: for GRID_ABC = (0, 90, 0) that is C = deg
    assert np.allclose(rot, abc_to_matrix(np.array([0.0, 90.0, deg])))
    return f"A 0.0,B 90.0,C {deg}"


@pytest.mark.parametrize(
    ("options", "statuses"),
    [
        ([], ["corrected", "corrected", "skipped"]),
        (["--orientation-limit", "90"], ["corrected", "corrected", "corrected"]),
        (["--allow-orientation"], ["corrected", "corrected", "corrected"]),
        (["--orientation-tol", "15", "--orientation-limit", "15"], ["corrected"] * 2 + ["skipped"]),
    ],
)
def test_orientation_flag_and_limit_as_correct(tmp_path, cell, options, statuses, capsys):
    src = tmp_path / "job.src"
    src.write_text(
        krl_src(
            f"LIN {{X 1000.0,Y 0.0,Z 1000.0,{_tilted(0.0)}}}",
            f"LIN {{X 1000.0,Y 0.0,Z 1000.0,{_tilted(10.0)}}}",
            f"LIN {{X 1000.0,Y 0.0,Z 1000.0,{_tilted(89.9)}}}",
        )
    )
    out, rep = tmp_path / "out.src", tmp_path / "r.csv"
    assert rewrite(src, "--cell", cell, "-o", out, "--report", rep, *options) == 0
    rows = report(rep)
    assert [r["status"] for r in rows] == statuses
    assert rows[0]["reason"] == ""  # at the grid's orientation: nothing to say
    tol = (
        float(options[options.index("--orientation-tol") + 1])
        if "--orientation-tol" in options
        else 5
    )
    if tol < 10:
        assert rows[1]["reason"].startswith("flag: orientation 10.0 deg")
    else:
        assert rows[1]["reason"] == ""
    if statuses[2] == "skipped":
        assert "orientation 89.9 deg" in rows[2]["reason"]
        assert "beyond the limit of" in rows[2]["reason"]
        assert "C 89.9}" in out.read_text()  # left exactly as written
    else:
        assert rows[2]["reason"].startswith("flag: orientation 89.9 deg")
        assert "flagged (see the report)" in capsys.readouterr().err


def test_orientation_in_the_base_frame_and_gcode_abc(tmp_path):
    """The check compares robot-frame orientations: base rotation times the written A, B, C."""
    base2 = (0.0, 0.0, 0.0, 90.0, 0.0, 0.0)  # rotated 90 deg about Z
    cell = write_cell(tmp_path, field="constant", base_data={2: base2}, program_frame=base2)
    write_grid(tmp_path / "grid.csv", field="constant", abc=GRID_ABC)
    # base_R^T grid_R: the grid's orientation written in base 2 is A -90 B 90 C 0
    src = tmp_path / "b.src"
    src.write_text(
        "DEF b( )\nBAS(#BASE,2)\nLIN {X 0.0,Y -1000.0,Z 1000.0,A -90.0,B 90.0,C 0.0}\n"
        "LIN {X 0.0,Y -1000.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\nEND\n"
    )
    rep = tmp_path / "r.csv"
    assert rewrite(src, "--cell", cell, "-o", tmp_path / "o.src", "--report", rep) == 0
    assert [r["status"] for r in report(rep)] == ["corrected", "skipped"]
    ngc = tmp_path / "p.ngc"
    ngc.write_text("G90 G0 X0 Y-1000 Z1000 A-90 B90 C0\nG1 X1 A0\nG1 X2 Y-1000 Z1000\n")
    rep2 = tmp_path / "r2.csv"
    assert rewrite(ngc, "--cell", cell, "-o", tmp_path / "p2.ngc", "--report", rep2) == 0
    rows = report(rep2)
    assert [r["status"] for r in rows] == ["corrected", "skipped", "skipped"]
    assert "orientation 90.0 deg" in rows[1]["reason"]  # A stays 0 for the next move too


# ---------------------------------------------------------------- item 4: precision


def test_inch_one_decimal_program_keeps_the_correction(realworld, tmp_path):
    """RS274NGC manual example 3 (G20, one decimal): z-1.1 must not become z-1.2."""
    cell = write_cell(tmp_path, field="constant")
    program = realworld / "gcode" / "printhor_example3_inch.gcode"
    out, rep = tmp_path / "e3.gcode", tmp_path / "r.csv"
    assert rewrite(program, "--cell", cell, "-o", out, "--report", rep) == 0
    # (the first holes set the start of G91 cycles repeated L3, L4: not corrected)
    first = out.read_text().splitlines()[8]
    e_in = E_CONST / 25.4  # the constant error in inches
    want = (5 + e_in[0], 6 + e_in[1], 0.2 + e_in[2], -1.1 + e_in[2])
    assert first == "n0090 g83 g90 x{:.3f} y{:.3f} r{:.3f} z{:.3f} q0.21".format(*want)
    for row in report(rep):
        if row["status"] == "corrected":
            assert float(row["residual_mm"]) <= 0.0005 * 25.4 * math.sqrt(3)


def test_integer_mm_krl_gets_hundredths_and_a_rounding_warning(tmp_path, cell, capsys):
    src = tmp_path / "int.src"
    src.write_text(krl_src("LIN {X 1000,Y 20,Z 1000,A 0,B 90,C 0}"))
    out = tmp_path / "o.src"
    assert rewrite(src, "--cell", cell, "-o", out) == 0
    x, y, z = np.array([1000, 20, 1000]) + E_CONST
    assert f"LIN {{X {x:.2f},Y {y:.2f},Z {z:.2f},A 0,B 90,C 0}}" in out.read_text()
    assert "warning" not in capsys.readouterr().err
    assert rewrite(src, "--cell", cell, "-o", tmp_path / "d0.src", "--decimals", "0") == 0
    err = capsys.readouterr().err
    assert "rounding to the written decimals leaves 1 position(s)" in err
    assert "tolerance (0.3 mm)" in err


# ---------------------------------------------------------------- item 5: parameters


def test_parameter_words_are_evaluated_or_reported(realworld, tmp_path, cell):
    """Parameters assigned in straight-line code are evaluated in the words that use them; a
    system parameter, one never set, or one set from either is reported with the reason."""
    lagun = realworld / "gcode" / "lagun_HEMA-P005.cnc"
    out = tmp_path / "lagun.cnc"
    assert rewrite(lagun, "--cell", cell, "-o", out) == 0
    assert out.read_bytes() == lagun.read_bytes()  # every move is in o<drill> (not given)
    program = (
        "#<_z_clearance> = 0.4\n#1=5 #<a> = [#1 + 2]\n"
        "G90 G0 X1000 Y0 Z1000\nG1 Z#<_z_clearance>\nG1 X1001 Y1\nG1 X1002 Y2 Z1002\n"
        "G1 X[#1*2] Y3 Z1003\nG1 X1004 Y4 Z-#1\nG1 X#<_x>\nG1 X1005 Y#2\n#3=[#5420+1]\n"
        "G1 Y6 Z#3\n"
    )
    moves = parse_gcode(program)
    assert [m.line for m in moves] == [3, 4, 5, 6, 7, 8, 9, 10, 12]
    assert [m.reason for m in moves[:6]] == [""] * 6
    assert moves[1].target == (1000, 0, 0.4)
    assert moves[4].target == (10, 3, 1003) and moves[5].target == (1004, 4, -5)
    assert "X#<_x> uses a parameter" in moves[6].reason and "run time" in moves[6].reason
    assert "Y#2 uses a parameter" in moves[7].reason and "not set before" in moves[7].reason
    assert "#3 is set from [#5420+1] (line 11)" in moves[8].reason
    assert "#5420 is a system parameter" in moves[8].reason
    ngc = tmp_path / "p.ngc"
    ngc.write_text(program)
    rep = tmp_path / "r.csv"
    argv = ["--cell", cell, "-o", tmp_path / "p2.ngc", "--report", rep, "--allow-partial"]
    assert rewrite(ngc, *argv) == 0
    assert [r["status"] for r in report(rep)] == ["corrected"] * 6 + ["skipped"] * 3


@pytest.mark.parametrize(
    ("text", "column", "message"),
    [
        ("#1 5\n", 1, "must be assigned"),
        ("#<a = 5\n", 2, "unclosed '<'"),
        ("G1 X[1+2\n", 5, "unclosed '['"),
        ("#1 = abc\n", 6, "cannot read the parameter's value"),
    ],
)
def test_malformed_parameters_are_located(text, column, message):
    with pytest.raises(InputError) as err:
        parse_gcode(text, "p.ngc")
    assert message in str(err.value) and err.value.column == column


# ---------------------------------------------------------------- item 6: G54 after offsets


@pytest.mark.parametrize(
    ("offset", "reason"),
    [
        ("G92 X0 Y0", "G92 offset"),
        ("G52 X10 Y10", "G52 offset"),
        ("G10 L2 P1 X100", "G10"),
        ("G68 X0 Y0 R30", "G68"),
    ],
)
def test_g54_does_not_cancel_an_offset(offset, reason):
    moves = parse_gcode(f"G90 G0 X0 Y0 Z0\n{offset}\nG54\nG1 X5 Y5 Z5\n")
    assert reason in moves[-1].reason


def test_g10_names_what_it_changes():
    moves = parse_gcode("G90 G0 X0 Y0 Z0\nG10 L1 P1 Z0.0 R5.0\nG1 X5 Y5 Z5\n")
    assert "G10 L1 (line 2) changes the tool table" in moves[-1].reason
    moves = parse_gcode("G90 G0 X0 Y0 Z0\nG10 L20 P1 X0\nG1 X5 Y5 Z5\n")
    assert "G10 L20 (line 2) changes the work offsets" in moves[-1].reason


@pytest.mark.parametrize(
    ("program", "cleared"),
    [
        ("G55\nG54\nG1 X5 Y5 Z5\n", True),  # G54 ends a G55 selection
        ("G92 X0\nG92.1\nG1 X5 Y5 Z5\n", True),
        ("G68 X0 Y0 R30\nG69\nG1 X5 Y5 Z5\n", True),
        ("G10 L2 P1 X100\nG54\nG1 X5 Y5 Z5\n", False),
    ],
)
def test_what_cancels_an_offset(program, cleared):
    moves = parse_gcode("G90 G0 X0 Y0 Z0\n" + program)
    assert (moves[-1].reason == "") == cleared


# ---------------------------------------------------------------- item 9: unknown motions


@pytest.mark.parametrize(
    ("code", "what"),
    [
        ("G5 X10 Y10 I1 J1 P1 Q1", "spline G5"),
        ("G38.2 Z-10", "probe G38.2"),
        ("G33 Z-10 K1", "spindle-synchronized motion G33"),
        ("G0.5 X10", "unknown G-code G0.5"),
        ("G999 X10", "unknown G-code G999"),
        ("G1 G999 X10", "unknown G-code G999"),  # whatever the order of the words
    ],
)
def test_unknown_motions_are_reported_not_corrected(tmp_path, cell, code, what):
    program = f"G90 G0 X1000 Y0 Z1000\n{code}\nX1001\nG1 X1002 Y1 Z1001\n"
    moves = parse_gcode(program)
    assert what in moves[1].reason and "not corrected" in moves[1].reason
    assert moves[2].reason  # the unknown motion mode stays in effect
    assert moves[3].reason == ""  # a known motion code ends it
    ngc = tmp_path / "u.ngc"
    ngc.write_text(program)
    out, rep = tmp_path / "u2.ngc", tmp_path / "r.csv"
    assert rewrite(ngc, "--cell", cell, "-o", out, "--report", rep) == 0
    assert [r["status"] for r in report(rep)] == ["corrected", "skipped", "skipped", "corrected"]
    assert out.read_text().splitlines()[1] == code  # the unknown motion's line is untouched


# ---------------------------------------------------------------- item 8: output folder


def test_existing_output_folder_with_a_dot(tmp_path, cell):
    src, dat = tmp_path / "job.src", tmp_path / "job.dat"
    src.write_text(krl_src("LIN XP1"))
    dat.write_text("DEFDAT job\nDECL E6POS XP1={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n")
    folder = tmp_path / "out.v2"
    folder.mkdir()
    assert rewrite(src, dat, "--cell", cell, "-o", folder) == 0
    assert (folder / "job.src").exists() and (folder / "job.dat").exists()
    (p1,) = parse_krl((folder / "job.dat").read_text())
    want = np.array([1000.0, 0.0, 1000.0]) + E_CONST
    assert np.allclose([p1.x, p1.y, p1.z], want, atol=0.005)  # 2 decimals at least (item 4)


# ---------------------------------------------------------------- item 2: what is a position

R2 = abc_to_matrix(np.array([90.0, 0.0, 0.0]))  # BASE_DATA[2] below: rotated 90 deg about Z


def test_sample_program_frames_are_never_corrected(realworld, tmp_path):
    """kukaKRLmagic: a tool frame assigned to $TOOL, frames passed to a routine that assigns them
    to $BASE: with --base 0 (which the old skip message advised) nothing may change."""
    cell = write_cell(tmp_path, field="constant")
    src = realworld / "krl" / "kukakrlmagic_sample_program.src"
    dat = src.with_suffix(".dat")
    out, rep = tmp_path / "out", tmp_path / "r.csv"
    assert rewrite(src, dat, "--cell", cell, "-o", out, "--report", rep, "--base", "0") == 0
    assert (out / src.name).read_bytes() == src.read_bytes()
    rows = {r["name"]: r for r in report(rep)}
    assert all(r["status"] != "corrected" for r in rows.values())
    assert "assigned to $TOOL at line 152" in rows["tool_operation"]["reason"]
    assert "not used by a motion" in rows["my_frame[1]"]["reason"]
    assert not any("--base" in r["reason"] for r in rows.values())


def test_frames_operands_and_constants_are_not_positions(tmp_path):
    cell = write_cell(tmp_path, field="constant", base_data={2: (0, 0, 0, 90, 0, 0)})
    src, dat = tmp_path / "j.src", tmp_path / "j.dat"
    src.write_text(
        "DEF j( )\nBAS(#BASE,0)\n$TOOL = TL1\n$BASE = BS1\nLIN XP1\n"
        "LIN BF:{X 1,Y 0,Z 0,A 0,B 90,C 0}\nP9 = XP1:OFS\nEND\n"
    )
    dat.write_text(
        "DEFDAT j\n"
        "DECL FRAME TL1={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n"
        "DECL FRAME BS1={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n"
        "DECL FRAME BF={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n"
        "DECL FRAME OFS={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n"
        "DECL E6POS XP1={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n"
        "ENDDAT\n"
    )
    rep = tmp_path / "r.csv"
    assert rewrite(src, dat, "--cell", cell, "-o", tmp_path / "o", "--report", rep) == 0
    rows = {r["name"]: r for r in report(rep) if r["file"] == "j.dat"}
    assert "assigned to $TOOL at line 3" in rows["TL1"]["reason"]
    assert "assigned to $BASE at line 4" in rows["BS1"]["reason"]
    assert "an operand of ':' at line 6" in rows["BF"]["reason"]
    assert "an operand of ':' at line 7" in rows["OFS"]["reason"]
    # XP1 is a motion target and also the left operand of ':' (a frame) at line 7: never corrected
    assert "an operand of ':' at line 7" in rows["XP1"]["reason"]
    assert all(r["status"] == "skipped" for r in rows.values())


def test_a_member_assigned_at_run_time_leaves_only_its_element(tmp_path, cell):
    """``fp[2].Y = 25`` changes fp[2] alone: fp[1] and fp[3] are corrected (p + e, base 1 = the
    robot frame), fp[2] is reported with the line that assigns it."""
    src, dat = tmp_path / "j.src", tmp_path / "j.dat"
    src.write_text(krl_src("LIN fp[1]", "fp[2].Y = 25", "LIN fp[2]", "LIN fp[3]"))
    dat.write_text(
        "DEFDAT j\nDECL E6POS fp[3]\n"
        + "".join(
            f"fp[{i}]={{X {1000 + 10 * i}.000,Y 0.000,Z 900.000,A 0.0,B 90.0,C 0.0}}\n"
            for i in (1, 2, 3)
        )
        + "ENDDAT\n"
    )
    rep = tmp_path / "r.csv"
    assert rewrite(src, dat, "--cell", cell, "-o", tmp_path / "o", "--report", rep) == 0
    rows = {r["name"]: r for r in report(rep)}
    assert rows["fp[2]"]["status"] == "skipped"
    assert rows["fp[2]"]["reason"] == "fp[2] is assigned at run time (j.src:4)"
    out = (tmp_path / "o" / "j.dat").read_text().splitlines()
    for i in (1, 3):
        assert rows[f"fp[{i}]"]["status"] == "corrected"
        want = np.array([1000 + 10 * i, 0, 900]) + E_CONST
        assert out[1 + i] == (
            f"fp[{i}]={{X {want[0]:.3f},Y {want[1]:.3f},Z {want[2]:.3f},A 0.0,B 90.0,C 0.0}}"
        )
    assert out[3] == dat.read_text().splitlines()[3]


def test_lone_dat_with_base_fdat_wins_and_only_pos(tmp_path):
    cell = write_cell(tmp_path, field="constant", base_data={2: (0, 0, 0, 90, 0, 0)})
    dat = tmp_path / "cfg.dat"
    dat.write_text(
        "DEFDAT cfg\n"
        "DECL E6POS XP1={X 1000.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}\n"
        "DECL E6POS XP2={X 1000.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "DECL FDAT FP2={TOOL_NO 1,BASE_NO 0,IPO_FRAME #TCP}\n"
        "DECL E6POS XP3={X 1000.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "DECL FDAT FP3={TOOL_NO 5,BASE_NO 0,IPO_FRAME #BASE}\n"
        "DECL E6POS XP4={X 1000.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "DECL CONST POS $NULLPOS={X 0.0,Y 0.0,Z 0.0,A 0.0,B 0.0,C 0.0}\n"
        "DECL FRAME TOOL_CORR={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 0.0,C 0.0}\n"
        "ENDDAT\n"
    )
    out, rep = tmp_path / "o.dat", tmp_path / "r.csv"
    assert rewrite(dat, "--cell", cell, "-o", out, "--report", rep) == 0
    assert out.read_bytes() == dat.read_bytes()  # without --base no motion says it is a position
    assert "(give the .src, or --base N)" in report(rep)[0]["reason"]
    assert rewrite(dat, "--cell", cell, "-o", out, "--report", rep, "--force", "--base", "0") == 0
    rows = {r["name"]: r for r in report(rep)}
    assert rows["XP1"]["status"] == "corrected"  # in BASE_DATA[2] (its FDAT), not --base 0
    want = np.array([1000.0, 0.0, 1000.0]) + R2.T @ E_CONST
    got = [float(rows["XP1"][k]) for k in ("x_new", "y_new", "z_new")]
    assert np.allclose(got, want, atol=5e-4)
    assert "IPO_FRAME #TCP" in rows["XP2"]["reason"] and rows["XP2"]["status"] == "skipped"
    assert "TOOL_NO 5" in rows["XP3"]["reason"] and rows["XP3"]["status"] == "skipped"
    assert rows["XP4"]["status"] == "corrected"  # no FDAT: --base 0
    assert np.allclose(
        [float(rows["XP4"][k]) for k in ("x_new", "y_new", "z_new")],
        [1000.25, -0.125, 1000.375],
        atol=5e-4,
    )
    assert "CONST" in rows["$NULLPOS"]["reason"]
    assert "POS/E6POS only, this is FRAME" in rows["TOOL_CORR"]["reason"]


# ---------------------------------------------------------------- item 3: STRUC positions


def test_struc_toolpath_members_are_corrected(realworld, tmp_path):
    """ChinaMilling CNC1: 790 points in gsCNC1[i].fCnC, run by LIN gsCNC1[counter].fCNC."""
    cell = write_cell(tmp_path, field="constant")
    src = realworld / "krl" / "chinamilling_CNC_LOOP.src"
    dat = realworld / "krl" / "chinamilling_CNC1.dat"
    rep = tmp_path / "r.csv"
    assert rewrite(src, dat, "--cell", cell, "-o", tmp_path / "a", "--report", rep) == 0
    rows = [r for r in report(rep) if r["file"] == dat.name]
    assert len(rows) == 790 and {r["status"] for r in rows} == {"skipped"}
    # the base is the caller's: CNC_LOOP is the module's main routine
    assert "start of routine CNC_LOOP (line 1): $BASE is inherited" in rows[0]["reason"]
    out = tmp_path / "b"
    # ChangeSpeed(), in the .src, keeps $BASE: BAS(#CP_DAT) and BAS(#PTP_DAT) set speeds only
    args = ("--report", rep, "--force", "--base", "0")
    assert rewrite(src, dat, "--cell", cell, "-o", out, *args) == 0
    rows = [r for r in report(rep) if r["file"] == dat.name]
    assert [r["name"] for r in rows[:2]] == ["gsCNC1[1].fCnC", "gsCNC1[2].fCnC"]
    assert {r["status"] for r in rows} == {"corrected"} and len(rows) == 790
    x, y, z = np.array([331.0737, -29.9896, 13.0]) + E_CONST
    first = (out / dat.name).read_text().splitlines()[5]
    assert first == (
        f"gsCNC1[1] = {{fCnC {{X {x:.4f}, Y {y:.4f}, Z {z:.4f}, A 0.000, B 0.000, C 0.000 }}, "
        "grFeedrate 2000}"
    )


# ---------------------------------------------------------------- item 7: true reasons


def test_reasons_for_local_declarations_and_trailing_clauses(tmp_path, cell):
    src = tmp_path / "loc.src"
    src.write_text(
        "DEF loc( )\ndecl axis joint_pos_tgt\nFRAME lfStartMillingPos\nDECL FRAME lfCorner[4]\n"
        "BAS(#BASE,1)\njoint_pos_tgt = GetJoints()\nPTP joint_pos_tgt\nLIN lfStartMillingPos\n"
        "LIN lfCorner[2] C_DIS\nLIN Shift(3) C_VEL\nLIN XGONE\nEND\n"
    )
    rep = tmp_path / "r.csv"
    assert rewrite(src, "--cell", cell, "-o", tmp_path / "o.src", "--report", rep) == 0
    rows = {r["name"]: r["reason"] for r in report(rep)}
    assert "declared (AXIS, loc.src:2)" in rows["joint_pos_tgt"]
    assert "declared (FRAME, loc.src:3)" in rows["lfStartMillingPos"]
    assert "declared (FRAME, loc.src:4)" in rows["lfCorner[2]"]
    assert rows["Shift(3)"] == "target 'Shift(3)' is an expression"  # C_VEL is not part of it
    assert rows["XGONE"] == "XGONE is not declared in the given files"


def test_config_dat_fdats_and_positions_are_read(tmp_path, cell):
    config = tmp_path / "config.dat"
    config.write_text(
        "DEFDAT $CONFIG\nDECL E6AXIS XHOME={A1 0.0,A2 -90.0,A3 90.0,A4 0.0,A5 0.0,A6 0.0}\n"
        "DECL FDAT FHOME={TOOL_NO 1,BASE_NO 0,IPO_FRAME #BASE}\nENDDAT\n"
    )
    src = tmp_path / "h.src"
    src.write_text(
        "DEF h( )\n;FOLD PTP HOME\nFDAT_ACT=FHOME\nPTP XHOME\n;ENDFOLD\n"
        "LIN {X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\nEND\n"
    )
    rep = tmp_path / "r.csv"
    assert rewrite(src, "--cell", cell, "-o", tmp_path / "a.src", "--report", rep) == 0
    rows = report(rep)
    assert "FDAT FHOME (line 3) is not in the given files" in rows[0]["reason"]
    assert rows[1]["reason"] == "XHOME is not declared in the given files"
    args = ("--report", rep, "--force", "--config-dat", config)
    assert rewrite(src, "--cell", cell, "-o", tmp_path / "b.src", *args) == 0
    rows = report(rep)
    assert rows[0]["status"] == "corrected"  # FHOME: BASE_NO 0, the robot frame
    assert "joint-space target" in rows[1]["reason"]


def test_config_dat_and_program_dat_with_strings_in_nested_aggregates(tmp_path):
    """A controller $config.dat (motion data with CHAR members, enums, booleans) gives
    BASE_DATA[2]; the program's own .dat carries such members too."""
    cell = write_cell(tmp_path, field="constant")  # declares no BASE_DATA[2]
    config = tmp_path / "config.dat"
    config.write_text(
        "DEFDAT  $CONFIG PUBLIC\n"
        'DECL ADAT TDEFAULT={TriggerPara {TriggerPath 0,TriggerTask[] " "}}\n'
        "DECL LDAT LDEFAULT={VEL 2.0,ACC 100.0,APO_DIST 100.0,ORI_TYP #VAR,CIRC_TYP #BASE}\n"
        "DECL PDAT PDEFAULT={VEL 100.0,ACC 100.0,APO_DIST 100.0,APO_MODE #CDIS}\n"
        'DECL FDAT FDEFAULT={TOOL_NO 1,BASE_NO 0,IPO_FRAME #BASE,POINT2[] "",TQ_STATE FALSE}\n'
        "BASE_DATA[2]={X 0.0,Y 0.0,Z 0.0,A 9.0E+01,B 0.0,C 0.0}\n"
        "ENDDAT\n"
    )
    src, dat = tmp_path / "job.src", tmp_path / "job.dat"
    src.write_text(krl_src("FDAT_ACT=FP1", "LIN XP1"))
    dat.write_text(
        "DEFDAT job\n"
        'DECL ADAT AP1={TriggerPara {TriggerPath 0,TriggerTask[] "drill, 8 mm"}}\n'
        "DECL E6POS XP1={X 1000.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        'DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " "}\n'
        "ENDDAT\n"
    )
    out, rep = tmp_path / "out", tmp_path / "r.csv"
    args = ("--cell", cell, "-o", out, "--report", rep, "--force")
    assert rewrite(src, dat, *args) == 0  # read; BASE_DATA[2] is unknown without --config-dat
    assert "BASE_DATA[2] is in neither" in report(rep)[0]["reason"]
    assert rewrite(src, dat, *args, "--config-dat", config) == 0
    row = report(rep)[0]
    assert row["name"] == "XP1" and row["status"] == "corrected"
    want = np.array([1000.0, 0.0, 1000.0]) + R2.T @ E_CONST
    assert np.allclose([float(row[k]) for k in ("x_new", "y_new", "z_new")], want, atol=5e-4)


def test_outputs_are_readable_by_others_under_umask_022(tmp_path, cell):
    """A transfer service must be able to read the programs (they were 0600 before)."""
    src, dat = tmp_path / "job.src", tmp_path / "job.dat"
    src.write_text(krl_src("LIN XP1"))
    dat.write_text("DEFDAT job\nDECL E6POS XP1={X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}\n")
    old = os.umask(0o022)
    try:
        assert (
            rewrite(src, dat, "--cell", cell, "-o", tmp_path / "o", "--report", tmp_path / "r") == 0
        )
    finally:
        os.umask(old)
    for path in (tmp_path / "o" / "job.src", tmp_path / "o" / "job.dat", tmp_path / "r"):
        assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_a_correction_beyond_the_safety_limit_names_its_file_and_line(tmp_path, capsys):
    """Issue 12 item 9: the refusal said 'correction ... at point 4' without file and line."""
    cell = write_cell(tmp_path, field="too_long")
    src = tmp_path / "far.src"
    src.write_text(krl_src("LIN {X 1000.0,Y 0.0,Z 1000.0,A 0.0,B 90.0,C 0.0}"))
    out = tmp_path / "o.src"
    assert rewrite(src, "--cell", cell, "-o", out) == 2
    err = capsys.readouterr().err.strip()
    assert f"{src}:3:" in err and "exceeds the safety limit of 5 mm" in err
    assert not out.exists()
    ngc = tmp_path / "far.ngc"
    ngc.write_text("G90\nG0 X1000 Y0 Z1000\n")
    assert rewrite(ngc, "--cell", cell, "-o", tmp_path / "o.ngc") == 2
    assert f"{ngc}:2:" in capsys.readouterr().err
