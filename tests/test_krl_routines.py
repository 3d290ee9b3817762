"""KRL calls and inline forms in a rewrite: a call of a routine of the given files that changes
neither $BASE nor $TOOL keeps them (``codegen.krl.routines``); one that changes them, or one
that is not in the given files, leaves them unknown; a KUKA inline form that applied its own
FDAT (``FDAT_ACT = FP1`` and ``BAS(#PTP_PARAMS, ..)``) moves in that FDAT's base and tool.

Expected rewrites are written by hand: the error is E_CONST = (0.25, -0.125, 0.375) mm
everywhere (``rewrite_helpers.const_model``), so a position in base 0 (the robot frame) moves by
it, and one in BASE_DATA[2] (rotated 30 deg about Z) by R^T E_CONST = (0.25 cos30 - 0.125 sin30,
-0.25 sin30 - 0.125 cos30, 0.375) = (0.154006, -0.233253, 0.375) mm.
"""

from __future__ import annotations

import numpy as np
import pytest
from rewrite_helpers import const_model, rewrite_krl

from accugrid.codegen.dialects import plugin_of
from accugrid.codegen.krl.rewrite import KrlPlacement
from accugrid.codegen.plugin_types import CORRECTED, Options
from accugrid.codegen.rewrite import rewrite
from accugrid.kinematics.frames import pose_from_xyzabc

OPTS = Options(model=const_model(), tool_number=1, allow_partial=True)
BASE_DATA = {2: pose_from_xyzabc(np.array([300.0, -200.0, 100.0, 30.0, 0.0, 0.0]))}
LIN = "LIN {X 500.000,Y 100.000,Z 300.000,A 0.000,B 90.000,C 0.000}"
LIN_CORRECTED = "LIN {X 500.250,Y 99.875,Z 300.375,A 0.000,B 90.000,C 0.000}"


def rewritten(texts: dict[str, str]):
    """(output texts, report rows) of ``texts`` rewritten with the constant error field."""
    result = rewrite_krl(texts, OPTS, BASE_DATA)
    return result.texts, result.rows


def program(*routines: str) -> str:
    """A .src whose main routine sets base 0, runs ``Sub(3)`` and moves to ``LIN``, followed
    by ``routines`` (lines joined)."""
    main = ["DEF p( )", "BAS (#BASE,0)", "Sub(3)", LIN, "END"]
    return "\r\n".join([*main, "", *routines]) + "\r\n"


KEEPS = [
    "DEF Sub(v :IN)",
    "REAL v",
    "$VEL.CP = v",
    "BAS (#VEL_CP, v)",
    "IF v < 0.1 THEN",
    "  Slow()",
    "ENDIF",
    "END",
    "",
    "DEF Slow( )",
    "BAS (#ACC_CP, 50)",
    "BAS (#PTP_DAT)",
    "END",
]


def test_a_call_of_a_routine_that_keeps_the_frames_keeps_them():
    src = program(*KEEPS)
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)
    assert rows.status.tolist() == [CORRECTED]


# what the routine Sub does at line 9 of p.src, and the reason the motion after its call keeps
CHANGES = [
    ("$BASE = BASE_DATA[2]", "which changes $BASE or $TOOL ($BASE set at line 9 of p.src)"),
    ("$TOOL = TOOL_DATA[1]", "which changes $BASE or $TOOL ($TOOL set at line 9 of p.src)"),
    ("BAS (#TOOL, 1)", "which changes $BASE or $TOOL (BAS(#TOOL, ..) at line 9 of p.src)"),
    ("BAS (#INITMOV, 0)", "which changes $BASE or $TOOL (BAS(#INITMOV, ..) at line 9 of p.src)"),
    (
        "BAS (#PTP_PARAMS, 100)",
        "which changes $BASE or $TOOL (BAS(#PTP_PARAMS, ..) at line 9 of p.src)",
    ),
    ("FDAT_ACT = FP1", "which changes $BASE or $TOOL ($BASE set at line 9 of p.src)"),
    (
        "SLIN XP1 WITH $BASE = BASE_DATA[2]",
        "which changes $BASE or $TOOL (SLIN WITH $BASE or $TOOL at line 9 of p.src)",
    ),
    (
        "SPLINE WITH $TOOL = TOOL_DATA[1]",
        "which changes $BASE or $TOOL (SPLINE WITH $BASE or $TOOL at line 9 of p.src)",
    ),
    ("Other()", "which calls Other() (p.src:9), which may change $BASE"),
]


