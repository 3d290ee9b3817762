"""Pre-flight rewrite of an RS274NGC program (see ``codegen.rewrite`` for what a rewrite is).

G-code positions are in the cell's program frame (G54); A, B, C words are the tool orientation
(as ``accugrid gcode`` writes them) and stay as written. A canned cycle's hole (X, Y, Z) is
corrected, and its R plane by the Z correction at (X, Y, R). Axes a line does not write keep their
commanded value; the report gives the remaining difference (``residual_mm``), and a move it
leaves farther than the tolerance from its correction is reported, not called corrected. The
moves read under O-word control flow are left as written, and the moves that set where they
start are not corrected (``_protect_flow_start``). Under G91 the
increments are recomputed from the commanded (rewritten) previous position, so every later move
lands where it should, corrected or as programmed: a G91 cycle's X, Y from the tool, its R from
the initial level and its Z from R. A G91 cycle repeated L times has one increment for all its
holes: corrected when their corrections agree within the written resolution, else it and the
moves that set its start are not. A cycle line that writes no Z or R gets the words its hole
needs. An arc moves rigidly with the moves that set its start (``codegen.gcode.arc_shift``);
in G18/G19 a cycle's axis is Y/X instead of Z. A corrected word written
as a parameter or an expression gets the corrected number in the expression's place (its value
as read where it is kept); a polar move gets its corrected radius and angle (``_polar_edits``).
With the cell's ``tool_data`` each move is corrected with the tool whose length offset is in
effect (G43), the cell's tool where none is; without it a move under the length offset of
another tool than the cell's, or of a tool not known, is reported.
"""

from __future__ import annotations

import math
from array import array

import numpy as np

from accugrid.codegen.gcode.arc_shift import shift_arcs
from accugrid.codegen.gcode.parse import RESETS, GcodeMoves, gcode_moves, modal_fill, polar_xy
from accugrid.codegen.gcode.section import GcodeSection
from accugrid.codegen.plugin_types import CORRECTED, SKIPPED, Options, Rows, Scan
from accugrid.codegen.program_text import (
    MIN_PLACES_INCH,
    MIN_PLACES_MM,
    comment_block,
    distinct_ints,
    formatted,
    insert_after_lines,
    number_text,
    precision,
)
from accugrid.codegen.rewrite import correct_points, rotations_of
from accugrid.codegen.splice import ByteSplicer, texts_of
from accugrid.infra.textsafe import fixed, fixed_bytes
from accugrid.kinematics.frames import rows_times, transform_points

__all__ = ["add_header", "scan_positions", "splice_positions"]

_BLOCK = 1 << 14  # moves per block of corrected numbers formatted and spliced at once


def scan_positions(texts: dict[str, str], opts: Options, placement: GcodeSection) -> Scan:
    """The moves of one RS274NGC program (``texts``: one path and its text) in the cell's
    program frame (``placement.robot_T_program``)."""
    ((path, text),) = texts.items()
    moves = gcode_moves(text, path)
    rows = Rows(
        [path],
        np.zeros(len(moves), np.int64),
        moves.line,
        list(moves.motion),
        list(moves.reason),
        moves.target.copy(),
    )
    # every move commands a position in the program frame, except a home or machine-coordinate
    # move (G28/G30/G53: a fixed machine position) and axis words under G80 (no motion)
    rows.commanded[:] = ~moves.resets
    if "G80" in moves.motion:
        rows.commanded &= np.array([m != "G80" for m in moves.motion], bool)
    _protect_polar_starts(moves, rows)
    _protect_flow_start(moves, rows)
    _tools(moves, rows, opts)
    if any(rows.reason):  # the moves with no reason
        at = np.flatnonzero(~np.fromiter(map(bool, rows.reason), bool, len(moves)))
    else:
        at = np.arange(len(moves))
    t = placement.robot_T_program
    robot, rotations = np.zeros((0, 3)), None
    if len(at):
        robot = transform_points(t, moves.target[at])
        abc = np.array([[r.get(k, math.nan) for k in "ABC"] for r in moves.rotaries])
        # each distinct A/B/C once (a program has few), then one row per point
        rotations = rotations_of(t[:3, :3], abc.reshape(-1, 3))[moves.rotary_index[at]]
    return Scan(rows, at, robot, rotations, state=(path, text, moves, t))


