"""KRL relative motions (LIN_REL, PTP_REL, CIRC_REL, ... in #BASE or #TOOL) in a rewrite: each
lands where an absolute program's corrected position would; a start that is not known is
reported, never guessed.

Expected values: the absolute position a relative motion reaches is worked out here from the
program text (start + increment, or start + R_start @ increment with #TOOL, R from scipy),
corrected with the grid model itself (``GridModel.correct``, not the rewrite), and the rewritten
increments are read back with this test's own reading of the aggregate.
"""

from __future__ import annotations

import csv
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import error_field, rewrite_krl, write_cell
from scipy.spatial.transform import Rotation

from accugrid.app.cli import main
from accugrid.codegen.plugin_types import Options
from accugrid.compensation import GridModel

HALF = 0.5e-3 * np.sqrt(3) + 1e-9  # 3 decimals, each axis off by at most half a unit
BASE2 = (300.0, -200.0, 100.0, 30.0, 0.0, 0.0)  # robot_T_base of BASE_DATA[2]
AGG = re.compile(r"\{([^}]*)\}")


def _rewrite(tmp_path, src: str, dat: str | None = None, *more):
    """Rewrite ``src`` (and ``dat``) with the smooth-field cell; (exit code, output .src text,
    report rows, the grid model)."""
    cell = write_cell(tmp_path, field="smooth", base_data={2: BASE2})
    (tmp_path / "p.src").write_text(src)
    inputs = [tmp_path / "p.src"]
    if dat is not None:
        (tmp_path / "p.dat").write_text(dat)
        inputs.append(tmp_path / "p.dat")
    out = tmp_path / "out"
    target = out if dat is not None else out / "p.src"
    report = tmp_path / "r.csv"
    args = [*map(str, inputs), "--cell", str(cell), "-o", str(target), "--report", str(report)]
    code = main(["rewrite", *args, *more])
    text = (out / "p.src").read_text() if code == 0 else ""
    rows = list(csv.DictReader(report.open())) if code == 0 else []
    return code, text, rows, GridModel.from_measurements(tmp_path / "grid.csv")


def components(line: str, which: int = 0) -> dict[str, float]:
    """The components of the ``which``-th aggregate of a line (this test's own reading)."""
    body = AGG.findall(line)[which]
    body = body.split(":", 1)[1] if ":" in body else body
    return {k.upper(): float(v) for k, v in (p.split() for p in body.split(","))}


def xyz(line: str, which: int = 0) -> np.ndarray:
    """X, Y, Z of an aggregate, a component not given being 0."""
    found = components(line, which)
    return np.array([found.get(k, 0.0) for k in "XYZ"])


def corrected_in(model: GridModel, base, points) -> np.ndarray:
    """Corrected positions (N, 3) in the base frame ``base`` (x, y, z, a, b, c) of points given
    in it."""
    rotation = Rotation.from_euler("ZYX", base[3:], degrees=True).as_matrix()
    robot = np.asarray(points, float) @ rotation.T + base[:3]
    return (model.correct(robot) - base[:3]) @ rotation


def rounded(values) -> np.ndarray:
    return np.round(np.asarray(values, float), 3)


def assert_chain_lands(lines: list[str], want: np.ndarray) -> None:
    """``lines``: an absolute aggregate, then #BASE relative ones; ``want`` (n, 3): where each
    must land. The start is written rounded; walking the increments reaches each within the
    rounding of one increment (a chain re-starts from where the motion before lands)."""
    reached = xyz(lines[0])
    np.testing.assert_allclose(reached, rounded(want[0]), atol=1e-9)
    for line, goal in zip(lines[1:], want[1:], strict=True):
        reached = reached + xyz(line)
        assert np.linalg.norm(reached - goal) <= HALF


CHAINS = {
    # LIN_REL {Z -50} after a corrected LIN, then LIN_REL {X 10, Y 5} (its own ", " kept)
    "after_an_absolute_motion": (
        "DEF p( )\nBAS (#BASE,2)\n"
        "LIN {X 1000.000,Y 100.000,Z 800.000,A 0.0,B 90.0,C 0.0}\n"
        "LIN_REL {Z -50.000}\n"
        "LIN_REL {X 10, Y 5} C_DIS\n"
        "END\n",
        [[1000, 100, 800], [1000, 100, 750], [1010, 105, 750]],
    ),
    # SLIN_REL segments of a SPLINE block in the block's base (2), each from the one before
    "segments_of_a_spline_block": (
        "DEF p( )\nBAS (#BASE,0)\nSPLINE WITH $BASE = BASE_DATA[2]\n"
        "SLIN {X 800.000,Y 300.000,Z 700.000,A 0.0,B 90.0,C 0.0}\n"
        "SLIN_REL {X 30.000}\n"
        "SLIN_REL {Y -15.000,Z 5.000}\n"
        "ENDSPLINE\nEND\n",
        [[800, 300, 700], [830, 300, 700], [830, 285, 705]],
    ),
}


