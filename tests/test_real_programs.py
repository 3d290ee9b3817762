"""Constructs of real CAM and controller programs that used to put holes in the wrong place, each
on its own minimal program: KSS 8 spline blocks with their own base, incremental (G91) canned
cycles, modal canned cycles that change depth, a dwell and a move on one line, a full circle.

Expected values come from the frame maths (a constant error field e = E_CONST: a corrected
position in a frame with rotation R is p + R^T e) and, for G-code, from LinuxCNC's ``rs274``
where it is installed; never from the code under test.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rewrite_helpers import E_CONST, error_field, rewrite_gcode, write_cell
from scipy.spatial.transform import Rotation
from test_gcode_rs274 import MOVE_RE, canonical

from accugrid.app.cli import main
from accugrid.codegen.krl.parse import scan_krl
from accugrid.codegen.plugin_types import Options
from accugrid.compensation import GridModel

BASE2 = (100.0, 50.0, 0.0, 90.0, 0.0, 0.0)  # robot_T_base of BASE_DATA[2]
R2 = Rotation.from_euler("ZYX", BASE2[3:], degrees=True).as_matrix()


def rewrite(*args) -> int:
    return main(["rewrite", *map(str, args)])


def report(path) -> list[dict[str, str]]:
    return list(csv.DictReader(open(path, newline="")))


def numbers(line: str) -> list[float]:
    """X, Y, Z of a KRL aggregate line."""
    inner = line[line.index("{") + 1 : line.index("}")]
    parts = dict(p.strip().split(None, 1) for p in inner.split(","))
    return [float(parts[k]) for k in "XYZ"]


# ---------------------------------------------------------------- KSS 8 spline blocks

SPLINE_DAT = (
    "DEFDAT s\n"
    'DECL FDAT FS1={TOOL_NO 1,BASE_NO 2,IPO_FRAME #BASE,POINT2[] " "}\n'
    "DECL E6POS XP1={X 220.000,Y 15.000,Z 40.000,A 0.0,B 90.0,C 0.0,S 6,T 27,E1 0.0}\n"
    "ENDDAT\n"
)


@pytest.mark.parametrize(
    "opening",
    [
        "SPLINE WITH $BASE = BASE_DATA[2]",
        "SPLINE WITH $BASE = SBASE(FS1.BASE_NO), $IPO_MODE = SIPO_MODE(FS1.IPO_FRAME)",
        "PTP_SPLINE WITH $BASE = BASE_DATA[2], $VEL_AXIS[1] = SVEL_JOINT(100.0)",
    ],
)
def test_spline_block_segments_move_in_the_blocks_base(tmp_path, opening):
    """The segments of a spline block are corrected in the block's base (BASE_DATA[2], rotated
    90 deg about Z), not in the base before it (0, the robot frame); after ENDSPLINE base 0
    holds again."""
    cell = write_cell(tmp_path, field="constant", base_data={2: BASE2})
    segment = "SPTP" if opening.startswith("PTP") else "SLIN"
    src = tmp_path / "s.src"
    lines = [
        "DEF s( )",
        "BAS (#BASE,0)",
        opening,
        f"  {segment} {{X 200.000,Y 0.000,Z 50.000,A 0.0,B 90.0,C 0.0}}",
        f"  {segment} XP1",
        "ENDSPLINE",
        "LIN {X 300.000,Y 0.000,Z 500.000,A 0.0,B 90.0,C 0.0}",
        "END",
    ]
    src.write_text("\n".join(lines) + "\n")
    (tmp_path / "s.dat").write_text(SPLINE_DAT)
    out = tmp_path / "out"
    assert (
        rewrite(src, tmp_path / "s.dat", "--cell", cell, "-o", out, "--report", tmp_path / "r.csv")
        == 0
    )
    new = (out / "s.src").read_text().splitlines()
    in_base2 = R2.T @ E_CONST  # the constant robot-frame error seen in base 2
    np.testing.assert_allclose(numbers(new[3]), [200.0, 0.0, 50.0] + in_base2, atol=6e-4)
    np.testing.assert_allclose(numbers(new[6]), [300.0, 0.0, 500.0] + E_CONST, atol=6e-4)
    xp1 = next(li for li in (out / "s.dat").read_text().splitlines() if "XP1=" in li)
    np.testing.assert_allclose(numbers(xp1), [220.0, 15.0, 40.0] + in_base2, atol=6e-4)
    assert all(row["status"] == "corrected" for row in report(tmp_path / "r.csv"))


def test_spline_block_whose_base_is_not_known_is_reported(tmp_path):
    cell = write_cell(tmp_path, field="constant")
    src = tmp_path / "u.src"
    text = (
        "DEF u( )\nBAS (#BASE,0)\nSPLINE WITH $BASE = lbase\n"
        "  SLIN {X 200.000,Y 0.000,Z 50.000,A 0.0,B 90.0,C 0.0}\n"
        "  SPL {X 210.000,Y 5.000,Z 50.000,A 0.0,B 90.0,C 0.0}\nENDSPLINE\n"
        "LIN {X 300.000,Y 0.000,Z 500.000,A 0.0,B 90.0,C 0.0}\nEND\n"
    )
    src.write_text(text)
    out = tmp_path / "u_out.src"
    argv = [src, "--cell", cell, "-o", out, "--report", tmp_path / "r.csv"]
    assert rewrite(*argv) == 2  # its two motions would land off: not a partial program silently
    assert not out.exists()
    assert rewrite(*argv, "--allow-partial") == 0
    rows = report(tmp_path / "r.csv")
    assert [(r["line"], r["status"]) for r in rows] == [
        ("4", "skipped"),
        ("5", "skipped"),
        ("7", "corrected"),
    ]
    for row in rows[:2]:
        assert "SPLINE block at line 3" in row["reason"] and "lbase" in row["reason"]
    assert out.read_text().splitlines()[:6] == text.splitlines()[:6]


def test_spline_block_base_is_the_same_in_every_reading_lane():
    """The whole-text reader (rigid lines between statements) and the line-by-line reader
    (lone CR line endings) give every segment the block's base."""
    lines = [
        "DEF s( )",
        "BAS (#BASE,0)",
        "SPLINE WITH $BASE = BASE_DATA[2]",
        "SLIN XP1",  # the rigid layout
        "SLIN  {X 1.0, Y 2.0, Z 3.0}",  # the statement reader, plain
        "SCIRC {X 1.0,Y 2.0,Z 3.0}, {X 2.0,Y 3.0,Z 3.0}",  # the statement reader
        "ENDSPLINE",
        "SLIN XP1",
        "END",
    ]
    for sep in ("\n", "\r\n", "\r"):
        scan = scan_krl(sep.join(lines) + sep, "s.src")
        bases = [(p.line, p.base.number) for p in scan.positions]
        bases += [(u.line, u.base.number) for u in scan.uses]
        assert sorted(bases) == [(4, 2), (5, 2), (6, 2), (6, 2), (8, 0)], sep


