"""Pre-flight rewrite of an RS274NGC program (see ``codegen.rewrite`` for what a rewrite is).

G-code positions are in the cell's program frame (G54); A, B, C words are the tool orientation
(as ``accugrid gcode`` writes them) and stay as written. A canned cycle's hole (X, Y, Z) is
corrected, and its R plane by the Z correction at (X, Y, R). Axes a line does not write keep their
commanded value; the report gives the remaining difference (``residual_mm``). Under G91 the
increments are recomputed from the commanded (rewritten) previous position, so every later move
lands where it should. Arcs are not corrected, nor the moves that set an arc's start.
"""

from __future__ import annotations

import math

import numpy as np

from accugrid.codegen.gcode.parse import GcodeMove, parse_gcode
from accugrid.codegen.program_text import (
    MIN_PLACES_INCH,
    MIN_PLACES_MM,
    formatted,
    number_text,
    precision,
    splice,
)
from accugrid.codegen.rewrite import (
    CORRECTED,
    Options,
    Result,
    Rows,
    correct_points,
    rotations_of,
    strict_check,
)

__all__ = ["rewrite_gcode"]


def rewrite_gcode(path: str, text: str, opts: Options) -> Result:
    """Rewrite one RS274NGC program."""
    moves = parse_gcode(text, path)
    rows = Rows(
        [path],
        np.zeros(len(moves), np.int64),
        [m.line for m in moves],
        [m.motion for m in moves],
        [m.reason for m in moves],
        np.array([m.target for m in moves], dtype=float).reshape(-1, 3),
    )
    _protect_arc_starts(moves, rows)
    todo = [i for i, r in enumerate(rows.reason) if not r]
    desired = np.array([m.target for m in moves], dtype=float).reshape(-1, 3)
    if todo:
        prog = desired[todo]
        t = opts.robot_T_program
        robot = prog @ t[:3, :3].T + t[:3, 3]
        abc = np.array([[moves[i].rotary.get(k, math.nan) for k in "ABC"] for i in todo])
        at = np.array(todo)
        corrected = correct_points(robot, rows, at, opts, rotations_of(t[:3, :3], abc))
        back = (corrected - robot) @ t[:3, :3]  # R^T e, row-wise
        for j in np.flatnonzero(np.isfinite(corrected[:, 0])).tolist():
            rows.status[at[j]] = CORRECTED
            desired[todo[j]] = prog[j] + back[j]
    r_planes = _corrected_r_planes(moves, rows, opts)
    edits = _gcode_edits(text, moves, rows, desired, r_planes, opts)
    strict_check(rows, opts)
    return Result({path: splice(text, edits)}, rows)


def _protect_arc_starts(moves: list[GcodeMove], rows: Rows) -> None:
    """An arc keeps its start point: the moves that set it are not corrected either."""
    reasons = rows.reason
    for i, m in enumerate(moves):
        if not m.is_arc:
            continue
        if m.incremental:
            for j in range(i):
                reasons[j] = reasons[j] or (
                    f"precedes the incremental arc at line {m.line}, whose start must not move"
                )
            continue
        why = f"sets the start of the arc at line {m.line}, which is not corrected"
        for j in m.setters:
            if j is not None and not reasons[j]:
                reasons[j] = why


def _corrected_r_planes(moves: list[GcodeMove], rows: Rows, opts: Options) -> np.ndarray:
    """(N,) corrected R plane (mm) of each corrected cycle that writes R; NaN: keep R.

    The R point is (X, Y, R) of the hole; only its Z correction can be written."""
    out = np.full(len(moves), np.nan)
    status = rows.status.tolist()
    idx = [
        i for i, m in enumerate(moves) if m.is_cycle and "R" in m.words and status[i] == CORRECTED
    ]
    if idx:
        pts = np.array([[moves[i].target[0], moves[i].target[1], moves[i].r_mm] for i in idx])
        t = opts.robot_T_program
        robot = pts @ t[:3, :3].T + t[:3, 3]
        corrected = correct_points(robot, rows, np.array(idx), opts, mark=False)
        back = (corrected - robot) @ t[:3, :3]
        out[idx] = pts[:, 2] + back[:, 2]  # NaN where the R point is outside: R kept
    return out


