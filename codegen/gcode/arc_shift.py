"""Arcs in a G-code rewrite: each G2/G3 arc (or helix) moves rigidly, its start, centre and end
shifted together by one vector written exactly in the program's decimals, so its radius is kept
exactly (as ``rs274`` checks it) and its shape is the programmed one.

The shift of an arc is the correction at its centre (the helix axis halfway), rounded to the
written resolution (``q``, one unit of the last decimal), provided every point of the arc (start,
end, centre and points along it: ``arc.arc_samples``), moved by it, lands within ``q`` of its own
correction, per axis; otherwise the arc is reported with by how much its correction varies. Arcs
that share an axis (below) take the mean of their centres' corrections on it, rounded and, where
needed, moved to the nearest value that holds every point of each of them within ``q``. The moves
that set the arc's start (the last move to write each of X, Y, Z before it) get the same shift on
that axis, so arcs chained end to start, helices of an orbital hole and arcs that share one plunge
move share their shift on the axes they share: where those arcs' corrections cannot agree on one
value, they are all reported, and so are the moves that set their start (which then stay as
programmed, like the arcs). Under G90.1 the centre words (absolute) get the shift too; under G91.1
(from the start) they stay as written. Under G91 the increments are those of the shifted positions
(``codegen.gcode.rewrite`` recomputes them). Arcs are not split.
"""

from __future__ import annotations

import math

import numpy as np

from accugrid.codegen.gcode.arc import PLANE_AXES, arc_centres, arc_samples
from accugrid.codegen.gcode.parse import AXES, GcodeMoves
from accugrid.codegen.plugin_types import CORRECTED, SKIPPED, Options, Rows
from accugrid.codegen.rewrite import correct_points, rotations_of
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import rows_times, transform_points

__all__ = ["shift_arcs"]

_EPS = 1e-9  # program units: slack on the rounding grid


