"""What the G-code reader takes of RS274NGC's words, each on its own minimal program: parameters
and expressions in positions (evaluated where decidable before run time, reported where not),
LinuxCNC's polar words ``@``/``^``, offsets on axes the correction does not touch (``G92 A0``,
a printer's ``G92 E0``) and ``%`` tape marks with a sequence number.

Expected positions come from LinuxCNC's ``rs274`` (the nominal moves of the input, and those of
the rewritten program) and from the frame maths of a known error field (``corrected``), never
from the code under test.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_gcode_rs274 import canonical
from test_real_programs import HALF, SMOOTH, corrected, gcode_rewrite, holes

from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.infra.errors import InputError


def statuses(rows) -> list[tuple[int, str]]:
    return [(r.line, r.status) for r in rows]


def commands(out: str) -> list[str]:
    """rs274's canonical commands without their numbers."""
    return [line.split("N.....")[-1].split("(")[0] for line in out.splitlines()]


# ---------------------------------------------------------------- offsets on other axes


def test_an_offset_on_the_rotary_axis_leaves_x_y_z_known(rs274, tmp_path):
    """`G92 A0` shifts the A axis only: the moves after it are corrected (X, Y, Z as
    programmed are the program frame's), rs274 reaches each corrected point; `G92 X0` still
    moves the frame and is reported until `G92.1`."""
    text = (
        "G21 G90 G17 F100\nG0 X100 Y50 Z20 A30\nG92 A0\nG1 X120 Y50 Z10 A5\nG1 X140 Z5\n"
        "G92 X0\nG1 X10\nG92.1\nG0 X150 Y60 Z30\nM2\n"
    )
    nominal, out = canonical(rs274, tmp_path, text)
    assert "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 30.0000" in out  # A only (rs274's own)
    new, rows = gcode_rewrite(text, SMOOTH)
    assert statuses(rows) == [
        (2, "corrected"),
        (4, "corrected"),
        (5, "corrected"),
        (7, "skipped"),
        (9, "corrected"),
    ]
    assert "G92 offset (line 6)" in rows[3].reason
    moves, _ = canonical(rs274, tmp_path, new)
    for k in (0, 1, 2, 4):  # every axis written, or carried from a corrected move
        np.testing.assert_allclose(moves[k, :3], corrected(SMOOTH, nominal[k, :3])[0], atol=HALF)
    np.testing.assert_array_equal(moves[:, 3], nominal[:, 3])  # A as programmed


def test_a_printers_extruder_reset_leaves_x_y_z_known():
    """A 3D printer's `G92 E0` resets the extruder, not the frame: every later move is placed
    and corrected (8,847 positions of one real printer file were lost to it)."""
    text = "G21 G90\nG92 E0\nG1 X100 Y50 Z0.3 E1.5 F1200\nG1 X110 E2.1\nG92 E0\nG1 Y60 E0.4\n"
    moves = parse_gcode(text)
    assert [m.reason for m in moves] == ["", "", ""]
    assert [m.target for m in moves] == [(100, 50, 0.3), (110, 50, 0.3), (110, 60, 0.3)]
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 3
    want = corrected(SMOOTH, [[100, 50, 0.3], [110, 50, 0.3], [110, 60, 0.3]])
    got = parse_gcode(new)
    np.testing.assert_allclose(got[0].target, want[0], atol=HALF)
    assert abs(got[1].x - want[1, 0]) <= HALF and abs(got[2].y - want[2, 1]) <= HALF
    assert "E1.5" in new and "G92 E0" in new and new.count("E") == text.count("E")


# ---------------------------------------------------------------- % after a sequence number


