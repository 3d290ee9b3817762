"""The lines of a RAPID module in the one layout RobotStudio and controllers write them, read
with array operations: the fast lane of the module reader (``codegen.rapid.rewrite.scan``) for a
module of 100,000 robtargets.

Two layouts, each alone on its line after at most 16 blanks (spaces, tabs), with no other
blank, and an optional CR before the LF:

- ``CONST|PERS|VAR robtarget name:=[[x,y,z],[q1,q2,q3,q4],[cf1,cf4,cf6,cfx],[e1,..,e6]];``
- ``MoveL|MoveJ name,speed,zone,tool;`` or ``...,tool\\WObj:=wobj;``

Every name ASCII (``[A-Za-z][A-Za-z0-9_]*``, at most 32 characters); x, y, z plain decimals
(``infra.decimals``: read exactly, what ``float`` gives). What follows z (orientation, confdata,
external axes) and what follows a move's target are read once per distinct text
(``codegen.krl.rigid.distinct``: mostly one for the whole module). A line in these layouts reads
as the statement reader reads it; every other line is left to that reader, which also decides
whether each of these lines stands alone as a statement (``codegen.rapid.rewrite``).

Offsets are byte (= character) offsets in the text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from accugrid.codegen.krl.rigid import distinct, strings, text_bytes
from accugrid.infra.decimals import read_decimals

__all__ = ["RigidModule", "read_rigid"]

_NAME_MAX = 32
_BLANKS = 16  # leading blanks looked at
_DECLS = (b"CONST robtarget ", b"PERS robtarget ", b"VAR robtarget ")
_MOVES = (b"MoveL ", b"MoveJ ")
_NUM = r"([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
_TAIL = re.compile(
    r"\],\[" + ",".join([_NUM] * 4) + r"\],\[" + ",".join([_NUM] * 4) + r"\],\["
    r"" + ",".join([_NUM] * 6) + r"\]\];\Z"
)
_REST = re.compile(r",([A-Za-z]\w*),([A-Za-z]\w*),([A-Za-z]\w*)(?:\\WObj:=([A-Za-z]\w*))?;\Z", re.A)
_WORD = np.zeros(256, bool)
_WORD[
    np.frombuffer(b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_0123456789", np.uint8)
] = True
_LETTER = _WORD.copy()
_LETTER[48:58] = False
_LETTER[95] = False
_FAR = np.iinfo(np.int64).max // 4
_U64 = np.dtype("<u8")


@dataclass
class RigidModule:
    """The rigid lines of a module. Every line: ``line_start`` (L,) offset where each line
    starts, ``line_end`` (L,) where its text ends (before CR LF); ``rigid`` (L,) bool.

    Declarations (k rows): ``decl_line`` (k,) 0-based line, ``names`` (k) str, ``span``
    (k, 3, 2) start/end offsets of x, y, z, ``xyz`` (k, 3) mm, ``places`` (k,) the most
    decimals among x, y, z, ``tail`` (k,) index into ``tails``: the 14 numbers after z (q1..q4,
    cf1, cf4, cf6, cfx, e1..e6) of each distinct text (t, 14).
    Moves (m rows): ``move_line`` (m,), ``targets`` (m) str, ``rest`` (m,) index into ``rests``:
    (speed, zone, tool, wobj or None) of each distinct text after the target."""

    line_start: np.ndarray
    line_end: np.ndarray
    rigid: np.ndarray
    decl_line: np.ndarray
    names: list[str]
    span: np.ndarray
    xyz: np.ndarray
    places: np.ndarray
    tail: np.ndarray
    tails: np.ndarray
    move_line: np.ndarray
    targets: list[str]
    rest: np.ndarray
    rests: list[tuple[str, str, str, str | None]]


def _windows(buf: np.ndarray, at: np.ndarray, width: int) -> np.ndarray:
    return sliding_window_view(buf, width)[np.clip(at, 0, len(buf) - width)]


def _prefix(words: np.ndarray, literal: bytes) -> np.ndarray:
    """Whether each row of ``words`` (n, k) uint64 (8 k bytes) starts with ``literal``."""
    size = words.shape[1] * 8
    pattern = np.frombuffer(literal.ljust(size, b"\0"), _U64)
    mask = np.frombuffer((b"\xff" * len(literal)).ljust(size, b"\0"), _U64)
    hit = np.ones(len(words), bool)
    for k in range(words.shape[1]):
        if mask[k]:
            hit &= (words[:, k] & mask[k]) == pattern[k]
    return hit


def _commas(positions: np.ndarray, at: np.ndarray, which: tuple[int, ...]) -> np.ndarray:
    """The ``which``-th (0: the first) of ``positions`` (sorted) at or after each offset ``at``
    (k,): (k, len(which)), _FAR where there are fewer."""
    first = np.searchsorted(positions, at)
    out = np.full((len(at), len(which)), _FAR)
    for col, k in enumerate(which):
        j = first + k
        inside = np.flatnonzero(j < len(positions))
        out[inside, col] = positions[j[inside]]
    return out


def _names_ok(buf: np.ndarray, at: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Whether each ``text[at:end]`` is an ASCII name of at most _NAME_MAX characters, followed
    by a byte that is no name character."""
    size = end - at
    ok = (size >= 1) & (size <= _NAME_MAX) & _LETTER[np.take(buf, at, mode="clip")]
    if not ok.any():
        return ok
    rows = _WORD[_windows(buf, at, _NAME_MAX + 1)]
    return ok & (np.argmin(rows, axis=1) == size)  # the first byte no name has is at the end