def shift_arcs(
    moves: GcodeMoves,
    rows: Rows,
    goals: np.ndarray,
    places: np.ndarray,
    opts: Options,
    robot_T_program: np.ndarray,
) -> dict[int, list[tuple[int, int, str]]]:
    """Shift every arc that can move rigidly (see the module docstring): ``goals`` (N, 3) mm,
    where each move's written axes should land, is set for the arcs and the moves that set their
    start (the arcs' and those moves' own corrections, as decided, are in ``goals`` on entry);
    arcs that cannot move and the moves that set their start get status skipped, the reason,
    and their programmed position back. ``places`` (N,): decimals written per move;
    ``robot_T_program`` (4, 4): the program frame in the robot frame. The edits
    of G90.1 centre words, by move: [(start, end, new text)].

    The nodes are (move, axis): an arc's end on each axis and the move that sets its start
    there, joined into components that move by one value; the components that share a move are
    one group, corrected or left as one (``_Nodes``). Every check is done on arrays; only the
    groups left get their reasons one by one."""
    arcs = np.array(sorted(moves.arcs), np.int64)
    if not len(arcs):
        return {}
    nodes = _Nodes(moves, arcs)
    fit = _ArcFit(moves, rows, arcs, opts, robot_T_program)
    move, axis, comp = nodes.move, nodes.axis, nodes.comp
    at = np.minimum(np.searchsorted(arcs, move), len(arcs) - 1)
    is_arc = arcs[at] == move
    at = np.where(is_arc, at, 0)  # the arc's row of an arc's node
    ok = (rows.status[move] == CORRECTED) & np.where(is_arc, fit.ok[at], ~moves.is_cycle[move])
    scale, written = moves.scale[move], places[move]
    ok &= _exact(moves.word_value[move, axis], written)
    count = nodes.count
    comp_ok = np.ones(count, bool)
    np.logical_and.at(comp_ok, comp, ok)
    for column in (scale, written):  # one unit and one count of decimals per component
        low, high = np.full(count, np.inf), np.full(count, -np.inf)
        np.minimum.at(low, comp, column)
        np.maximum.at(high, comp, column)
        comp_ok &= low == high
    comp_q = np.ones(count)
    comp_q[comp] = 10.0 ** -written.astype(float)
    # the shifts every point of every arc of a component allows, and its centres' mean
    top, bottom = np.full(count, -np.inf), np.full(count, np.inf)
    total, arcs_in = np.zeros(count), np.zeros(count)
    on_arc = np.flatnonzero(is_arc)
    c_arc, a_arc, k_arc = comp[on_arc], at[on_arc], axis[on_arc]
    np.maximum.at(top, c_arc, np.nan_to_num(fit.high[a_arc, k_arc], nan=np.inf))
    np.minimum.at(bottom, c_arc, np.nan_to_num(fit.low[a_arc, k_arc], nan=-np.inf))
    np.add.at(total, c_arc, np.nan_to_num(fit.centre[a_arc, k_arc]))
    np.add.at(arcs_in, c_arc, 1.0)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        lo = np.ceil((top - comp_q) / comp_q - _EPS)
        hi = np.floor((bottom + comp_q) / comp_q + _EPS)
        value = np.clip(np.round(total / arcs_in / comp_q), lo, hi) * comp_q
    comp_ok &= lo <= hi
    group_ok = np.ones(nodes.groups, bool)
    np.logical_and.at(group_ok, nodes.group_of_comp, comp_ok)
    group = nodes.group_of_comp[comp]  # of each node
    edits: dict[int, list[tuple[int, int, str]]] = {}
    absolute = [j for j in arcs.tolist() if moves.arcs[j].absolute]
    if absolute:  # G90.1 centres: their words move too
        for g in sorted(set(group[np.isin(move, absolute) & group_ok[group]].tolist())):
            mine = np.flatnonzero((group == g) & is_arc)
            keys = zip(move[mine].tolist(), axis[mine].tolist(), strict=True)
            shift = dict(zip(keys, value[comp[mine]].tolist(), strict=True))
            found: dict[int, list[tuple[int, int, str]]] = {}
            why, culprit = _centre_edits(moves, places, sorted(shift), shift, found)
            if why:
                group_ok[g] = False
                _leave(moves, rows, goals, nodes.members(g), why, culprit)
            else:
                edits.update(found)
    good = group_ok[group]
    goals[move[good], axis[good]] = (
        moves.target[move[good], axis[good]] + value[comp[good]] * scale[good]
    )
    for g in np.flatnonzero(~group_ok).tolist():  # their reasons, one by one
        members = nodes.members(g)
        why, culprit = "its arcs cannot move as one", min(j for j, _ in members if j in moves.arcs)
        for c in sorted(set(comp[group == g].tolist()), key=nodes.first_move):
            mine = nodes.component(c)
            found = _component_why(moves, rows, places, fit, mine, mine[0][1])
            if found[0]:
                why, culprit = found
                break
        _leave(moves, rows, goals, members, why, culprit)  # every one left goes back
    return edits


def _exact(values, places):
    """Whether each word value (program units; NaN: none written) is a whole number of units of
    its ``places``-th decimal (a shift by such a number writes it exactly)."""
    scaled = np.asarray(values) * 10.0 ** np.asarray(places, float)
    return np.isnan(scaled) | (np.abs(scaled - np.round(scaled)) < 1e-6)