# ---------------------------------------------------------------- G-code: incremental cycles

PROGRAM_ABC = (500.0, -200.0, 100.0, 0.0, 180.0, 0.0)  # robot_T_program: Z down, X reversed
T_PROGRAM = np.eye(4)
T_PROGRAM[:3, :3] = Rotation.from_euler("ZYX", PROGRAM_ABC[3:], degrees=True).as_matrix()
T_PROGRAM[:3, 3] = PROGRAM_ABC[:3]


def _grid(field: str) -> GridModel:
    axes = [np.arange(-600.0, 601.0, 100.0)] * 3
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return GridModel.from_measurements((pts, pts - error_field(pts, field)))


SMOOTH, CONSTANT = _grid("smooth"), _grid("constant")


def corrected(model: GridModel, program_xyz) -> np.ndarray:
    """Where a program-frame point (N, 3) must be commanded: p + R^T e(T p), e from the grid."""
    p = np.atleast_2d(np.asarray(program_xyz, float))
    robot = p @ T_PROGRAM[:3, :3].T + T_PROGRAM[:3, 3]
    return p + (model.correct(robot) - robot) @ T_PROGRAM[:3, :3]


def gcode_rewrite(text: str, model: GridModel):
    """The rewritten text and its report rows; positions left uncorrected are kept and reported
    (allow_partial: these tests look at each position's outcome)."""
    opts = Options(model=model, decimals=3, allow_partial=True)
    result = rewrite_gcode("p.ngc", text, opts, T_PROGRAM)
    return result.texts["p.ngc"], list(result.rows)


