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

from accugrid.codegen.gcode.parse import RESETS, GcodeMoves, gcode_moves, modal_fill
from accugrid.codegen.program_text import (
    MIN_PLACES_INCH,
    MIN_PLACES_MM,
    distinct_ints,
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
    partial_check,
    rotations_of,
)
from accugrid.codegen.splice import ByteSplicer, texts_of
from accugrid.codegen.textsafe import fixed_bytes
from accugrid.kinematics.frames import rows_times, transform_points

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
    if any(rows.reason):  # the moves with no reason
        at = np.flatnonzero(~np.fromiter(map(bool, rows.reason), bool, len(moves)))
    else:
        at = np.arange(len(moves))
    desired = moves.target.copy()
    if len(at):
        prog = desired[at]
        t = opts.robot_T_program
        robot = transform_points(t, prog)
        abc = np.array([[r.get(k, math.nan) for k in "ABC"] for r in moves.rotaries])
        # each distinct A/B/C once (a program has few), then one row per point
        rotations = rotations_of(t[:3, :3], abc.reshape(-1, 3))[moves.rotary_index[at]]
        corrected = correct_points(robot, rows, at, opts, rotations)
        back = rows_times(corrected - robot, t[:3, :3])  # R^T e, row-wise
        done = np.flatnonzero(np.isfinite(corrected[:, 0]))
        rows.status[at[done]] = CORRECTED
        desired[at[done]] = prog[done] + back[done]
    r_planes = _corrected_r_planes(moves, rows, opts)
    out = _gcode_edits(text, moves, rows, desired, r_planes, opts)
    partial_check(rows, opts)
    return Result({path: out}, rows)


def _protect_arc_starts(moves: GcodeMoves, rows: Rows) -> None:
    """An arc keeps its start point: the moves that set it are not corrected either."""
    reasons = rows.reason
    if "G2" not in moves.motion and "G3" not in moves.motion:
        return
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
        robot = transform_points(t, pts)
        corrected = correct_points(robot, rows, idx, opts, mark=False)
        back = rows_times(corrected - robot, t[:3, :3])
        out[idx] = pts[:, 2] + back[:, 2]  # NaN where the R point is outside: R kept
    return out