class _Nodes:
    """The nodes (move, axis) of the arcs ``arcs`` (move indices, sorted) and of the moves that
    set their starts: ``move``, ``axis`` (M,) and ``comp`` (M,) the component of each (what
    moves by one value: an arc's start and end on an axis, an end that is the next arc's start,
    a move that sets the start of several arcs), ``count`` components, each in one of
    ``groups`` groups (``group_of_comp``): components that share a move are one group."""

    def __init__(self, moves: GcodeMoves, arcs: np.ndarray) -> None:
        # imported here: scipy.sparse costs a G-code rewrite without arcs 0.16 s of start-up
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        setters = moves.setters[arcs]  # (A, 3)
        ends = 3 * arcs[:, None] + np.arange(3)
        begins = np.where(setters >= 0, 3 * setters + np.arange(3), ends)
        both = np.concatenate([ends.ravel(), begins.ravel()])
        ids, inverse = np.unique(both, return_inverse=True)
        m, half = len(ids), len(ends.ravel())
        self.move, self.axis = ids // 3, ids % 3
        edges = coo_matrix((np.ones(half), (inverse[:half], inverse[half:])), shape=(m, m))
        self.count, self.comp = connected_components(edges, directed=False)
        first = np.unique(self.move, return_index=True)[1]  # one node of each move
        mate = first[np.searchsorted(self.move[first], self.move)]
        shared = (np.ones(m), (self.comp[mate], self.comp))
        self.groups, self.group_of_comp = connected_components(
            coo_matrix(shared, shape=(self.count, self.count)), directed=False
        )

    def members(self, g: int) -> list[tuple[int, int]]:
        """The nodes of group ``g`` as (move, axis), in order."""
        k = np.flatnonzero(self.group_of_comp[self.comp] == g)
        return sorted(zip(self.move[k].tolist(), self.axis[k].tolist(), strict=True))

    def component(self, c: int) -> list[tuple[int, int]]:
        """The nodes of component ``c`` as (move, axis), in order."""
        k = np.flatnonzero(self.comp == c)
        return sorted(zip(self.move[k].tolist(), self.axis[k].tolist(), strict=True))

    def first_move(self, c: int) -> int:
        return int(self.move[self.comp == c].min())


class _ArcFit:
    """The corrections across the arcs ``arcs`` (move indices, sorted), in program units on each
    program axis: ``low``, ``high`` (A, 3) the smallest and largest over each arc's samples,
    ``centre`` (A, 3) at its centre (the helix axis halfway); ``ok`` (A,): its start is known,
    its own end correction accepted and every sample corrected (NaN rows otherwise)."""

    def __init__(
        self, moves: GcodeMoves, rows: Rows, arcs: np.ndarray, opts: Options, t: np.ndarray
    ) -> None:
        self.arcs = arcs
        self.ok = np.isfinite(moves.start[arcs]).all(axis=1) & (rows.status[arcs] == CORRECTED)
        self.low, self.high, self.centre = (np.full((len(arcs), 3), np.nan) for _ in range(3))
        use = np.flatnonzero(self.ok)
        if not len(use):
            return
        idx = arcs[use]
        words = [moves.arcs[i] for i in idx.tolist()]
        start, end, scale = moves.start[idx], moves.target[idx], moves.scale[idx]
        centre = arc_centres(words, start, end, scale)
        helix = np.array([PLANE_AXES[a.plane][2] for a in words])
        n = np.arange(len(idx))
        centre[n, helix] = (start[n, helix] + end[n, helix]) / 2
        points, owner = arc_samples(words, start, end, centre)
        points = np.concatenate([centre, points])
        owner = np.concatenate([n, owner])
        robot = transform_points(t, points)
        abc = np.array([[r.get(k, math.nan) for k in "ABC"] for r in moves.rotaries])
        rotations = rotations_of(t[:3, :3], abc.reshape(-1, 3))[moves.rotary_index[idx[owner]]]
        corrected = correct_points(robot, rows, idx[owner], opts, rotations, mark=False)
        shift = rows_times(corrected - robot, t[:3, :3]) / scale[owner, None]  # program units
        bad = np.zeros(len(idx), bool)
        np.logical_or.at(bad, owner, np.isnan(shift[:, 0]))
        low = np.full((len(idx), 3), np.inf)
        high = np.full((len(idx), 3), -np.inf)
        np.minimum.at(low, owner, shift)
        np.maximum.at(high, owner, shift)
        fine = ~bad
        self.low[use[fine]], self.high[use[fine]] = low[fine], high[fine]
        self.centre[use[fine]] = shift[: len(idx)][fine]
        self.ok[use[bad]] = False

    def row(self, arc: int) -> int:
        """The row of the arc (a move index) ``arc``."""
        return int(np.searchsorted(self.arcs, arc))