@pytest.mark.parametrize(("statement", "reason"), CHANGES)
def test_a_call_of_a_routine_that_changes_the_frames_leaves_them_unknown(statement, reason):
    src = program("DEF Sub(v :IN)", "REAL v", statement, "END")
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src  # nothing corrected
    assert rows.reason[0] == f"base unknown: after the call Sub() at line 3, {reason}"


def test_a_call_of_a_routine_not_given_or_given_the_frames_leaves_them_unknown():
    src = program()  # Sub is not in the given files
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src
    assert rows.reason[0] == "base unknown: after the call Sub() at line 3, which may change $BASE"
    src = program(*KEEPS).replace("Sub(3)", "Sub($BASE.X)")  # an :OUT parameter could set it
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src
    assert rows.reason[0].endswith("which has $BASE or $TOOL among its arguments")


PING_PONG = [
    "DEF Sub(n :IN)",
    "INT n",
    "IF n > 0 THEN",
    "  Pong(n - 1)",
    "ENDIF",
    "END",
    "",
    "DEF Pong(n :IN)",
    "INT n",
    "Sub(n)",
    "END",
]


def test_routines_that_call_each_other_keep_the_frames_unless_one_changes_them():
    src = program(*PING_PONG)
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)
    changing = program(*PING_PONG[:-1], "BAS (#BASE, 2)", "END")
    texts, rows = rewritten({"p.src": changing})
    assert texts["p.src"] == changing
    assert rows.reason[0] == (
        "base unknown: after the call Sub() at line 3, which calls Pong() (p.src:10), which "
        "changes $BASE or $TOOL"
    )


def test_a_routine_of_another_module_is_found_when_other_modules_can_call_it():
    """A GLOBAL routine or a module's main routine (its first) of another given file; not a
    local routine of another module, nor a name two other modules define."""
    src = program()
    lib = "\r\n".join(["DEF lib( )", "END", "", "GLOBAL DEF Sub(v :IN)", "REAL v", "END", ""])
    texts, _ = rewritten({"p.src": src, "lib.src": lib})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)
    main = "\r\n".join(["DEF Sub(v :IN)", "REAL v", "END", ""])  # module Sub's main routine
    texts, _ = rewritten({"p.src": src, "Sub.src": main})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)
    local = lib.replace("GLOBAL DEF", "DEF")
    texts, rows = rewritten({"p.src": src, "lib.src": local})
    assert texts["p.src"] == src
    assert rows.reason[0].endswith("which may change $BASE")
    texts, rows = rewritten({"p.src": src, "lib.src": lib, "Sub.src": main})
    assert texts["p.src"] == src
    assert rows.reason[0].endswith(
        "is defined in more than one of the given files (lib.src, Sub.src)"
    )