def holes(moves: np.ndarray, out: str) -> tuple[np.ndarray, np.ndarray]:
    """The hole bottoms (STRAIGHT_FEED ends) of rs274's G81 expansion, and the R plane each
    feed starts from (the traverse before it)."""
    kinds = [m.group(1) for m in MOVE_RE.finditer(out)]
    feeds = np.array([i for i, kind in enumerate(kinds) if kind == "STRAIGHT_FEED"], np.int64)
    return moves[feeds, :3], moves[feeds - 1, :3]


HALF = 0.5e-3 + 1e-9  # half the last written decimal (3 decimals), mm per axis


def test_incremental_cycle_holes_land_on_their_corrections(rs274, tmp_path):
    """G91 G81: X, Y from where the tool is, R from its Z, Z from R. Each hole (and R plane) is
    corrected as the absolute point it reaches and written back as differences of corrected
    positions: rs274's holes are the independently corrected ones, not dragged."""
    text = (
        "G21 G90 G17 G98 F100\n"
        "G0 X250 Y0 Z50\n"
        "G91 G81 X25 Y25 Z-50 R-25\n"
        "X25 Y-10 Z-40 R-20\n"
        "G80\n"
        "G91 G0 X-10 Y5\n"
        "G90 G0 Z100\n"
        "M2\n"
    )
    nominal_holes = np.array([[275.0, 25.0, -25.0], [300.0, 15.0, -10.0]])
    nominal_r = np.array([[275.0, 25.0, 25.0], [300.0, 15.0, 30.0]])
    moves, out = canonical(rs274, tmp_path, text)
    np.testing.assert_allclose(holes(moves, out)[0], nominal_holes)  # as read here
    np.testing.assert_allclose(holes(moves, out)[1], nominal_r)
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 5
    moves, out = canonical(rs274, tmp_path, new)
    bottoms, r_planes = holes(moves, out)
    np.testing.assert_allclose(bottoms, corrected(SMOOTH, nominal_holes), atol=HALF)
    want_r = corrected(SMOOTH, nominal_r)[:, 2]  # only the Z of the R point can be written
    np.testing.assert_allclose(r_planes[:, 2], want_r, atol=HALF)
    # the G91 move after the cycles lands on its own correction too (X, Y it writes)
    after = corrected(SMOOTH, [[290.0, 20.0, 50.0]])[0]
    np.testing.assert_allclose(moves[-2, :2], after[:2], atol=HALF)
    assert np.abs(bottoms - nominal_holes).max() > 0.01  # the field moves them measurably


def test_incremental_cycle_continuation_lines_get_their_own_r_and_z(rs274, tmp_path):
    """G91 continuation lines that write only X, Y: each hole's R (from the tool's Z) and Z
    (from R) words are added where they differ from those in effect."""
    text = (
        "G21 G90 G17 G98 F100\nG0 X250 Y0 Z50\nG91 G81 X25 Y25 Z-50 R-25\nX25 Y-10\n"
        "X-5 Y40\nG80\nM2\n"
    )
    xy = np.array([[275.0, 25.0], [300.0, 15.0], [295.0, 55.0]])
    nominal_holes = np.column_stack([xy, np.full(3, -25.0)])
    nominal_r = np.column_stack([xy, np.full(3, 25.0)])
    np.testing.assert_allclose(holes(*canonical(rs274, tmp_path, text))[0], nominal_holes)
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 4
    assert " R-" in new.splitlines()[3]  # added: the line had none
    bottoms, r_planes = holes(*canonical(rs274, tmp_path, new))
    np.testing.assert_allclose(bottoms, corrected(SMOOTH, nominal_holes), atol=HALF)
    np.testing.assert_allclose(r_planes[:, 2], corrected(SMOOTH, nominal_r)[:, 2], atol=HALF)