def _component_why(moves, rows, places, fit, members, axis):
    """Why one axis's component (the nodes (move, axis) that must move by one value: the arcs'
    ends and the moves that set their starts) cannot move, and the arc (move index) it is
    about; ("", -1) when it can."""
    arcs = sorted({j for j, _ in members if j in moves.arcs})
    for j, _ in sorted(members):
        if j in moves.arcs:
            if rows.status[j] != CORRECTED:
                return rows.reason[j] or "not corrected", j
            if not np.isfinite(moves.start[j]).all():
                return "its start is not known", j
            if not fit.ok[fit.row(j)]:
                return "part of the arc is outside the grid or refused by the policy", j
        elif rows.status[j] != CORRECTED or moves.is_cycle[j]:
            what = "a canned cycle" if moves.is_cycle[j] else "not corrected"
            return f"its start is set at line {moves.line[j]}, {what}", arcs[0]
    scales = {float(moves.scale[j]) for j, _ in members}
    decimals = {int(places[j]) for j, _ in members}
    if len(scales) > 1 or len(decimals) > 1:
        return "its start is written in other units or decimals", arcs[0]
    scale, written = scales.pop(), decimals.pop()
    q = 10.0**-written
    text = moves.text
    for j, k in members:
        if not _exact(moves.word_value[j, k], written):
            a, b = int(moves.word_start[j, k]), int(moves.word_end[j, k])
            why = (
                f"{AXES[k]}{text[a:b]} at line {moves.line[j]} has more decimals than the "
                f"{written} written: the arc cannot move exactly"
            )
            return why, arcs[0]
    top = max(fit.high[fit.row(i), axis] for i in arcs)
    bottom = min(fit.low[fit.row(i), axis] for i in arcs)
    lo, hi = math.ceil((top - q) / q - _EPS), math.floor((bottom + q) / q + _EPS)
    if lo > hi:
        what = "the arc" if len(arcs) == 1 else f"the {len(arcs)} arcs that share this axis"
        why = (
            f"the {AXES[axis]} correction varies by {(top - bottom) * scale:.4f} mm across "
            f"{what}: no one shift holds every point within the written {q * scale:g} mm"
        )
        return why, arcs[0]
    return "", -1


def _centre_edits(moves, places, group, shift, edits):
    """Add the G90.1 arcs' centre word edits of ``group`` to ``edits``; ("", -1), or why not and
    the arc (move index) when a centre word the shift needs is not written."""
    for i, k in group:
        arc = moves.arcs.get(i)
        if arc is None or not arc.absolute or k == PLANE_AXES[arc.plane][2]:
            continue
        word = arc.centre[k]
        if word is None:
            return f"its absolute (G90.1) centre has no {'IJK'[k]} word to move it by", i
        value = word.value + shift[(i, k)]
        new = fixed(value, max(int(places[i]), word.decimals))
        if float(new) != word.value:
            edits.setdefault(i, []).append((word.start, word.end, new))
    return "", -1


def _leave(moves, rows, goals, group, why, culprit) -> None:
    """The arcs of ``group`` and the moves that set their starts stay as programmed, reported:
    the arc ``culprit`` (a move index) with ``why``, the others as chained to it."""
    arcs = sorted({j for j, _ in group if j in moves.arcs})
    line = int(moves.line[culprit])
    for j in sorted({j for j, _ in group}):
        if j in moves.arcs:
            if rows.status[j] == CORRECTED:
                rows.status[j] = SKIPPED
            if rows.status[j] == SKIPPED and not rows.reason[j]:
                rows.reason[j] = (
                    why if j == culprit else f"chained to the arc at line {line}: {why}"
                )
        elif rows.status[j] == CORRECTED:
            first = next((i for i in arcs if i > j), arcs[-1])
            rows.status[j] = SKIPPED
            rows.reason[j] = (
                f"sets the start of the arc at line {moves.line[first]}, which is not corrected"
            )
        goals[j] = moves.target[j]