def splice_positions(scan: Scan, corrected: np.ndarray, opts: Options) -> dict[str, bytearray]:
    """The program's bytes with the corrected moves (``corrected`` (M, 3) mm robot frame, NaN
    rows: not corrected) written in the program frame: their repeated G91 cycles, R planes and
    the increments after them made to agree, arcs shifted rigidly (``arc_shift``)."""
    path, text, moves, t = scan.state
    rows, at = scan.rows, scan.at
    desired = moves.target.copy()
    if len(at):
        back = rows_times(corrected - scan.robot, t[:3, :3])  # R^T e, row-wise
        done = np.flatnonzero(np.isfinite(corrected[:, 0]))
        rows.status[at[done]] = CORRECTED
        desired[at[done]] = desired[at][done] + back[done]
    _repeated_holes(moves, rows, desired, opts, t)
    own = desired.copy()  # where each corrected move should land: its own correction
    centre_edits = shift_arcs(moves, rows, desired, _places(moves, opts), opts, t)
    r_planes = _corrected_r_planes(moves, rows, opts, t)
    return {path: _gcode_edits(text, moves, rows, (desired, own), r_planes, opts, centre_edits)}


def add_header(text: str, lines: list[str]) -> str:
    """The program with the header as ``( )`` comments after its leading ``%`` lines."""
    return insert_after_lines(text, comment_block(text, lines, "({})"), "%")


def _tools(moves: GcodeMoves, rows: Rows, opts: Options) -> None:
    """Each move's tool (``GcodeMoves.tool_spans``); a move whose tool is not known is not
    placed, with the reason, nor, without the cell's ``tool_data``, one whose length offset is
    another tool's than the cell's."""
    for start, stop, tool in moves.tool_spans():
        why = f"tool unknown: {tool}" if isinstance(tool, str) else ""
        if opts.tool_data is None:
            why = why or opts.other_tool(tool)
        elif not why:
            rows.tool[start:stop] = tool
        if why:
            for i in range(start, stop):
                rows.reason[i] = rows.reason[i] or why


def _protect_polar_starts(moves: GcodeMoves, rows: Rows) -> None:
    """A polar move that writes only its radius ``@`` or only its angle ``^`` takes the other
    from where the tool is, and so do the holes of a G91 polar cycle (their depth too: R from
    the initial level, Z from R): the moves that set its start (``_start_setters``) are not
    corrected, so it lands as programmed."""
    for i, (radius, angle) in moves.polar.items():
        g91_cycle = bool(moves.is_cycle[i] and moves.incremental[i])
        if radius is not None and angle is not None and not g91_cycle:
            continue
        why = f"sets the start of the polar move at line {moves.line[i]}, which is not corrected"
        for j in _start_setters(moves, i, [0, 1, 2] if g91_cycle else [0, 1]):
            if not rows.reason[j]:
                rows.reason[j] = why


def _protect_flow_start(moves: GcodeMoves, rows: Rows) -> None:
    """The moves read under O-word control flow (or a modal state not known) are left as
    written: a loop runs them again from where the last one ends, a subroutine from where it is
    called. So that they land as programmed, the moves that set where they start
    (``_start_setters``) are not corrected either."""
    first = moves.flow_from
    if first >= len(moves):
        return
    why = (
        f"sets the start of line {moves.line[first]}, read under control flow and left as "
        "written (it and the moves after it may run from elsewhere or again)"
    )
    for j in _start_setters(moves, first, [0, 1, 2]):
        if not rows.reason[j]:
            rows.reason[j] = why


def _start_setters(moves: GcodeMoves, i: int, axes: list[int]) -> list[int]:
    """The moves that set where move ``i`` starts on ``axes`` (0, 1, 2: X, Y, Z) and, for a
    canned-cycle block that continues a run, those that set its depth and R plane: the block
    before it (whose depth and R words are in effect) and the move that set the run's initial
    level (G98's retract, a G91 R's base)."""
    out = set(moves.setters[i, axes].tolist())
    if moves.is_cycle[i] and not moves.first_cycle[i]:
        run = i - 1
        out.add(run)
        while run > 0 and not moves.first_cycle[run]:
            run -= 1
        out.add(int(moves.setters[run, moves.cycle_axis[run]]))
    return sorted(out - {-1})


