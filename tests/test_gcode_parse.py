"""RS274NGC parser: modal state, absolute targets, spans, and what it refuses to guess."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from accugrid.codegen.gcode.parse import parse_gcode
from accugrid.infra.errors import InputError


def test_words_any_order_case_no_spaces_comments_and_spans():
    text = "%\nN10g21g90(set up; mm)\nn20 G0 x1.5Y-2Z10.25 ; go\ny3 X4(mid)z.5\nN30G1Z-1.0F100\n%\n"
    moves = parse_gcode(text, "a.ngc")
    assert [m.target for m in moves] == [(1.5, -2.0, 10.25), (4.0, 3.0, 0.5), (4.0, 3.0, -1.0)]
    assert [m.motion for m in moves] == ["G0", "G0", "G1"]
    assert [m.line for m in moves] == [3, 4, 5]
    for m in moves:
        for w in m.words.values():
            assert float(text[w.start : w.end]) == w.value
    assert moves[1].setters == (0, 0, 0) and moves[2].setters == (1, 1, 1)


def test_incremental_and_inch_targets_are_absolute_mm():
    moves = parse_gcode("G20 G90 G0 X1 Y1 Z1\nG91 G1 X0.5 Z-2\nY-1\n")
    assert moves[0].scale == 25.4
    assert moves[1].incremental
    expected = [(25.4, 25.4, 25.4), (38.1, 25.4, -25.4), (38.1, 0.0, -25.4)]
    for m, e in zip(moves, expected, strict=True):
        assert m.target == pytest.approx(e)


def test_canned_cycles_sticky_z_r_and_retract():
    text = "G17 G90 G0 X0 Y0 Z50\nG99 G81 X10 Y20 Z-5 R2 F100\nX30\nG98 G83 X40 Z-8 R3 Q1\nG80\n"
    moves = parse_gcode(text)
    holes = moves[1:]
    assert [h.target for h in holes] == [(10, 20, -5), (30, 20, -5), (40, 20, -8)]
    assert [h.motion for h in holes] == ["G81", "G81", "G83"]
    assert holes[0].end == (10, 20, 2)  # G99: back to R
    assert holes[2].end == (40, 20, 50)  # G98: back to the Z the run of cycles began at (rs274)
    assert "R" in holes[0].words and not any(h.reason for h in holes)


def test_incremental_cycles_as_linuxcnc_reads_them():
    """G91: X, Y from where the tool is (each of L repeats), R from the current Z, Z from R;
    a G98 retract to the higher of the start Z and R (checked against rs274's moves)."""
    text = "G21 G90 G98 G0 X250 Y0 Z50\nG91 G81 X25 Y25 Z-50 R-25 L2\nX5 Z-4 R-1\n"
    first, second = parse_gcode(text)[1:]
    assert first.target == (275, 25, -25) and first.r_mm == 25 and first.end == (300, 50, 50)
    assert second.target == (305, 50, 45) and second.r_mm == 49 and second.end == (305, 50, 50)
    assert not first.reason and not second.reason


def test_g98_retracts_to_the_initial_level_of_the_run():
    """G98 retracts to the Z where the run of cycle blocks began (not the previous hole's
    retract); G80 or another motion mode ends the run (as rs274 expands it)."""
    text = (
        "G21 G90 G98 G0 X0 Y0 Z10\nG81 X1 Z-5 R20\nX2 R5\nG80\nG0 Z30\nG99 G81 X3 Z-5 R4\n"
        "G98 X4 R2\n"
    )
    ends = [m.end[2] for m in parse_gcode(text)]
    assert ends == [10, 20, 10, 30, 4, 30]


@pytest.mark.parametrize(
    ("program", "reason"),
    [
        ("G0 X0 Y0 Z0\nG55 G0 X1 Y1 Z1\n", "G55"),
        ("G0 X0 Y0 Z0\nG92 X0 Y0\nG0 X1 Y1 Z1\n", "G92"),
        ("G0 X0 Y0 Z0\nG2 X10 Y0 I#5420 J0\n", "arc I#5420 uses a parameter"),
        ("G0 X0 Y0 Z0\nG2 X10 Y0\n", "arc without a centre (I, J) or a radius R"),
        ("G0 X0 Y0 Z0\nG18 G3 X10 Z0 R5 K1\n", "arc with both R and K/I"),
        ("G0 X0 Y0 Z0\nG3 X0 Y0 I5 P0.5\n", "not a number of turns"),
        ("G0 X0 Y0 Z0\nG41 D1 G1 X10\n", "cutter compensation"),
        ("G0 Z5\n", "X,Y not known"),
        ("G0 X0 Y0 Z0\nG18 G81 X1 Z-1 R1\n", "without an R plane or Y depth"),
        ("G0 X0 Y0 Z0\nG28\nG91 G81 X1 Y1 Z-1 R1\n", "X,Y,Z not known"),
        ("G0 X0 Y0 Z0\nG91 G81 X1 Y1 Z-1 R1 L0.5\n", "not a repeat count"),
        ("G0 X0 Y0 Z0\nG91 G81 X1 Y1 Z-1 R1 L1000000000\n", "more than 10000 repeats"),
        ("o100 sub\nG0 X0 Y0 Z0\n", "O-word"),
    ],
)
def test_not_guessed(program, reason):
    moves = parse_gcode(program)
    assert reason in moves[-1].reason


def test_home_and_machine_moves_make_the_position_unknown():
    moves = parse_gcode("G0 X0 Y0 Z0\nG28 Z10\nG0 X5\nG53 G0 Z0\n")
    assert moves[1].motion == "G28" and moves[1].reason
    assert math.isnan(moves[2].target[1]) and "not known" in moves[2].reason


@pytest.mark.parametrize(
    ("text", "line", "column"),
    [("G0 X1 (open\n", 1, 7), ("G0 X1\nG1 X2 Y$3\n", 2, 7), ("G0 X1 X2\n", 1, 8)],
)
def test_malformed(text, line, column):
    with pytest.raises(InputError) as err:
        parse_gcode(text, "bad.ngc")
    assert (err.value.line, err.value.column) == (line, column)


def test_the_gcode_dialect_does_not_import_krl():
    """A dialect is a unit: shared program text lives in codegen.program_text (issue 10)."""
    code = (  # the registry's light plug-in modules load with the package: not counted
        "import sys, accugrid; before = set(sys.modules); "
        "import accugrid.codegen.gcode.rewrite; "
        "new = set(sys.modules) - before; "
        "print(sorted(m for m in new if m.startswith('accugrid.codegen.krl')))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_a_number_beyond_the_float_range_is_located():
    with pytest.raises(InputError) as err:
        parse_gcode("G0 X1 Y1 Z1\nG1 X" + "9" * 320 + " Y1\n", "big.ngc")
    assert (err.value.line, err.value.column) == (2, 5) and "out of range" in str(err.value)


def test_a_byte_order_mark_is_not_a_word():
    body = "G21 G90\nG0 X1 Y2 Z3\n"
    plain = parse_gcode(body)
    for bom in ("\xef\xbb\xbf", "\ufeff"):  # as latin-1 (rewrite reads bytes), or decoded
        moves = parse_gcode(bom + body)
        assert [m.target for m in moves] == [m.target for m in plain]
        assert moves[0].words["X"].start == plain[0].words["X"].start + len(bom)


@pytest.mark.parametrize(
    ("line", "target"),
    [
        ("G0 X1 (a) Y2 (b; c) Z3 ; d (e\n", (1.0, 2.0, 3.0)),
        ("G0 (a)(b)X1(c)Y2 Z3()\n", (1.0, 2.0, 3.0)),
        ("G0 X1 Y2 Z3 (((nested opening)\n", (1.0, 2.0, 3.0)),
    ],
)
def test_comments_anywhere_in_a_line(line, target):
    (move,) = parse_gcode(line)
    assert move.target == target


def test_a_closing_parenthesis_without_an_opening_one_is_located():
    with pytest.raises(InputError) as err:
        parse_gcode("G0 X1 (a) Y2) Z3\n")
    assert err.value.column == 13 and "')' without '('" in str(err.value)
