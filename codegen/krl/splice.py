"""Many number literals of a program replaced at once, as bytes (the output of the KRL rewrite,
``codegen.krl.rewrite``): the new literals formatted in one pass and read back exactly
(``literals``), then copied into the program's bytes with array operations (``ByteSplicer``),
never a Python string per literal.
"""

from __future__ import annotations

import numpy as np

from accugrid.codegen.textsafe import fixed_format, fixed_ready

__all__ = ["ByteSplicer", "literals"]

_EDITS = 1 << 16  # edits spliced at a time (bounds the index arrays and the text encoded)
_RUNS = 1024  # at most this many length-changing edits in them: copy the text between whole


def literals(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``fixed(v, places)`` of every value (n,): their bytes one after another (uint8), the
    length of each (n,), and the value each one reads as (n,) float (what ``float`` gives).

    Formatted with array operations (``_digits``) when every value times 10**places is below
    2**52 and places <= 15 (the usual program), else by ``%``-formatting. Raises ValueError for
    NaN or infinity, like ``fixed``."""
    ready = fixed_ready(values, places)
    scale = 10.0**places
    if not len(ready):
        return np.zeros(0, np.uint8), np.zeros(0, np.int64), np.zeros(0)
    if places > 15 or not (np.abs(ready) * scale < 2.0**52).all():
        text = ((fixed_format(places) + "\n") * len(ready)) % tuple(ready.tolist())
        pieces = text.split("\n")[:-1]
        written = np.fromiter(map(float, pieces), float, len(pieces))
        data = np.frombuffer(text.encode("ascii"), np.uint8)
        return data[data != 10], np.fromiter(map(len, pieces), np.int64, len(pieces)), written
    whole = _nearest(ready, scale)
    size = np.abs(whole)
    written = np.where(whole < 0, -(size / scale), size / scale)
    data, lengths = _digits(size, whole < 0, places)
    return data, lengths, written


def _nearest(values: np.ndarray, scale: float) -> np.ndarray:
    """The integer nearest to each exact product value * scale (n,) as float, ties to even
    (what printing value with log10(scale) decimals rounds to); |value * scale| < 2**52.

    The product is made exact as hi + lo (Dekker's two-product: hi the rounded product, lo its
    error), so the only case the rounded product cannot decide, hi exactly halfway between two
    integers, is decided by the sign of lo."""
    hi = values * scale
    split = 134217729.0  # 2**27 + 1
    c = split * values
    v_hi = c - (c - values)
    v_lo = values - v_hi
    c = split * scale
    s_hi = c - (c - scale)
    s_lo = scale - s_hi
    lo = ((v_hi * s_hi - hi) + v_hi * s_lo + v_lo * s_hi) + v_lo * s_lo
    nearest = np.rint(hi)
    off = hi - nearest  # exact
    nearest += (off == 0.5) & (lo > 0)
    nearest -= (off == -0.5) & (lo < 0)
    return nearest


def _digits(size: np.ndarray, negative: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray]:
    """The text of each size / 10**places (n,) (integers below 2**52 as floats) with ``places``
    decimals and a ``-`` where ``negative``: its bytes one after another and each length (n,).

    Digit k (from the right) of a is floor(a / 10**k) - 10 * floor(a / 10**(k + 1)); each floor
    is exact: a / 10**k is at least 10**-k from the next integer up, more than its rounding
    error (below 2**-53 * a / 10**k) while a < 2**53."""
    n = len(size)
    width = max(len(str(int(size.max()))), places + 1)  # digit columns
    floors = [size] + [np.floor(size / 10.0**k) for k in range(1, width + 1)]
    point = 1 if places else 0
    chars = np.empty((1 + width + point, n), np.uint8)  # one text a column: sign, digits, point
    chars[0] = 45
    shown = np.empty((1 + width + point, n), bool)
    shown[0] = negative
    whole = np.ones(n, np.int64)  # digits before the point: at least one
    for k in range(places + 1, width):
        whole[floors[k] >= 1] = k - places + 1
    row = 1
    for k in range(width - 1, -1, -1):
        if k == places - 1:
            chars[row] = 46
            shown[row] = True
            row += 1
        chars[row] = (floors[k] - 10.0 * floors[k + 1] + 48.0).astype(np.uint8)
        shown[row] = k < places + whole
        row += 1
    lengths = shown.sum(axis=0)
    shown = np.ascontiguousarray(shown.T)  # text by text (compacting contiguous rows is fast)
    return np.ascontiguousarray(chars.T)[shown], lengths


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