def test_repeated_incremental_cycle_is_corrected_or_left_as_programmed(rs274, tmp_path):
    """G91 G81 ... L2 moves by one increment to both holes. Where their corrections are equal
    (a constant field) both land on them; where they differ (a varying field) the block and the
    move that sets its start are reported, and the holes land exactly as programmed."""
    text = "G21 G90 G17 G98 F100\nG0 X250 Y0 Z50\nG91 G81 X25 Y25 Z-50 R-25 L2\nG80\nM2\n"
    nominal = np.array([[275.0, 25.0, -25.0], [300.0, 50.0, -25.0]])
    new, rows = gcode_rewrite(text, CONSTANT)
    assert [r.status for r in rows] == ["corrected", "corrected"]
    bottoms = holes(*canonical(rs274, tmp_path, new))[0]
    np.testing.assert_allclose(bottoms, nominal + T_PROGRAM[:3, :3].T @ E_CONST, atol=HALF)

    text = text.replace("X25 Y25", "X100 Y100")  # 141 mm apart: corrections 0.01 mm apart
    nominal = np.array([[350.0, 100.0, -25.0], [450.0, 200.0, -25.0]])
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["skipped", "skipped"]
    assert "sets the start of the G91 cycle at line 3" in rows[0].reason
    assert "repeated L2" in rows[1].reason and "differ by" in rows[1].reason
    assert new == text
    np.testing.assert_allclose(holes(*canonical(rs274, tmp_path, new))[0], nominal)


def test_incremental_chain_after_an_unknown_position_is_reported(tmp_path):
    """After G28 the position is not known: the G91 cycle and moves after it are reported,
    never guessed, and kept as written."""
    text = "G21 G90 G0 X250 Y0 Z50\nG28\nG91 G81 X25 Y25 Z-50 R-25\nG0 X5\nG90 G0 X10 Y10 Z10\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected", "skipped", "skipped", "skipped", "corrected"]
    assert "not known" in rows[2].reason and "not known" in rows[3].reason
    assert new.splitlines()[1:4] == text.splitlines()[1:4]


def test_incremental_cycle_with_a_repeat_count_not_read_keeps_its_start(tmp_path):
    """A G91 cycle whose L is not read (beyond the repeats checked) is reported, the move that
    sets its start is not corrected (so its holes are where the program puts them) and what
    follows it under G91 is not known."""
    text = (
        "G21 G90 G0 X250 Y0 Z50\nG91 G81 X1 Y1 Z-50 R-25 L1000000000\nG80 G0 X5\n"
        "G90 G0 X10 Y10 Z10\n"
    )
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["skipped", "skipped", "skipped", "corrected"]
    assert "sets the start of the G91 cycle at line 2" in rows[0].reason
    assert "more than 10000 repeats" in rows[1].reason and "not known" in rows[2].reason
    assert new.splitlines()[:3] == text.splitlines()[:3]


@pytest.mark.parametrize("mode", ["G90", "G91"])
def test_cycle_with_a_k_word_is_reported(tmp_path, mode):
    """``G81 ... K2`` (Fanuc and Masso: K repeats the cycle; RS274NGC has no K on G81): its
    holes are not known, so it is reported and kept as written. Under G91 its holes move with
    their start: the move that sets it is not corrected either, and what follows under G91 is
    not known; under G90 the move before it is corrected, as is the absolute move after it."""
    text = f"G21 G90 G17 G98 F100\nG0 X250 Y0 Z50\n{mode} G81 X25 Y25 Z-50 R-25 K2\n"
    text += "G80 G0 X5\nG90 G0 X10 Y10 Z10\nM2\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    incremental = mode == "G91"
    assert [r.status for r in rows] == [
        "skipped" if incremental else "corrected",
        "skipped",
        "skipped" if incremental else "corrected",
        "corrected",
    ]
    assert rows[1].reason.startswith("canned cycle G81 with a K word (line 3)")
    lines, written = new.splitlines(), text.splitlines()
    assert lines[2] == written[2]
    if incremental:
        assert "sets the start of the G91 cycle at line 3" in rows[0].reason
        assert "not known" in rows[2].reason
        assert lines[:4] == written[:4]


