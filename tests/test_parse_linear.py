"""Issue 12 item 3: the KRL and G-code readers are linear in their input.

Each input here made the old patterns backtrack exponentially (G-code words) or polynomially
with a high power (runs of spaces, brackets, comments): past 60 s for the issue's cases. A linear
reader reads each in milliseconds; the tests assert the outcome (the parse, or an InputError at
the right place), never a time.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.codegen.gcode.expressions import Parameters
from accugrid.codegen.gcode.parse import _fast_line, _scan, parse_gcode
from accugrid.codegen.krl.parse import scan_krl
from accugrid.infra.errors import InputError

RUN = 65536  # 64 KiB


def test_gcode_many_long_words_then_garbage():
    """The issue's case: X111111111111 Y111111111111 ... V111111111111 @ (exponential before)."""
    words = " ".join(letter + "1" * 12 for letter in "XYZABCUVWIJKPQ")
    with pytest.raises(InputError) as err:
        parse_gcode(f"G1 {words} @\n", "w.ngc")
    assert err.value.column == len(f"G1 {words} @")
    assert "'@'" in str(err.value)


@pytest.mark.parametrize(
    ("line", "column", "message"),
    [
        ("(" * RUN, 1, "unclosed '(' comment"),
        ("G1 X" + "[" * RUN, 5, "unclosed '['"),
        ("#" * RUN, RUN + 1, "cannot read this parameter"),
        ("G1 X1" + " " * RUN + "@", RUN + 6, "'@'"),
        ("G1 X" + " " * RUN + "Y", 4, "'X'"),
    ],
)
def test_gcode_long_runs_are_refused_where_they_go_wrong(line, column, message):
    with pytest.raises(InputError) as err:
        parse_gcode(line + "\n", "r.ngc")
    assert err.value.line == 1 and err.value.column == column
    assert message in str(err.value)


def test_gcode_long_runs_that_are_fine():
    assert parse_gcode("()" * (RUN // 2) + "; done\n") == []
    moves = parse_gcode("\n" * RUN + "G90 G0 X1 Y2 Z3\n" + " " * RUN + "\n")
    assert [m.target for m in moves] == [(1.0, 2.0, 3.0)] and moves[0].line == RUN + 1
    moves = parse_gcode("G90 G0 X1 Y2 Z3" + " " * RUN + "(" + "x" * RUN + ")\n")
    assert moves[0].target == (1.0, 2.0, 3.0)


def test_krl_bas_with_a_run_of_spaces():
    """The issue's case: BAS(#BASE, followed by 5,000 spaces (no closing parenthesis)."""
    text = "DEF a( )\nBAS(#BASE,1)\nBAS(#BASE," + " " * 5000 + "\nLIN {X 1,Y 2,Z 3}\nEND\n"
    (pos,) = scan_krl(text).positions
    assert pos.base.kind == "number" and pos.base.number == 1  # the broken BAS changes nothing
    text = "DEF a( )\nBAS(#BASE," + " " * 5000 + ")\nLIN {X 1,Y 2,Z 3}\nEND\n"
    (pos,) = scan_krl(text).positions
    assert pos.base.kind == "unknown" and "not a number" in pos.base.reason


def test_krl_spaces_inside_braces():
    """The issue's case: 64 KiB of spaces inside braces."""
    (pos,) = scan_krl("DECL E6POS P1={" + " " * RUN + "}\n").positions
    assert pos.numbers == {} and "partial aggregate" in pos.reason
    (pos,) = scan_krl("DECL E6POS P1={X 1," + " " * RUN + "Y 2}\n").positions
    assert pos.values == {"X": 1.0, "Y": 2.0}
    (pos,) = scan_krl("DECL E6POS P1={X 1, Y 2 {" + " " * RUN + "}, Z 3}\n").positions
    assert pos.values == {"X": 1.0, "Z": 3.0} and "component Y is '2 {" in pos.reason


@pytest.mark.parametrize(
    ("line", "column"),
    [
        ("LIN {X 1," + " " * RUN + "@}", RUN + 10),
        ("LIN {X 1, " + "A" * RUN + "}", 11),
    ],
)
def test_krl_long_runs_are_refused_where_they_go_wrong(line, column):
    with pytest.raises(InputError) as err:
        scan_krl("DEF a( )\n" + line + "\nEND\n", "a.src")
    assert err.value.line == 2 and err.value.column == column


def test_krl_long_runs_that_are_fine():
    text = (
        "DEF a( )\n"
        + "p"
        + " " * RUN
        + "q\n"  # neither an assignment nor a call
        + "SLIN XP1 WITH $BASE = "
        + " " * RUN
        + "x\n"  # a spline's own base from a variable
        + "P"
        + " " * RUN
        + ".X = 1\n"  # a member assignment with spaces
        + "END\n"
    )
    scan = scan_krl(text)
    (use,) = scan.uses
    assert use.base.kind == "unknown" and "WITH $BASE = x" in use.base.reason
    assert "P" in scan.assigned


NUMBERS = st.from_regex(r"[-+]?(\d{1,6}(\.\d{0,4})?|\.\d{1,4})", fullmatch=True)


@given(
    words=st.lists(
        st.tuples(st.sampled_from("XYZABCRFSNT"), NUMBERS, st.sampled_from(["", " ", "\t", "  "])),
        max_size=8,
        unique_by=lambda w: w[0],
    ),
    gcodes=st.lists(st.sampled_from(["0", "1", "81", "90", "91", "20", "21", "54"]), max_size=3),
    lower=st.booleans(),
)
def test_gcode_fast_and_word_by_word_readers_agree(words, gcodes, lower):
    """Plain blocks take the one-regex path, blocks with parameters the word-by-word one: on a
    plain block both must read the same words, G-codes and spans."""
    line = " ".join(f"G{g}" for g in gcodes) + "".join(f" {k}{gap}{v}" for k, v, gap in words)
    line = line.lower() if lower else line
    fast = _fast_line(line, 7, None, 1)
    slow = _scan(line, 7, None, 1, Parameters())
    assert fast[:3] == slow[:3] and not slow.why and not slow.assigns
    for word in (w for w in fast.words.values() if w is not None):
        assert line[word.start - 7 : word.end - 7] == word.literal


KEYS = ["X", "Y", "Z", "A", "B", "C", "E1", "S", "T"]


@given(
    items=st.lists(
        st.tuples(
            st.sampled_from(KEYS),
            NUMBERS,
            st.sampled_from(["", " ", "  "]),  # before the key
            st.sampled_from([" ", "  ", "\t"]),  # between key and value
            st.sampled_from(["", " "]),  # before the comma
        ),
        min_size=1,
        max_size=9,
        unique_by=lambda item: item[0],
    )
)
def test_krl_flat_and_item_by_item_aggregate_readers_agree(items):
    """A flat aggregate is read in one regex pass, one with a string or a nested aggregate item
    by item: the same components must give the same numbers and spans either way."""
    body = ",".join(f"{lead}{k}{gap}{v}{trail}" for k, v, lead, gap, trail in items)
    flat = scan_krl("DECL E6POS P={" + body + "}\n").positions[0]
    mixed = scan_krl("DECL E6POS P={" + body + ', NOTE "x"}\n').positions[0]
    assert flat.numbers == mixed.numbers
    assert {k: float(v) for k, v, *_ in items} == flat.values