def test_a_numbered_tape_mark_after_the_program_end_is_read(rs274, tmp_path):
    """`N890 %` after M30 (where rs274 stops reading) was refused whole; it is a tape mark."""
    text = "%\nN10 G21 G90 G17\nN20 G0 X100 Y50 Z20\nN30 G1 Z5 F100\nN40 M30\nN890 %\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert statuses(rows) == [(3, "corrected"), (4, "corrected")]
    assert new.endswith("N40 M30\nN890 %\n")
    nominal, _ = canonical(rs274, tmp_path, text)
    moves, _ = canonical(rs274, tmp_path, new)
    want = corrected(SMOOTH, nominal[:, :3])
    np.testing.assert_allclose(moves[0, :3], want[0], atol=HALF)
    assert abs(moves[1, 2] - want[1, 2]) <= HALF  # the Z it writes


# ---------------------------------------------------------------- parameters and expressions

EXPRESSIONS = (
    "G21 G90 G17 F100\n"
    "G0 X100 Y0 Z20\n"
    "#1=50 #<depth>=-3\n"
    "G1 X#1 Y[#1*2] Z#<depth>\n"
    "G1 x sin[30] Y#1\n"
    "G1 X [1+2] Z[#<depth>*2]\n"
    "#1=5 G0 X#1 #1=70\n"
    "G0 X-#1 Y [ atan[1]/[1] + 2**3 mod 5 ]\n"
    "M2\n"
)


def test_expressions_are_read_as_rs274_moves(rs274, tmp_path):
    """The reader's targets are rs274's moves, including an assignment on a move's line
    (taking effect after it) and operator precedence."""
    nominal, _ = canonical(rs274, tmp_path, EXPRESSIONS)
    moves = parse_gcode(EXPRESSIONS)
    assert [m.reason for m in moves] == [""] * 6
    np.testing.assert_allclose([m.target for m in moves], nominal[:, :3], atol=1e-4)
    # line 7 reads #1 before its own assignments (50), the last one holds after it (70)
    assert moves[4].x == 50 and moves[5].x == -70 and moves[5].y == 48


def test_corrected_expression_words_become_numbers(rs274, tmp_path):
    """A corrected word written as a parameter or an expression gets the corrected number in
    the expression's place (the rest of the line as it was); rs274 reaches the independently
    corrected points; the assignments stay as they are."""
    nominal, out = canonical(rs274, tmp_path, EXPRESSIONS)
    new, rows = gcode_rewrite(EXPRESSIONS, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 6
    assert commands(canonical(rs274, tmp_path, new)[1]) == commands(out)
    lines = new.splitlines()
    number = r"(-?\d+\.\d+)"
    assert lines[2] == "#1=50 #<depth>=-3"
    assert re.fullmatch(f"G1 X{number} Y{number} Z{number}", lines[3])
    assert re.fullmatch(f"G1 x {number} Y{number}", lines[4])
    assert re.fullmatch(f"G1 X {number} Z{number}", lines[5])
    assert re.fullmatch(f"#1=5 G0 X{number} #1=70", lines[6])
    assert re.fullmatch(f"G0 X{number} Y {number}", lines[7])
    moves, _ = canonical(rs274, tmp_path, new)
    want = corrected(SMOOTH, nominal[:, :3])
    # each axis a line writes is the corrected one; the others are carried from the move before
    written = [(0, 1, 2), (0, 1, 2), (0, 1), (0, 2), (0,), (0, 1)]
    for k, axes in enumerate(written):
        for i in axes:
            assert abs(moves[k, i] - want[k, i]) <= HALF, (k, i)
    assert np.abs(moves[:, :3] - nominal[:, :3]).max() > 0.1  # the field moves them


@pytest.mark.parametrize(
    ("line", "why"),
    [
        ("G1 X#<_x>", "#<_x> is a system parameter or not set: read at run time"),
        ("G1 X#2", "#2 is not set before this line"),
        ("G1 X#5221", "#5221 is a system parameter, read at run time"),
        ("#3=[#5420+1]\nG1 X#3", "#3 is set from [#5420+1] (line 3): #5420 is a system"),
        ("G1 X[sqrt[-1]]", "SQRT[-1] is not defined"),
        ("G1 X[1/0]", "division by zero"),
    ],
)
def test_words_not_decidable_before_run_time_are_reported(line, why):
    """Per position, with the reason; the axis is unknown until written again, the line is
    left as it is."""
    text = f"G21 G90\nG0 X100 Y50 Z20\n{line}\nG1 Y60\nG1 X110\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected", "skipped", "skipped", "corrected"]
    assert why in rows[1].reason and "uses a parameter or an expression" in rows[1].reason
    assert "X not known" in rows[2].reason
    assert new.splitlines()[2:-2] == text.splitlines()[2:-2]