# ---------------------------------------------------------------- G-code: modal canned cycles


@pytest.mark.parametrize("cycle", ["G81", "G82 P0.5", "G83 Q2", "G73 Q2"])
def test_each_modal_cycle_hole_gets_its_own_depth_and_r_plane(rs274, tmp_path, cycle):
    """Continuation lines of a canned cycle write X, Y only: each hole keeps the depth and R
    plane in effect. Each one's corrected Z and R are written as words added to its line where
    they differ from those in effect; rs274's expansion puts every hole bottom and R plane on
    its independent correction."""
    text = (
        "G21 G90 G17 G99 F100\n"
        "G0 X0 Y0 Z50\n"
        f"{cycle} X10 Y10 Z-5 R2\n"
        "X150 Y10\n"
        "x150 y150 (lower case, a comment)\n"
        "X300 Y-100 Z-8\n"
        "G80\n"
        "M2\n"
    )
    xy = np.array([[10.0, 10.0], [150.0, 10.0], [150.0, 150.0], [300.0, -100.0]])
    nominal_holes = np.column_stack([xy, [-5.0, -5.0, -5.0, -8.0]])
    nominal_r = np.column_stack([xy, np.full(4, 2.0)])
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected"] * 5
    lines = new.splitlines()
    assert lines[3].startswith("X") and " Z-5.3" in lines[3] and " R1." in lines[3]
    assert " z-5.3" in lines[4] and lines[4].endswith("(lower case, a comment)")
    moves, out = canonical(rs274, tmp_path, new)
    feeds = holes(moves, out)[0]
    # each hole's feeds are near its X, Y; G73/G83 feed in pecks: the deepest is the bottom
    near = [feeds[np.abs(feeds[:, :2] - p).max(axis=1) < 1.0] for p in xy]
    deepest = np.array([f[np.argmin(f[:, 2])] for f in near])
    np.testing.assert_allclose(deepest, corrected(SMOOTH, nominal_holes), atol=HALF)
    assert np.abs(deepest[1:, 2] - deepest[0, 2]).max() > 0.005  # the depths differ per hole
    for k, want in enumerate(corrected(SMOOTH, nominal_r)[:, 2]):
        assert np.isclose(moves[:, 2], want, atol=HALF).any(), f"R plane of hole {k}"
    # the same feeds (a changed R plane may add a traverse to it between holes)
    assert len(holes(*canonical(rs274, tmp_path, text))[0]) == len(feeds)


# ---------------------------------------------------------------- G-code: lines that hid a move


def test_a_dwell_and_a_move_on_one_line_is_a_move(rs274, tmp_path):
    """`G4 P0.1 G0 X100 Y50` dwells, then moves: it gets its report row and correction, and the
    next `G0 Z5` is corrected at (100, 50, 5), not at (0, 0, 5)."""
    text = "G21 G90 G17\nG0 X0 Y0 Z20\nG4 P0.1 G0 X100 Y50\nG0 Z5\nM2\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [(r.line, r.status) for r in rows] == [
        (2, "corrected"),
        (3, "corrected"),
        (4, "corrected"),
    ]
    moves, out = canonical(rs274, tmp_path, new)
    assert "DWELL(0.1000)" in out
    # each line writes its own axes: line 3 X, Y (Z stays where line 2 left it), line 4 Z
    after_dwell = corrected(SMOOTH, [[100.0, 50.0, 20.0]])[0]
    np.testing.assert_allclose(moves[1, :2], after_dwell[:2], atol=HALF)
    want_z = corrected(SMOOTH, [[100.0, 50.0, 5.0]])[0, 2]
    assert abs(moves[2, 2] - want_z) <= HALF
    np.testing.assert_array_equal(moves[2, :2], moves[1, :2])


