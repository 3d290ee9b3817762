"""The lines of a KRL file in the one layout a controller writes them, read with array
operations: the fast lane of the whole-text reader (``codegen.krl.parse``) for the .dat and .src
of a 100,000-position program.

Two layouts, each alone on its line after optional blanks (spaces, tabs), with exactly the single
spaces shown and an optional CR before the LF:

- ``DECL E6POS|POS|FRAME name={X x,Y y,Z z[,A a,B b,C c]tail}``
- ``LIN|PTP|SLIN|SPTP name[ C_DIS|C_PTP|C_VEL|C_ORI]``

``name`` is ASCII (``[A-Za-z_][A-Za-z0-9_]*``, at most 32 characters); every number a plain
decimal (``infra.decimals``: read exactly, what ``float`` gives). ``tail`` is empty
or starts with a comma; the caller decides on each distinct tail (``distinct``). A line in these
layouts reads as the statement reader reads it; every other line is left to that reader.

Offsets are byte (= character) offsets in the text, whose bytes ``codegen.bytescan.text_bytes``
gives; bytes are compared eight at a time as one 64-bit word (``infra.decimals.words_at``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from accugrid.codegen.bytescan import U64, strings, windows
from accugrid.codegen.program_text import row_counts
from accugrid.infra.decimals import read_decimals, words_at

__all__ = ["RigidLines", "read_rigid"]


_DECLS = ((b"DECL E6POS ", "E6POS"), (b"DECL POS ", "POS"), (b"DECL FRAME ", "FRAME"))
_MOTIONS = ((b"LIN ", "LIN"), (b"PTP ", "PTP"), (b"SLIN ", "SLIN"), (b"SPTP ", "SPTP"))
_CLAUSES = (b" C_DIS", b" C_PTP", b" C_VEL", b" C_ORI")
_NAME_MAX = 32  # longer names (KRL allows 24) are left to the statement reader
_WORD = np.zeros(256, bool)
_WORD[np.frombuffer(b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_", np.uint8)] = True
_WORD[48:58] = True
_DIGIT = np.zeros(256, bool)
_DIGIT[48:58] = True


@dataclass
class RigidLines:
    """The rigid lines among n lines given to ``read_rigid``.

    Declarations (k rows): ``decl_line`` (k,) index among the lines given, ``brace`` (k,) offset
    of the ``{``, ``span`` (k, 3, 2) start/end offsets of the X, Y, Z literals, ``xyz`` and
    ``abc`` (k, 3) mm/deg (``abc`` NaN when not given), ``places`` (k,) int16 the most decimals
    among the X, Y, Z literals, ``types`` and ``names`` (k) str, ``tail``
    (k, 2) start/end offsets of what follows the last number up to the ``}``.
    Motions to a name (m rows): ``use_line`` (m,), ``use_at`` (m,) offset of the name,
    ``motions`` and ``targets`` (m) str."""

    decl_line: np.ndarray
    brace: np.ndarray
    span: np.ndarray
    xyz: np.ndarray
    abc: np.ndarray
    places: np.ndarray
    types: list[str]
    names: list[str]
    tail: np.ndarray
    use_line: np.ndarray
    use_at: np.ndarray
    motions: list[str]
    targets: list[str]

    def select(self, keep: np.ndarray) -> RigidLines:
        """The same lines with only the declarations ``keep`` (k,) bool."""
        if keep.all():
            return self
        rows = np.flatnonzero(keep).tolist()
        return RigidLines(
            self.decl_line[keep],
            self.brace[keep],
            self.span[keep],
            self.xyz[keep],
            self.abc[keep],
            self.places[keep],
            [self.types[i] for i in rows],
            [self.names[i] for i in rows],
            self.tail[keep],
            self.use_line,
            self.use_at,
            self.motions,
            self.targets,
        )


def _at(buf: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``buf[at]`` with offsets out of ``buf`` reading its first or last byte."""
    return np.take(buf, at, mode="clip")


def _is(buf: np.ndarray, at: np.ndarray, literal: bytes) -> np.ndarray:
    """Whether ``literal`` (at most 8 bytes) is at each offset ``at`` (k,)."""
    pattern = np.frombuffer(literal.ljust(8, b"\0"), U64)[0]
    mask = np.frombuffer((b"\xff" * len(literal)).ljust(8, b"\0"), U64)[0]
    return (words_at(buf, at) & mask) == pattern


_FAR = np.iinfo(np.int64).max // 4  # an offset past every text


def _following(positions: np.ndarray, at: np.ndarray, count: int) -> np.ndarray:
    """The first ``count`` of ``positions`` (sorted) at or after each offset ``at`` (k,):
    (k, count), _FAR where there are fewer."""
    if not len(positions):
        return np.full((len(at), count), _FAR)
    j = np.searchsorted(positions, at)[:, None] + np.arange(count)
    return np.where(j < len(positions), positions[np.minimum(j, len(positions) - 1)], _FAR)


