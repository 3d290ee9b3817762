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
from array import array

import numpy as np

from accugrid.codegen.gcode.parse import GcodeMoves, gcode_moves
from accugrid.codegen.program_text import (
    MIN_PLACES_INCH,
    MIN_PLACES_MM,
    Splicer,
    formatted,
    number_text,
    precision,
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

_BLOCK = 1 << 14  # moves per block of corrected numbers formatted and spliced at once


def rewrite_gcode(path: str, text: str, opts: Options) -> Result:
    """Rewrite one RS274NGC program."""
    moves = gcode_moves(text, path)
    rows = Rows(
        [path],
        np.zeros(len(moves), np.int64),
        moves.line,
        list(moves.motion),
        list(moves.reason),
        moves.target.copy(),
    )
    _protect_arc_starts(moves, rows)
    todo = [i for i, r in enumerate(rows.reason) if not r]
    desired = moves.target.copy()
    if todo:
        prog = desired[todo]
        t = opts.robot_T_program
        robot = prog @ t[:3, :3].T + t[:3, 3]
        abc = np.array([[r.get(k, math.nan) for k in "ABC"] for r in moves.rotaries])
        at = np.array(todo)
        # each distinct A/B/C once (a program has few), then one row per point
        rotations = rotations_of(t[:3, :3], abc.reshape(-1, 3))[moves.rotary_index[at]]
        corrected = correct_points(robot, rows, at, opts, rotations)
        back = (corrected - robot) @ t[:3, :3]  # R^T e, row-wise
        done = np.flatnonzero(np.isfinite(corrected[:, 0]))
        rows.status[at[done]] = CORRECTED
        desired[at[done]] = prog[done] + back[done]
    r_planes = _corrected_r_planes(moves, rows, opts)
    out = _gcode_edits(text, moves, rows, desired, r_planes, opts)
    strict_check(rows, opts)
    return Result({path: out}, rows)


def _protect_arc_starts(moves: GcodeMoves, rows: Rows) -> None:
    """An arc keeps its start point: the moves that set it are not corrected either."""
    reasons = rows.reason
    arcs = [i for i, m in enumerate(moves.motion) if m == "G2" or m == "G3"]
    for i in arcs:
        line = int(moves.line[i])
        if moves.incremental[i]:
            for j in range(i):
                reasons[j] = reasons[j] or (
                    f"precedes the incremental arc at line {line}, whose start must not move"
                )
            continue
        why = f"sets the start of the arc at line {line}, which is not corrected"
        for j in moves.setters[i].tolist():
            if j >= 0 and not reasons[j]:
                reasons[j] = why


def _corrected_r_planes(moves: GcodeMoves, rows: Rows, opts: Options) -> np.ndarray:
    """(N,) corrected R plane (mm) of each corrected cycle that writes R; NaN: keep R.

    The R point is (X, Y, R) of the hole; only its Z correction can be written."""
    out = np.full(len(moves), np.nan)
    wrote_r = moves.is_cycle & (moves.word_start[:, 3] >= 0) & (rows.status == CORRECTED)
    idx = np.flatnonzero(wrote_r)
    if len(idx):
        pts = np.column_stack([moves.target[idx, 0], moves.target[idx, 1], moves.r_mm[idx]])
        t = opts.robot_T_program
        robot = pts @ t[:3, :3].T + t[:3, 3]
        corrected = correct_points(robot, rows, idx, opts, mark=False)
        back = (corrected - robot) @ t[:3, :3]
        out[idx] = pts[:, 2] + back[:, 2]  # NaN where the R point is outside: R kept
    return out


def _gcode_edits(
    text: str,
    moves: GcodeMoves,
    rows: Rows,
    desired: np.ndarray,
    r_planes: np.ndarray,
    opts: Options,
) -> bytearray:
    """Walk the program with the commanded (rewritten) position; the new program's bytes.

    ``desired`` (N, 3) mm: where each move should land (program frame); ``r_planes`` (N,) mm:
    corrected R planes (NaN: keep). Absolute words are formatted a block of moves at a time;
    only increments (which depend on what was written before) are formatted on the way."""
    out = Splicer(text)
    scales = moves.scale.reshape(-1, 1)
    places = _places(moves, opts)
    corrected = (rows.status == CORRECTED).reshape(-1, 1)
    reached_rows = array("d")  # where each corrected move reaches, 3 per move
    reached_at = array("q")  # the move of each
    cmd = [math.nan] * 3
    cycle_z = r_cmd = math.nan
    for first in range(0, len(moves), _BLOCK):
        block = slice(first, first + _BLOCK)
        absolute = formatted(
            np.where(corrected[block], desired[block] / scales[block], np.nan).ravel(),
            np.repeat(places[block], 3),
        )
        r_texts = formatted(r_planes[block] / scales[block, 0], places[block])
        edits: list[tuple[int, int, str]] = []
        columns = zip(
            moves.motion[block],
            corrected[block, 0].tolist(),
            moves.incremental[block].tolist(),
            moves.is_cycle[block].tolist(),
            moves.scale[block].tolist(),
            moves.word_start[block].tolist(),
            moves.word_end[block].tolist(),
            moves.word_value[block].tolist(),
            desired[block].tolist(),
            moves.r_mm[block].tolist(),
            moves.retract[block],
            strict=True,
        )
        for b, (
            motion,
            changed,
            inc,
            is_cycle,
            scale,
            starts,
            ends,
            values,
            goals,
            r_mm,
            retract,
        ) in enumerate(columns):
            if motion in ("G28", "G30", "G53"):
                cmd = [math.nan] * 3
                continue
            incremental = inc and not is_cycle
            end = list(cmd)
            for i in range(3):
                start = starts[i]
                if start < 0:
                    continue
                old_text = new_text = text[start : ends[i]]
                if incremental:
                    goal = goals[i]
                    if not (math.isnan(cmd[i]) or math.isnan(goal)):
                        value = (goal - cmd[i]) / scale
                        new_text = number_text(old_text, values[i], value, int(places[first + b]))
                elif changed and absolute[3 * b + i] is not None:
                    new_text = absolute[3 * b + i]
                    if float(new_text) == values[i]:
                        new_text = old_text
                if new_text != old_text:
                    edits.append((start, ends[i], new_text))
                written = float(new_text) * scale
                if is_cycle and i == 2:
                    cycle_z = written
                elif incremental:
                    end[i] = cmd[i] + written
                else:
                    end[i] = written
            if is_cycle and starts[3] >= 0:
                new_text = text[starts[3] : ends[3]]
                if r_texts[b] is not None and float(r_texts[b]) != values[3]:
                    new_text = r_texts[b]
                    edits.append((starts[3], ends[3], new_text))
                r_cmd = float(new_text) * scale
            if is_cycle:
                reached = [end[0], end[1], cycle_z]
                if inc or math.isnan(r_mm):
                    end = [end[0], end[1], math.nan]
                elif retract == "G99":
                    end = [end[0], end[1], r_cmd]
                else:
                    end = [end[0], end[1], max(cmd[2], r_cmd)]
            else:
                reached = end
            if changed:
                reached_rows.extend(reached)
                reached_at.append(first + b)
            cmd = end
        edits.sort()
        if edits:
            out.add(*map(list, zip(*edits, strict=True)))
    if reached_at:
        at = np.frombuffer(reached_at, dtype=np.int64)
        reached = np.frombuffer(reached_rows, dtype=float).reshape(-1, 3)
        off = np.abs(reached - desired[at])
        residual = np.linalg.norm(off, axis=1)
        wrote = moves.word_start[at, :3] >= 0
        rounding = np.where(wrote, off, 0.0).max(axis=1)
        rows.new[at] = reached
        rows.residual_mm[at] = residual
        rows.rounding_mm[at] = rounding
    return out.finish()


def _places(moves: GcodeMoves, opts: Options) -> np.ndarray:
    """Decimals of each move's corrected numbers (N,): ``--decimals``, else the file's precision
    but never coarser than 0.01 mm (0.001 in under G20)."""
    if opts.decimals is not None:
        return np.full(len(moves), opts.decimals)
    found = [
        precision(moves.text[s:e] for s, e in zip(starts, ends, strict=True))
        for starts, ends in _word_spans(moves)
    ]
    found = max(found) if found else precision(())
    return np.where(moves.scale == 1.0, max(found, MIN_PLACES_MM), max(found, MIN_PLACES_INCH))


def _word_spans(moves: GcodeMoves):
    """(starts, ends) lists of the X, Y, Z numbers written, a block of moves at a time (only
    blocks that write any)."""
    for first in range(0, len(moves), _BLOCK):
        starts = moves.word_start[first : first + _BLOCK, :3]
        written = starts >= 0
        if written.any():
            ends = moves.word_end[first : first + _BLOCK, :3]
            yield starts[written].tolist(), ends[written].tolist()