def read_rigid(text: str) -> RigidModule | None:
    """The rigid lines of a RAPID module; None when ``text`` is not latin-1 (never so for a
    program read by ``read_program``)."""
    buf = text_bytes(text)
    if buf is None:
        return None
    n = len(text)
    body = buf[:n]
    newlines = np.flatnonzero(body == 10)
    line_start = np.concatenate([[0], newlines + 1])
    line_end = np.concatenate([newlines, [n]])
    line_end -= (np.take(buf, line_end - 1, mode="clip") == 13) & (line_end > line_start)
    head = _windows(buf, line_start, _BLANKS)
    blank = (head == 32) | (head == 9)
    s = line_start + np.where(blank.all(axis=1), _BLANKS, np.argmin(blank, axis=1))
    heads = _windows(buf, s, 16).view(_U64)
    commas = np.flatnonzero(body == 44)
    decl = np.zeros(len(s), bool)
    name_at = s.copy()
    for prefix in _DECLS:
        hit = _prefix(heads, prefix)
        decl |= hit
        name_at[hit] += len(prefix)
    move = np.zeros(len(s), bool)
    for prefix in _MOVES:
        hit = _prefix(heads, prefix)
        move |= hit
        name_at[hit] += len(prefix)
    d = np.flatnonzero(decl)
    decls = _declarations(buf, text, body, d, name_at[d], line_end[d], commas)
    m = np.flatnonzero(move)
    moves = _moves(buf, text, m, name_at[m], line_end[m], commas)
    rigid = np.zeros(len(s), bool)
    rigid[decls[0]] = True
    rigid[moves[0]] = True
    return RigidModule(line_start, line_end, rigid, *decls, *moves)


def _declarations(buf, text, body, lines, name_at, end, commas):
    colons = np.flatnonzero(body == 58)
    colon = _commas(colons, name_at, (0,))[:, 0]
    good = (colon < end) & _names_ok(buf, name_at, colon)
    good &= _prefix(_windows(buf, colon, 8).view(_U64), b":=[[")
    c = _commas(commas, colon, (0, 1, 2, 15))  # after x, y, z and before e6
    good &= c[:, 3] < end
    at = np.stack([colon + 4, c[:, 0] + 1, c[:, 1] + 1], axis=1)
    stop = np.stack([c[:, 0], c[:, 1], c[:, 2] - 1], axis=1)
    good &= np.take(buf, c[:, 2] - 1, mode="clip") == 93  # "]" after z
    keep = np.flatnonzero(good)
    at, stop = at[keep], stop[keep]
    values, places, plain = read_decimals(buf, at.ravel(), stop.ravel())
    span = np.stack([at, stop], axis=2)
    tail_span = np.stack([stop[:, 2], end[keep]], axis=1)
    found, which = distinct(buf, tail_span, text) if len(keep) else ([], np.zeros(0, np.int64))
    tails = np.full((len(found), 14), np.nan)
    parsed = np.zeros(len(found), bool)
    for i, tail in enumerate(found):
        match = _TAIL.match(tail)
        if match:
            tails[i] = [float(v) for v in match.groups()]
            parsed[i] = True
    ok = plain.reshape(-1, 3).all(axis=1) & parsed[which]
    rows = np.flatnonzero(ok)
    names = strings(buf, name_at[keep][rows], (colon - name_at)[keep][rows])
    return (
        lines[keep][rows],
        names,
        span[rows],
        values.reshape(-1, 3)[rows],
        places.reshape(-1, 3)[rows].max(axis=1),
        which[rows],
        tails,
    )


def _moves(buf, text, lines, name_at, end, commas):
    comma = _commas(commas, name_at, (0,))[:, 0]
    keep = np.flatnonzero((comma < end) & _names_ok(buf, name_at, comma))
    rest_span = np.stack([comma[keep], end[keep]], axis=1)
    found, which = distinct(buf, rest_span, text) if len(keep) else ([], np.zeros(0, np.int64))
    rests = [_REST.match(rest) for rest in found]
    ok = np.array([r is not None for r in rests], bool)[which] if len(keep) else np.zeros(0, bool)
    rows = np.flatnonzero(ok)
    targets = strings(buf, name_at[keep][rows], (comma - name_at)[keep][rows])
    return (
        lines[keep][rows],
        targets,
        which[rows],
        [r.groups() if r else None for r in rests],
    )