@pytest.mark.parametrize("case", sorted(CHAINS))
def test_base_relative_chain_lands_on_the_corrected_absolute_positions(tmp_path, case):
    """Each increment is the difference of corrected positions; a component the aggregate does
    not give is added (``{X .., Y .., Z -49.9..}``)."""
    src, nominal = CHAINS[case]
    code, text, rows, model = _rewrite(tmp_path, src)
    assert code == 0 and [r["status"] for r in rows] == ["corrected"] * 3
    lines = [ln for ln in text.splitlines() if "{" in ln]
    assert_chain_lands(lines, corrected_in(model, BASE2, nominal))
    np.testing.assert_allclose([float(rows[2][k]) for k in ("x", "y", "z")], nominal[2])
    changed = np.abs(xyz(lines[1]) - np.subtract(nominal[1], nominal[0]))
    assert changed.max() > 0.5e-3  # the field varies: the increment is not the programmed one
    if case == "after_an_absolute_motion":  # X and Y added to {Z -50.000}; ", " kept
        assert set(components(lines[1])) == {"X", "Y", "Z"} and "{X " in lines[1]
        assert ", Y " in lines[2] and lines[2].endswith("} C_DIS")


def test_tool_relative_motion_is_in_the_tool_frame_of_its_start(tmp_path):
    """#TOOL: the increment is in the tool frame at the start (A 20, B 70, C 10 in base 2)."""
    abc = (20.0, 70.0, 10.0)
    src = (
        "DEF p( )\nBAS (#BASE,2)\n"
        f"PTP {{X 900.000,Y -50.000,Z 700.000,A {abc[0]},B {abc[1]},C {abc[2]}}}\n"
        "PTP_REL {Y 4.000,Z 30.000} #TOOL\n"
        "END\n"
    )
    code, text, rows, model = _rewrite(tmp_path, src)
    assert code == 0
    tool = Rotation.from_euler("ZYX", abc, degrees=True).as_matrix()
    start = np.array([900.0, -50.0, 700.0])
    target = start + tool @ [0.0, 4.0, 30.0]
    want = corrected_in(model, BASE2, [start, target])
    lines = text.splitlines()
    written = xyz(lines[2])
    np.testing.assert_allclose(written + tool @ xyz(lines[3]), want[1], atol=HALF * 1.5)
    np.testing.assert_allclose([float(rows[1][k]) for k in ("x", "y", "z")], target, atol=1e-4)


def test_circ_rel_points_are_both_relative_to_the_start(tmp_path):
    src = (
        "DEF p( )\nBAS (#BASE,0)\n"
        "LIN {X 1500.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "CIRC_REL {X 20.000,Y 20.000}, {X 40.000,Y 0.000,Z 0.000}\n"
        "LIN_REL {Z 10.000}\n"
        "END\n"
    )
    code, text, rows, model = _rewrite(tmp_path, src)
    assert code == 0
    start = np.array([1500.0, 0.0, 1000.0])
    nominal = [start, start + [20, 20, 0], start + [40, 0, 0], start + [40, 0, 10]]
    want = corrected_in(model, (0,) * 6, nominal)
    lines = text.splitlines()
    written = xyz(lines[2])
    aux, end = xyz(lines[3], 0), xyz(lines[3], 1)
    np.testing.assert_allclose(written + aux, want[1], atol=HALF)
    np.testing.assert_allclose(written + end, want[2], atol=HALF)
    np.testing.assert_allclose(written + end + xyz(lines[4]), want[3], atol=2 * HALF)
    assert [r["status"] for r in rows] == ["corrected"] * 4


def test_named_start_from_the_dat(tmp_path):
    """PTP XP1 (declared in the .dat) then LIN_REL: the start is XP1 as corrected."""
    src = "DEF p( )\nBAS (#BASE,0)\nPTP XP1\nLIN_REL {Z -20.000}\nEND\n"
    dat = "DEFDAT p\nDECL E6POS XP1={X 1400.000,Y 200.000,Z 900.000,A 0.0,B 90.0,C 0.0}\nENDDAT\n"
    code, text, rows, model = _rewrite(tmp_path, src, dat)
    assert code == 0
    want = corrected_in(model, (0,) * 6, [[1400, 200, 900], [1400, 200, 880]])
    written = xyz((tmp_path / "out" / "p.dat").read_text().splitlines()[1])
    np.testing.assert_allclose(written, rounded(want[0]), atol=1e-9)
    np.testing.assert_allclose(written + xyz(text.splitlines()[3]), want[1], atol=HALF)


