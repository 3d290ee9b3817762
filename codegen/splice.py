"""Many number literals of a program replaced at once, as bytes (the output of both rewriters,
``codegen.krl.rewrite`` and ``codegen.gcode.rewrite``): the new literals formatted in one pass and
read back exactly (``literals``), then copied into the program's bytes with array operations
(``ByteSplicer``), never a Python string per literal.
"""

from __future__ import annotations

import numpy as np

from accugrid.codegen.program_text import row_counts
from accugrid.infra.textsafe import fixed_bytes

__all__ = ["ByteSplicer", "literals", "texts_of"]

_EDITS = 1 << 16  # edits spliced at a time (bounds the index arrays and the text encoded)


def literals(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``fixed(v, places)`` of every value (n,): their bytes one after another (uint8), the
    length of each (n,), and the value each one reads as (n,) float (what ``float`` gives), from
    the formatter's array form ``textsafe.fixed_bytes``. Raises ValueError for NaN or infinity,
    like ``fixed``."""
    cells, written = fixed_bytes(np.asarray(values, dtype=float).reshape(-1), places)
    return (*texts_of(cells), written)


def texts_of(cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The texts of rows (m, w) uint8 of NUL-padded ASCII (``fixed_bytes``' cells) one after
    another (uint8) and the length of each (m,)."""
    shown = cells != 0
    return cells[shown], row_counts(shown)


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
            size = int(lengths[a:b].sum())
            source = self.text[lo:hi].encode("latin-1")
            self.out += _spliced(source, starts[a:b] - lo, ends[a:b] - lo, new[:size], lengths[a:b])
            new = new[size:]
            self.last = hi

    def finish(self) -> bytearray:
        """The new program's bytes, every edit made."""
        for at in range(self.last, len(self.text), _EDITS * 64):  # the rest, as it is
            self.out += self.text[at : at + _EDITS * 64].encode("latin-1")
        self.last = len(self.text)
        return self.out


def _spliced(
    source: bytes, starts: np.ndarray, ends: np.ndarray, new: np.ndarray, lengths: np.ndarray
) -> bytearray:
    """``source`` with ``source[starts[k]:ends[k]]`` replaced by the k-th piece of ``new`` for
    every k (``ByteSplicer.add``'s edits, offsets in source).

    The text between two edits that change the length keeps one shift: each such stretch is
    copied whole (joined as bytes, with room for the new text of those edits between them), then
    every new byte is put where it goes."""
    delta = lengths - (ends - starts)
    moves = np.flatnonzero(delta)
    view = memoryview(source)
    cut_at = [0, *ends[moves].tolist()], [*starts[moves].tolist(), len(source)]
    pieces: list = [b""] * (2 * len(moves) + 1)
    pieces[0::2] = map(view.__getitem__, map(slice, *cut_at))
    pieces[1::2] = map(bytes, lengths[moves].tolist())  # room for the new text
    out = bytearray().join(pieces)
    shift = np.concatenate(([0], np.cumsum(delta)))  # of the text after edit k: shift[k + 1]
    first = starts + shift[:-1] - np.concatenate(([0], np.cumsum(lengths)[:-1]))
    into = np.repeat(first, lengths) + np.arange(len(new))  # where each new byte goes
    np.frombuffer(out, np.uint8)[into] = new
    return out
