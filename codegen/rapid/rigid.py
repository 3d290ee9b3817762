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
(``codegen.bytescan.distinct``: mostly one for the whole module). A line in these layouts reads
as the statement reader reads it; every other line is left to that reader, which also decides
whether each of these lines stands alone as a statement (``codegen.rapid.rewrite``).

Offsets are byte (= character) offsets in the text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from accugrid.codegen.bytescan import U64, ascii_word, distinct, strings, text_bytes, windows
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
_LETTER = np.zeros(256, bool)  # ASCII letters, by byte
_LETTER[65:91] = _LETTER[97:123] = True
_LINES = 1 << 16  # lines read at a time
_NAMES = 1 << 13  # names measured at a time
_BYTES = 1 << 24  # bytes looked at at a time for line ends
_XYZ_MAX = 56  # bytes from "[[" to the "]" after z: three plain decimals of at most 17


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


def _prefix(words: np.ndarray, literal: bytes) -> np.ndarray:
    """Whether each row of ``words`` (n, k) uint64 (8 k bytes) starts with ``literal``."""
    size = words.shape[1] * 8
    pattern = np.frombuffer(literal.ljust(size, b"\0"), U64)
    mask = np.frombuffer((b"\xff" * len(literal)).ljust(size, b"\0"), U64)
    hit = np.ones(len(words), bool)
    for k in range(words.shape[1]):
        if mask[k]:
            hit &= (words[:, k] & mask[k]) == pattern[k]
    return hit


