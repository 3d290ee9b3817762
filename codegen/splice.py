"""Many number literals of a program replaced at once, as bytes (the output of both rewriters,
``codegen.krl.rewrite`` and ``codegen.gcode.rewrite``): the new literals formatted in one pass and
read back exactly (``literals``), then copied into the program's bytes with array operations
(``ByteSplicer``), never a Python string per literal.
"""

from __future__ import annotations

import numpy as np

from accugrid.codegen.textsafe import fixed_bytes

__all__ = ["ByteSplicer", "literals"]

_EDITS = 1 << 16  # edits spliced at a time (bounds the index arrays and the text encoded)
_RUNS = 1024  # at most this many length-changing edits in them: copy the text between whole


def literals(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``fixed(v, places)`` of every value (n,): their bytes one after another (uint8), the
    length of each (n,), and the value each one reads as (n,) float (what ``float`` gives), from
    the formatter's array form ``textsafe.fixed_bytes``. Raises ValueError for NaN or infinity,
    like ``fixed``."""
    cells, written = fixed_bytes(np.asarray(values, dtype=float).reshape(-1), places)
    shown = cells != 0
    return cells[shown], shown.sum(axis=1), written


class ByteSplicer:
    """``text`` (latin-1) as bytes with spans replaced, built a block of edits at a time (each
    block after the previous one, sorted, non-overlapping): the text is encoded a part at a time
    and the new program exists once, as bytes."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.out = bytearray()
        self.last = 0  # text copied up to here

    def add(
        self, starts: np.ndarray, ends: np.ndarray, new: np.ndarray, lengths: np.ndarray
    ) -> None:
        """Replace ``text[starts[k]:ends[k]]`` by the k-th new piece for every k: ``new``
        (uint8) holds the pieces one after another, ``lengths`` (m,) their lengths."""
        for a in range(0, len(starts), _EDITS):
            b = min(a + _EDITS, len(starts))
            lo, hi = self.last, int(ends[b - 1])
            offset = np.concatenate(([0], np.cumsum(lengths[a:b])))
            source = np.frombuffer(self.text[lo:hi].encode("latin-1"), np.uint8)
            part = np.empty(
                len(source) + int(offset[-1] - (ends[a:b] - starts[a:b]).sum()), np.uint8
            )
            _splice_part(
                source, part, starts[a:b] - lo, ends[a:b] - lo, new[: offset[-1]], lengths[a:b]
            )
            new = new[offset[-1] :]
            self.out += memoryview(part)
            self.last = hi

    def finish(self) -> bytearray:
        """The new program's bytes, every edit made."""
        for at in range(self.last, len(self.text), _EDITS * 64):  # the rest, as it is
            self.out += self.text[at : at + _EDITS * 64].encode("latin-1")
        self.last = len(self.text)
        return self.out


def _splice_part(
    source: np.ndarray,
    target: np.ndarray,
    starts: np.ndarray,
    ends: np.ndarray,
    new: np.ndarray,
    lengths: np.ndarray,
) -> None:
    """``target`` = ``source`` with the edits of ``ByteSplicer.add`` made (offsets in source)."""
    delta = lengths - (ends - starts)
    shift = np.concatenate(([0], np.cumsum(delta)))  # of the text after edit k: shift[k + 1]
    first = starts + shift[:-1]  # where each new piece goes
    into = np.repeat(first - np.concatenate(([0], np.cumsum(lengths)[:-1])), lengths)
    into += np.arange(len(new))
    moves = np.flatnonzero(delta).tolist()
    if len(moves) <= _RUNS:  # the text between length changes keeps one shift: one copy each
        lo = 0
        for k in moves:
            hi, s = int(starts[k]), int(shift[k])
            target[lo + s : hi + s] = source[lo:hi]
            lo = int(ends[k])
        s = int(shift[-1])
        target[lo + s :] = source[lo:]
    else:  # every byte kept, in order, where no new byte goes
        kept = np.ones(len(source), bool)
        old = ends - starts
        kept[
            np.repeat(starts - np.concatenate(([0], np.cumsum(old)[:-1])), old)
            + np.arange(int(old.sum()))
        ] = False
        free = np.ones(len(target), bool)
        free[into] = False
        target[free] = source[kept]
    target[into] = new
