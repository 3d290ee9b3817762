"""Program text as bytes for the dialects' fast lanes (``codegen.krl.rigid``,
``codegen.rapid.rigid``): the text's latin-1 bytes with PAD NUL bytes after them, fixed-width
windows at many offsets at once, which of their bytes are name characters, strings cut out of
them, and the distinct strings of many spans.
Offsets are byte (= character) offsets in the text."""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from accugrid.codegen.program_text import row_counts

__all__ = ["PAD", "U64", "ascii_word", "distinct", "strings", "text_bytes", "windows"]

PAD = 64  # NUL bytes after the text, so that every window read (at most PAD wide) exists
U64 = np.dtype("<u8")  # eight bytes compared as one word
_ENCODE = 1 << 22  # characters encoded at a time


def text_bytes(text: str) -> np.ndarray | None:
    """The latin-1 bytes of ``text`` and PAD NUL bytes after them (uint8); None when ``text``
    has a character beyond latin-1 (never so for a program read by ``read_program``). Encoded a
    block at a time into the one array: the whole text's bytes exist once, not twice."""
    buf = np.zeros(len(text) + PAD, np.uint8)
    try:
        for a in range(0, len(text), _ENCODE):
            part = text[a : a + _ENCODE].encode("latin-1")
            buf[a : a + len(part)] = memoryview(part)
    except UnicodeEncodeError:
        return None
    return buf


def windows(buf: np.ndarray, at: np.ndarray, width: int) -> np.ndarray:
    """``buf[at[i] : at[i] + width]`` of every i, (len(at), width) uint8 (a copy); an offset
    out of ``buf`` reads its first or last ``width`` bytes."""
    return sliding_window_view(buf, width)[np.clip(at, 0, len(buf) - width)]


def ascii_word(window: np.ndarray) -> np.ndarray:
    """Whether each byte of ``window`` (any shape, uint8) is an ASCII letter, digit or ``_``,
    by ranges in uint8 arithmetic (a table look-up of a (k, 33) window makes an index of every
    byte first: 3x as long)."""
    letter = window | 32  # A-Z as a-z; no other byte lands in a-z
    letter -= 97  # a-z: 0..25, every other byte wraps above
    word = letter < 26
    word |= (window - 48) < 10
    word |= window == 95
    return word


def strings(buf: np.ndarray, at: np.ndarray, length: np.ndarray) -> list[str]:
    """``text[at[i] : at[i] + length[i]]`` of every i (1 <= length < PAD, no LF)."""
    if not len(at):
        return []
    width = int(length.max()) + 1
    cut = windows(buf, at, width)
    column = np.arange(width)
    cut[np.arange(len(at)), length] = 10  # each string and a LF, one after another
    joined = cut[column <= length[:, None]].tobytes().decode("latin-1")
    return joined.split("\n")[:-1]


def _same(buf: np.ndarray, at: np.ndarray, first: int, size: int) -> np.ndarray:
    """Whether ``buf[a : a + size]`` equals ``buf[first : first + size]`` for each a in ``at``."""
    equal = np.ones(len(at), bool)
    for a in range(0, size, PAD):
        width = min(PAD, size - a)
        words, rest = divmod(width, 8)
        if words:
            rows = windows(buf, at + a, 8 * words).view(U64)
            equal &= row_counts(rows != buf[first + a : first + a + 8 * words].view(U64)) == 0
        if rest:
            lo = first + a + 8 * words
            rows = windows(buf, at + a + 8 * words, rest)
            equal &= row_counts(rows != buf[lo : lo + rest]) == 0
    return equal


def distinct(buf: np.ndarray, span: np.ndarray, text: str) -> tuple[list[str], np.ndarray]:
    """The distinct strings ``text[start:end]`` of the spans (k, 2), in order of first
    appearance, and the index of each span's string among them (k,)."""
    which = np.full(len(span), -1, np.int64)
    found: list[str] = []
    length = span[:, 1] - span[:, 0]
    for _ in range(4):  # the common case: one or a few tails, compared as bytes
        left = np.flatnonzero(which < 0)
        if not left.size:
            return found, which
        first = left[0]
        size = int(length[first])
        same = left[length[left] == size]
        same = same[_same(buf, span[same, 0], int(span[first, 0]), size)]
        which[same] = len(found)
        found.append(text[span[first, 0] : span[first, 1]])
    index: dict[str, int] = {s: i for i, s in enumerate(found)}
    for i in np.flatnonzero(which < 0).tolist():
        which[i] = index.setdefault(text[span[i, 0] : span[i, 1]], len(index))
    return list(index), which
