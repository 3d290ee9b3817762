"""KRL relative motions (``LIN_REL``, ``PTP_REL``, ``SLIN_REL``, ``SPTP_REL``, ``CIRC_REL``,
``SCIRC_REL``) in a rewrite: corrected as the absolute positions they reach, written back as the
increments between corrected positions, so each lands where an absolute program would.

A relative aggregate is an increment from the position the robot is at: the target of the motion
before it in program order, in the base frame (``#BASE``, the default) or the tool frame at that
start (``#TOOL``: R = the start's A, B, C); components it does not give are 0; both points of a
``CIRC_REL`` are relative to the circle's start. A start is known when it is an absolute aggregate
or a stored position that is placed, or a relative motion whose own start is known, written after
the last statement that makes the position depend on the path (a routine's start, a jump target,
a branch or loop, a call, a change of $BASE or $TOOL: ``parse.Relative``), in the same base.
What is not known is reported with the reason, never guessed.

Written back: the increment from where the start now lands (its corrected, rounded numbers, or
its numbers as written when it is not corrected) to the relative motion's own target (corrected,
or as programmed when it is not), ``d = R^T (goal - start)``; a component the aggregate does not
give is added when its increment is not 0 (``X 0.12,`` before the first given one, ``,Z 1.5``
after the last).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from accugrid.codegen.krl.parse import KrlScan, Relative
from accugrid.codegen.krl.tables import MOTION
from accugrid.codegen.program_text import distinct_ints
from accugrid.codegen.splice import literals
from accugrid.kinematics.frames import abc_to_matrix

__all__ = ["Chains", "resolve", "write_increments"]


@dataclass
class Chains:
    """The relative motions of every file, resolved; per file s, arrays over its k relative
    motions in table order: ``rows[s]`` (k,) their table rows, ``start[s]`` (k, 2) the (file,
    table row) of each one's start ((-1, -1): not known, its reason is in the rows'),
    ``prior[s]`` (k,) the index among them of a start that is itself a relative motion (-1:
    none), ``rotation[s]`` (k, 3, 3) the frame its increment is in (base_R_increment), ``xyz[s]``
    (k, 3) mm base frame the absolute position it reaches, ``abc[s]`` (k, 3) deg the orientation
    there (NaN: not known), ``generation[s]`` (k,) how many relative motions lead to it."""

    rows: list[np.ndarray]
    start: list[np.ndarray] = field(default_factory=list)
    prior: list[np.ndarray] = field(default_factory=list)
    rotation: list[np.ndarray] = field(default_factory=list)
    xyz: list[np.ndarray] = field(default_factory=list)
    abc: list[np.ndarray] = field(default_factory=list)
    generation: list[np.ndarray] = field(default_factory=list)


def resolve(
    scans: list[KrlScan],
    frames: list[np.ndarray],
    reasons: list[list[str]],
    named,
    poses: list[np.ndarray],
) -> Chains:
    """Resolve the start of every relative motion.

    ``frames[s]`` (n_s,) the index in ``poses`` of each table row's robot_T_base (-1: not
    placed) and ``reasons[s]`` each row's reason so far, both of file s; ``named(name)``: the
    (file, row) of the stored position a motion to ``name`` goes to, or why it is not known. A
    relative motion whose start is not known gets its reason in ``reasons`` and frame -1. The
    starts are found row by row (list and dict look-ups), the positions a generation of a chain
    at a time."""

    def where(s: int, p: int) -> str:
        table = scans[s].table
        return f"{table.name[p]} at {Path(scans[s].path or '').name}:{table.line[p]}"

    same_base: dict[tuple[int, int], bool] = {}
    chains = Chains([np.array(sorted(scan.relative), np.int64) for scan in scans])
    known_abc = [(~np.isnan(scan.table.abc).any(axis=1)).tolist() for scan in scans]
    for s, scan in enumerate(scans):
        t, u = scan.table, scan.use_table
        rel = chains.rows[s]
        k = len(rel)
        motions = np.flatnonzero(t.kind == MOTION)
        line = t.line[rel]
        at = np.searchsorted(t.line[motions], line) - 1
        prev = np.where(at >= 0, motions[np.maximum(at, 0)], -1).tolist()
        prev_line = np.where(at >= 0, t.line[motions[np.maximum(at, 0)]], -1).tolist()
        at_use = (np.searchsorted(u.line, line) - 1).tolist()
        use_line = [int(u.line[j]) if j >= 0 else -1 for j in at_use]
        turns = (np.nan_to_num(t.abc[rel]) != 0).any(axis=1).tolist()
        index = {r: i for i, r in enumerate(rel.tolist())}
        start = np.full((k, 2), -1, np.int64)
        prior = np.full(k, -1, np.int64)
        generation = np.zeros(k, np.int64)
        oriented = [False] * k  # the orientation at the relative motion is known
        tools = np.zeros(k, bool)
        frame_s = frames[s]
        for i, r in enumerate(rel.tolist()):
            info: Relative = scan.relative[r]
            p, j = prev[i], at_use[i]
            s2, p2, why = s, p, ""
            if frame_s[r] < 0:
                why = reasons[s][r]
            elif max(use_line[i], prev_line[i]) <= info.since:
                why = f"relative motion whose start is not known: {info.why}"
                if p < 0 and use_line[i] < 0:
                    why = "relative motion with no motion before it: its start is not known"
            elif p < 0 or use_line[i] > prev_line[i]:
                found = u.reason[j] or named(u.name[j])
                if isinstance(found, str):
                    why = f"its start {u.text[j]} (line {use_line[i]}) is not known: {found}"
                else:
                    s2, p2 = found
            before = index.get(p2, -1) if s2 == s else -1
            if not why:
                if frames[s2][p2] < 0 or reasons[s2][p2]:
                    why = f"its start ({where(s2, p2)}) is not placed: " + (
                        reasons[s2][p2] or "no base"
                    )
                else:
                    pair = (int(frames[s2][p2]), int(frame_s[r]))
                    if pair not in same_base:
                        same_base[pair] = np.array_equal(poses[pair[0]], poses[pair[1]])
                    if not same_base[pair]:
                        why = f"its start ({where(s2, p2)}) is in another base"
            start_oriented = oriented[before] if before >= 0 else known_abc[s2][p2]
            if not why and info.tool and not start_oriented:
                why = f"#TOOL: the orientation at its start ({where(s2, p2)}) is not known"
            if why:
                reasons[s][r] = why
                frame_s[r] = -1
                continue
            start[i] = s2, p2
            tools[i] = info.tool
            oriented[i] = start_oriented and not turns[i]
            if before >= 0:
                prior[i] = before
                generation[i] = generation[before] + 1
        xyz, abc = np.full((k, 3), np.nan), np.full((k, 3), np.nan)
        rotation = np.tile(np.eye(3), (k, 1, 1))
        increment = np.nan_to_num(t.xyz[rel])
        for g in range(int(generation.max(initial=-1)) + 1):
            now = np.flatnonzero((generation == g) & (start[:, 0] >= 0))
            first = prior[now] < 0
            from_xyz, from_abc = np.empty((len(now), 3)), np.empty((len(now), 3))
            for f in distinct_ints(start[now[first], 0]):
                mine = first & (start[now, 0] == f)
                table = scans[f].table
                from_xyz[mine] = table.xyz[start[now[mine], 1]]
                from_abc[mine] = table.abc[start[now[mine], 1]]
            from_xyz[~first] = xyz[prior[now[~first]]]
            from_abc[~first] = abc[prior[now[~first]]]
            tool = now[tools[now]]
            if len(tool):
                rotation[tool] = abc_to_matrix(from_abc[tools[now]])
            xyz[now] = from_xyz + np.einsum("nij,nj->ni", rotation[now], increment[now])
            turned = np.array([turns[i] for i in now.tolist()], bool).reshape(-1)
            abc[now] = np.where(turned[:, None], np.nan, from_abc)
        chains.start.append(start)
        chains.prior.append(prior)
        chains.rotation.append(rotation)
        chains.xyz.append(xyz)
        chains.abc.append(abc)
        chains.generation.append(generation)
    return chains


_OPEN_RE = re.compile(r"\{\s*+(?:[A-Za-z_]\w*+\s*+:(?!:)\s*+)?+")


def write_increments(
    chains: Chains,
    scans: list[KrlScan],
    goals: list[np.ndarray],
    corrected: list[np.ndarray],
    places: list[int],
) -> tuple[list[list[tuple[int, int, str]]], list[np.ndarray]]:
    """The edits of every relative motion whose start is known, and where each lands.

    ``goals[s]`` (n_s, 3) mm base frame: each table row's corrected target (NaN: not corrected),
    ``corrected[s]`` (n_s,) bool: whether it is written corrected, ``places[s]`` the decimals of
    file s. Returns per file the edits (start, end, new text) and ``reached`` (k_s, 3) mm: where
    each relative motion lands (NaN: start not known). A generation of the chains at a time."""
    edits: list[list[tuple[int, int, str]]] = []
    reached_all = []
    for s, rows in enumerate(chains.rows):
        start, prior = chains.start[s], chains.prior[s]
        reached = np.full((len(rows), 3), np.nan)
        texts: list[list[str]] = [[] for _ in rows]
        values = np.full((len(rows), 3), np.nan)
        for g in range(int(chains.generation[s].max(initial=-1)) + 1):
            now = np.flatnonzero((chains.generation[s] == g) & (start[:, 0] >= 0))
            first = prior[now] < 0
            lands = np.empty((len(now), 3))
            for f in distinct_ints(start[now[first], 0]):
                mine = np.flatnonzero(first & (start[now, 0] == f))
                p = start[now[mine], 1]
                lands[mine] = scans[f].table.xyz[p]
                done = corrected[f][p]
                if done.any():
                    lands[mine[done]] = literals(goals[f][p[done]], places[f])[2].reshape(-1, 3)
            lands[~first] = reached[prior[now[~first]]]
            r = rows[now]
            goal = np.where(corrected[s][r][:, None], goals[s][r], chains.xyz[s][now])
            rotation = chains.rotation[s][now]
            step = np.einsum("nji,nj->ni", rotation, goal - lands)  # R^T (goal - start)
            data, lengths, written = literals(step.ravel(), places[s])
            written = written.reshape(-1, 3)
            reached[now] = lands + np.einsum("nij,nj->ni", rotation, written)
            values[now] = written
            cut = np.concatenate(([0], np.cumsum(lengths))).tolist()
            joined = data.tobytes().decode("ascii")
            pieces = [joined[a:b] for a, b in zip(cut[:-1], cut[1:], strict=True)]
            for n, i in enumerate(now.tolist()):
                texts[i] = pieces[3 * n : 3 * n + 3]
        mine = []
        for i in np.flatnonzero(start[:, 0] >= 0).tolist():
            mine += _aggregate_edits(scans[s], int(rows[i]), texts[i], values[i])
        edits.append(mine)
        reached_all.append(reached)
    return edits, reached_all


def _aggregate_edits(scan: KrlScan, r: int, new: list[str], values: np.ndarray) -> list:
    """The edits that write increments ``new`` (X, Y, Z texts) into table row r's aggregate: a
    given component replaced when its value changes, a missing one added when not 0."""
    t, text = scan.table, scan.text
    span = t.span[r].reshape(3, 2)
    old = t.xyz[r]
    given = span[:, 0] >= 0
    out = []
    for i in np.flatnonzero(given).tolist():
        if values[i] != old[i]:
            out.append((int(span[i, 0]), int(span[i, 1]), new[i]))
    missing = [i for i in range(3) if not given[i] and values[i] != 0.0]
    if not missing:
        return out
    brace = int(t.agg[r])
    gap = ", " if ", " in text[brace : text.find("}", brace)] else ","
    before, after = [], []
    for i in missing:
        (after if given[:i].any() else before).append(f"{'XYZ'[i]} {new[i]}")
    if after:  # after the last given component before them
        last = max(i for i in range(3) if given[i] and i < missing[-1])
        end = int(span[last, 1])
        out.append((end, end, "".join(gap + item for item in after)))
    if before:
        if given.any():  # before the first given component's key
            at = int(span[np.flatnonzero(given)[0], 0])
            while at > 0 and text[at - 1] in " \t":
                at -= 1
            at -= 1  # the key letter
            out.append((at, at, "".join(item + gap for item in before)))
        else:  # after the brace (and a type prefix), before any other component
            at = _OPEN_RE.match(text, brace).end()
            rest = text[at : text.find("}", brace)].strip()
            out.append((at, at, gap.join(before) + (gap if rest else "")))
    return out