def read_rigid(buf: np.ndarray, starts: np.ndarray, ends: np.ndarray, text: str) -> RigidLines:
    """The rigid lines among the lines ``text[starts[i]:ends[i]]`` (n,) (without their CR LF);
    ``buf``: ``text_bytes(text)``."""
    s = starts.copy()
    indented = np.flatnonzero((_at(buf, s) == 32) | (_at(buf, s) == 9))
    if indented.size:
        head = windows(buf, s[indented], 16)
        blank = (head == 32) | (head == 9)
        s[indented] += np.where(blank.all(axis=1), 0, np.argmin(blank, axis=1))
    words = windows(buf, s, 16).view(U64)
    kind = np.zeros(len(starts), np.int8)  # 1..3: a declaration, 4..7: a motion
    length = np.zeros(len(starts), np.int64)
    for code, (prefix, _) in enumerate(_DECLS + _MOTIONS, start=1):
        pattern = np.frombuffer(prefix.ljust(16, b"\0"), U64)
        mask = np.frombuffer((b"\xff" * len(prefix)).ljust(16, b"\0"), U64)
        hit = ((words[:, 0] & mask[0]) == pattern[0]) & ((words[:, 1] & mask[1]) == pattern[1])
        kind[hit] = code
        length[hit] = len(prefix)
    name_at = s + length
    d = np.flatnonzero((kind >= 1) & (kind <= 3))
    m = np.flatnonzero(kind >= 4)
    lo, hi = (int(starts[0]), int(ends[-1])) if len(starts) else (0, 0)
    decl = _declarations(buf, lo, hi, d, name_at[d], ends[d], kind[d])
    uses = _motions(buf, m, name_at[m], ends[m], kind[m])
    return RigidLines(*decl, *uses)


def _name_ok(buf: np.ndarray, at: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Whether ``text[at[i] : at[i] + size[i]]`` is an ASCII name of at most _NAME_MAX."""
    ok = (size >= 1) & (size <= _NAME_MAX) & ~_DIGIT[_at(buf, at)]
    if not ok.any():
        return ok
    width = int(size[ok].max())
    rows = windows(buf, at, width)
    return ok & (row_counts(~_WORD[rows] & (np.arange(width) < size[:, None])) == 0)


def _literals(
    buf: np.ndarray, at: np.ndarray, end: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``read_decimals`` of the literals at ``at[i, j]:end[i, j]`` (k, 6): values, decimals and
    which are plain, (k, 6) each. An A, B or C literal written as the first row's (the tool
    orientation, mostly one for the whole file) is read once: same length, at most 8, and the
    same 8 bytes up to its end."""
    k = len(at)
    again = np.ones((k, 6), bool)
    for j in (3, 4, 5):
        size = end[:, j] - at[:, j]
        word = words_at(buf, end[:, j] - 8)
        same = (size[1:] == size[0]) & (size[0] <= 8) & (word[1:] == word[0]) & (end[0, j] >= 8)
        again[1:, j] = ~same
    read = np.flatnonzero(again.ravel())
    values, places, plain = np.empty(6 * k), np.empty(6 * k, np.int64), np.empty(6 * k, bool)
    values[read], places[read], plain[read] = read_decimals(
        buf, at.ravel()[read], end.ravel()[read]
    )
    values, places, plain = values.reshape(k, 6), places.reshape(k, 6), plain.reshape(k, 6)
    for j in (3, 4, 5):
        same = ~again[:, j]
        values[same, j], places[same, j], plain[same, j] = values[0, j], places[0, j], plain[0, j]
    return values, places, plain


def _declarations(buf, lo, hi, lines, name_at, ends, kind):
    k = len(lines)
    if not k:
        none = np.zeros(0, np.int64)
        return (
            none,
            none,
            np.zeros((0, 3, 2), np.int64),
            np.zeros((0, 3)),
            np.zeros((0, 3)),
            np.zeros(0, np.int16),
            [],
            [],
            np.zeros((0, 2), np.int64),
        )
    part = buf[lo:hi]
    braces = np.flatnonzero(part == 123) + lo
    commas = np.flatnonzero(part == 44) + lo
    brace = _following(braces, name_at, 1)[:, 0]
    size = brace - 1 - name_at
    good = (brace >= name_at) & (brace < ends) & _is(buf, brace - 1, b"={X ")
    good &= _name_ok(buf, name_at, size)
    # the literals end at the next commas (the last one, C or Z, may end at the closing brace)
    end = np.minimum(_following(commas, brace, 6), ends[:, None] - 1)
    at = np.concatenate([brace[:, None], end[:, :5]], axis=1) + 3
    good &= _is(buf, end[:, 0], b",Y ") & _is(buf, end[:, 1], b",Z ")
    abc = good & _is(buf, end[:, 2], b",A ")
    abc_rows = np.flatnonzero(abc)
    good[abc_rows] &= _is(buf, end[abc_rows, 3], b",B ") & _is(buf, end[abc_rows, 4], b",C ")
    tail_at = np.where(abc, end[:, 5], end[:, 2])
    good &= (_at(buf, ends - 1) == 125) & ((_at(buf, tail_at) == 44) | (tail_at == ends - 1))
    values, places, plain = _literals(buf, at, end)
    good &= plain[:, :3].all(axis=1) & (plain[:, 3:].all(axis=1) | ~abc)
    xyz = values[:, :3]
    abc = np.where(abc[:, None], values[:, 3:], np.nan)
    span = np.stack([at[:, :3], end[:, :3]], axis=2)
    keep = np.flatnonzero(good)
    types = np.array([t for _, t in _DECLS], dtype=object)[kind[keep] - 1].tolist()
    return (
        lines[keep],
        brace[keep],
        span[keep],
        np.ascontiguousarray(xyz[keep]),
        abc[keep],
        places[keep, :3].max(axis=1).astype(np.int16),
        types,
        strings(buf, name_at[keep], size[keep]),
        np.stack([tail_at[keep], ends[keep] - 1], axis=1),
    )


def _motions(buf, lines, name_at, ends, kind):
    rest = ends - name_at
    clause = np.zeros(len(lines), bool)
    for literal in _CLAUSES:
        clause |= _is(buf, ends - 6, literal)
    size = rest - 6 * (clause & (rest > 6))
    keep = np.flatnonzero(_name_ok(buf, name_at, size))
    motions = np.array([t for _, t in _MOTIONS], dtype=object)[kind[keep] - 4].tolist()
    return lines[keep], name_at[keep], motions, strings(buf, name_at[keep], size[keep])