def _names(buf: np.ndarray, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The length of the name at each offset ``at`` (k,) (up to the first byte no name has) and
    whether it is an ASCII name of 1 to _NAME_MAX characters. A block of offsets at a time:
    the windows and their masks stay small beside the text."""
    size = np.empty(len(at), np.int64)  # 0: none, or too long
    for a in range(0, len(at), _NAMES):
        window = windows(buf, at[a : a + _NAMES], _NAME_MAX + 1)
        size[a : a + _NAMES] = np.argmin(ascii_word(window), axis=1)
    return size, (size >= 1) & _LETTER[np.take(buf, at, mode="clip")]


class _Texts:
    """The distinct texts of spans, across the blocks of a module, each matched by ``pattern``
    once (``matches``: in order of first appearance, None where it does not match)."""

    def __init__(self, pattern: re.Pattern) -> None:
        self.pattern = pattern
        self.index: dict[str, int] = {}
        self.matches: list[re.Match | None] = []

    def of(self, buf: np.ndarray, text: str, spans: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The index of each span's (k, 2) text among the distinct ones (k,) and whether it
        matches (k,)."""
        if not len(spans):
            return np.zeros(0, np.int64), np.zeros(0, bool)
        found, which = distinct(buf, spans, text)
        ids = np.empty(len(found), np.int64)
        for i, piece in enumerate(found):
            ids[i] = self.index.setdefault(piece, len(self.index))
            if ids[i] == len(self.matches):
                self.matches.append(self.pattern.match(piece))
        ok = np.array([m is not None for m in self.matches], bool)
        return ids[which], ok[ids[which]]


def read_rigid(text: str) -> RigidModule | None:
    """The rigid lines of a RAPID module; None when ``text`` is not latin-1 (never so for a
    program read by ``read_program``). Read a block of lines at a time: the temporaries stay
    small beside the text."""
    buf = text_bytes(text)
    if buf is None:
        return None
    n = len(text)
    newlines = [np.zeros(0, np.int64)]
    for a in range(0, n, _BYTES):
        newlines.append(np.flatnonzero(buf[a : min(a + _BYTES, n)] == 10) + a)
    line_end = np.concatenate([*newlines, [n]]).astype(np.int64)
    line_start = np.concatenate([[0], line_end[:-1] + 1])
    line_end -= (np.take(buf, line_end - 1, mode="clip") == 13) & (line_end > line_start)
    tails, rests = _Texts(_TAIL), _Texts(_REST)
    decls, moves = [], []
    for a in range(0, len(line_start), _LINES):
        b = min(a + _LINES, len(line_start))
        d, m = _block(buf, text, a, line_start[a:b], line_end[a:b], tails, rests)
        decls.append(d)
        moves.append(m)
    table = np.full((len(tails.matches), 14), np.nan)
    for i, match in enumerate(tails.matches):
        if match:
            table[i] = [float(v) for v in match.groups()]
    decl = [np.concatenate([part[k] for part in decls]) for k in (0, 2, 3, 4, 5)]
    move = [np.concatenate([part[k] for part in moves]) for k in (0, 2)]
    rigid = np.zeros(len(line_start), bool)
    rigid[decl[0]] = True
    rigid[move[0]] = True
    names = [name for part in decls for name in part[1]]
    targets = [name for part in moves for name in part[1]]
    ends = [m.groups() if m else None for m in rests.matches]
    return RigidModule(
        line_start,
        line_end,
        rigid,
        decl[0],
        names,
        *decl[1:],
        table,
        move[0],
        targets,
        *move[1:],
        ends,
    )


def _block(buf, text, first, line_start, line_end, tails, rests):
    """The rigid declarations and moves among the lines (their starts and ends), the first of
    them the module's line ``first`` (0-based)."""
    head = windows(buf, line_start, _BLANKS)
    blank = (head == 32) | (head == 9)
    s = line_start + np.where(blank.all(axis=1), _BLANKS, np.argmin(blank, axis=1))
    heads = windows(buf, s, 16).view(U64)
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
    m = np.flatnonzero(move)
    return (
        _declarations(buf, text, d + first, name_at[d], line_end[d], tails),
        _moves(buf, text, m + first, name_at[m], line_end[m], rests),
    )


def _declarations(buf, text, lines, name_at, end, tails):
    size, good = _names(buf, name_at)
    colon = name_at + size
    good &= _prefix(windows(buf, colon, 8).view(U64), b":=[[")
    # x, y, z: up to the first two commas and the "]" within _XYZ_MAX bytes of the "[["
    first = colon + 4
    window = windows(buf, first, _XYZ_MAX)
    rows = np.arange(len(first))
    comma = window == 44
    c0 = np.argmax(comma, axis=1)
    good &= comma[rows, c0]
    comma[rows, c0] = False
    c1 = np.argmax(comma, axis=1)
    good &= comma[rows, c1]
    bracket = window == 93
    c2 = np.argmax(bracket, axis=1)
    good &= bracket[rows, c2] & (c1 < c2) & (first + c2 < end)
    keep = np.flatnonzero(good)
    at = first[keep, None] + np.stack([np.zeros_like(c0), c0 + 1, c1 + 1], axis=1)[keep]
    stop = first[keep, None] + np.stack([c0, c1, c2], axis=1)[keep]
    values, places, plain = read_decimals(buf, at.ravel(), stop.ravel())
    span = np.stack([at, stop], axis=2)
    tail_span = np.stack([stop[:, 2], end[keep]], axis=1)
    which, parsed = tails.of(buf, text, tail_span)
    rows = np.flatnonzero(plain.reshape(-1, 3).all(axis=1) & parsed)
    names = strings(buf, name_at[keep][rows], size[keep][rows])
    xyz, places = values.reshape(-1, 3)[rows], places.reshape(-1, 3)[rows].max(axis=1)
    return lines[keep][rows], names, span[rows], xyz, places, which[rows]


def _moves(buf, text, lines, name_at, end, rests):
    size, good = _names(buf, name_at)
    comma = name_at + size
    keep = np.flatnonzero(good & (np.take(buf, comma, mode="clip") == 44))
    which, parsed = rests.of(buf, text, np.stack([comma[keep], end[keep]], axis=1))
    rows = np.flatnonzero(parsed)
    return lines[keep][rows], strings(buf, name_at[keep][rows], size[keep][rows]), which[rows]