def test_an_assignment_to_a_parameter_not_known_forgets_them_all():
    text = "#1=5\n#[#5420]=2\nG0 X#1 Y0 Z0\n"
    (move,) = parse_gcode(text)
    assert "#1 is not known after #[#5420] = .." in move.reason


def test_an_assignment_to_a_work_offset_moves_the_frame():
    text = "G0 X1 Y2 Z3\n#5221=10\nG0 X4\n"
    moves = parse_gcode(text)
    assert moves[0].reason == "" and "#5221 assigned (line 2)" in moves[1].reason


@pytest.mark.parametrize(
    ("text", "message"),
    [("G1 X[1+]\n", "cannot read the expression"), ("G1 @1 X2\n", "polar words @ ^ with X")],
)
def test_malformed_words_are_located(text, message):
    with pytest.raises(InputError) as err:
        parse_gcode(text, "p.ngc")
    assert message in str(err.value) and err.value.line == 1


# ---------------------------------------------------------------- polar coordinates

POLAR = (
    "G21 G90 G17 F100\n"
    "G0 X0 Y0 Z20\n"
    "G1 @100 ^30\n"  # absolute: radius and angle about the origin
    "G91 @5 ^10\n"  # incremental: added to the tool's own radius and angle
    "@-3 ^-20\n"
    "G90 G0 Z10\n"
    "G0 @80.5 ^-90\n"
    "M2\n"
)


def test_polar_words_are_read_as_rs274_moves(rs274, tmp_path):
    nominal, _ = canonical(rs274, tmp_path, POLAR)
    moves = parse_gcode(POLAR)
    np.testing.assert_allclose([m.target for m in moves], nominal[:, :3], atol=1e-4)
    r, a = 105.0, math.radians(40.0)  # after `G91 @5 ^10`
    np.testing.assert_allclose(moves[2].target[:2], (r * math.cos(a), r * math.sin(a)))