class _Commanded:
    """The walk's state between moves: ``cmd`` where the rewritten program leaves the tool (mm,
    NaN: unknown), the sticky cycle depth ``cycle_z`` and R plane ``r_cmd`` as written (mm), and
    where each corrected move reaches (``reached_rows``, 3 per move, of the moves ``reached_at``).
    """

    def __init__(self) -> None:
        self.cmd = [math.nan] * 3
        self.cycle_z = self.r_cmd = math.nan
        self.reached_rows = array("d")
        self.reached_at = array("q")


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
    corrected R planes (NaN: keep). Stretches of absolute moves (none a G28/G30/G53) are done
    in bulk (``_bulk_block``), the rest move by move (``_walk_block``), where increments (which
    depend on what was written before) are formatted on the way."""
    out = ByteSplicer(text)
    places = _places(moves, opts)
    corrected = rows.status == CORRECTED
    walk = _Commanded()
    for first in range(0, len(moves), _BLOCK):
        for part, step in _stretches(moves, slice(first, first + _BLOCK)):
            out.add(*step(text, moves, part, corrected, desired, r_planes, places, walk))
    if walk.reached_at:
        at = np.frombuffer(walk.reached_at, dtype=np.int64)
        reached = np.frombuffer(walk.reached_rows, dtype=float).reshape(-1, 3)
        off = np.abs(reached - desired[at])
        residual = np.linalg.norm(off, axis=1)
        wrote = moves.word_start[at, :3] >= 0
        off_written = np.where(wrote, off, 0.0)
        rounding = np.maximum(np.maximum(off_written[:, 0], off_written[:, 1]), off_written[:, 2])
        rows.new[at] = reached
        rows.residual_mm[at] = residual
        rows.rounding_mm[at] = rounding
    return out.finish()


_MIN_BULK = 256  # moves: a shorter stretch of absolute moves is walked with its neighbours


def _stretches(moves: GcodeMoves, block: slice):
    """(slice, step) of each stretch of the moves ``block``, in order: ``_bulk_block`` for runs
    of at least ``_MIN_BULK`` absolute moves that do not reset the position, ``_walk_block`` for
    the moves between them."""
    walked = moves.incremental[block] | moves.resets[block]
    n = len(walked)
    runs = np.flatnonzero(np.diff(walked, prepend=True, append=True)).reshape(-1, 2)
    done = 0
    for lo, hi in runs[runs[:, 1] - runs[:, 0] >= min(_MIN_BULK, n)].tolist():
        if lo > done:
            yield slice(block.start + done, block.start + lo), _walk_block
        yield slice(block.start + lo, block.start + hi), _bulk_block
        done = hi
    if done < n:
        yield slice(block.start + done, block.start + n), _walk_block


def _walk_block(text, moves, block, corrected, desired, r_planes, places, walk):
    """The edits of the moves ``block`` (a slice), move by move, carrying ``walk`` (a
    ``_Commanded``) on: as ``ByteSplicer.add`` takes them (starts, ends sorted, the new texts'
    bytes one after another, their lengths)."""
    first = block.start
    scales = moves.scale.reshape(-1, 1)
    absolute = formatted(
        np.where(corrected[block, None], desired[block] / scales[block], np.nan).ravel(),
        np.repeat(places[block], 3),
    )
    r_texts = formatted(r_planes[block] / scales[block, 0], places[block])
    edits: list[tuple[int, int, str]] = []
    columns = zip(
        moves.motion[block],
        corrected[block].tolist(),
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
    cmd, cycle_z, r_cmd = walk.cmd, walk.cycle_z, walk.r_cmd
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
        if motion in RESETS:
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
            walk.reached_rows.extend(reached)
            walk.reached_at.append(first + b)
        cmd = end
    walk.cmd, walk.cycle_z, walk.r_cmd = cmd, cycle_z, r_cmd
    edits.sort()
    starts = np.array([e[0] for e in edits], np.int64)
    ends = np.array([e[1] for e in edits], np.int64)
    texts = [e[2] for e in edits]
    lengths = np.fromiter(map(len, texts), np.int64, len(texts))
    return starts, ends, np.frombuffer("".join(texts).encode("ascii"), np.uint8), lengths


def _bulk_block(text, moves, block, corrected, desired, r_planes, places, walk):
    """``_walk_block`` in bulk for a block whose moves are all absolute (none resets the
    position): every number is formatted and compared at once, X and Y carried forward where a
    move does not write them, and only the Z ends that depend on the previous one (a G98 retract,
    the higher of the previous end and R; a straight move without Z) are carried one by one."""
    n = len(moves.motion[block])
    scale = moves.scale[block]
    values = moves.word_value[block]
    cycle = moves.is_cycle[block]
    wrote = moves.word_start[block] >= 0  # (n, 4) X, Y, Z, R written
    wrote_r = cycle & wrote[:, 3]
    goal = np.full((n, 4), np.nan)  # the corrected numbers in program units (NaN: keep)
    fix = corrected[block, None] & wrote[:, :3]
    goal[:, :3] = np.where(fix, desired[block] / scale[:, None], np.nan)
    goal[:, 3] = np.where(wrote_r, r_planes[block] / scale, np.nan)
    goal = goal.ravel()
    new = np.full(4 * n, np.nan)  # the value each new text reads as
    place = np.repeat(places[block], 4)
    # the texts fixed gives and the values they read as, from the formatter's array form: the
    # texts' bytes of each count of places, and each number's group and row in them
    cells_of, group, row = [], np.full(4 * n, -1, np.int64), np.empty(4 * n, np.int64)
    for p in distinct_ints(place):
        idx = np.flatnonzero(np.isfinite(goal) & (place == p))
        if not len(idx):
            continue
        cells, new[idx] = fixed_bytes(goal[idx], p)
        group[idx], row[idx] = len(cells_of), np.arange(len(idx))
        cells_of.append(cells)
    edit = np.isfinite(new) & (new != values.ravel())
    written = np.where(edit, new, values.ravel()).reshape(n, 4) * scale[:, None]  # NaN: none
    r_cmd = modal_fill(written[:, 3], wrote_r, walk.r_cmd)
    cycle_z = modal_fill(written[:, 2], cycle & wrote[:, 2], walk.cycle_z)
    end = np.empty((n, 3))
    for i in range(2):  # X, Y: as written, else where the previous move left them
        end[:, i] = modal_fill(written[:, i], wrote[:, i], walk.cmd[i])
    # Z: a straight move's as written; a cycle's retract: nothing known without an R plane,
    # R under G99, the higher of the previous end and R under G98
    r_mm = moves.r_mm[block]
    g99 = moves.g99[block]
    end[:, 2] = np.where(cycle, np.where(np.isnan(r_mm), np.nan, r_cmd), written[:, 2])
    carried = np.flatnonzero((cycle & ~g99 & ~np.isnan(r_mm)) | ~(cycle | wrote[:, 2])).tolist()
    if carried:  # those that depend on the previous end: one by one
        z, r, hole = end[:, 2].tolist(), r_cmd.tolist(), cycle.tolist()
        for k in carried:
            before = z[k - 1] if k else walk.cmd[2]
            z[k] = max(before, r[k]) if hole[k] else before
        end[:, 2] = z
    changed = np.flatnonzero(corrected[block])
    if len(changed):  # a cycle reaches its hole bottom, a straight move its end
        reached = end[changed]
        holes = np.flatnonzero(cycle[changed])
        reached[holes, 2] = cycle_z[changed[holes]]
        walk.reached_rows.frombytes(reached.tobytes())
        walk.reached_at.frombytes((block.start + changed).astype(np.int64).tobytes())
    walk.cmd = end[-1].tolist()
    walk.cycle_z, walk.r_cmd = float(cycle_z[-1]), float(r_cmd[-1])
    at = np.flatnonzero(edit)
    starts = moves.word_start[block].ravel()[at]
    order = np.argsort(starts, kind="stable")
    at = at[order]
    # the new texts in the edits' order, as rows of their cells (NUL-padded on the left)
    if len(cells_of) == 1:
        rows = cells_of[0][row[at]]
    else:
        rows = np.zeros((len(at), max((c.shape[1] for c in cells_of), default=1)), np.uint8)
        for g, cells in enumerate(cells_of):
            mine = np.flatnonzero(group[at] == g)
            rows[mine, rows.shape[1] - cells.shape[1] :] = cells[row[at[mine]]]
    ends = moves.word_end[block].ravel()[at]
    return starts[order], ends, *texts_of(rows)


def _places(moves: GcodeMoves, opts: Options) -> np.ndarray:
    """Decimals of each move's corrected numbers (N,): ``--decimals``, else the file's precision
    but never coarser than 0.01 mm (0.001 in under G20)."""
    if opts.decimals is not None:
        return np.full(len(moves), opts.decimals)
    found = _file_precision(moves)
    return np.where(moves.scale == 1.0, max(found, MIN_PLACES_MM), max(found, MIN_PLACES_INCH))


def _file_precision(moves: GcodeMoves) -> int:
    """``precision`` of the X, Y, Z literals written (the reader kept their most decimals)."""
    return moves.places if moves.places >= 0 else precision(())
