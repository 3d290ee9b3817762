"""The whole-text reader of plain KRL lines agrees with the statement-by-statement reader:
``scan_krl`` reads a text with ``\\n`` line endings by the whole-text scanner (plain
declarations and motions in bulk, the rest by the statement reader) and the same text with lone
``\\r`` endings line by line through the statement reader alone; both must find the same
positions, uses, bases, declarations and errors. (G-code's bulk reader against its line reader:
``tests/test_gcode_bulk.py``.)
"""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from accugrid.codegen.krl.parse import scan_krl
from accugrid.infra.errors import InputError

NUMBER = st.one_of(
    st.floats(-5000, 5000, allow_nan=False).map(lambda v: f"{v:.3f}"),
    st.sampled_from(["0", "-0.0", "1.", ".5", "+2", "1e3", "-2.5E-1", "9e999", "12", "007"]),
)
GAP = st.sampled_from(["", " ", "\t", "  "])
NAME = st.sampled_from(["XP1", "XP2", "P3", "xp1", "lfPos", "C_DIS", "XP1[2]"])
TAIL = st.sampled_from(
    [
        "",
        ",S 'B010',T 'B000010'",
        ",S 'B010',T 'B000010',E1 0.0,E2 0.0,E3 0.0,E4 0.0,E5 0.0,E6 0.0",
        ",E1 12.5",
        ",S 6,T 27",
        ",X 1",
        ",S 'B01{0'",
        ",S 'Q1'",
        ", E1 foo",
        ",A1 0",
        ",S 'B010' ,T 'B10'",
    ]
)


@st.composite
def aggregates(draw) -> str:
    x, y, z = draw(NUMBER), draw(NUMBER), draw(NUMBER)
    gap = draw(GAP)
    body = f"X{gap or ' '}{x},{gap}Y {y},Z {z}"
    if draw(st.booleans()):
        body += f",A {draw(NUMBER)},B {draw(NUMBER)},C {draw(NUMBER)}"
    return "{" + draw(GAP) + body + draw(TAIL) + draw(GAP) + "}"


@st.composite
def krl_lines(draw) -> str:
    kind = draw(st.integers(0, 12))
    comment = draw(st.sampled_from(["", " ; note", ';"quoted"', " ; a:b {x}"]))
    clause = draw(st.sampled_from(["", " C_DIS", " C_PTP", " C_VEL", "  C_DIS "]))
    motion = draw(st.sampled_from(["LIN", "PTP", "SLIN", "SPTP", "lin", "CIRC"]))
    if kind <= 2:
        typ = draw(st.sampled_from(["E6POS", "POS", "FRAME", "AXIS", "e6pos"]))
        const = draw(st.sampled_from(["", "CONST "]))
        return f"DECL {const}{typ} {draw(NAME)}{draw(GAP)}={draw(GAP)}{draw(aggregates())}{comment}"
    if kind <= 4:
        return f"{draw(GAP)}{motion} {draw(NAME)}{clause}{comment}"
    if kind <= 6:
        return (
            f"{motion}{draw(st.sampled_from([' ', '  ', '']))}{draw(aggregates())}{clause}{comment}"
        )
    return draw(
        st.sampled_from(
            [
                "DEF prog( )",
                "END",
                "$BASE = BASE_DATA[2]",
                "BAS (#BASE,1)",
                "$BASE = $NULLFRAME",
                "FOR i = 1 TO 3",
                "ENDFOR",
                "IF a THEN",
                "ELSE",
                "ENDIF",
                "mark:",
                "GOTO mark",
                "Sub1()",
                "XP2 = {X 1,Y 2,Z 3}",
                "$TOOL = XP1",
                "E6POS lfPos",
                "DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}",
                "FDAT_ACT = FP1",
                "",
                "; comment",
                "&ACCESS RVP",
            ]
        )
    )


def _table(scan) -> tuple:
    t, u = scan.table, scan.use_table
    arrays = (t.line, t.column, t.kind, t.agg, t.span, t.places, u.line, u.column)
    return (
        [a.tolist() for a in arrays],
        np.nan_to_num(t.xyz, nan=1e300).tolist(),
        np.nan_to_num(t.abc, nan=1e300).tolist(),
        t.type,
        t.name,
        t.reason,
        t.external,
        u.motion,
        u.name,
        u.text,
        u.reason,
    )


def _read(text: str):
    try:
        scan = scan_krl(text, "p.src")
    except InputError as exc:
        return str(exc)
    return (
        _table(scan),
        scan.positions,
        scan.uses,
        scan.declared,
        scan.fdats,
        scan.frame_uses,
        scan.assigned,
        scan.base_data,
    )


@given(st.lists(krl_lines(), max_size=30))
def test_krl_whole_text_scanner_reads_as_the_statement_reader(lines):
    """Bulk and line-by-line reading of the same program give the same tables and objects."""
    bulk = _read("\n".join(lines))
    one_by_one = _read("\r".join(lines))
    assert bulk == one_by_one