def _gcode_edits(
    text: str,
    moves: list[GcodeMove],
    rows: Rows,
    desired: np.ndarray,
    r_planes: np.ndarray,
    opts: Options,
) -> list[tuple[int, int, str]]:
    """Walk the program with the commanded (rewritten) position; new word numbers.

    ``desired`` (N, 3) mm: where each move should land (program frame); ``r_planes`` (N,) mm:
    corrected R planes (NaN: keep). Absolute words are formatted in one pass beforehand; only
    increments (which depend on what was written before) are formatted on the way."""
    edits: list[tuple[int, int, str]] = []
    scales = np.array([m.scale for m in moves]).reshape(-1, 1)
    places = _places(moves, scales[:, 0], opts)
    corrected = (rows.status == CORRECTED).reshape(-1, 1)
    absolute = formatted(
        np.where(corrected, desired / scales, np.nan).ravel(), np.repeat(places, 3)
    )
    r_texts = formatted(r_planes / scales[:, 0], places)
    reached_rows: list[tuple[int, list[float]]] = []
    reached_at: list[int] = []  # the move of each reached_rows entry
    cmd = [math.nan] * 3
    cycle_z = r_cmd = math.nan
    status = rows.status.tolist()
    for n, move in enumerate(moves):
        if move.motion in ("G28", "G30", "G53"):
            cmd = [math.nan] * 3
            continue
        changed = status[n] == CORRECTED
        incremental = move.incremental and not move.is_cycle
        end = list(cmd)
        for i, k in enumerate("XYZ"):
            word = move.words.get(k)
            if word is None:
                continue
            old_text = new_text = word.literal
            if incremental:
                goal = float(desired[n, i])
                if not (math.isnan(cmd[i]) or math.isnan(goal)):
                    value = (goal - cmd[i]) / move.scale
                    new_text = number_text(old_text, word.value, value, int(places[n]))
            elif changed and absolute[3 * n + i] is not None:
                new_text = absolute[3 * n + i]
                if float(new_text) == word.value:
                    new_text = old_text
            if new_text != old_text:
                edits.append((word.start, word.end, new_text))
            written = float(new_text) * move.scale
            if move.is_cycle and i == 2:
                cycle_z = written
            elif incremental:
                end[i] = cmd[i] + written
            else:
                end[i] = written
        if move.is_cycle and "R" in move.words:
            word = move.words["R"]
            new_text = word.literal
            if r_texts[n] is not None and float(r_texts[n]) != word.value:
                new_text = r_texts[n]
                edits.append((word.start, word.end, new_text))
            r_cmd = float(new_text) * move.scale
        if move.is_cycle:
            reached = [end[0], end[1], cycle_z]
            if move.incremental or math.isnan(move.r_mm):
                end = [end[0], end[1], math.nan]
            elif move.retract == "G99":
                end = [end[0], end[1], r_cmd]
            else:
                end = [end[0], end[1], max(cmd[2], r_cmd)]
        else:
            reached = end
        if changed:
            reached_rows.append((n, reached))
            reached_at.append(n)
        cmd = end
    if reached_rows:
        reached = np.array([new for _, new in reached_rows])
        off = np.abs(reached - desired[reached_at])
        residual = np.linalg.norm(off, axis=1).tolist()
        wrote = np.array([[k in moves[n].words for k in "XYZ"] for n in reached_at])
        rounding = np.where(wrote, off, 0.0).max(axis=1).tolist()
        at = np.array(reached_at)
        rows.new[at] = reached
        rows.residual_mm[at] = residual
        rows.rounding_mm[at] = rounding
    return edits


def _places(moves: list[GcodeMove], scales: np.ndarray, opts: Options) -> np.ndarray:
    """Decimals of each move's corrected numbers (N,): ``--decimals``, else the file's precision
    but never coarser than 0.01 mm (0.001 in under G20)."""
    if opts.decimals is not None:
        return np.full(len(moves), opts.decimals)
    found = precision(w.literal for m in moves for k, w in m.words.items() if k in "XYZ")
    return np.where(scales == 1.0, max(found, MIN_PLACES_MM), max(found, MIN_PLACES_INCH))