# KUKA's inline form of a PTP to P1 (KSS 8.3): the controller writes SET_CD_PARAMS (0) between
# BAS(#PTP_PARAMS, ..), which sets $BASE and $TOOL from FDAT_ACT, and the motion
FORM = [
    "DEF p( )",
    ";FOLD PTP P1 Vel=100 % PDAT1 Tool[1] Base[2] ;%{PE}",
    ";FOLD Parameters ;%{h}",
    ";Params IlfProvider=kukaroboter.basistech.inlineforms.movement.old; Kuka.PointName=P1",
    ";ENDFOLD",
    "$BWDSTART = FALSE",
    "PDAT_ACT = PPDAT1",
    "FDAT_ACT = FP1",
    "BAS(#PTP_PARAMS, 100.0)",
    "SET_CD_PARAMS (0)",
    "PTP XP1",
    ";ENDFOLD",
    "END",
]
XP1 = "DECL E6POS XP1={X 100.000,Y 50.000,Z 200.000,A 0.000,B 90.000,C 0.000,S 6,T 27}"
XP1_CORRECTED = "DECL E6POS XP1={X 100.154,Y 49.767,Z 200.375,A 0.000,B 90.000,C 0.000,S 6,T 27}"
DAT = [
    "DEFDAT p",
    XP1,
    'DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " "}',
    "DECL PDAT PPDAT1={VEL 100.000,ACC 100.000,APO_DIST 100.000}",
    "ENDDAT",
]


def lines(*given: str) -> str:
    return "\n".join(given) + "\n"


def test_an_inline_form_moves_in_its_own_fdat_past_the_controllers_call():
    dat = lines(*DAT)
    texts, rows = rewritten({"p.src": lines(*FORM), "p.dat": dat})
    assert texts["p.dat"] == dat.replace(XP1, XP1_CORRECTED)
    assert texts["p.src"] == lines(*FORM)
    assert rows.status.tolist() == [CORRECTED]


@pytest.mark.parametrize(
    ("change", "call", "motion"),
    [
        # the form's FDAT is set but not applied (no BAS(#PTP_PARAMS, ..)) before the call
        ({"BAS(#PTP_PARAMS, 100.0)": "BAS(#PTP_DAT)"}, "SET_CD_PARAMS() at line 10", 11),
        # FDAT_ACT names another point's FDAT than the form's
        ({"FDAT_ACT = FP1": "FDAT_ACT = FP2"}, "SET_CD_PARAMS() at line 10", 11),
        # the call is outside the form: a routine not given, after its ;ENDFOLD
        (
            {"SET_CD_PARAMS (0)": ";ENDFOLD\nSET_CD_PARAMS (0)", ";ENDFOLD\nEND": "END"},
            "SET_CD_PARAMS() at line 11",
            12,
        ),
    ],
)
def test_a_call_outside_an_applied_inline_form_leaves_the_frames_unknown(change, call, motion):
    src = lines(*FORM)
    for old, new in change.items():
        assert old in src
        src = src.replace(old, new)
    dat = lines(*DAT, "DECL FDAT FP2={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE}")
    texts, rows = rewritten({"p.src": src, "p.dat": dat})
    assert texts["p.dat"] == dat
    assert rows.reason[0] == (
        f"used at line {motion} where the base unknown: after the call {call}, which may change "
        "$BASE"
    )


SHIFT = ["DEFFCT INT Shift(k :IN)", "INT k", "$BASE = BASE_DATA[k]", "RETURN k", "ENDFCT"]


def test_a_function_of_the_given_files_called_in_an_expression_is_followed():
    """A function that changes $BASE leaves it unknown after the statement that calls it, and
    makes a routine that calls it one that changes it; a built-in function (not in the given
    files) changes nothing."""
    src = "\r\n".join(["DEF p( )", "BAS (#BASE,0)", "n = Shift(2)", LIN, "END", "", *SHIFT, ""])
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src
    assert rows.reason[0] == (
        "base unknown: after the call Shift() at line 3, which changes $BASE or $TOOL ($BASE set "
        "at line 9 of p.src)"
    )
    src = program("DEF Sub(v :IN)", "REAL v", "IF Shift(2) > 0 THEN", "ENDIF", "END", "", *SHIFT)
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src
    assert rows.reason[0] == (
        "base unknown: after the call Sub() at line 3, which calls Shift() (p.src:9), which "
        "changes $BASE or $TOOL"
    )
    pure = [*SHIFT[:2], "k = k * 2 + SIN(30)", *SHIFT[3:]]
    src = program("DEF Sub(v :IN)", "REAL v", "v = Shift(2)", "END", "", *pure)
    texts, _ = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)


