"""KRL parser: positions, exact number spans, and the base frame context."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from accugrid.codegen.krl.parse import BaseRef, parse_krl, scan_krl
from accugrid.infra.errors import InputError


def spans_ok(text, pos):
    for key, num in pos.numbers.items():
        literal = text[num.start : num.end]
        if num.decimals >= 0:
            assert float(literal) == num.value, key


def test_dat_declarations_values_and_spans():
    text = (
        "DEFDAT  P1 PUBLIC\r\n"
        "DECL GLOBAL E6POS XP1={X 1.5E+02,Y -2.25,Z .5,A 0.0,B 90,C -1.0e-3,S 'B010',T 'B00011011',"
        "E1 0.0,E2 0.0}\r\n"
        "DECL POS p2 = { x 10 , y 20 , z 30 }   ; comment {X 9}\r\n"
        "DECL FRAME fr[2]\r\n"
        " fr[1]={X 1,Y 2,Z 3,A 0,B 0,C 0}\r\n"
        "decl e6axis ax1={A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\r\n"
        "ENDDAT\r\n"
    )
    pos = parse_krl(text, "p1.dat")
    assert [p.name for p in pos] == ["XP1", "p2", "fr[1]", "ax1"]
    xp1 = pos[0]
    assert (xp1.x, xp1.y, xp1.z, xp1.c) == (150.0, -2.25, 0.5, -0.001)
    assert (xp1.s, xp1.t) == (2, 0b11011)
    assert xp1.type == "E6POS" and xp1.line == 2 and xp1.kind == "decl"
    assert "E1" in xp1.numbers and not xp1.reason
    for p in pos:
        spans_ok(text, p)
    assert pos[1].values == {"X": 10, "Y": 20, "Z": 30} and not pos[1].reason
    assert pos[2].type == "FRAME" and pos[2].kind == "assign" and pos[2].key == "FR[1]"
    assert "joint-space" in pos[3].reason


def test_motions_inline_circ_partial_arithmetic_and_comments():
    text = "\n".join(
        [
            "DEF t()",
            "BAS(#BASE, 2)",
            ";FOLD LIN P9 Vel=2 m/s CPDAT1 Tool[1] Base[2];%{PE}%R 8.3.31,%MKUKATPBASIS",
            "; LIN {X 9,Y 9,Z 9}",
            'MsgNotify("a;b")',
            "lin {x 1,y 2,z 3,a 0,b 0,c 0} c_dis",
            "CIRC {X 4,Y 5,Z 6}, {POS: X 7,Y 8,Z 9,A 0,B 0,C 0}, CA 90",
            "LIN {Z 100}",
            "PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}",
            "LIN P1:{X 0,Y 4,Z 0,A 0,B 0,C 0}",
            "LIN_REL {X 5}",
            "END",
        ]
    )
    scan = scan_krl(text, "t.src")
    pos = scan.positions
    assert [p.line for p in pos] == [6, 7, 7, 8, 9, 10, 11]
    assert [(p.x, p.y, p.z) for p in pos[:3]] == [(1, 2, 3), (4, 5, 6), (7, 8, 9)]
    assert all(not p.reason for p in pos[:3])
    # the base after the call MsgNotify() is unknown: a call may change $BASE
    assert pos[0].base.kind == "unknown" and "MsgNotify" in pos[0].base.reason
    assert "partial aggregate" in pos[3].reason
    assert "joint-space" in pos[4].reason
    assert "frame arithmetic" in pos[5].reason
    assert "relative motion" in pos[6].reason
    assert scan.uses[0].name == "P1" and "frame operand of ':'" in scan.uses[0].reason
    for p in pos:
        spans_ok(text, p)


def _bases(text, **kw):
    scan = scan_krl(text, "b.src", **kw)
    return [
        (p.base.kind, p.base.number if p.base.kind == "number" else p.base.reason)
        for p in scan.positions
    ]


AGG = "LIN {X 1,Y 2,Z 3}"


def test_base_context_rules():
    text = "\n".join(
        [
            "DEF b()",
            AGG,  # start of routine: inherited
            "$BASE = BASE_DATA[3]",
            AGG,
            "BAS (#BASE,4)",
            AGG,
            "$BASE = {FRAME: X 10,Y 0,Z 5,A 90,B 0,C 0}",
            AGG,
            "$BASE = BASE_DATA[1]:gfShift",
            AGG,
            "$BASE = EK(ROOT, #EX_KIN, OFFS)",
            AGG,
            "$BASE = BASE_DATA[2]",
            "IF a THEN",
            "  $BASE = BASE_DATA[5]",
            "ENDIF",
            AGG,
            "$BASE = BASE_DATA[2]",
            "IF a THEN",
            "  x = 1",
            "ELSE",
            "  y = 2",
            "ENDIF",
            AGG,
            "END",
        ]
    )
    kinds = _bases(text)
    assert kinds[0][0] == "unknown" and "inherited" in kinds[0][1]
    assert kinds[1] == ("number", 3) and kinds[2] == ("number", 4)
    scan = scan_krl(text, "b.src")
    assert scan.positions[3].base.kind == "literal"
    assert scan.positions[3].base.xyzabc == (10, 0, 5, 90, 0, 0)
    assert "frame arithmetic" in kinds[4][1]
    assert "EK()" in kinds[5][1]
    assert kinds[6][0] == "unknown" and "branch" in kinds[6][1]
    assert kinds[7] == ("number", 2)
    # --base N: the routine starts in BASE_DATA[N]
    start = _bases(text, initial_base=BaseRef("number", 0, number=6))
    assert start[0] == ("number", 6) and start[1] == ("number", 3)


def test_fdat_labels_loops_and_calls():
    text = "\n".join(
        [
            "DEF c()",
            "FDAT_ACT = FP1",
            "PTP XP1",
            "Sub()",
            "PTP XP2",
            "BAS(#BASE,1)",
            "Jump1:",
            "LIN XP3",
            "BAS(#BASE,2)",
            "GOTO Jump1",
            "LOOP",
            "  LIN {X 1,Y 2,Z 3}",
            "  BAS(#BASE,3)",
            "ENDLOOP",
            "END",
            "DECL FDAT FP1={TOOL_NO 1,BASE_NO 7,IPO_FRAME #BASE}",
            "DECL FDAT FP2={TOOL_NO 1,BASE_NO 7,IPO_FRAME #TCP}",
        ]
    )
    scan = scan_krl(text, "c.src")
    uses = {u.name: u for u in scan.uses}
    assert uses["XP1"].base.kind == "fdat" and uses["XP1"].base.fdat == "FP1"
    assert scan.fdats["FP1"].base_no == 7
    assert scan.fdats["FP2"].base_no is None and "external TCP" in scan.fdats["FP2"].reason
    assert uses["XP2"].base.kind == "unknown" and "Sub()" in uses["XP2"].base.reason
    assert "jump target" in uses["XP3"].base.reason
    assert "loop" in scan.positions[0].base.reason
    trusted = scan_krl(text, "c.src", trust_calls=True)
    assert {u.name: u for u in trusted.uses}["XP2"].base.kind == "fdat"


@pytest.mark.parametrize(
    ("text", "line", "column"),
    [
        ("DEF a()\nLIN {X 1,Y 2\nEND\n", 2, 5),
        ("DEF a()\nLIN X 1}\nEND\n", 2, 8),
        ('DEF a()\n$OUT[1]=TRUE\nMsg("open\nEND', 3, 5),
        ("DEFDAT a\nDECL E6POS P={X 1,X 2,Y 3,Z 4}\n", 2, 21),
        ("DEF a()\nLIN {X 1,Y 'Q1',Z 3}\n", 2, 12),
        ('DEF a()\nLIN {X 1,Y 2,Z 3,N[] "a" b}\n', 2, 18),
        ("DEF a()\nLIN {X 1,Y 2,Z 3,N {Q 0,R 1} x}\n", 2, 18),
        ("DEF a()\nLIN {X 1,Y 2,Z 3,N[] 5}\n", 2, 18),
        ('DEFDAT a\nDECL ADAT T={P {Q 0,R[] " "}\n', 2, 13),
    ],
)
def test_malformed_programs_name_line_and_column(text, line, column):
    with pytest.raises(InputError) as err:
        parse_krl(text, "bad.src")
    assert (err.value.path, err.value.line, err.value.column) == ("bad.src", line, column)


def test_binary_data_is_refused():
    with pytest.raises(InputError, match="binary") as err:
        parse_krl("DEF a()\nLIN {X 1}\n\x00\x01\x02", "bin.src")
    assert err.value.line == 3


keyword = st.sampled_from(["LIN", "lin", "Lin", "PTP", "ptp", "SLIN"])
ws = st.text(" \t", min_size=0, max_size=3)
ws1 = st.text(" \t", min_size=1, max_size=3)
num = st.floats(-5000, 5000, allow_nan=False).map(lambda v: f"{v:.{3}f}")
comment = st.sampled_from(["", " ; LIN {X 0,Y 0,Z 0}", ";", " ;FOLD {PE}", "   "])


@given(keyword, ws, ws, ws1, st.lists(num, min_size=6, max_size=6), comment, st.booleans())
def test_random_whitespace_case_and_comments(kw, w0, w1, w2, values, tail, typed):
    keys = ["X", "y", "Z", "a", "B", "c"]
    items = [f"{w0}{k}{w2}{v}{w1}" for k, v in zip(keys, values, strict=True)]
    prefix = f"{w0}POS:{w1}" if typed else ""
    line = f"{w0}{kw}{w2}{{{prefix}{','.join(items)}}}{w1}{tail}"
    text = f"DEF r()\r\n;{line}\r\n{line}\r\nEND\r\n"
    (pos,) = parse_krl(text, "r.src")
    assert pos.line == 3
    assert [pos.x, pos.y, pos.z, pos.a, pos.b, pos.c] == [float(v) for v in values]
    for key, value in zip("XYZABC", values, strict=True):
        n = pos.numbers[key]
        assert text[n.start : n.end] == value


def test_spline_inline_form_sets_its_own_base():
    """KSS 8 inline forms: SPTP XP1 WITH ..., $BASE = SBASE(FP1.BASE_NO), ..."""
    text = "\n".join(
        [
            "DEF s()",
            "SPTP XP1 WITH $VEL_AXIS[1] = SVEL_JOINT(100.0), $TOOL = STOOL2(FP1), "
            "$BASE = SBASE(FP1.BASE_NO), $IPO_MODE = SIPO_MODE(FP1.IPO_FRAME)",
            "SLIN {X 1,Y 2,Z 3} WITH $BASE = BASE_DATA[4]",
            "SLIN {X 1,Y 2,Z 3} WITH $BASE = lbase",
            "SLIN {X 1,Y 2,Z 3}",
            "END",
        ]
    )
    scan = scan_krl(text, "s.src")
    assert scan.uses[0].base.kind == "fdat" and scan.uses[0].base.fdat == "FP1"
    kinds = [p.base.kind for p in scan.positions]
    assert kinds == ["number", "unknown", "unknown"]
    assert scan.positions[0].base.number == 4
    assert "lbase" in scan.positions[1].base.reason
    assert "inherited" in scan.positions[2].base.reason  # WITH applies to its motion only


def test_huge_literals_are_located_or_reported():
    """Issue 12 item 6: 5,000 digits ended in an internal error (int() limit, float overflow)."""
    with pytest.raises(InputError) as err:
        scan_krl("DEF a( )\nLIN {X " + "9" * 400 + ",Y 1,Z 1}\nEND\n", "a.src")
    assert (err.value.line, err.value.column) == (2, 8) and "out of range" in str(err.value)
    scan = scan_krl(
        "DEF a( )\nBAS(#BASE," + "9" * 5000 + ")\nLIN {X 1,Y 2,Z 3}\n"
        "$BASE = BASE_DATA[" + "9" * 5000 + "]\nLIN {X 1,Y 2,Z 3}\nEND\n"
    )
    first, second = scan.positions
    assert first.base.kind == "unknown" and "not a number" in first.base.reason
    assert second.base.kind == "unknown" and "not a BASE_DATA number" in second.base.reason


# a controller $config.dat as KSS writes it: motion data with nested aggregates, CHAR members
# (NAME[] "text", also empty and holding , { ; ), enums, booleans, reals with exponents
CONFIG_DAT = (
    "DEFDAT  $CONFIG PUBLIC\n"
    'DECL ADAT TDEFAULT={TriggerPara {TriggerPath 0,TriggerTask[] " "}}\n'
    'DECL ADAT TSPOT={TriggerPara {TriggerPath 1,TriggerTask[] ""},'
    'Spot {Gun 2,Name[] "a, {b}; c"}}\n'
    'DECL FDAT FHOME={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " ",TQ_STATE FALSE}\n'
    "DECL LDAT LCPDAT1={VEL 2.0,ACC 100.0,APO_DIST 100.0,APO_FAC 50.0,AXIS_VEL 100.0,"
    "AXIS_ACC 100.0,ORI_TYP #VAR,CIRC_TYP #BASE,JERK_FAC 50.0,GEAR_JERK 100.0,EXAX_IGN 0}\n"
    "DECL PDAT PPDAT1={VEL 100.0,ACC 100.0,APO_DIST 100.0,APO_MODE #CDIS,GEAR_JERK 50.0}\n"
    'DECL TOOL_INFO_T TINFO={Name[] "drill, 8 mm",Mass 1.5E+01,Fixed TRUE,Load {M -1,F 1e-3}}\n'
    "BASE_DATA[1]={X 1.0E+03,Y -250.5,Z 0.0,A 90.0,B 0.0,C 0.0}\n"
    "BASE_DATA[2]={X 12.5,Y 0.0,Z 7.0,A 0.0,B -0.5,C 180.0}\n"
    "DECL E6POS XP1={X 1.5E+02,Y -2.25,Z .5,A 0.0,B 90.0,C 0.0,S 6,T 27,E1 0.0,E2 0.0}\n"
    "ENDDAT\n"
)


def test_config_dat_with_strings_and_nested_aggregates_is_read():
    scan = scan_krl(CONFIG_DAT, "$config.dat")
    assert scan.base_data == {
        1: ((1000.0, -250.5, 0.0, 90.0, 0.0, 0.0), 8),  # line 8
        2: ((12.5, 0.0, 7.0, 0.0, -0.5, 180.0), 9),
    }
    assert (scan.fdats["FHOME"].base_no, scan.fdats["FHOME"].tool_no) == (2, 1)
    pos = parse_krl(CONFIG_DAT, "$config.dat")
    assert [p.name for p in pos] == ["XP1"]  # motion data and strings are no positions
    assert (pos[0].x, pos[0].y, pos[0].z, pos[0].s, pos[0].t) == (150.0, -2.25, 0.5, 6, 27)
    assert not pos[0].reason
    spans_ok(CONFIG_DAT, pos[0])
    inline = parse_krl('DEF a()\nLIN {X 1,Y 2,Z 3,N[] "",M {Q 1,R[] "a, b"}}\nEND\n', "a.src")
    assert inline[0].values == {"X": 1, "Y": 2, "Z": 3} and not inline[0].reason