def _polar_edits(text, edits, moves, i, where, goals, changed, places) -> None:
    """The ``@`` radius and ``^`` angle of polar move ``i``, written so that it reaches
    ``goals`` (X, Y, Z mm, program frame) from ``cmd``, where the rewritten program leaves the
    tool (``where``: cmd and the move's end, whose X, Y are set here as LinuxCNC reads the words
    written). Only a move that writes both is rewritten (one word alone keeps its words): under
    G90 the goal's radius and angle, under G91 their differences from the tool's; the radius
    gets one decimal more than the file, the angle as many as keep the arc it rounds to a tenth
    of that, and each word keeps its text where its value does not change. A G90 polar cycle
    keeps its words."""
    cmd, end = where
    radius, angle = moves.polar[i]
    scale, inc = float(moves.scale[i]), bool(moves.incremental[i])
    values = [None if w is None else w.value for w in (radius, angle)]
    known = not (math.isnan(cmd[0]) or math.isnan(cmd[1]) or math.isnan(goals[0]))
    if radius is not None and angle is not None and known and (changed or inc):
        r_base = math.hypot(cmd[0], cmd[1]) if inc else 0.0
        a_base = math.degrees(math.atan2(cmd[1], cmd[0])) if inc else 0.0
        r_goal = math.hypot(goals[0], goals[1])
        r_new = (r_goal - r_base) / scale
        # the angle nearest the one written (no turn of 360 degrees added or lost)
        a_goal = math.degrees(math.atan2(goals[1], goals[0])) - a_base
        a_new = angle.value + (a_goal - angle.value + 180.0) % 360.0 - 180.0
        p = int(places[i]) + 1
        a_places = p + max(0, math.ceil(math.log10(max(r_goal / scale, 1e-9) * math.pi / 180)))
        for word, new, decimals, k in ((radius, r_new, p, 0), (angle, a_new, a_places, 1)):
            new_text = number_text(word.literal, word.value, new, decimals)
            if new_text is not word.literal:
                edits.append((word.start, word.end, new_text))
                values[k] = float(new_text)
    r = None if values[0] is None else values[0] * scale
    end[0], end[1] = polar_xy(cmd, r, values[1], inc)


def _repeated_holes(
    moves: GcodeMoves, rows: Rows, desired: np.ndarray, opts: Options, t: np.ndarray
) -> None:
    """A G91 cycle repeated L times moves by one increment to each hole: corrected only when
    every hole's correction is its first hole's within the written resolution. Otherwise it is
    not corrected (``desired`` back to the target; the reason says by how much they differ),
    and neither are the moves that set its start X and Y, so that its holes land as programmed
    (one increment cannot undo a corrected start for every hole)."""
    repeated = sorted(i for i, count in moves.repeats.items() if moves.incremental[i])
    if not repeated:
        return
    places = _places(moves, opts)
    for i in repeated:
        if rows.status[i] != CORRECTED:
            continue
        step = np.nan_to_num(moves.word_value[i, :3]) * moves.scale[i]
        step[moves.cycle_axis[i]] = 0.0  # the hole's position moves, not its depth
        k = np.arange(1, moves.repeats[i])[:, None]
        holes = moves.target[i] + k * step
        robot = transform_points(t, holes)
        abc = np.array([moves.rotaries[moves.rotary_index[i]].get(k, math.nan) for k in "ABC"])
        rotations = np.repeat(rotations_of(t[:3, :3], abc[None]), len(holes), axis=0)
        at = np.full(len(holes), i)
        corrected = correct_points(robot, rows, at, opts, rotations, mark=False)
        shift = rows_times(corrected - robot, t[:3, :3])
        spread = float(np.abs(shift - (desired[i] - moves.target[i])).max(initial=0.0))
        if spread <= moves.scale[i] * 10.0 ** -int(places[i]):
            continue
        why = "outside the grid" if math.isnan(spread) else f"differ by {spread:.4f} mm"
        rows.status[i] = SKIPPED
        rows.reason[i] = (
            f"G91 cycle repeated L{moves.repeats[i]}: one increment for all its holes, whose "
            f"corrections {why} (more than the written resolution); left as programmed"
        )
        desired[i] = moves.target[i]
    todo = [i for i in repeated if rows.status[i] != CORRECTED]
    while todo:  # the moves that set their start, and those of a cycle among them
        i = todo.pop()
        count = f"L{moves.repeats[i]}" if moves.repeats[i] else "an unknown number of times"
        why = (
            f"sets the start of the G91 cycle at line {moves.line[i]}, repeated {count}, which is "
            "not corrected"
        )
        axes = [k for k in range(3) if k != moves.cycle_axis[i]]
        for j in moves.setters[i, axes].tolist():
            if j >= 0 and rows.status[j] == CORRECTED:
                rows.status[j] = SKIPPED
                rows.reason[j] = why
                desired[j] = moves.target[j]
                if moves.incremental[j] and moves.repeats.get(j, 1) != 1:
                    todo.append(j)


def _corrected_r_planes(moves: GcodeMoves, rows: Rows, opts: Options, t: np.ndarray) -> np.ndarray:
    """(N,) corrected R plane (mm) of each corrected cycle that writes R (program frame ``t``
    (4, 4) in the robot frame); NaN: keep R.

    The R point is the hole's with R on the cycle's axis (Z in G17: (X, Y, R)); only its
    correction along that axis can be written (in its R word, or one added to its line)."""
    out = np.full(len(moves), np.nan)
    idx = np.flatnonzero(moves.is_cycle & ~np.isnan(moves.r_mm) & (rows.status == CORRECTED))
    if len(idx):
        pts = moves.target[idx].copy()
        k, axis = np.arange(len(idx)), moves.cycle_axis[idx]
        pts[k, axis] = moves.r_mm[idx]
        robot = transform_points(t, pts)
        corrected = correct_points(robot, rows, idx, opts, mark=False)
        back = rows_times(corrected - robot, t[:3, :3])
        out[idx] = pts[k, axis] + back[k, axis]  # NaN where the R point is outside: R kept
    return out