def test_relative_motion_left_uncorrected_lands_as_programmed(tmp_path):
    """The start is corrected, the relative target is outside the grid (x > 2500): with
    --allow-partial it is left uncorrected, and its increment changes so that it still lands
    where the program put it, not dragged by the start's correction."""
    src = (
        "DEF p( )\nBAS (#BASE,0)\n"
        "LIN {X 2400.000,Y 0.000,Z 1000.000,A 0.0,B 90.0,C 0.0}\n"
        "LIN_REL {X 200.000}\n"
        "END\n"
    )
    code, text, rows, _ = _rewrite(tmp_path, src, None, "--allow-partial", "--outside", "refuse")
    assert code == 0
    assert [r["status"] for r in rows][0] == "corrected" and rows[1]["status"] != "corrected"
    lines = text.splitlines()
    np.testing.assert_allclose(xyz(lines[2]) + xyz(lines[3]), [2600, 0, 1000], atol=HALF)


@pytest.mark.parametrize(
    "before, why",
    [
        ("", "no motion before it"),
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nIF $IN[1] THEN\n", "IF at line 4"),
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nGO( )\n", "the call GO() at line 4"),
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nM1:\n", "jump target M1"),
        # the cell's tool (TOOL_DATA[1]): the only reason is the chain broken by setting it
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\n$TOOL = TOOL_DATA[1]\n", "the tool set at line 4"),
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nBAS (#BASE,2)\n", "$BASE set at line 4"),
        ("LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nFOR I=1 TO 20\n", "FOR at line 4"),
        ("LIN P9\n", "P9 (line 3) is not known: it is not a position given in these files"),
        ("LIN XP[I]\n", "XP[I] (line 3) is not known: its index is a variable"),
        ("LIN {X 1000,Y 0,Z 900}\n", "#TOOL: the orientation at its start (LIN at p.src:3)"),
        ("LIN {X 1000,Y 0}\n", "partial aggregate"),
        ("LIN $POS_ACT\n", "system variable $POS_ACT"),
        ("PTP {A1 0,A2 -90,A3 90,A4 0,A5 0,A6 0}\n", "joint-space target"),
        (
            "LIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\nSPLINE WITH $BASE = BASE_DATA[2]\n"
            "SLIN {X 1,Y 2,Z 3}\nENDSPLINE\n",
            "its start (SLIN at p.src:5) is in another base",
        ),
    ],
)
def test_relative_motion_whose_start_is_not_known_is_reported(tmp_path, capsys, before, why):
    """Reported with the reason; the job fails without --allow-partial (a partial program)."""
    src = f"DEF p( )\nBAS (#BASE,0)\n{before}LIN_REL {{Z -5.000}} #TOOL\nEND\n"
    code, *_ = _rewrite(tmp_path, src)
    assert code == 2
    assert why in capsys.readouterr().err
    code, text, rows, _ = _rewrite(tmp_path, src, None, "--allow-partial")
    assert code == 0 and text.splitlines()[-2] == src.splitlines()[-2]
    row = next(r for r in rows if r["name"] == "LIN_REL")
    assert row["status"] == "skipped" and why in row["reason"]


def test_kss8_inline_form_start_and_settings_between(tmp_path):
    """Forms real programs write: the KSS 8 inline form (SPTP XP1 WITH ..., $TOOL =
    STOOL2(FP1), $BASE = SBASE(FP1.BASE_NO), ...), a relative spline motion with its own WITH
    $BASE, and $VEL/$APO assignments, a TRIGGER and a WAIT between a start and a LIN_REL, which
    do not move the robot."""
    src = (
        "DEF p( )\nBAS (#BASE,2)\n"
        "SPTP XP1 WITH $VEL_AXIS[1] = SVEL_JOINT(100.0), $TOOL = STOOL2(FP1), "
        "$BASE = SBASE(FP1.BASE_NO), $IPO_MODE = SIPO_MODE(FP1.IPO_FRAME), "
        "$LOAD = SLOAD(FP1.TOOL_NO)\n"
        "SLIN_REL {Z -25.000} WITH $BASE = SBASE(FP1.BASE_NO)\n"
        "$VEL.CP=0.3\n$APO.CDIS=10.0\nTRIGGER WHEN PATH=-20 DELAY=0 DO SUCK() PRIO=-1\n"
        "WAIT SEC 0\n"
        "LIN_REL {X 12.000} C_DIS\n"
        "END\n"
    )
    dat = (
        "DEFDAT p\n"
        'DECL FDAT FP1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " "}\n'
        "DECL E6POS XP1={X 1100.000,Y 300.000,Z 850.000,A 0.0,B 90.0,C 0.0,S 2,T 0,E1 0.0}\n"
        "ENDDAT\n"
    )
    code, text, rows, model = _rewrite(tmp_path, src, dat)
    assert code == 0
    nominal = np.array([[1100, 300, 850], [1100, 300, 825], [1112, 300, 825]], float)
    want = corrected_in(model, BASE2, nominal)
    written = xyz((tmp_path / "out" / "p.dat").read_text().splitlines()[2])
    lines = text.splitlines()
    np.testing.assert_allclose(written + xyz(lines[3]), want[1], atol=HALF)
    np.testing.assert_allclose(written + xyz(lines[3]) + xyz(lines[8]), want[2], atol=2 * HALF)
    assert lines[3].endswith("} WITH $BASE = SBASE(FP1.BASE_NO)")
    assert lines[8].endswith("} C_DIS")
    assert all(r["status"] == "corrected" for r in rows)


def _field_grid() -> GridModel:
    axes = [np.arange(600.0, 1401.0, 100.0)] * 3
    points = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return GridModel.from_measurements((points, points - error_field(points, "smooth")))


FIELD = _field_grid()
_MM = st.integers(-40_000, 40_000).map(lambda k: k / 1000)  # an increment, mm, 3 decimals
_STEP = st.tuples(
    st.booleans(),  # #TOOL
    st.lists(st.sampled_from("XYZ"), min_size=1, max_size=3, unique=True),
    st.tuples(_MM, _MM, _MM),
)


@settings(max_examples=40, deadline=None)
@given(
    start=st.tuples(*[st.integers(900_000, 1_100_000).map(lambda k: k / 1000)] * 3),
    abc=st.tuples(*[st.integers(-180, 180)] * 3),
    steps=st.lists(_STEP, min_size=1, max_size=6),
)
def test_every_point_of_a_relative_chain_lands_on_its_correction(start, abc, steps):
    """A start and a chain of LIN_REL (#BASE or #TOOL, some of X, Y, Z given) in the robot
    frame: after the rewrite, walking the written increments from the written start reaches
    each point's correction (the grid model's, worked out here) within the rounding of one
    increment: the rounding does not add up along the chain."""
    tool = Rotation.from_euler("ZYX", abc, degrees=True).as_matrix()
    lines = [
        "DEF p( )",
        "BAS (#BASE,0)",
        "LIN {{X {:.3f},Y {:.3f},Z {:.3f},A {},B {},C {}}}".format(*start, *abc),
    ]
    nominal = [np.array(start)]
    for in_tool, keys, values in steps:
        given_xyz = dict(zip("XYZ", values, strict=True))
        body = ",".join(f"{k} {given_xyz[k]:.3f}" for k in "XYZ" if k in keys)
        lines.append(f"LIN_REL {{{body}}}" + (" #TOOL" if in_tool else ""))
        increment = np.array([given_xyz[k] if k in keys else 0.0 for k in "XYZ"])
        nominal.append(nominal[-1] + (tool if in_tool else np.eye(3)) @ increment)
    text = "\n".join([*lines, "END", ""])
    opts = Options(model=FIELD, decimals=3)
    result = rewrite_krl({"p.src": text}, opts)
    assert (result.rows.status == 1).all()  # every point corrected
    want = FIELD.correct(np.array(nominal))
    out = result.texts["p.src"].splitlines()
    reached = xyz(out[2])
    np.testing.assert_allclose(reached, rounded(want[0]), atol=1e-9)
    for k, (in_tool, _, _) in enumerate(steps, start=1):
        reached = reached + (tool if in_tool else np.eye(3)) @ xyz(out[2 + k])
        assert np.linalg.norm(reached - want[k]) <= HALF


def test_relative_motion_that_sets_its_own_tool_is_reported(tmp_path):
    src = (
        "DEF p( )\nBAS (#BASE,0)\nLIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\n"
        "SLIN_REL {Z -5.000} WITH $TOOL = TOOL_DATA[1]\nEND\n"
    )  # the cell's tool: the reason is the relative motion's own (another tool: the tool's)
    code, text, rows, _ = _rewrite(tmp_path, src, None, "--allow-partial")
    assert code == 0 and text.splitlines()[3] == src.splitlines()[3]
    assert "it sets its own tool (WITH $TOOL, line 4)" in rows[1]["reason"]


def test_relative_motion_with_an_external_axis_is_reported(tmp_path):
    """LIN_REL {Z 10, E1 360}: the external axis moves with it, so where the TCP lands in the
    robot frame depends on the external kinematics: reported, not corrected."""
    src = (
        "DEF p( )\nBAS (#BASE,0)\nLIN {X 1000,Y 0,Z 900,A 0,B 90,C 0}\n"
        "LIN_REL {Z 10, E1 360} C_DIS\nEND\n"
    )
    code, text, rows, _ = _rewrite(tmp_path, src, None, "--allow-partial")
    assert code == 0 and text.splitlines()[3] == src.splitlines()[3]
    assert rows[1]["status"] == "skipped" and "external axis E1 = 360" in rows[1]["reason"]