def test_a_full_circle_without_end_point_words_keeps_its_start(rs274, tmp_path):
    """`G2 I12.5 J0` is a full circle: it gets a report row. In this field its correction varies
    across its 25 mm by more than the written 0.001 mm, so neither it nor the moves that set its
    start are corrected, and rs274 cuts the same circle (where it varies less, the circle moves
    rigidly: tests/test_arcs.py)."""
    text = "G21 G90 G17 F100\nG0 X40 Y10 Z5\nG1 Z-2\nG2 I12.5 J0\nG0 Z10\nG0 X100 Y100\nM2\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [(r.line, r.status) for r in rows] == [
        (2, "skipped"),
        (3, "skipped"),
        (4, "skipped"),
        (5, "corrected"),
        (6, "corrected"),
    ]
    assert "correction varies by" in rows[2].reason
    assert "line 4" in rows[0].reason and "line 4" in rows[1].reason
    assert new.splitlines()[:4] == text.splitlines()[:4]
    arcs = [line for line in canonical(rs274, tmp_path, new)[1].splitlines() if "ARC_FEED" in line]
    before = [
        line for line in canonical(rs274, tmp_path, text)[1].splitlines() if "ARC_FEED" in line
    ]
    assert len(arcs) == 1 and arcs[0].split("ARC_FEED")[1] == before[0].split("ARC_FEED")[1]


def test_a_cycle_hole_left_uncorrected_keeps_its_programmed_depth(rs274, tmp_path):
    """A continuation hole outside the grid is not corrected: it gets back the depth and R
    plane its program gives, not the previous hole's corrected ones."""
    text = "G21 G90 G17 G99 F100\nG0 X0 Y0 Z50\nG81 X10 Y10 Z-5 R2\nX2000 Y0\nG80\nM2\n"
    new, rows = gcode_rewrite(text, SMOOTH)
    assert [r.status for r in rows] == ["corrected", "corrected", "outside"]
    bottoms, r_planes = holes(*canonical(rs274, tmp_path, new))
    np.testing.assert_allclose(bottoms[0], corrected(SMOOTH, [[10.0, 10.0, -5.0]])[0], atol=HALF)
    np.testing.assert_array_equal(bottoms[1], [2000.0, 0.0, -5.0])
    np.testing.assert_array_equal(r_planes[1], [2000.0, 0.0, 2.0])


cycle_line = st.tuples(
    st.sampled_from(["", "G90 ", "G91 "]),
    st.sampled_from(["", "G98 ", "G99 "]),
    st.tuples(st.integers(200, 400), st.integers(200, 400)),  # X, Y under G90
    st.tuples(st.integers(-40, 40), st.integers(-40, 40)),  # under G91
    st.one_of(st.none(), st.integers(-30, -12)),  # Z: below every R
    st.one_of(st.none(), st.integers(-10, 10)),  # R
)


@settings(max_examples=25, deadline=None)
@given(st.lists(cycle_line, min_size=1, max_size=6), st.sampled_from(["G81", "G82 P0.1"]))
def test_every_cycle_hole_lands_on_its_correction(rs274, tmp_path_factory, lines, cycle):
    """Random canned-cycle blocks, absolute and incremental, with and without Z and R (sticky):
    the holes rs274 drills for the rewritten program are the independent corrections of the
    holes it drills for the original (each line writes X and Y)."""
    folder = tmp_path_factory.mktemp("cycles")
    text = ["G21 G90 G17 G98 F100", "G0 X300 Y100 Z60", f"{cycle} X300 Y100 Z-20 R5"]
    incremental = False
    for mode, retract, absolute, steps, z, r in lines:
        incremental = mode == "G91 " if mode else incremental
        x, y = steps if incremental else absolute
        words = [f"X{x}", f"Y{y}"] + ([f"Z{z}"] if z is not None else [])
        text.append(mode + retract + " ".join(words + ([f"R{r}"] if r is not None else [])))
    text = "\n".join([*text, "G80", "M2"]) + "\n"
    bottoms, r_planes = holes(*canonical(rs274, folder, text))
    new, rows = gcode_rewrite(text, SMOOTH)
    assert all(r.status == "corrected" for r in rows), [r.reason for r in rows]
    after = holes(*canonical(rs274, folder, new))
    np.testing.assert_allclose(after[0], corrected(SMOOTH, bottoms), atol=HALF)
    np.testing.assert_allclose(after[1][:, 2], corrected(SMOOTH, r_planes)[:, 2], atol=HALF)