class _Commanded:
    """The walk's state between moves: ``cmd`` where the rewritten program leaves the tool (mm,
    NaN: unknown), the sticky cycle depth ``cycle_z`` and R plane ``r_cmd`` as written (mm),
    where each corrected move reaches (``reached_rows``, 3 per move, of the moves ``reached_at``)
    and the other edits of some moves (``extra``).
    """

    def __init__(self, fill: np.ndarray, extra: dict) -> None:
        self.fill = fill  # (N,) cycles read without a reason: may get Z, R words added
        self.extra = extra  # move -> its other edits [(start, end, new text)]
        self.cmd = [math.nan] * 3
        self.il = math.nan  # the initial level of the run of cycles (mm, as commanded)
        self.cycle_z = self.r_cmd = math.nan
        self.reached_rows = array("d")
        self.reached_at = array("q")


def _gcode_edits(
    text: str,
    moves: GcodeMoves,
    rows: Rows,
    goals: tuple[np.ndarray, np.ndarray],
    r_planes: np.ndarray,
    opts: Options,
    extra: dict[int, list[tuple[int, int, str]]],
) -> bytearray:
    """Walk the program with the commanded (rewritten) position; the new program's bytes.

    ``goals``: (desired, own) (N, 3) mm each: where each move's written axes should land and
    where it should land by its own correction (program frame; they differ where an arc's shift
    moves it), which the report's residual is measured from; ``r_planes`` (N,) mm: corrected R
    planes (NaN: keep); ``extra``: other edits by move, (start, end, new text) each (an arc's
    centre words). Stretches of absolute moves (none a G28/G30/G53, a G18/G19 cycle or one with
    ``extra`` edits) are done in bulk (``_bulk_block``), the rest move by move (``_walk_block``),
    where increments (which depend on what was written before) are formatted on the way."""
    desired, own = goals
    places = _places(moves, opts)
    corrected = rows.status == CORRECTED
    read = np.fromiter(map(bool, moves.reason), bool, len(moves)) if any(moves.reason) else False
    # the moves read under control flow are left as written (``_protect_flow_start``)
    flow = moves.flow_from
    extra = {i: e for i, e in extra.items() if i < flow}
    walked = moves.incremental | moves.resets | (moves.cycle_axis != 2)  # G18/G19 cycles too
    if extra:
        walked[list(extra)] = True
    out = ByteSplicer(text)
    walk = _Commanded(moves.is_cycle & ~read, extra)
    for first in range(0, flow, _BLOCK):
        for part, step in _stretches(moves, slice(first, min(first + _BLOCK, flow)), walked):
            out.add(*step(text, moves, part, corrected, desired, r_planes, places, walk))
    if walk.reached_at:
        at = np.frombuffer(walk.reached_at, dtype=np.int64)
        reached = np.frombuffer(walk.reached_rows, dtype=float).reshape(-1, 3)
        off = np.abs(reached - desired[at])
        residual = np.linalg.norm(reached - own[at], axis=1)
        wrote = _written(moves, at)
        off_written = np.where(wrote, off, 0.0)
        rounding = np.maximum(np.maximum(off_written[:, 0], off_written[:, 1]), off_written[:, 2])
        rows.new[at] = reached
        rows.residual_mm[at] = residual
        rows.rounding_mm[at] = rounding
        far = np.flatnonzero(residual > opts.tolerance_mm)
        if len(far):
            _too_far(rows, at[far], residual[far], wrote[far], opts.tolerance_mm)
        _dragged(moves, rows, flow, opts.tolerance_mm)
    return out.finish()


def _written(moves: GcodeMoves, at: np.ndarray) -> np.ndarray:
    """(M, 3) bool: the axes the lines of moves ``at`` (M,) write (a polar move writes X, Y)."""
    wrote = moves.word_start[at, :3] >= 0
    if moves.polar:
        wrote[:, :2] |= np.isin(at, np.fromiter(moves.polar, np.int64))[:, None]
    return wrote