def test_initmov_sets_the_world_base_and_tool_1():
    """KUKA's BAS(#INITMOV, 0) (BAS.SRC INITMOV: base corrections off, BASE(0), $TOOL =
    TOOL_DATA[1]): a motion after it is in base 0, not in the BASE_DATA[2] set before."""
    src = "\r\n".join(["DEF p( )", "BAS (#BASE,2)", "BAS (#INITMOV,0 )", LIN, "END", ""])
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(LIN, LIN_CORRECTED)
    assert rows.status.tolist() == [CORRECTED]


IN_BASE_2 = "LIN {X 100.000,Y 50.000,Z 200.000,A 0.000,B 90.000,C 0.000}"
IN_BASE_2_CORRECTED = "LIN {X 100.154,Y 49.767,Z 200.375,A 0.000,B 90.000,C 0.000}"


def local_routine(*main: str, drill: str = "DEF Drill( )", more=()) -> str:
    return "\r\n".join(["DEF p( )", *main, "END", "", drill, IN_BASE_2, "END", *more, ""])


def test_a_local_routine_starts_in_the_base_of_every_call_of_it():
    """Drill (neither GLOBAL nor the module's main routine) runs only where p calls it."""
    src = local_routine("BAS (#BASE,2)", "Drill()", "Drill()")
    texts, _ = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(IN_BASE_2, IN_BASE_2_CORRECTED)
    # through another local routine that keeps the base: found one round later
    src = local_routine("BAS (#BASE,2)", "Pass()", more=["", "DEF Pass( )", "Drill()", "END"])
    texts, _ = rewritten({"p.src": src})
    assert texts["p.src"] == src.replace(IN_BASE_2, IN_BASE_2_CORRECTED)


@pytest.mark.parametrize(
    ("main", "drill"),
    [
        (["BAS (#BASE,2)", "Drill()", "BAS (#BASE,0)", "Drill()"], "DEF Drill( )"),  # two bases
        (["BAS (#BASE,2)", "Drill()", "BAS (#TOOL,2)", "Drill()"], "DEF Drill( )"),  # two tools
        (["Drill()"], "DEF Drill( )"),  # p's own base is its caller's
        (["BAS (#BASE,2)", "Drill()"], "GLOBAL DEF Drill( )"),  # other modules may call it
        # a trigger runs it wherever the robot is
        (["BAS (#BASE,2)", "Drill()", "TRIGGER WHEN DISTANCE=0 DELAY=0 DO Drill() PRIO=-1"], ""),
    ],
)
def test_a_routine_whose_calls_do_not_tell_its_base_starts_in_its_callers(main, drill):
    src = local_routine(*main, drill=drill or "DEF Drill( )")
    texts, rows = rewritten({"p.src": src})
    assert texts["p.src"] == src
    line = src.split("\r\n").index("DEF Drill( )" if not drill else drill) + 1
    assert rows.reason[0] == (
        f"base unknown: start of routine Drill (line {line}): $BASE is inherited from the caller "
        "(--base N states it)"
    )


def test_a_local_routine_starts_in_its_calls_base_with_trust_calls_too():
    """--trust-calls: the call of a routine not given keeps the base the local routine's call
    then has."""
    src = local_routine("BAS (#BASE,2)", "Other()", "Drill()")
    trusted = KrlPlacement(BASE_DATA, trust_calls=True)
    texts = rewrite(plugin_of("krl"), {"p.src": src}, OPTS, trusted).texts
    assert texts["p.src"] == src.replace(IN_BASE_2, IN_BASE_2_CORRECTED)
    texts, rows = rewritten({"p.src": src})  # without: Other() may change it
    assert texts["p.src"] == src and "start of routine Drill" in rows.reason[0]
