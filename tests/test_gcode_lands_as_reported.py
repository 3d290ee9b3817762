"""Every G-code move lands where its report row says: a corrected move within the tolerance of its
own correction (the axes its line writes within the written rounding), a move not corrected as
programmed. Each case is a minimal program of a construct real programs use: G91 and polar moves
in an O-word loop, a G91 move that leaves an axis unwritten, canned-cycle holes written in polar
words, a plunge that writes Z alone.

Expected positions: LinuxCNC's ``rs274`` runs the input (checked against the positions recomputed
here) and the rewritten program; corrections come from the grid's correction function
(``corrected``), never from the rewrite code.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from rewrite_helpers import rewrite_gcode, write_cell
from test_arcs import STEEP, linear_grid
from test_gcode_rs274 import canonical
from test_real_programs import HALF, T_PROGRAM, corrected, gcode_rewrite, holes

from accugrid.app.jobs.rewrite import RewriteRequest, rewrite_job
from accugrid.codegen.plugin_types import STATUSES, Options

STEEPER = linear_grid(2e-3)  # corrections that differ by 1.2 mm over 300 mm
LOOPS = 40


def spiral(k: np.ndarray) -> np.ndarray:
    """The points of ``G91 G1 @1 ^9`` repeated from X50 Y0 Z20: radius 50 + k mm, k * 9 deg."""
    turn = np.radians(9.0 * k)
    return np.column_stack([(50 + k) * np.cos(turn), (50 + k) * np.sin(turn), np.full(len(k), 20)])


def staircase(k: np.ndarray) -> np.ndarray:
    """The points of ``G91 G1 X2 Y1`` repeated from X50 Y0 Z20."""
    return np.column_stack([50 + 2.0 * k, 1.0 * k, np.full(len(k), 20.0)])


def written_axes(line: str) -> list[int]:
    """The axes (0, 1, 2) a line writes: X, Y, Z words, and X, Y for polar words."""
    code = re.sub(r"\([^)]*\)|;.*", "", line).upper()
    axes = [i for i, a in enumerate("XYZ") if re.search(a + r"\s*[-+.\d\[#]", code)]
    return sorted(set(axes) | ({0, 1} if re.search(r"[@^]", code) else set()))


def check_straight_moves(text, new, rows, model, tolerance, rs274, tmp_path):
    """Programs of straight moves only, one rs274 move per row: each row's move where it says.
    Corrected: within the tolerance of its correction; not corrected because it would land
    farther ("lands ..."): the axes its line writes corrected, at the distance it reports;
    otherwise the axes its line writes as programmed, and the move within the tolerance of
    where it is programmed unless its reason gives the distance."""
    nominal, _ = canonical(rs274, tmp_path, text)
    moves, _ = canonical(rs274, tmp_path, new)
    assert len(nominal) == len(moves) == len(rows)
    lines = text.splitlines()
    for k, row in enumerate(rows):
        axes = written_axes(lines[row.line - 1])
        if row.status != "corrected" and not row.reason.startswith("lands"):
            np.testing.assert_allclose(moves[k, axes], nominal[k, axes], atol=HALF)
            off = np.linalg.norm(moves[k, :3] - nominal[k, :3])
            reported = re.search(r"lands (\d+\.\d+) mm from where it is programmed", row.reason)
            assert off <= tolerance if reported is None else abs(off - float(reported[1])) < 6e-4
            continue
        want = corrected(model, nominal[k, :3])[0]
        np.testing.assert_allclose(moves[k, axes], want[axes], atol=HALF)
        off = np.linalg.norm(moves[k, :3] - want)
        if row.status == "corrected":
            assert off <= tolerance, (row.line, moves[k], want)
        else:  # rs274 prints 4 decimals
            assert off > tolerance and abs(off - row.residual_mm) < 2e-4, (row.reason, off)
    return nominal, moves


# ---------------------------------------------------------------- O-word loops


@pytest.mark.parametrize(("body", "points"), [("G1 @1 ^9", spiral), ("G1 X2 Y1", staircase)])
def test_an_o_word_loop_of_g91_moves_is_left_as_written_from_its_programmed_start(
    rs274, tmp_path, body, points
):
    """A loop repeats its G91 (or polar) line from where the last pass ended: the scanner reads
    one pass, so the line is left as written and reported, and the move that sets where the loop
    starts is not corrected either: every pass lands as programmed. A move before it that does
    not set that start is corrected."""
    text = (
        "G21 G90 G17 F100\n"
        "G0 X10 Y10 Z40\n"
        "G0 X50 Y0 Z20\n"
        "G91\n"
        f"o100 repeat [{LOOPS}]\n"
        f"{body}\n"
        "o100 endrepeat\n"
        "G90 G0 Z30\n"
        "M2\n"
    )
    nominal, _ = canonical(rs274, tmp_path, text)
    want = points(np.arange(1, LOOPS + 1, dtype=float))
    np.testing.assert_allclose(nominal[2 : 2 + LOOPS, :3], want, atol=1e-4)  # rs274 as here
    new, rows = gcode_rewrite(text, STEEP)
    assert [(r.line, r.status) for r in rows] == [
        (2, "corrected"),
        (3, "skipped"),
        (6, "skipped"),
        (8, "skipped"),
    ]
    assert "read under control flow and left as written" in rows[1].reason
    assert rows[2].reason == rows[3].reason == "O-word control flow from line 5"
    assert new.splitlines()[2:] == text.splitlines()[2:]  # byte for byte after line 2
    moves, _ = canonical(rs274, tmp_path, new)
    np.testing.assert_allclose(moves[0, :3], corrected(STEEP, nominal[0, :3])[0], atol=HALF)
    np.testing.assert_allclose(moves[1:, :3], nominal[1:, :3], atol=1e-4)


def test_a_canned_cycle_continued_in_a_loop_keeps_its_programmed_depth(rs274, tmp_path):
    """Holes continued in a loop (X from the tool, the depth and R words of the block before the
    loop, under G91 R from the initial level Z20 and Z from R) are drilled as programmed: the
    block that sets their start, depth and R plane is not corrected."""
    text = (
        "G21 G90 G17 G98 F100\n"
        "G0 X50 Y0 Z20\n"
        "G81 X50 Y0 Z-5 R2\n"
        "o100 repeat [5]\n"
        "G91 X10\n"
        "G90\n"
        "o100 endrepeat\n"
        "G80 G0 Z30\n"
        "M2\n"
    )
    nominal, out = canonical(rs274, tmp_path, text)
    bottoms = holes(nominal, out)[0]
    want = np.column_stack([50 + 10.0 * np.arange(6), np.zeros(6), [-5.0] + [20 + 2 - 5] * 5])
    np.testing.assert_allclose(bottoms, want, atol=1e-4)
    new, rows = gcode_rewrite(text, STEEP)
    assert all(r.status == "skipped" for r in rows)
    assert new == text
    moves, new_out = canonical(rs274, tmp_path, new)
    np.testing.assert_allclose(holes(moves, new_out)[0], want, atol=1e-4)


# ---------------------------------------------------------------- canned cycles in polar words


@pytest.mark.parametrize(
    ("line", "turns"),
    [("G91 @5 ^20", [(55.0, 30.0)]), ("G91 ^30 L3", [(50.0, 40.0), (50.0, 70.0), (50.0, 100.0)])],
)
def test_g91_polar_holes_after_a_first_hole_keep_their_programmed_depth(
    rs274, tmp_path, line, turns
):
    """A G91 polar cycle continues a G90 first hole: its holes turn about the origin from where
    the tool is, R from the run's initial level (the Z before the first hole), Z from R. They
    are reported, so the moves that set their start, depth, R words and initial level are not
    corrected either: rs274 drills every hole as programmed, none at a corrected depth."""
    text = (
        f"G21 G90 G17 G98 F100\nG0 X60 Y0 Z20\nG81 @50 ^10 Z-5 R2\n{line}\n"
        "G90 G80 G0 X0 Y0 Z30\nM2\n"
    )
    nominal, out = canonical(rs274, tmp_path, text)
    polar = np.array([(50.0, 10.0), *turns])
    depth = [-5.0] + [20 + 2 - 5.0] * len(turns)  # G91: R from the initial level, Z from R
    turn = np.radians(polar[:, 1])
    want = np.column_stack([polar[:, 0] * np.cos(turn), polar[:, 0] * np.sin(turn), depth])
    np.testing.assert_allclose(holes(nominal, out)[0], want, atol=1e-4)
    new, rows = gcode_rewrite(text, STEEP)
    moves, new_out = canonical(rs274, tmp_path, new)
    np.testing.assert_allclose(holes(moves, new_out)[0], want, atol=1e-4)
    assert [r.status for r in rows] == ["skipped"] * 3 + ["corrected"]
    assert "G91 canned cycle with polar words" in rows[2].reason
    assert all("sets the start of the polar move at line 4" in r.reason for r in rows[:2])


# ---------------------------------------------------------------- axes a line does not write


def test_a_g91_move_whose_unwritten_axis_would_land_off_is_reported(rs274, tmp_path):
    """`G91 G1 Y300` writes no X, Z: it keeps those of the corrected line before it, whose
    correction differs from its own by more than the tolerance. Its Y is corrected, but it is
    reported with the distance rs274 puts it from its correction, not called corrected; the next
    G91 line, which writes every axis, is corrected."""
    text = "G21 G90 G17 F100\nG0 X100 Y-300 Z20\nG91 G1 Y300\nX-50 Y0 Z0\nG90 G0 X50 Y0 Z30\nM2\n"
    new, rows = gcode_rewrite(text, STEEPER)
    nominal, _ = check_straight_moves(text, new, rows, STEEPER, 0.3, rs274, tmp_path)
    np.testing.assert_allclose(nominal[:3, :3], [[100, -300, 20], [100, 0, 20], [50, 0, 20]])
    assert [r.status for r in rows] == ["corrected", "skipped", "corrected", "corrected"]
    # independently: the Z it would keep is farther than the tolerance from its own
    keep = corrected(STEEPER, nominal[0, :3])[0, 2]
    assert abs(keep - corrected(STEEPER, nominal[1, :3])[0, 2]) > 0.3
    assert "tolerance (0.3 mm)" in rows[1].reason and "(X, Z)" in rows[1].reason


def test_a_plunge_that_writes_z_alone_under_an_uncorrected_move_is_not_called_corrected(
    rs274, tmp_path
):
    """`G1 Z20` below a move outside the grid (left as programmed): only its Z can be
    corrected, its X, Y stay 1.3 mm from its correction: reported with that distance, not
    called corrected; a later move that writes every axis is corrected."""
    text = "G21 G90 G17 F100\nG0 X100 Y0 Z2000\nG1 Z20\nG0 X150 Y50 Z30\nM2\n"
    new, rows = gcode_rewrite(text, STEEPER)
    nominal, _ = check_straight_moves(text, new, rows, STEEPER, 0.3, rs274, tmp_path)
    assert [r.status for r in rows] == ["outside", "skipped", "corrected"]
    off = corrected(STEEPER, nominal[1, :3])[0] - nominal[1, :3]
    assert math.hypot(*off[:2]) > 1.0  # what it would have been off by in X, Y
    assert "tolerance (0.3 mm)" in rows[1].reason and "(X, Y)" in rows[1].reason


def test_a_move_left_as_programmed_under_a_corrected_one_says_how_far_it_lands(rs274, tmp_path):
    """`G1 Z2000` (outside the grid, not corrected) keeps the X, Y of the corrected move before
    it, 1.3 mm from where it is programmed: its reason gives that distance, in G90 and in G91."""
    for mode in ("", "G91 "):
        text = f"G21 G90 G17 F100\nG0 X100 Y0 Z20\n{mode}G1 Z{2000 - 20 * bool(mode)}\nM2\n"
        new, rows = gcode_rewrite(text, STEEPER)
        assert [r.status for r in rows] == ["corrected", "outside"]
        assert "mm from where it is programmed" in rows[1].reason
        assert "(X, Y) stay where corrected moves" in rows[1].reason
        check_straight_moves(text, new, rows, STEEPER, 0.3, rs274, tmp_path)


def test_the_tolerance_decides_what_is_called_corrected(rs274, tmp_path):
    """The same plunge is corrected where its X, Y would stay within the tolerance."""
    text = "G21 G90 G17 F100\nG0 X100 Y0 Z2000\nG1 Z20\nM2\n"
    opts = Options(model=STEEPER, decimals=3, allow_partial=True, tolerance_mm=2.0)
    result = rewrite_gcode("p.ngc", text, opts, T_PROGRAM)
    new, rows = result.texts["p.ngc"], list(result.rows)
    assert [r.status for r in rows] == ["outside", "corrected"]
    assert 1.0 < rows[1].residual_mm <= 2.0
    check_straight_moves(text, new, rows, STEEPER, 2.0, rs274, tmp_path)


def test_a_rewrite_request_holds_holes_to_the_default_tolerance(tmp_path):
    """The API's request, like the command, holds holes to the default tolerance (0.3 mm): a
    plunge whose X, Y stay a few hundredths from its correction is corrected."""
    program = tmp_path / "p.ngc"
    program.write_text("G21 G90 G17\nG0 X1000 Y0 Z500\nG1 Z400\nM2\n")
    cell = write_cell(tmp_path)
    request = RewriteRequest(outputs={program: tmp_path / "out.ngc"}, cell=str(cell))
    rows = rewrite_job(request).result.rows
    assert [STATUSES[s] for s in rows.status] == ["corrected", "corrected"]
    assert 0.0 < rows.residual_mm[1] < 0.3