def _dragged(moves: GcodeMoves, rows: Rows, flow: int, tol: float) -> None:
    """A move not corrected lands as programmed on the axes its line writes; one it does not
    write stays where the move that last wrote it left it. Where that move's words were
    rewritten (``rows.new`` known) and this leaves a commanded move (before control flow, row
    < ``flow``) farther than the tolerance ``tol`` (mm) from where it is programmed, its reason
    says so. A canned cycle's own axis after it (its retract level) is not counted."""
    idx = np.flatnonzero((rows.status[:flow] != CORRECTED) & rows.commanded[:flow])
    if not len(idx):
        return
    axes = np.arange(3)
    setter = np.where(_written(moves, idx), -1, moves.setters[idx])
    known = (setter >= 0) & np.isfinite(rows.new[np.maximum(setter, 0), axes])
    j = np.where(known, setter, 0)
    known &= ~(moves.is_cycle[j] & (moves.cycle_axis[j] == axes))
    off = np.where(known, rows.new[j, axes] - moves.target[j, axes], 0.0)
    distance = np.linalg.norm(off, axis=1)
    for k in np.flatnonzero(distance > tol).tolist():
        i = int(idx[k])
        letters = ", ".join(a for a, d in zip("XYZ", known[k].tolist(), strict=True) if d)
        dragged = (
            f"lands {distance[k]:.3f} mm from where it is programmed: the axes its line does not "
            f"write ({letters}) stay where corrected moves before it leave them"
        )
        rows.reason[i] = "; ".join(filter(None, (rows.reason[i], dragged)))


def _too_far(rows: Rows, far: np.ndarray, residual: np.ndarray, wrote: np.ndarray, tol) -> None:
    """Moves ``far`` (M,) whose axes written are corrected but that land ``residual`` (M,) mm
    from their correction, more than the tolerance ``tol`` (mm), because of the axes their lines
    do not write (``wrote`` (M, 3) bool): not called corrected, with the reason."""
    for i, r, written in zip(far.tolist(), residual.tolist(), wrote.tolist(), strict=True):
        axes = ", ".join(k for k, w in zip("XYZ", written, strict=True) if not w)
        why = (
            f"the axes its line does not write ({axes}) stay where the moves before it leave "
            "them (those it writes are corrected)"
            if axes
            else "it moves with the moves that set its start"
        )
        rows.status[i] = SKIPPED
        flag = rows.reason[i] and f"; {rows.reason[i]}"  # what the policy flagged
        rows.reason[i] = (
            f"lands {r:.3f} mm from its correction, more than the tolerance ({tol:g} mm): "
            f"{why}{flag}"
        )


_MIN_BULK = 256  # moves: a shorter stretch of absolute moves is walked with its neighbours


def _stretches(moves: GcodeMoves, block: slice, walked: np.ndarray):
    """(slice, step) of each stretch of the moves ``block``, in order: ``_bulk_block`` for runs
    of at least ``_MIN_BULK`` moves not ``walked`` (N,) (absolute moves that do not reset the
    position, nor polar), ``_walk_block`` for the moves between them."""
    walked = walked[block].copy()
    if moves.polar:  # polar moves are written from where the tool is
        polar = np.fromiter(moves.polar, np.int64, len(moves.polar))
        polar = polar[(polar >= block.start) & (polar < block.stop)] - block.start
        walked[polar] = True
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
        moves.cycle_axis[block].tolist(),
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
        axis,
    ) in enumerate(columns):
        if motion in RESETS:
            cmd = [math.nan] * 3
            continue
        if walk.extra and first + b in walk.extra:
            edits.extend(walk.extra[first + b])
        if is_cycle and moves.first_cycle[first + b]:
            walk.il = cmd[axis]
        if is_cycle and inc:
            r_goal = r_planes[first + b] if changed else math.nan
            reached, end, cycle_z, r_cmd = _incremental_cycle(
                text,
                edits,
                cmd,
                (starts, ends, values),
                goals,
                r_mm if math.isnan(r_goal) else r_goal,
                (scale, int(places[first + b]), retract, moves.repeats.get(first + b, 1)),
                (cycle_z, r_cmd, walk.il),
                changed,
                walk.fill[first + b],
                axis,
            )
            if changed:
                walk.reached_rows.extend(reached)
                walk.reached_at.append(first + b)
            if first + b in moves.polar:  # a polar cycle's holes turn about the origin
                radius, angle = (None if w is None else w.value for w in moves.polar[first + b])
                times = moves.repeats.get(first + b, 1)
                xy = polar_xy(cmd, radius and radius * scale, angle, True, times) if times else None
                end = [*(xy or (math.nan, math.nan)), end[2]]
            cmd = end
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
            # a word kept as written may be a parameter or an expression: its value as read
            written = (values[i] if new_text is old_text else float(new_text)) * scale
            if is_cycle and i == axis:
                cycle_z = written
            elif incremental:
                end[i] = cmd[i] + written
            else:
                end[i] = written
        if is_cycle and starts[3] >= 0:
            r_value = values[3]
            if r_texts[b] is not None and float(r_texts[b]) != values[3]:
                r_value = float(r_texts[b])
                edits.append((starts[3], ends[3], r_texts[b]))
            r_cmd = r_value * scale
        if first + b in moves.polar:
            _polar_edits(text, edits, moves, first + b, (cmd, end), goals, changed, places)
        if walk.fill[first + b] and (starts[axis] < 0 or starts[3] < 0):
            r_goal = r_planes[first + b] if changed else math.nan
            spans = (starts, ends)
            if first + b in moves.polar:  # added after the polar words too
                polar = [w for w in moves.polar[first + b] if w is not None]
                spans = (starts + [w.start for w in polar], ends + [w.end for w in polar])
            cycle_z, r_cmd = _added_words(
                text,
                edits,
                spans,
                (goals[axis], r_mm if math.isnan(r_goal) else r_goal),
                (cycle_z, r_cmd),
                (scale, int(places[first + b]), axis),
            )
        if is_cycle:
            reached = list(end)
            reached[axis] = cycle_z
            if inc or math.isnan(r_mm):
                end[axis] = math.nan
            elif retract == "G99":
                end[axis] = r_cmd
            else:
                end[axis] = max(walk.il, r_cmd)
        else:
            reached = end
        if changed:
            walk.reached_rows.extend(reached)
            walk.reached_at.append(first + b)
        cmd = end
    walk.cmd, walk.cycle_z, walk.r_cmd = cmd, cycle_z, r_cmd
    edits.sort(key=lambda e: e[:2])  # stable: the words added at one place stay in order
    starts = np.array([e[0] for e in edits], np.int64)
    ends = np.array([e[1] for e in edits], np.int64)
    texts = [e[2] for e in edits]
    lengths = np.fromiter(map(len, texts), np.int64, len(texts))
    return starts, ends, np.frombuffer("".join(texts).encode("ascii"), np.uint8), lengths


