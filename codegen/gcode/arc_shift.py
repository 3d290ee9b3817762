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
from accugrid.codegen.program_text import decimals_of
from accugrid.codegen.rewrite import CORRECTED, SKIPPED, Options, Rows, correct_points, rotations_of
from accugrid.infra.textsafe import fixed
from accugrid.kinematics.frames import rows_times, transform_points

__all__ = ["shift_arcs"]

_EPS = 1e-9  # program units: slack on the rounding grid


def shift_arcs(
    moves: GcodeMoves, rows: Rows, goals: np.ndarray, places: np.ndarray, opts: Options
) -> dict[int, list[tuple[int, int, str]]]:
    """Shift every arc that can move rigidly (see the module docstring): ``goals`` (N, 3) mm,
    where each move's written axes should land, is set for the arcs and the moves that set their
    start (the arcs' and those moves' own corrections, as decided, are in ``goals`` on entry);
    arcs that cannot move and the moves that set their start get status skipped, the reason,
    and their programmed position back. ``places`` (N,): decimals written per move. The edits
    of G90.1 centre words, by move: [(start, end, new text)]."""
    arcs = sorted(moves.arcs)
    if not arcs:
        return {}
    nodes = _Nodes()
    for i in arcs:
        for k in range(3):
            j = int(moves.setters[i, k])
            nodes.join((i, k), (j, k) if j >= 0 else (i, k))
    # components (their roots) joined through the moves they hold (an arc's three axes, the axes
    # a move sets for different arcs): a group moves as one or stays as programmed as one
    groups = _Nodes()
    first_root: dict[int, tuple] = {}
    for node in list(nodes.parent):
        root = nodes.root(node)
        groups.join(first_root.setdefault(node[0], root), root)
    known = [i for i in arcs if np.isfinite(moves.start[i]).all()]
    fit = _ArcFit(moves, rows, [i for i in known if rows.status[i] == CORRECTED], opts)
    members: dict = {}  # component root -> its nodes
    for node in nodes.parent:
        members.setdefault(nodes.root(node), []).append(node)
    by_group: dict = {}
    for root in members:
        by_group.setdefault(groups.root(root), []).append(root)
    edits: dict[int, list[tuple[int, int, str]]] = {}
    for components in by_group.values():
        shifts, why, at = {}, "", -1
        for root in sorted(components, key=lambda r: min(members[r])):
            value, why, at = _component_shift(moves, rows, places, fit, members[root], root[1])
            if why:
                break
            shifts[root] = value
        group = sorted({node for root in components for node in members[root]})
        shift = {node: shifts[nodes.root(node)] for node in group} if not why else {}
        centre_edits: dict[int, list[tuple[int, int, str]]] = {}
        if not why:
            why, at = _centre_edits(moves, places, group, shift, centre_edits)
        if why:
            _leave(moves, rows, goals, group, why, at)
            continue
        for (j, k), value in shift.items():
            goals[j, k] = moves.target[j, k] + value * moves.scale[j]
        edits.update(centre_edits)
    return edits


class _Nodes:
    """Union-find of hashable nodes."""

    def __init__(self) -> None:
        self.parent: dict = {}

    def root(self, node):
        parent = self.parent.setdefault(node, node)
        while parent != node:
            grand = self.parent[parent]
            self.parent[node] = grand
            node, parent = parent, grand
        return node

    def join(self, a, b) -> None:
        ra, rb = self.root(a), self.root(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


class _ArcFit:
    """The corrections across the arcs ``arcs`` (indices of moves, whose own end correction the
    policy accepted), in program units on each program axis: ``low``, ``high`` (3,) the smallest
    and largest over each arc's samples and ``centre`` (3,) at its centre (the helix axis
    halfway), by move; an arc with a sample not corrected has none (absent)."""

    def __init__(self, moves: GcodeMoves, rows: Rows, arcs: list[int], opts: Options) -> None:
        self.low: dict[int, np.ndarray] = {}
        self.high: dict[int, np.ndarray] = {}
        self.centre: dict[int, np.ndarray] = {}
        if not arcs:
            return
        idx = np.array(arcs, np.int64)
        words = [moves.arcs[i] for i in arcs]
        start, end, scale = moves.start[idx], moves.target[idx], moves.scale[idx]
        centre = arc_centres(words, start, end, scale)
        helix = np.array([PLANE_AXES[a.plane][2] for a in words])
        rows_n = np.arange(len(idx))
        centre[rows_n, helix] = (start[rows_n, helix] + end[rows_n, helix]) / 2
        points, owner = arc_samples(words, start, end, centre)
        points = np.concatenate([centre, points])
        owner = np.concatenate([rows_n, owner])
        t = opts.robot_T_program
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
        for n, i in enumerate(arcs):
            if not bad[n]:
                self.low[i], self.high[i], self.centre[i] = low[n], high[n], shift[n]


def _component_shift(moves, rows, places, fit, members, axis):
    """The shift (program units) of one axis's component: the nodes (move, axis) that must move
    by one value (the arcs' ends and the moves that set their starts); (value, "", -1) or
    (nan, why, the arc it is about)."""
    arcs = sorted({j for j, _ in members if j in moves.arcs})
    for j, _ in sorted(members):
        if j in moves.arcs:
            if rows.status[j] != CORRECTED:
                return math.nan, rows.reason[j] or "not corrected", j
            if not np.isfinite(moves.start[j]).all():
                return math.nan, "its start is not known", j
            if j not in fit.low:
                return math.nan, "part of the arc is outside the grid or refused by the policy", j
        elif rows.status[j] != CORRECTED or moves.is_cycle[j]:
            what = "a canned cycle" if moves.is_cycle[j] else "not corrected"
            return math.nan, f"its start is set at line {moves.line[j]}, {what}", arcs[0]
    scales = {float(moves.scale[j]) for j, _ in members}
    decimals = {int(places[j]) for j, _ in members}
    if len(scales) > 1 or len(decimals) > 1:
        return math.nan, "its start is written in other units or decimals", arcs[0]
    scale, written = scales.pop(), decimals.pop()
    q = 10.0**-written
    text = moves.text
    for j, k in members:
        a, b = int(moves.word_start[j, k]), int(moves.word_end[j, k])
        if a >= 0 and decimals_of(text[a:b]) > written:
            why = (
                f"{AXES[k]}{text[a:b]} at line {moves.line[j]} has more decimals than the "
                f"{written} written: the arc cannot move exactly"
            )
            return math.nan, why, arcs[0]
    top = max(fit.high[i][axis] for i in arcs)
    bottom = min(fit.low[i][axis] for i in arcs)
    lo, hi = math.ceil((top - q) / q - _EPS), math.floor((bottom + q) / q + _EPS)
    if lo > hi:
        what = "the arc" if len(arcs) == 1 else f"the {len(arcs)} arcs that share this axis"
        why = (
            f"the {AXES[axis]} correction varies by {(top - bottom) * scale:.4f} mm across "
            f"{what}: no one shift holds every point within the written {q * scale:g} mm"
        )
        return math.nan, why, arcs[0]
    centre = sum(fit.centre[i][axis] for i in arcs) / len(arcs)
    return min(max(round(centre / q), lo), hi) * q, "", -1


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
