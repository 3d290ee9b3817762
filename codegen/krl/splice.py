"""Many number literals of a program replaced at once, as bytes (the output of the KRL rewrite,
``codegen.krl.rewrite``): the new literals formatted in one pass and read back exactly
(``literals``), then copied into the program's bytes with array operations (``splice_bytes``),
never a Python string per literal.
"""

from __future__ import annotations

import numpy as np

from accugrid.codegen.krl.rigid import PAD, plain_decimals
from accugrid.codegen.textsafe import fixed_format, fixed_ready

__all__ = ["literals", "splice_bytes"]

_RUNS = 4096  # at most this many length-changing edits: copy the text between them whole


def literals(values: np.ndarray, places: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``fixed(v, places)`` of every value (n,): their bytes one after another (uint8), the
    length of each (n,), and the value each one reads as (n,) float (what ``float`` gives).

    Raises ValueError for NaN or infinity, like ``fixed``."""
    ready = fixed_ready(values, places)
    n = len(ready)
    if not n:
        return np.zeros(0, np.uint8), np.zeros(0, np.int64), np.zeros(0)
    text = ((fixed_format(places) + "\n") * n) % tuple(ready.tolist())
    data = np.frombuffer(text.encode("ascii") + bytes(PAD), np.uint8)
    ends = np.flatnonzero(data[: len(text)] == 10)
    starts = np.concatenate(([0], ends[:-1] + 1))
    points = np.flatnonzero(data[: len(text)] == 46)
    written, _, exact = plain_decimals(data, starts, ends, points)
    for i in np.flatnonzero(~exact).tolist():  # over 15 digits: read as float reads it
        written[i] = float(text[starts[i] : ends[i]])
    return data[: len(text)][data[: len(text)] != 10], ends - starts, written


def splice_bytes(
    data: bytes, starts: np.ndarray, ends: np.ndarray, new: np.ndarray, lengths: np.ndarray
) -> bytearray:
    """``data`` with ``data[starts[k]:ends[k]]`` replaced by the k-th new piece for every k:
    ``new`` (uint8) holds the pieces one after another, ``lengths`` (m,) their lengths. The
    spans (m,) are sorted and do not overlap."""
    if not len(starts):
        return bytearray(data)
    source = np.frombuffer(data, np.uint8)
    delta = lengths - (ends - starts)
    shift = np.concatenate(([0], np.cumsum(delta)))  # of the text after edit k: shift[k + 1]
    out = bytearray(len(data) + int(shift[-1]))
    target = np.frombuffer(out, np.uint8)
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
    return out