def _added_words(text, edits, spans, goals, sticky, how):
    """The depth and R words a cycle's line needs but does not write: where the hole bottom and
    R plane it should reach (``goals``, absolute mm) differ from the depth and R plane in effect
    (``sticky``, mm, as written), `` Z..``/`` R..`` (the depth's letter: the cycle's axis) are
    added after its last position word (in the case of its letters). ``spans``: the line's
    (starts, ends) of X, Y, Z, R (and of its polar words after them); ``how``: (mm per unit,
    decimals, the cycle's axis). Adds the edit to ``edits``; the depth and R plane now in effect
    (mm)."""
    starts, ends = spans
    scale, places, axis = how
    sticky, added = list(sticky), []
    for n, (k, letter) in enumerate(((axis, "XYZ"[axis]), (3, "R"))):
        if starts[k] >= 0 or math.isnan(goals[n]):
            continue
        new_text = fixed(goals[n] / scale, places)
        if float(new_text) * scale != sticky[n]:
            added.append(letter + new_text)
            sticky[n] = float(new_text) * scale
    if added:  # one edit: " Z.. R.." after the line's last position word
        words = " " + " ".join(added)
        lower = _lower_case(text, np.asarray(starts))
        edits.append((max(ends), max(ends), words.lower() if lower else words))
    return sticky[0], sticky[1]


