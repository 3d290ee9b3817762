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
from accugrid.codegen.splice import literals
from accugrid.kinematics.frames import abc_to_matrix

__all__ = ["Chains", "resolve", "write_increments"]


@dataclass
class Chains:
    """The relative motions of every file (``rows[s]``: their table rows, ascending), resolved:
    ``start[s][k]`` (file, row) of the k-th one's start ((-1, -1): not known, ``reason[s][k]``
    says why), ``rotation[s][k]`` (3, 3) the frame its increment is in (base_R_increment),
    ``xyz[s][k]`` (3,) mm base frame the absolute position it reaches, ``abc[s][k]`` (3,) deg the
    orientation there (NaN: not known)."""

    rows: list[np.ndarray]
    start: list[list[tuple[int, int]]] = field(default_factory=list)
    rotation: list[list[np.ndarray]] = field(default_factory=list)
    xyz: list[list[np.ndarray]] = field(default_factory=list)
    abc: list[list[np.ndarray]] = field(default_factory=list)
    reason: list[list[str]] = field(default_factory=list)


def resolve(
    scans: list[KrlScan],
    frames: list[np.ndarray],
    reasons: list[list[str]],
    named,
    poses: list[np.ndarray],
) -> Chains:
    """Resolve the start of every relative motion (files in order, rows in order).

    ``frames[s]`` (n_s,) the index in ``poses`` of each table row's robot_T_base (-1: not
    placed) and ``reasons[s]`` each row's reason so far, both of file s; ``named(name)``: the
    (file, row) of the stored position a motion to ``name`` goes to, or None. A relative motion
    whose start is not known gets its reason in ``reasons`` and frame -1."""

    def where(s: int, p: int) -> str:
        table = scans[s].table
        return f"{table.name[p]} at {Path(scans[s].path or '').name}:{table.line[p]}"

    chains = Chains([np.array(sorted(scan.relative), np.int64) for scan in scans])
    for s, scan in enumerate(scans):
        t, u = scan.table, scan.use_table
        motions = np.flatnonzero(t.kind == MOTION)
        lines = t.line[motions]
        starts, rotations, xyzs, abcs, whys = [], [], [], [], []
        resolved: dict[int, int] = {}  # row -> k of the relative motions known so far
        for r in chains.rows[s].tolist():
            info: Relative = scan.relative[r]
            line = int(t.line[r])
            k = int(np.searchsorted(lines, line)) - 1
            p = int(motions[k]) if k >= 0 else -1
            j = int(np.searchsorted(u.line, line)) - 1
            use_line = int(u.line[j]) if j >= 0 else -1
            start, why = (s, p), ""
            if frames[s][r] < 0:
                why = reasons[s][r]
            elif max(use_line, int(t.line[p]) if p >= 0 else -1) <= info.since:
                why = f"relative motion whose start is not known: {info.why}"
                if p < 0 and use_line < 0:
                    why = "relative motion with no motion before it: its start is not known"
            elif p < 0 or use_line > t.line[p]:
                found = None if u.reason[j] else named(u.name[j])
                start = found if found is not None else (-1, -1)
                if found is None:
                    why = u.reason[j] or f"{u.text[j]} is not a position given in these files"
                    why = f"its start {u.text[j]} (line {use_line}) is not known: {why}"
            if not why:
                s2, p2 = start
                if frames[s2][p2] < 0 or reasons[s2][p2] and p2 not in resolved:
                    why = f"its start ({where(s2, p2)}) is not placed: " + (
                        reasons[s2][p2] or "no base"
                    )
                elif not np.array_equal(poses[frames[s2][p2]], poses[frames[s][r]]):
                    why = f"its start ({where(s2, p2)}) is in another base"
            xyz = abc = rotation = None
            if not why:
                if s2 == s and p2 in resolved:
                    at = resolved[p2]
                    start_xyz, start_abc = xyzs[at], abcs[at]
                else:
                    start_xyz, start_abc = scans[s2].table.xyz[p2], scans[s2].table.abc[p2]
                rotation = np.eye(3)
                if info.tool:
                    if np.isnan(start_abc).any():
                        why = f"#TOOL: the orientation at its start ({where(s2, p2)}) is not known"
                    else:
                        rotation = abc_to_matrix(start_abc)
                increment = np.nan_to_num(t.xyz[r])
                turn = np.nan_to_num(t.abc[r])
                xyz = start_xyz + rotation @ increment
                abc = start_abc if not turn.any() else np.full(3, np.nan)
            if why:
                reasons[s][r] = why
                frames[s][r] = -1
                start = (-1, -1)
            else:
                resolved[r] = len(starts)
            starts.append(start)
            rotations.append(rotation)
            xyzs.append(xyz)
            abcs.append(abc)
            whys.append(why)
        chains.start.append(starts)
        chains.rotation.append(rotations)
        chains.xyz.append(xyzs)
        chains.abc.append(abcs)
        chains.reason.append(whys)
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
    each relative motion lands (NaN: start not known)."""
    written: dict[tuple[int, int], np.ndarray] = {}  # where a start lands as written

    def lands(s: int, p: int) -> np.ndarray:
        if (s, p) not in written:
            table = scans[s].table
            value = table.xyz[p]
            if corrected[s][p]:
                value = literals(goals[s][p], places[s])[2]
            written[s, p] = value
        return written[s, p]

    edits: list[list[tuple[int, int, str]]] = []
    reached_all = []
    for s, rows in enumerate(chains.rows):
        scan, mine = scans[s], []
        reached = np.full((len(rows), 3), np.nan)
        for k, r in enumerate(rows.tolist()):
            s2, p2 = chains.start[s][k]
            if s2 < 0:
                continue
            start = lands(s2, p2)
            goal = goals[s][r] if corrected[s][r] else chains.xyz[s][k]
            rotation = chains.rotation[s][k]
            texts, lengths, values = literals(rotation.T @ (goal - start), places[s])
            pieces = np.split(texts, np.cumsum(lengths)[:-1])
            new = [bytes(piece).decode("ascii") for piece in pieces]
            mine += _aggregate_edits(scan, r, new, values)
            written[s, r] = reached[k] = start + rotation @ values
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