def test_corrected_polar_moves_land_on_their_corrections(rs274, tmp_path):
    """A polar move that writes both words is corrected: its radius and angle are written
    (under G91 as differences from where the rewritten program leaves the tool), and rs274's X,
    Y are the independently corrected ones; the words keep their letters and places."""
    nominal, out = canonical(rs274, tmp_path, POLAR)
    new, rows = gcode_rewrite(POLAR, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 6
    assert commands(canonical(rs274, tmp_path, new)[1]) == commands(out)
    lines = new.splitlines()
    assert re.fullmatch(r"G1 @\d+\.\d{4} \^\d+\.\d+", lines[2])
    assert re.fullmatch(r"G91 @\d\.\d{4} \^\d+\.\d+", lines[3])
    assert re.fullmatch(r"@-\d\.\d{4} \^-\d+\.\d+", lines[4])
    moves, _ = canonical(rs274, tmp_path, new)
    want = corrected(SMOOTH, nominal[:, :3])
    # rs274 prints 4 decimals; the rewrite rounds the radius to 4, the angle finer
    np.testing.assert_allclose(moves[1:, :2][[0, 1, 2, 4]], want[1:, :2][[0, 1, 2, 4]], atol=2e-4)
    assert np.abs(moves[1:4, :2] - nominal[1:4, :2]).max() > 0.1


def test_a_polar_move_with_one_word_keeps_its_start(rs274, tmp_path):
    """`^90` alone keeps the tool's radius: it is reported, and the move that sets its start is
    not corrected, so rs274 ends it where the input does."""
    text = "G21 G90 G17 F100\nG0 X100 Y0 Z20\n^90\nG0 X50 Y50 Z20\nM2\n"
    nominal, _ = canonical(rs274, tmp_path, text)
    new, rows = gcode_rewrite(text, SMOOTH)
    assert statuses(rows) == [(2, "skipped"), (3, "skipped"), (4, "corrected")]
    assert "polar ^ without @" in rows[1].reason and "line 3" in rows[0].reason
    moves, _ = canonical(rs274, tmp_path, new)
    np.testing.assert_allclose(moves[:2], nominal[:2], atol=1e-4)
    np.testing.assert_allclose(moves[2, :2], corrected(SMOOTH, nominal[2:3, :3])[0, :2], atol=HALF)


BOLT_CIRCLE = (
    "G21 G17 G90 F100\n"
    "G0 X40 Y0 Z10\n"
    "G91 G81 R2.5 Z-12 ^60 L6\n"  # six holes, each turned 60 degrees about the origin
    "G90 G80 G0 Z20\n"
    "G0 X50 Y10\n"
    "G81 @30 ^45 R2 Z-3\n"  # one hole at radius 30, 45 degrees
    "G80 G0 Z20\n"
    "M2\n"
)


def test_polar_cycles_are_read_as_rs274_drills_them(rs274, tmp_path):
    """A bolt circle drilled by a G91 cycle turning `^60` six times, then a G90 polar hole: the
    holes are where rs274 drills them, and the moves after them are placed."""
    nominal, out = canonical(rs274, tmp_path, BOLT_CIRCLE)
    bottoms = holes(nominal, out)[0]
    turn = np.radians(60.0 * np.arange(1, 7))
    circle = np.column_stack([40 * np.cos(turn), 40 * np.sin(turn), np.full(6, 0.5)])
    np.testing.assert_allclose(bottoms[:6], circle, atol=1e-4)
    moves = parse_gcode(BOLT_CIRCLE)
    np.testing.assert_allclose(moves[1].target, circle[0], atol=1e-9)
    np.testing.assert_allclose(moves[2].target, (40, 0, 20), atol=1e-9)  # after the sixth
    np.testing.assert_allclose(moves[4].target, bottoms[6], atol=1e-4)


def test_a_g90_polar_hole_is_corrected_and_the_g91_circle_drilled_as_programmed(rs274, tmp_path):
    """The G91 polar cycle's holes depend on where it starts: reported, and the move that sets
    its start is not corrected, so rs274 drills them as programmed; the G90 polar hole gets its
    corrected radius and angle, and rs274 drills it on the independent correction."""
    nominal, out = canonical(rs274, tmp_path, BOLT_CIRCLE)
    new, rows = gcode_rewrite(BOLT_CIRCLE, SMOOTH)
    assert statuses(rows) == [
        (2, "skipped"),
        (3, "skipped"),
        (4, "corrected"),
        (5, "corrected"),
        (6, "corrected"),
        (7, "corrected"),
    ]
    assert "G91 canned cycle with polar words" in rows[1].reason and "line 3" in rows[0].reason
    moves, new_out = canonical(rs274, tmp_path, new)
    assert commands(new_out) == commands(out)
    bottoms = holes(moves, new_out)[0]
    np.testing.assert_allclose(bottoms[:6], holes(nominal, out)[0][:6], atol=1e-4)
    want = corrected(SMOOTH, holes(nominal, out)[0][6:])[0]
    np.testing.assert_allclose(bottoms[6, :2], want[:2], atol=2e-4)  # @, ^ finer than Z
    assert abs(bottoms[6, 2] - want[2]) <= HALF
    assert re.search(r"G81 @\d+\.\d{4} \^\d+\.\d+ R", new)


FUNCTIONS = [
    "[atan[1]/[1] + 2**3 mod 5]",
    "[1+2*3-4/2]",
    "[2**2**3]",
    "[1 lt 2 and 0]",
    "[-2**2]",
    "[7 mod -3]",
    "[-7 mod 3]",
    "[round[-2.5]]",
    "[fix[-2.5]]",
    "[fup[-2.5]]",
    "[1+1 eq 2]",
    "[abs[-2] + sqrt[16] + exp[1] + ln[2]]",
    "[acos[0.5] + asin[0.5] + tan[30] + cos[60]]",
    "[3 gt 2 xor 1 or 0]",
    "[5.5 ne 5.50001]",
]


def test_functions_and_operators_as_rs274_evaluates_them(rs274, tmp_path):
    text = "G21 G90 G17 F100\nG0 X0 Y0 Z0\n" + "".join(f"G1 Z{f}\n" for f in FUNCTIONS) + "M2\n"
    nominal, _ = canonical(rs274, tmp_path, text)
    moves = parse_gcode(text)
    assert [m.reason for m in moves] == [""] * len(moves)
    np.testing.assert_allclose([m.z for m in moves[1:]], nominal[1:, 2], atol=1e-4)


@st.composite
def chains(draw):
    """A chain of + - * over small integers, written without brackets: (text, Python's value)."""
    numbers = draw(st.lists(st.integers(-50, 50), min_size=1, max_size=8))
    ops = draw(
        st.lists(st.sampled_from("+-*"), min_size=len(numbers) - 1, max_size=len(numbers) - 1)
    )
    text = str(numbers[0]) + "".join(f" {op} {n}" for op, n in zip(ops, numbers[1:], strict=True))
    return text, eval(text)  # Python's precedence of + - * is RS274NGC's


@given(chains(), st.integers(0, 2))
@settings(max_examples=200, deadline=None)
def test_arithmetic_follows_precedence(chain, set_by):
    """`Z[a op b op c ..]`, directly or through a parameter set on an earlier line, is the value
    of the chain with * before + and -, left to right."""
    text, value = chain
    if set_by == 0:
        program = f"G0 X0 Y0 Z[{text}]\n"
    else:
        name = "#7" if set_by == 1 else "#<chain>"
        program = f"{name} = [{text}]\nG0 X0 Y0 Z{name}\n"
    (move,) = parse_gcode(program)
    assert move.reason == "" and move.z == value


def test_a_polar_continuation_hole_gets_its_own_depth_and_r_plane(rs274, tmp_path):
    """A G90 cycle continued by a line of polar words only: that hole's corrected Z and R words
    are added after its polar words, and rs274 drills every hole on its correction."""
    text = "G21 G17 G90 F100\nG0 X0 Y0 Z20\nG81 @300 ^10 R2 Z-3\n@300 ^80\nG80 G0 Z20\nM2\n"
    nominal, out = canonical(rs274, tmp_path, text)
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 4
    assert re.fullmatch(r"@\d+\.\d{4} \^\d+\.\d+ Z-\d\.\d{3} R\d\.\d{3}", new.splitlines()[3])
    moves, new_out = canonical(rs274, tmp_path, new)
    bottoms, r_planes = holes(moves, new_out)
    want = corrected(SMOOTH, holes(nominal, out)[0])
    np.testing.assert_allclose(bottoms[:, :2], want[:, :2], atol=2e-4)
    np.testing.assert_allclose(bottoms[:, 2], want[:, 2], atol=HALF)
    want_r = corrected(SMOOTH, holes(nominal, out)[1])[:, 2]
    np.testing.assert_allclose(r_planes[:, 2], want_r, atol=HALF)
    assert abs(bottoms[1, 2] - bottoms[0, 2]) > 0.01  # the holes need their own depths