def _incremental_cycle(text, edits, cmd, words, goal, r_goal, how, sticky, changed, fill, axis):
    """One G91 canned-cycle block, written so that its first hole reaches ``goal`` and its R
    plane ``r_goal`` (absolute mm, program frame) from where the rewritten program leaves the
    tool (``cmd``): the hole's position (X, Y in G17) as increments from ``cmd``, R from the
    initial level, the depth (Z in G17; on the cycle's ``axis``) from R (as LinuxCNC reads
    them). ``words``: the block's (starts, ends, values) of X, Y, Z, R; ``how``:
    (mm per unit, decimals, retract, L repeats); ``sticky``: the Z and R words in effect (mm, as
    written) and the initial level (mm).
    A repeated block not ``changed`` (corrected) keeps its X, Y step as written; with ``fill``
    (a line read without a reason) the R and Z words it needs but does not write are added.
    Adds the edits to ``edits``; (the first hole's bottom, where the block leaves the tool, the
    Z and R words now in effect), mm. Where ``cmd`` or a goal is not known a word is kept."""
    starts, ends, values = words
    scale, places, retract, repeats = how
    cycle_z, r_cmd, il = sticky

    def write(i: int, base: float, want: float) -> float:
        """Word ``i`` as the increment from ``base`` to ``want``; its value (mm) written."""
        old_text = new_text = text[starts[i] : ends[i]]
        if not (math.isnan(base) or math.isnan(want)):
            new_text = number_text(old_text, values[i], (want - base) / scale, places)
        if new_text != old_text:
            edits.append((starts[i], ends[i], new_text))
        return (values[i] if new_text is old_text else float(new_text)) * scale

    fixed_step = repeats != 1 and not changed  # its start is as programmed: so is its step

    def add(letter: str, base: float, want: float, sticky: float) -> float:
        """The word the line needs but does not write, added where it differs from ``sticky``
        (mm, as written); the value (mm) in effect."""
        if not fill or math.isnan(base) or math.isnan(want):
            return sticky
        new_text = fixed((want - base) / scale, places)
        if float(new_text) * scale == sticky:
            return sticky
        lower = _lower_case(text, np.asarray(starts))
        edits.append((max(ends), max(ends), " " + (letter.lower() if lower else letter) + new_text))
        return float(new_text) * scale

    step = [
        (values[i] * scale if fixed_step else write(i, cmd[i], goal[i]))
        if starts[i] >= 0 and i != axis
        else 0.0
        for i in range(3)
    ]
    if starts[3] >= 0:
        r_cmd = write(3, il, r_goal)
    else:
        r_cmd = add("R", il, r_goal, r_cmd)
    level = il + r_cmd  # the R plane reached
    if starts[axis] >= 0:
        cycle_z = write(axis, level, goal[axis])
    else:
        cycle_z = add("XYZ"[axis], level, goal[axis], cycle_z)
    hole = [cmd[i] + step[i] for i in range(3)]
    hole[axis] = level + cycle_z
    times = repeats if repeats else math.nan  # 0: not known
    end = [cmd[i] + times * step[i] for i in range(3)]
    end[axis] = level if retract == "G99" else max(il, level)
    return hole, end, cycle_z, r_cmd


