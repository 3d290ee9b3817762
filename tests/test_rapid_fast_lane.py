"""The array paths of the RAPID rewrite against the statement reader they stand in for: the rigid
lines (``codegen.rapid.rigid``) read with array operations and joined with the statements give
the robtargets, reasons, frames and splices the statement reader alone gives, on modules in the
layout RobotStudio writes and near it (other spacing and case, exponents, long quaternions, and
the rigid lines inside ``%%%`` blocks, records, unfinished statements or named like a word
around them); and the quaternion matrices against scipy's."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from accugrid.codegen.rapid import rewrite
from accugrid.codegen.rapid.rigid import read_rigid
from accugrid.codegen.rapid.section import RapidSection
from accugrid.infra.errors import InputError

SECTION = RapidSection(robot_T_wobj=np.eye(4), tool="tDrill", wobj="wobjPanel")
ORIENT = "[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]"
NAMES = ["p1", "p2", "Target_3", "P4", "pArr"]
NUMBER = st.one_of(
    st.integers(-2000, 2000).map(str),
    st.integers(-(10**7), 10**7).map(lambda k: f"{k / 1000:.3f}"),
    st.integers(-(10**5), 10**5).map(lambda k: f"{k / 100:.2f}"),
    st.sampled_from(["1.5E+02", "-0.0", ".5", "12.", "+3.25", "123456789.5", "1.123456789"]),
)
TAILS = st.sampled_from(
    [
        ORIENT,
        "[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]",
        "[0.025428088,-0.706649427,0.706649427,-0.025428088],[0,0,-1,1],"
        "[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]",
        "[0.9,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]",  # not unit
        "[1,0,0,0],[0,0,0,0],[250,9E+09,9E+09,9E+09,9E+09,9E+09]",  # an external axis
        "[1,0,0,0],[0,-1,2,5],[9E9,9E9,9E9,9E9,9E9,9E9]",
    ]
)


@st.composite
def declaration(draw) -> str:
    name = draw(st.sampled_from(NAMES))
    xyz = ",".join(draw(st.lists(NUMBER, min_size=3, max_size=3)))
    kind = draw(st.sampled_from(["CONST", "PERS", "VAR", "LOCAL CONST", "const", "TASK PERS"]))
    indent = draw(st.sampled_from(["", "    ", "\t", " " * 20]))
    value = f"[[{xyz}],{draw(TAILS)}]"
    if draw(st.integers(0, 5)) == 0:
        value = value.replace(",", ", ", 1)  # near the layout: a blank inside
    if name == "pArr" and draw(st.booleans()):
        return f"{indent}{kind} robtarget pArr{{2}}:=[{value},{value}];"
    return f"{indent}{kind} robtarget {name}:={value};"


@st.composite
def statement(draw) -> str:
    name = draw(st.sampled_from(NAMES + ["pArr{1}", "pArr{2}", "pOther"]))
    instr = draw(st.sampled_from(["MoveL", "MoveJ", "movel", "MoveC", "TriggL", "MoveAbsJ"]))
    tool = draw(st.sampled_from(["tDrill", "tDrill", "tOther", "TDRILL"]))
    wobj = draw(st.sampled_from(["\\WObj:=wobjPanel", "", "\\WObj:=wobj0", "\\WObj:=wOther"]))
    indent = draw(st.sampled_from(["", "        ", "\t\t"]))
    if instr == "MoveC":
        other = draw(st.sampled_from(NAMES))
        return f"{indent}MoveC {other},{name},v100,fine,{tool}{wobj};"
    if instr == "TriggL":
        return f"{indent}TriggL {name},v100,trig1,fine,{tool}{wobj};"
    pick = draw(st.integers(0, 9))
    if pick == 0:
        return f"{indent}{instr} Offs({name},0,0,30),v100,z5,{tool}{wobj};"
    if pick == 1:
        return f"{indent}Drill {name};"
    if pick == 2:
        return f"{indent}{name} := CRobT(\\Tool:=tDrill);"
    if pick == 3:
        return f"{indent}{instr} {name}, v100, fine, {tool}{wobj};"  # near the layout
    if pick == 4:
        return f"{indent}{instr} [[1,2,3],{ORIENT}],v100,fine,{tool}{wobj};"
    if pick == 5:
        return f"{indent}wobjPanel.uframe.trans.x := 5;"
    return f"{indent}{instr} {name},v100,fine,{tool}{wobj};"


# what keeps rigid lines from standing alone as statements (or shares their words)
TRAPS = [
    "%%%\n  VERSION:1\n%%%",
    "CASE 1",
    "x := 1 +",
    "RECORD rec\n  num a;",
    "ENDRECORD",
    "PERS tooldata tDrill:=[TRUE,[[0,0,250],[1,0,0,0]],[25,[0,0,0],[1,0,0,0],0,0,0]];",
    'PERS wobjdata wobjPanel:=[FALSE,TRUE,"",[[0,0,0],[1,0,0,0]],[[0,0,0],[1,0,0,0]]];',
    "PERS tooldata p1:=[TRUE,[[0,0,0],[1,0,0,0]],[1,[0,0,0],[1,0,0,0],0,0,0]];",
    "VAR robtarget v100;",
    "! a comment; with a semicolon",
    "TEST x",
    "MODULE (",
    ")",
]


@st.composite
def module(draw) -> str:
    lines = ["MODULE M"]
    lines += draw(st.lists(declaration(), max_size=8))
    if draw(st.booleans()):
        lines.insert(draw(st.integers(1, len(lines))), draw(st.sampled_from(TRAPS)))
    lines.append("PROC main()")
    lines += draw(st.lists(statement(), max_size=10))
    if draw(st.booleans()):
        lines.insert(draw(st.integers(1, len(lines))), draw(st.sampled_from(TRAPS)))
    lines += ["ENDPROC", "PROC Drill(robtarget p)", "MoveL p,v5,fine,tDrill;", "ENDPROC"]
    lines.append("ENDMODULE")
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    return newline.join(lines) + newline


TOOLS = {"tdrill": (-1, np.eye(4)), "tother": (2, np.eye(4))}  # the cell's and tool 2


def _both(text: str, ignore: bool, tools=None):
    """(scan as the module reader does it, scan by the statement reader alone); an InputError
    is compared by its message."""
    out = []
    for reader in (
        lambda: rewrite.scan("m.mod", text, SECTION, ignore, tools),
        lambda: rewrite._scan("m.mod", text, SECTION, ignore, None, tools),
    ):
        try:
            out.append(reader())
        except InputError as error:
            out.append(str(error))
    return out


def _same(a, b) -> None:
    if isinstance(a, str) or isinstance(b, str):
        assert a == b
        return
    assert a.name == b.name
    assert a.reason == b.reason
    assert a.others == b.others
    for key in ("xyz", "quat", "cfx", "spans", "places", "line", "frame", "commanded", "tool"):
        np.testing.assert_array_equal(getattr(a, key), getattr(b, key), err_msg=key)


@settings(max_examples=300, deadline=None)
@given(module(), st.booleans(), st.integers(0, 3), st.booleans())
def test_fast_lane_reads_as_the_statement_reader(text, ignore, decimals, several_tools):
    fast, slow = _both(text, ignore, TOOLS if several_tools else None)
    _same(fast, slow)
    if isinstance(fast, str):
        return
    new = fast.xyz + np.array([0.25, -0.125, 1 / 3])
    new[np.array([bool(r) for r in fast.reason], bool)] = np.nan
    opts = SimpleNamespace(decimals=None if decimals == 0 else decimals)
    assert rewrite.splice(text, fast, new, opts) == rewrite.splice(text, slow, new, opts)


def test_fast_lane_reads_the_layout_robotstudio_writes():
    names = [f"Target_{i}" for i in range(50)]
    decls = [f"    CONST robtarget {n}:=[[{i}.5,-2,30.125],{ORIENT}];" for i, n in enumerate(names)]
    moves = [f"        MoveL {n},v100,fine,tDrill\\WObj:=wobjPanel;" for n in names]
    lines = ["MODULE M", *decls, "    PROC main()", *moves, "    ENDPROC", "ENDMODULE"]
    text = "\r\n".join(lines) + "\r\n"
    r = read_rigid(text)
    assert r.rigid.sum() == 100 and r.names == names and r.targets == names
    found = rewrite._scan("m.mod", text, SECTION, False, r)
    assert found is not None  # every rigid line stands alone
    _same(found, rewrite._scan("m.mod", text, SECTION, False, None))
    assert found.reason == [""] * 50 and (found.frame == 1).all()
    # inside a %%% block the lines are no statements: the statement reader reads them all
    fenced = text.replace("MODULE M\r\n", "MODULE M\r\n%%%\r\n", 1).replace(
        "    PROC main()", "%%%\r\n    PROC main()", 1
    )
    assert rewrite._scan("m.mod", fenced, SECTION, False, read_rigid(fenced)) is None
    _same(*_both(fenced, False))


def test_rigid_move_before_an_arc_is_its_start_whoever_declares_the_target():
    # pA declared by a statement (LOCAL), moved to on a rigid line, then an arc: pA is the
    # arc's start; pB (rigid) likewise; pC (rigid) moved to only after the arc stays placeable
    text = (
        "MODULE M\n"
        f"LOCAL CONST robtarget pA:=[[1,2,3],{ORIENT}];\n"
        f"CONST robtarget pB:=[[4,5,6],{ORIENT}];\n"
        f"CONST robtarget pC:=[[7,8,9],{ORIENT}];\n"
        "PROC main()\n"
        "MoveL pA,v100,fine,tDrill\\WObj:=wobjPanel;\n"
        "MoveC [[1,1,1],{o}],[[2,2,2],{o}],v100,fine,tDrill\\WObj:=wobjPanel;\n"
        "MoveJ pB,v100,fine,tDrill;\n"
        "MoveC [[1,1,1],{o}],[[2,2,2],{o}],v100,fine,tDrill;\n"
        "MoveL pC,v100,fine,tDrill;\n"
        "ENDPROC\nENDMODULE\n"
    ).replace("{o}", ORIENT)
    assert read_rigid(text).rigid.sum() == 5  # pB, pC and the three MoveL/MoveJ
    fast, slow = _both(text, False)
    _same(fast, slow)
    reasons = dict(zip(fast.name, fast.reason, strict=True))
    assert "start of the circular move at line 7" in reasons["pA"]
    assert "start of the circular move at line 9" in reasons["pB"]
    assert reasons["pC"] == ""


@settings(max_examples=50)
@given(
    st.lists(
        st.tuples(*[st.floats(-2, 2, allow_nan=False, allow_infinity=False)] * 4).filter(
            lambda q: sum(v * v for v in q) > 1e-6
        ),
        min_size=1,
        max_size=20,
    )
)
def test_quaternion_matrices_are_scipys_bits(quats):
    q = np.array(quats)
    theirs = Rotation.from_quat(np.roll(q, -1, axis=1)).as_matrix().reshape(-1, 3, 3)
    np.testing.assert_array_equal(rewrite._matrices(q), theirs)