def _bulk_block(text, moves, block, corrected, desired, r_planes, places, walk):
    """``_walk_block`` in bulk for a block whose moves are all absolute (none resets the
    position): every number is formatted and compared at once, X and Y carried forward where a
    move does not write them, the Z and R words a cycle's line needs added (``_added_words``),
    and only the Z ends that depend on the previous one (a G98 retract, the higher of the
    previous end and R; a straight move without Z) are carried one by one."""
    n = len(moves.motion[block])
    scale = moves.scale[block]
    values = moves.word_value[block]
    cycle = moves.is_cycle[block]
    wrote = moves.word_start[block] >= 0  # (n, 4) X, Y, Z, R written
    wrote_r = cycle & wrote[:, 3]
    r_mm = moves.r_mm[block]
    fill = walk.fill[block]
    # the numbers in program units (NaN: keep): the corrected X, Y, Z, R words, then the Z and R
    # a cycle's line needs where it does not write them (added if they differ from those in
    # effect)
    goal = np.full((n, 6), np.nan)
    fix = corrected[block, None] & wrote[:, :3]
    goal[:, :3] = np.where(fix, desired[block] / scale[:, None], np.nan)
    goal[:, 3] = np.where(wrote_r, r_planes[block] / scale, np.nan)
    goal[:, 4] = np.where(fill & ~wrote[:, 2], desired[block, 2] / scale, np.nan)
    r_need = np.where(corrected[block] & ~np.isnan(r_planes[block]), r_planes[block], r_mm)
    goal[:, 5] = np.where(fill & ~wrote[:, 3], r_need / scale, np.nan)
    goal = goal.ravel()
    new = np.full(6 * n, np.nan)  # the value each new text reads as
    place = np.repeat(places[block], 6)
    # the texts fixed gives and the values they read as, from the formatter's array form: the
    # texts' bytes of each count of places, and each number's group and row in them
    cells_of, group, row = [], np.full(6 * n, -1, np.int64), np.empty(6 * n, np.int64)
    for p in distinct_ints(place):
        idx = np.flatnonzero(np.isfinite(goal) & (place == p))
        if not len(idx):
            continue
        cells, new[idx] = fixed_bytes(goal[idx], p)
        group[idx], row[idx] = len(cells_of), np.arange(len(idx))
        cells_of.append(cells)
    new = new.reshape(n, 6)
    edit = np.zeros((n, 6), bool)
    edit[:, :4] = np.isfinite(new[:, :4]) & (new[:, :4] != values)
    written = np.where(edit[:, :4], new[:, :4], values) * scale[:, None]  # NaN: none
    added = new[:, 4:] * scale[:, None]  # NaN: none
    sticky = []  # the depth and R plane in effect after each move, each word added where needed
    for k, wrote_k, before in ((2, cycle & wrote[:, 2], walk.cycle_z), (3, wrote_r, walk.r_cmd)):
        value = np.where(wrote_k, written[:, k], added[:, k - 2])
        after = modal_fill(value, wrote_k | ~np.isnan(added[:, k - 2]), before)
        edit[:, k + 2] = ~np.isnan(added[:, k - 2]) & (
            added[:, k - 2] != np.append(before, after[:-1])
        )
        sticky.append(after)
    cycle_z, r_cmd = sticky
    end = np.empty((n, 3))
    for i in range(2):  # X, Y: as written, else where the previous move left them
        end[:, i] = modal_fill(written[:, i], wrote[:, i], walk.cmd[i])
    # Z: a straight move's as written; a cycle's retract: nothing known without an R plane,
    # R under G99, the higher of the previous end and R under G98
    g99 = moves.g99[block]
    end[:, 2] = np.where(cycle, np.where(np.isnan(r_mm), np.nan, r_cmd), written[:, 2])
    starts_run = moves.first_cycle[block]
    carried = (cycle & ~g99 & ~np.isnan(r_mm)) | ~(cycle | wrote[:, 2]) | starts_run
    if carried.any():  # those that depend on the previous end (or set the initial level)
        z, r, hole = end[:, 2].tolist(), r_cmd.tolist(), cycle.tolist()
        run_start, high = starts_run.tolist(), (~g99 & ~np.isnan(r_mm)).tolist()
        for k in np.flatnonzero(carried).tolist():
            before = z[k - 1] if k else walk.cmd[2]
            if not hole[k]:
                z[k] = before
                continue
            if run_start[k]:
                walk.il = before
            if high[k]:
                z[k] = max(walk.il, r[k])
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
    # where each edit goes: a word's number, or (the words added to a line, one edit) after the
    # line's last word
    added = edit[:, 4:].copy()  # (n, 2) the Z, R words added to each line
    edit[:, 4], edit[:, 5] = added.any(axis=1), False
    spans = np.empty((n, 6, 2), np.int64)
    spans[:, :4, 0], spans[:, :4, 1] = moves.word_start[block], moves.word_end[block]
    spans[:, 4:, :] = moves.word_end[block].max(axis=1)[:, None, None]
    at = np.flatnonzero(edit.ravel())
    starts = spans[:, :, 0].ravel()[at]
    order = np.argsort(starts, kind="stable")
    at = at[order]
    # the new texts in the edits' order, as rows of cells (NULs are dropped): a number's cells
    # end at column 2 + width; added words are " Z" and its cells, then " R" and its cells (the
    # rows only as wide as a number's where no word is added: half the cells to read back)
    width = max((c.shape[1] for c in cells_of), default=1)
    adds = np.flatnonzero(at % 6 == 4)
    rows = np.zeros((len(at), 4 + 2 * width if len(adds) else 2 + width), np.uint8)

    def put(mine: np.ndarray, numbers: np.ndarray, stop: int) -> None:
        """The cells of the numbers ``numbers`` (flat indices) into ``rows[mine]``, ending at
        column ``stop``."""
        for g, cells in enumerate(cells_of):
            sel = group[numbers] == g
            rows[mine[sel], stop - cells.shape[1] : stop] = cells[row[numbers[sel]]]

    words = np.flatnonzero(at % 6 < 4)
    put(words, at[words], 2 + width)
    if len(adds):
        k = at[adds] // 6
        lower = 32 * _lower_cases(text, moves, block.start + k)
        for col, letter in enumerate((ord("Z"), ord("R"))):
            has = added[k, col]
            mine, stop = adds[has], (col + 1) * (2 + width)
            rows[mine, stop - width - 2] = ord(" ")
            rows[mine, stop - width - 1] = letter + lower[has]
            put(mine, at[mine] + col, stop)
    ends = spans[:, :, 1].ravel()[at]
    return starts[order], ends, *texts_of(rows)


def _lower_cases(text: str, moves: GcodeMoves, lines: np.ndarray) -> np.ndarray:
    """``_lower_case`` of the moves ``lines`` (M,) as 0/1 (M,) uint8: the byte before each
    first number, the line read again only where that is a blank."""
    starts = moves.word_start[lines]
    first = np.where(starts >= 0, starts, np.iinfo(np.int64).max).min(axis=1)
    before = np.frombuffer(
        "".join(map(text.__getitem__, (first - 1).tolist())).encode("latin-1", "replace"), np.uint8
    )
    lower = ((before >= ord("a")) & (before <= ord("z"))).astype(np.uint8)
    for k in np.flatnonzero((before == ord(" ")) | (before == ord("\t"))).tolist():
        lower[k] = _lower_case(text, starts[k])
    return lower


def _lower_case(text: str, starts) -> bool:
    """Whether the letter of a line's first position word (``starts``: its X, Y, Z, R number
    starts, -1: none) is lower case."""
    letter_at = min(a for a in starts.tolist() if a >= 0) - 1
    while text[letter_at] in " \t":
        letter_at -= 1
    return text[letter_at].islower()


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
